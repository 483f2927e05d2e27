#!/usr/bin/env python3
"""Stability table of fix pe_jump/async on the inhomogeneous wave.

For every coarse step h_S = ratio * dx and every K (fine step h_F = h_S/K)
runs in.wave-inhomogeneous for NC coarse steps (default 20000) and reports
either the step at which fix pe_jump/async stopped with its "is unstable"
error, or, for runs that finish, the largest ratio of the jump energy
H - H~ to the pseudo-energy H~ seen in the thermo output (every NC/20
coarse steps). A run that finishes with a small ratio is stable.

Usage:
    python3 stability_table.py [--lmp PATH] [--N 250] [--ncoarse 20000]
                               [--ratios 0.3,0.4,...] [--K 5,10,20]

The LAMMPS binary is taken from --lmp, else from the environment variable
LMP, else ../../build/lmp if it exists, else `lmp` on the PATH.
Only the Python standard library is needed. Serial runs, one at a time;
with the defaults (24 runs) a few minutes on one core.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def find_lmp(arg):
    if arg:
        return arg
    if os.environ.get("LMP"):
        return os.environ["LMP"]
    guess = os.path.normpath(os.path.join(HERE, "..", "..", "build", "lmp"))
    if os.path.exists(guess):
        return guess
    found = shutil.which("lmp")
    if not found:
        sys.exit("no LAMMPS binary: pass --lmp PATH or set LMP")
    return found


def thermo_rows(text):
    rows, cols = [], None
    for line in text.splitlines():
        w = line.split()
        if not w:
            continue
        if w[0] == "Step":
            cols = w
            continue
        if cols and len(w) == len(cols):
            try:
                rows.append(dict(zip(cols, map(float, w))))
            except ValueError:
                pass
    return rows


def run(opts, tmp, ratio, K):
    N = opts.N
    hS = ratio / N
    T = opts.ncoarse * hS
    tout = (opts.ncoarse // 20) * hS
    log = os.path.join(tmp, "log.lammps")
    cmd = [opts.lmp, "-in", "in.wave-inhomogeneous", "-screen", "none", "-log", log,
           "-var", "N", str(N), "-var", "hS_dx", repr(ratio), "-var", "K", str(K),
           "-var", "T", repr(T), "-var", "tout", repr(tout)]
    res = subprocess.run(cmd, cwd=HERE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         universal_newlines=True)
    text = open(log).read() if os.path.exists(log) else ""
    err = re.search(r"^ERROR.*unstable at step (\d+)", text + "\n" + res.stdout, re.M)
    if err:
        # one LAMMPS step of fix pe_jump/async is one coarse step
        return "stop %d" % int(err.group(1))
    if res.returncode != 0 or "WAVE async" not in text:
        sys.exit("LAMMPS failed (%s):\n%s\n%s" % (" ".join(cmd), res.stdout[-2000:], text[-2000:]))
    rows = thermo_rows(text)
    jump = max((r["v_H"] - r["v_Ht"]) / abs(r["v_Ht"]) for r in rows)
    return "ok %.2g" % jump


def main(argv):
    ap = argparse.ArgumentParser(description="stability table of fix pe_jump/async, wave example")
    ap.add_argument("--lmp")
    ap.add_argument("--N", type=int, default=250)
    ap.add_argument("--ncoarse", type=int, default=20000)
    ap.add_argument("--ratios", default="0.3,0.4,0.5,0.6,0.7,0.8,0.9,1.0")
    ap.add_argument("--K", default="5,10,20")
    opts = ap.parse_args(argv)
    opts.lmp = find_lmp(opts.lmp)
    ratios = [float(r) for r in opts.ratios.split(",")]
    Ks = [int(k) for k in opts.K.split(",")]

    print("N = %d, %d coarse steps: 'ok x' = finished, x = max (H - H~)/|H~| at the"
          " thermo outputs;\n'stop n' = fix stopped with its instability error in"
          " coarse step (LAMMPS step) n\n" % (opts.N, opts.ncoarse))
    print("| h_S/dx | " + " | ".join("K = %d" % k for k in Ks) + " |")
    print("|---" * (1 + len(Ks)) + "|")
    with tempfile.TemporaryDirectory(prefix="pejump-wave-") as tmp:
        for ratio in ratios:
            cells = [run(opts, tmp, ratio, K) for K in Ks]
            print("| %g | " % ratio + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
