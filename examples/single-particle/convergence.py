#!/usr/bin/env python3
"""Convergence study of fix pe_jump on a single particle (paper section 3.1).

Runs in.single-particle for a sweep of time steps and the paper's three
quadrature rules (midpoint, 3- and 5-point Gauss-Lobatto), computes the l1
error of the trajectory

    e_l1(dt) = (1/N) sum_{n=1..N} |q_n - q_ref(t_n)|,   N = T/dt,

against a converged reference (lobatto 5 at dt_min/REFINE, written at the
nodes t = k dt_min, so every run of the sweep can be sampled exactly), and
prints a table of errors, force evaluations (f_ID[5] of the fix) and observed
orders log2(e(2 dt)/e(dt)). The plot of the error against the force
evaluations goes to convergence.png (if matplotlib is available).

Usage:
    python3 convergence.py [--lmp PATH] [--np N] [--T 100] [--dts 0.1 0.05 ...]
                           [--refine 64] [--workdir DIR] [--plot convergence.png]

The LAMMPS binary is taken from --lmp, else from the environment variable
LMP, else ../../build/lmp (relative to this script) if it exists, else `lmp`
on the PATH. With --np N > 1 every run is started with mpirun -np N.
Only the Python standard library is needed for the table; matplotlib for the
plot.
"""

import argparse
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
RULES = [("midpoint", "midpoint"), ("lobatto 3", "lobatto3"), ("lobatto 5", "lobatto5")]


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


def run_lammps(opts, workdir, tag, dt, quad, every):
    """Run in.single-particle; return (q by step, cumulative force evaluations)."""
    qfile = os.path.join(workdir, "q.%s.dat" % tag)
    log = os.path.join(workdir, "log.%s" % tag)
    cmd = []
    if opts.np > 1:
        cmd += ["mpirun", "--oversubscribe", "--allow-run-as-root", "-np", str(opts.np)]
    cmd += [opts.lmp, "-in", "in.single-particle", "-screen", "none", "-log", log,
            "-var", "dt", repr(dt), "-var", "quad", quad, "-var", "T", repr(opts.T),
            "-var", "every", str(every), "-var", "qfile", qfile, "-var", "nthermo", "0"]
    res = subprocess.run(cmd, cwd=HERE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         universal_newlines=True)
    text = open(log).read() if os.path.exists(log) else ""
    m = re.search(r"PEJUMP_SUMMARY steps (\d+) evaluations (\S+)", text)
    if res.returncode != 0 or not m:
        sys.exit("LAMMPS failed (%s):\n%s\n%s" % (" ".join(cmd), res.stdout[-2000:], text[-2000:]))
    q = {}
    with open(qfile) as f:
        for line in f:
            if line.startswith("#"):
                continue
            step, _, val = line.split()
            q[int(step)] = float(val)
    return q, float(m.group(2))


def main(argv):
    ap = argparse.ArgumentParser(description="pe_jump single-particle convergence study")
    ap.add_argument("--lmp", help="LAMMPS binary with fix pe_jump")
    ap.add_argument("--np", type=int, default=1, help="MPI ranks per run (default 1)")
    ap.add_argument("--T", type=float, default=100.0, help="final time (paper: 1000)")
    ap.add_argument("--dts", type=float, nargs="+", default=[0.1, 0.05, 0.025, 0.0125, 0.00625])
    ap.add_argument("--refine", type=int, default=64,
                    help="reference step = smallest dt / REFINE (default 64)")
    ap.add_argument("--workdir", help="keep q files and logs here (default: temporary)")
    ap.add_argument("--plot", default=os.path.join(HERE, "convergence.png"))
    opts = ap.parse_args(argv)
    opts.lmp = find_lmp(opts.lmp)

    dts = sorted(opts.dts, reverse=True)
    dtmin = dts[-1]
    ratios = [dt / dtmin for dt in dts]
    if any(abs(r - round(r)) > 1e-9 for r in ratios):
        sys.exit("every dt must be an integer multiple of the smallest one")

    tmp = None
    workdir = opts.workdir
    if workdir:
        os.makedirs(workdir, exist_ok=True)
        workdir = os.path.abspath(workdir)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="pejump-conv-")
        workdir = tmp.name

    dtref = dtmin / opts.refine
    print("LAMMPS: %s, %d rank(s), T = %g" % (opts.lmp, opts.np, opts.T))
    print("reference: lobatto 5, dt = %.10g (= %g / %d)" % (dtref, dtmin, opts.refine))
    qref, evref = run_lammps(opts, workdir, "reference", dtref, "lobatto 5", opts.refine)
    # reference sample k (step k*refine) is at time k*dtmin

    results = {}
    for quad, tag in RULES:
        for dt, ratio in zip(dts, ratios):
            stride = int(round(ratio)) * opts.refine
            q, evals = run_lammps(opts, workdir, "%s.dt%g" % (tag, dt), dt, quad, 1)
            nsteps = max(q)
            err = 0.0
            for n in range(1, nsteps + 1):
                err += abs(q[n] - qref[n * stride])
            results[(quad, dt)] = (err / nsteps, evals, nsteps)

    lines = []
    lines.append("| quadrature | dt | steps | force evaluations | l1 error | observed order |")
    lines.append("|---|---|---|---|---|---|")
    for quad, _ in RULES:
        prev = None
        for dt in dts:
            err, evals, nsteps = results[(quad, dt)]
            order = "" if prev is None else "%.3f" % math.log2(prev / err)
            lines.append("| %s | %g | %d | %.0f | %.4e | %s |" % (quad, dt, nsteps, evals, err, order))
            prev = err
    print("\n".join(lines))

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not available: no plot")
        return
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for (quad, _), marker in zip(RULES, "os^"):
        xs = [results[(quad, dt)][1] for dt in dts]
        ys = [results[(quad, dt)][0] for dt in dts]
        ax.loglog(xs, ys, marker=marker, label=quad)
    # slope -2 guide, a factor 2 below the last midpoint point
    x0, y0 = results[("midpoint", dts[-1])][1], 0.5 * results[("midpoint", dts[-1])][0]
    xs = [x0 / 16.0, x0]
    ax.loglog(xs, [y0 * (x0 / x) ** 2 for x in xs], "k--", lw=1, label="slope -2")
    ax.set_xlabel("force evaluations (f_ID[5])")
    ax.set_ylabel("l1 error of q")
    ax.set_title("fix pe_jump, single particle, T = %g" % opts.T)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(opts.plot, dpi=120)
    print("plot: %s" % opts.plot)


if __name__ == "__main__":
    main(sys.argv[1:])
