#!/usr/bin/env python3
"""Pseudo-energy conservation table of the nonlinear string (paper Table of
section 3.3) and the midpoint time-step sweep (paper Figure on the maximal
pseudo-energy variation against the time step).

For alpha in {0, 0.8, 0.99} and A in {0.01, 0.1, 0.3} runs in.nonlinear-string
with quadrature midpoint, legendre 3 and legendre 5 at dt = 0.0033 up to t = 1
and prints max_n |H~^n - H~^0| / |H~^0| (the PEJUMP_SUMMARY line of the log).
Then, for alpha = 0.99, A = 0.3 and the midpoint rule, it halves dt three
times and prints the observed order of the pseudo-energy error.

Usage:
    python3 pseudo_energy_table.py [--lmp PATH] [--np N]

The LAMMPS binary is taken from --lmp, else from the environment variable
LMP, else ../../build/lmp if it exists, else `lmp` on the PATH.
Only the Python standard library is needed.
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


def run(opts, tmp, **var):
    log = os.path.join(tmp, "log.lammps")
    cmd = []
    if opts.np > 1:
        cmd += ["mpirun", "--oversubscribe", "--allow-run-as-root", "-np", str(opts.np)]
    cmd += [opts.lmp, "-in", "in.nonlinear-string", "-screen", "none", "-log", log,
            "-var", "nthermo", "0"]
    for key, val in var.items():
        cmd += ["-var", key, str(val)]
    res = subprocess.run(cmd, cwd=HERE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         universal_newlines=True)
    text = open(log).read() if os.path.exists(log) else ""
    m = re.search(r"^PEJUMP_SUMMARY max.*max\|H~-H~0\|/\|H~0\| (\S+)", text, re.M)
    ev = re.search(r"^PEJUMP_SUMMARY .*force evaluations (\S+)", text, re.M)
    if res.returncode != 0 or not m:
        sys.exit("LAMMPS failed (%s):\n%s\n%s" % (" ".join(cmd), res.stdout[-2000:], text[-2000:]))
    return float(m.group(1)), float(ev.group(1))


def main(argv):
    ap = argparse.ArgumentParser(description="nonlinear string pseudo-energy table")
    ap.add_argument("--lmp")
    ap.add_argument("--np", type=int, default=1)
    opts = ap.parse_args(argv)
    opts.lmp = find_lmp(opts.lmp)

    rules = ["midpoint", "legendre 3", "legendre 5"]
    alphas = ["0", "0.8", "0.99"]
    amps = ["0.01", "0.1", "0.3"]
    with tempfile.TemporaryDirectory(prefix="pejump-string-") as tmp:
        print("max_n |H~^n - H~^0| / |H~^0|, dt = 0.0033, t in [0, 1]\n")
        print("| rule | " + " | ".join("a=%s A=%s" % (a, u) for a in alphas for u in amps) + " |")
        print("|---" * (1 + len(alphas) * len(amps)) + "|")
        for rule in rules:
            row = [run(opts, tmp, alpha=a, A=u, quad=rule)[0] for a in alphas for u in amps]
            print("| %s | " % rule + " | ".join("%.1e" % x for x in row) + " |")

        print("\nmidpoint, alpha = 0.99, A = 0.3: time-step sweep\n")
        print("| dt | steps | max rel. pseudo-energy variation | observed order |")
        print("|---|---|---|---|")
        prev = None
        for k in range(4):
            dt = 0.0033 / 2 ** k
            err, _ = run(opts, tmp, alpha="0.99", A="0.3", quad="midpoint", dt=repr(dt))
            order = "" if prev is None else "%.2f" % math.log2(prev / err)
            print("| %.6g | %d | %.3e | %s |" % (dt, round(1.0 / dt), err, order))
            prev = err


if __name__ == "__main__":
    main(sys.argv[1:])
