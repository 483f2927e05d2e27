#!/usr/bin/env python3
"""Stability map of fix pe_jump/async on the inhomogeneous 1D wave.

The paper's test case (Marazzato et al., CMAME 347 (2019), section
"Inhomogeneous wave propagation"): u_tt = (c(x)^2 u_x)_x on (0,1), u = 0 at
both ends, c = 10 for x <= 0.5 and c = 1 for x > 0.5, discretised on N
intervals of length dx = 1/N with lumped unit masses. Site i (i = 0..N) is
LAMMPS atom i+1 at x = i a + u_i (rest spacing a = 1 by default, so that the
harmonic bond energy K (r - a)^2 = K (u_i - u_{i-1})^2); the spring between sites i-1 and
i has the energy (1/2) (c/dx)^2 (u_i - u_{i-1})^2, i.e. bond_style harmonic
K = c(x_{i-1/2})^2 / (2 dx^2). The end sites 0 and N are outside the fix
group (fixed). The fast group is the c = 10 half (sites 1..N/2, x_i <= 0.5,
the last of them is the mixed atom), the slow atoms are the rest.

Initial values: u0(x) = 1e-2 exp(-(20(x-0.2))^2) on (0,0.5), and
v0 = -c1 u0'(x) = 80 (x-0.2) exp(-(20(x-0.2))^2) on (0,0.5) (a right-going
pulse; the v0 printed in the paper lacks the factor c1, see
doc/theory.md, section 6).

For every coarse step h_S (given as h_S/dx) and every K (fine steps per
coarse step, h_F = h_S/K), run NCOARSE coarse steps with
"fix pe_jump/async K fast" (default midpoint rule and kick initialisation,
or --quadrature) and print energies at every coarse node. A run is
"stable" if it completes; otherwise the step at which the fix stopped
with its "is unstable at step N" ERROR is recorded. Any other end (another
error, a crash, a NaN/inf in the thermo output, a time-out) is reported as
such. For completed runs the table gives the largest variation of the
pseudo-energy H~ = pe + f_ID and of the discrete energy H = pe + ke over
the coarse nodes, relative to their initial values.

Usage (one run at a time, serial LAMMPS):
  python3 bench/stability/wave_stability.py [--lmp build/lmp] [--N 250]
      [--hs 0.3,0.4,...] [--K 5,10,20] [--ncoarse 20000]
      [--quadrature midpoint] [--spacing 1] [--integrator async|sync]
      [--workdir DIR] [--out table.md]
--integrator sync runs fix pe_jump with h = h_F everywhere for the same
number of fine steps (the synchronous reference); --spacing changes the
rest spacing of the sites (only the round-off of the positions depends
on it, as long as neighbouring sites do not cross).
The markdown table goes to stdout (and to --out if given); inputs, data
files and logs of every run stay in --workdir.
"""

import argparse
import math
import os
import re
import subprocess
import sys
import time

C_FAST, C_SLOW = 10.0, 1.0


def u0(x):
    return 1.0e-2 * math.exp(-(20.0 * (x - 0.2)) ** 2) if 0.0 < x < 0.5 else 0.0


def v0(x):
    # -c1 u0'(x)
    return 80.0 * (x - 0.2) * math.exp(-(20.0 * (x - 0.2)) ** 2) if 0.0 < x < 0.5 else 0.0


def c_of(x):
    return C_FAST if x <= 0.5 else C_SLOW


