#!/usr/bin/env python3
"""Stability map of fix pe_jump/async on the 2d spring lattice with a stiff
inclusion (examples/spring-lattice), with and without the buffer keyword.

For every coarse step h_S, every K and every buffer value, run
examples/spring-lattice/in.spring-lattice for NCOARSE coarse steps on a
small lattice (default 60 x 20 cells, inclusion radius 8: 2400 atoms) with
quadrature lobatto 3, and report "ok" with the largest jump energy over the
first and the last tenth of the thermo samples (relative to H~), or the
coarse step of the fix's "is unstable" error.

  python3 bench/stability/lattice_stability.py --hs 0.2,0.3,0.4 --K 10 --buffer 0,1
"""

import argparse
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
INPUT = os.path.join(ROOT, "examples", "spring-lattice", "in.spring-lattice")


def run(lmp, workdir, hs, k, buffer, ncoarse, nx, ny, radius, quad):
    tag = f"hs{hs}_K{k}_b{buffer}"
    log = os.path.join(workdir, f"log.{tag}")
    nout = max(1, ncoarse // 100)
    cmd = [lmp, "-nocite", "-echo", "none", "-screen", "none", "-log", log, "-in", INPUT,
           "-var", "nx", str(nx), "-var", "ny", str(ny), "-var", "R", str(radius),
           "-var", "hS", str(hs), "-var", "K", str(k), "-var", "T", repr(ncoarse * hs),
           "-var", "tout", repr(nout * hs), "-var", "quad", f"{quad} buffer {buffer}"]
    subprocess.run(cmd, cwd=workdir, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   timeout=3600)
    text = open(log).read()
    m = re.search(r"unstable at step (\d+)", text)
    if m:
        return {"stable": False, "coarse_step": int(m.group(1)) // k}
    if "Loop time" not in text:
        err = re.search(r"ERROR: (.*)", text)
        return {"stable": False, "other": err.group(1)[:80] if err else "no loop time"}
    # thermo rows: Step Time ... ; columns named in the header line
    lines = text.splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.split()[:1] == ["Step"])
    cols = lines[head].split()
    rows = []
    for ln in lines[head + 1:]:
        p = ln.split()
        if len(p) != len(cols) or not p[0].isdigit():
            break
        rows.append([float(x) for x in p])
    # jump energy = H - H~ = v_H - v_Ht
    out = {"stable": True}
    if "v_H" in cols and "v_Ht" in cols and len(rows) >= 10:
        h, ht = cols.index("v_H"), cols.index("v_Ht")
        scale = abs(rows[0][ht])
        tenth = max(1, len(rows) // 10)
        out["j_first"] = max(r[h] - r[ht] for r in rows[:tenth]) / scale
        out["j_last"] = max(r[h] - r[ht] for r in rows[-tenth:]) / scale
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lmp", default=os.path.join(ROOT, "build", "lmp"))
    ap.add_argument("--hs", default="0.2,0.27,0.3,0.4,0.5,0.6,0.7")
    ap.add_argument("--K", default="5,10,20")
    ap.add_argument("--buffer", default="0,1")
    ap.add_argument("--ncoarse", type=int, default=2000)
    ap.add_argument("--nx", type=int, default=60)
    ap.add_argument("--ny", type=int, default=20)
    ap.add_argument("--R", type=float, default=8.0)
    ap.add_argument("--quadrature", default="lobatto 3")
    ap.add_argument("--workdir", default="lattice_stability_runs")
    args = ap.parse_args()
    args.workdir = os.path.abspath(args.workdir)
    os.makedirs(args.workdir, exist_ok=True)
    lmp = os.path.abspath(args.lmp)
    ks = [int(x) for x in args.K.split(",")]
    bufs = [int(x) for x in args.buffer.split(",")]
    print(f"lattice {args.nx} x {args.ny}, R = {args.R}, {args.ncoarse} coarse steps, "
          f"quadrature {args.quadrature}; cell: ok (largest jump energy / |H~| in the first / "
          f"last tenth) or the coarse step of the instability error")
    print("| h_S | buffer | " + " | ".join(f"K = {k}" for k in ks) + " |")
    print("|---|---|" + "---|" * len(ks))
    for hs in [float(x) for x in args.hs.split(",")]:
        for b in bufs:
            cells = []
            for k in ks:
                r = run(lmp, args.workdir, hs, k, b, args.ncoarse, args.nx, args.ny, args.R,
                        args.quadrature)
                if r["stable"]:
                    cells.append("ok" + (f" ({r['j_first']:.2g}/{r['j_last']:.2g})"
                                         if "j_first" in r else ""))
                elif "coarse_step" in r:
                    cells.append(f"**{r['coarse_step']}**")
                else:
                    cells.append(r["other"])
            print(f"| {hs} | {b} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