def write_data(path, n, a):
    dx = 1.0 / n
    lines = [
        f"inhomogeneous 1D wave, N = {n} intervals (site i = atom i+1 at x = i + u_i)",
        "",
        f"{n + 1} atoms",
        f"{n} bonds",
        "1 atom types",
        "2 bond types",
        "",
        f"{-a:.17g} {(n + 1) * a:.17g} xlo xhi",
        "-1.0 1.0 ylo yhi",
        "-1.0 1.0 zlo zhi",
        "",
        "Masses",
        "",
        "1 1.0",
        "",
        "Atoms # bond",
        "",
    ]
    for i in range(n + 1):
        lines.append(f"{i + 1} 1 1 {i * a + u0(i * dx):.17g} 0.0 0.0")
    lines += ["", "Velocities", ""]
    for i in range(n + 1):
        lines.append(f"{i + 1} {v0(i * dx):.17g} 0.0 0.0")
    lines += ["", "Bonds", ""]
    for i in range(1, n + 1):
        btype = 1 if c_of((i - 0.5) * dx) == C_FAST else 2
        lines.append(f"{i} {btype} {i} {i + 1}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def nfast(n):
    # sites 1..n_fast have x_i <= 0.5
    return sum(1 for i in range(1, n) if i / n <= 0.5)


def write_input(path, data, n, a, hs_dx, k, ncoarse, quadrature, integrator="async"):
    dx = 1.0 / n
    hf = hs_dx * dx / k
    kfast = C_FAST ** 2 / (2.0 * dx * dx)
    kslow = C_SLOW ** 2 / (2.0 * dx * dx)
    quad = f" quadrature {quadrature}" if quadrature else ""
    if integrator == "async":
        fix = f"fix             1 chain pe_jump/async {k} fast{quad}"
        thermo = ("thermo_style    custom step f_1[6] pe ke etotal v_Ht f_1[2] f_1[7] f_1[8] "
                  "f_1[9] f_1[5]")
    else:
        # fix pe_jump at the fine step everywhere, same columns (every
        # output is a "coarse node", no classes)
        fix = (f"fix             1 chain pe_jump{quad}\n"
               "variable        one equal 1\nvariable        zero equal 0")
        thermo = ("thermo_style    custom step v_one pe ke etotal v_Ht f_1[2] v_zero v_zero "
                  "v_zero f_1[5]")
    text = f"""# inhomogeneous wave, N = {n}, h_S = {hs_dx} dx, K = {k}, h_F = h_S/K
units           lj
dimension       3
atom_style      bond
boundary        f f f
atom_modify     map array
read_data       {data}
bond_style      harmonic
bond_coeff      1 {kfast:.17g} {a:.17g}
bond_coeff      2 {kslow:.17g} {a:.17g}
comm_modify     cutoff 2.0
group           ends id 1 {n + 1}
group           chain subtract all ends
group           fast id 2:{nfast(n) + 1}
{fix}
timestep        {hf:.17g}
variable        Ht equal pe+f_1
{thermo}
thermo_modify   norm no format float %.17g
thermo          {k}
run             {k * ncoarse}
"""
    with open(path, "w") as f:
        f.write(text)


NCOLUMNS = 11    # step, coarse flag, pe, ke, etotal, H~, jump energy, 3 counts, evaluations


def parse_log(text):
    rows, reading = [], False
    for line in text.splitlines():
        words = line.split()
        if words and words[0] == "Step" and len(words) == NCOLUMNS:
            reading = True
            continue
        if reading:
            if len(words) != NCOLUMNS:
                reading = False
                continue
            try:
                rows.append([float(w) for w in words])
            except ValueError:
                reading = False
    return rows


def wait_for_binary(lmp, patience=900.0):
    """the binary may be rebuilt while the study runs: wait until it is back"""
    waited = 0.0
    while not (os.path.isfile(lmp) and os.access(lmp, os.X_OK)):
        if waited >= patience:
            sys.exit(f"{lmp} is missing")
        time.sleep(15.0)
        waited += 15.0
    if waited:
        time.sleep(15.0)    # let a link finish


def run_one(lmp, workdir, n, a, hs_dx, k, ncoarse, quadrature, timeout, integrator="async"):
    tag = f"N{n}_a{a:g}_hs{hs_dx:g}_K{k}" + (
        "_" + quadrature.replace(" ", "") if quadrature else "") + (
        "_sync" if integrator == "sync" else "")
    data = os.path.join(workdir, f"wave_N{n}_a{a:g}.data")
    write_data(data, n, a)
    inp = os.path.join(workdir, f"in.{tag}")
    log = os.path.join(workdir, f"log.{tag}")
    write_input(inp, os.path.basename(data), n, a, hs_dx, k, ncoarse, quadrature, integrator)
    for attempt in range(40):
        if attempt:
            time.sleep(30.0)
        wait_for_binary(lmp)
        if os.path.exists(log):
            os.remove(log)
        t0 = time.time()
        try:
            proc = subprocess.run([lmp, "-nocite", "-in", os.path.basename(inp), "-log",
                                   os.path.basename(log), "-screen", "none"], cwd=workdir,
                                  capture_output=True, text=True, timeout=timeout)
            rc, hung = proc.returncode, False
        except subprocess.TimeoutExpired:
            rc, hung = None, True
        wall = time.time() - t0
        # the binary or its shared library is being rebuilt (the loader
        # fails before LAMMPS starts, no log): wait and run again
        if rc in (126, 127) and not os.path.exists(log):
            print(f"# {tag}: {lmp} does not start ({proc.stderr.strip()[:200]}): "
                  "waiting for the build", file=sys.stderr, flush=True)
            continue
        break
    text = open(log).read() if os.path.exists(log) else ""
    rows = parse_log(text)
    res = {"tag": tag, "hs": hs_dx, "K": k, "wall": wall, "rc": rc, "rows": len(rows)}

    nonfinite = [r for r in rows if not all(math.isfinite(v) for v in r)]
    err = re.search(r"^ERROR.*$", text, re.M)
    if hung:
        res["status"] = f"HANG (no end after {timeout} s)"
    elif nonfinite:
        res["status"] = f"NaN/inf in thermo output at step {int(nonfinite[0][0])}"
    elif err:
        m = re.search(r"is unstable at step (\d+)", err.group(0))
        if m:
            step = int(m.group(1))
            res["status"] = "unstable"
            res["step"] = step
            res["error"] = err.group(0)
        else:
            res["status"] = "other ERROR: " + err.group(0)
    elif rc != 0:
        res["status"] = f"crash (exit code {rc}, no ERROR line)"
    elif not rows or int(rows[-1][0]) != k * ncoarse:
        res["status"] = "incomplete output"
    else:
        res["status"] = "stable"

    coarse = [r for r in rows if r[1] == 1.0 and all(math.isfinite(v) for v in r)]
    if coarse:
        ht0, h0 = coarse[0][5], coarse[0][4]
        res["dHt"] = max(abs(r[5] - ht0) for r in coarse) / abs(ht0)
        res["dH"] = max(abs(r[4] - h0) for r in coarse) / abs(h0)
        res["Hmax"] = max(r[4] for r in coarse) / h0
        # bounded or growing: largest jump energy (H - H~) over the first and
        # over the last tenth of the coarse nodes, relative to H(0)
        tenth = max(1, len(coarse) // 10)
        res["J_first"] = max(r[6] for r in coarse[:tenth]) / abs(h0)
        res["J_last"] = max(r[6] for r in coarse[-tenth:]) / abs(h0)
        # growth factor of the amplitude per coarse step before an error, from
        # the jump energy J over its last rise by a factor 100 (or from the
        # start): (J_end / J_start)^(1 / (2 coarse steps))
        if res["status"] == "unstable" and len(coarse) >= 5:
            j_end = coarse[-1][6]
            first = 0
            for idx in range(len(coarse) - 1, -1, -1):
                if coarse[idx][6] <= 0.01 * j_end:
                    first = idx
                    break
            steps = (coarse[-1][0] - coarse[first][0]) / k
            if steps >= 4 and coarse[first][6] > 0.0:
                res["rho"] = (j_end / coarse[first][6]) ** (0.5 / steps)
        res["counts"] = tuple(int(v) for v in coarse[-1][7:10])
        res["evals"] = coarse[-1][10]
        res["ncoarse_rows"] = len(coarse)
        # every thermo row (every K steps) must be a coarse node
        res["all_coarse"] = len(coarse) == len(rows)
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--lmp", default=os.path.join(here, "..", "..", "build", "lmp"))
    ap.add_argument("--N", type=int, default=250)
    ap.add_argument("--hs", default="0.3,0.4,0.5,0.6,0.7,0.8,0.9,1.0",
                    help="coarse steps h_S/dx, comma separated")
    ap.add_argument("--K", default="5,10,20", help="fine steps per coarse step")
    ap.add_argument("--ncoarse", type=int, default=20000)
    ap.add_argument("--spacing", type=float, default=1.0,
                    help="rest spacing a of the lattice sites (x_i = i a + u_i; default 1)")
    ap.add_argument("--quadrature", default="", help='e.g. "lobatto 3" (default: midpoint)')
    ap.add_argument("--workdir", default="wave_stability_runs")
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--out", default="")
    ap.add_argument("--integrator", choices=["async", "sync"], default="async",
                    help="sync: fix pe_jump with h = h_F everywhere, for comparison")
    args = ap.parse_args()

    if args.N % 2:
        sys.exit("N must be even (the interface x = 0.5 is a lattice site)")
    lmp = os.path.abspath(args.lmp)
    os.makedirs(args.workdir, exist_ok=True)
    hs_list = [float(v) for v in args.hs.split(",")]
    k_list = [int(v) for v in args.K.split(",")]

    results = {}
    for hs in hs_list:
        for k in k_list:
            r = run_one(lmp, args.workdir, args.N, args.spacing, hs, k, args.ncoarse, args.quadrature,
                        args.timeout, args.integrator)
            results[(hs, k)] = r
            extra = ""
            if r["status"] == "stable":
                extra = (f" dHt {r['dHt']:.2e} dH {r['dH']:.2e} J {r['J_first']:.3g}"
                         f"/{r['J_last']:.3g}")
            elif "step" in r:
                extra = f" step {r['step']} (coarse step {r['step'] / k:.1f})"
                if "rho" in r:
                    extra += f" growth {r['rho']:.5f} per coarse step"
            print(f"# {r['tag']}: {r['status']}{extra} [{r['wall']:.1f} s]", file=sys.stderr,
                  flush=True)

    out = []
    quad = args.quadrature or "midpoint"
    what = "fix pe_jump/async K fast" if args.integrator == "async" else \
        "fix pe_jump at h = h_F (reference)"
    out.append(f"{what}: N = {args.N}, {args.ncoarse} coarse steps, quadrature {quad}, init kick, "
               f"spacing {args.spacing:g}. Cell: h_F/dx; result. Stable runs: dH~ = largest "
               "|H~ - H~(0)|/|H~(0)| and dH = largest |H - H(0)|/H(0) over the coarse nodes, "
               "J = largest jump energy / H(0) over the first / the last tenth of the coarse nodes "
               "(equal values: bounded, no slow growth). Unstable runs: the step (and coarse "
               "step) of the ERROR.")
    out.append("")
    out.append("| h_S/dx | " + " | ".join(f"K = {k}" for k in k_list) + " |")
    out.append("|---|" + "---|" * len(k_list))
    for hs in hs_list:
        cells = []
        for k in k_list:
            r = results[(hs, k)]
            hf = f"h_F = {hs / k:.3g} dx: "
            if r["status"] == "stable":
                cells.append(hf + f"stable; dH~ {r['dHt']:.1e}; dH {r['dH']:.1e}; "
                             f"J {r['J_first']:.2f}/{r['J_last']:.2f}")
            elif r["status"] == "unstable":
                grow = f", growth {r['rho']:.4f}/coarse step" if "rho" in r else ""
                cells.append(hf + f"ERROR at step {r['step']} (coarse step {r['step'] // k}"
                             f"{grow})")
            else:
                cells.append(hf + r["status"])
        out.append(f"| {hs:g} | " + " | ".join(cells) + " |")
    text = "\n".join(out) + "\n"
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
