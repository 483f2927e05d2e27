#!/usr/bin/env python3
"""Energy conservation summary of LAMMPS logs of in.lj-liquid.

    python3 energy_stats.py [--teq 0.5] log.lammps [more logs ...]

For each log: the integrator (from the fix command echoed in the log), the
loop time, and for etotal (H = pe + ke) and v_Ht (pseudo-energy of fix
pe_jump, = etotal for fix nve):
  * change during the melt of the fcc lattice, E(teq) - E(0) (teq = 0.5 tau
    by default), and over the whole run, E(end) - E(0)
  * on the equilibrated part t >= teq: change E(end) - E(teq), least-squares
    drift per tau, rms fluctuation about that line, and max - min
"""
import math
import re
import sys


def parse(path):
    integ, loop, cols, rows = "?", None, None, []
    with open(path) as fh:
        for line in fh:
            m = re.match(r"\s*fix\s+integrate\s+\S+\s+(.*)$", line)
            if m and not line.lstrip().startswith('"'):
                integ = " ".join(m.group(1).split())
            w = line.split()
            if not w:
                continue
            if w[0] == "Step":
                cols = w
                continue
            if w[0] == "Loop":
                loop = float(w[3])
                cols = None
                continue
            if cols and len(w) == len(cols):
                try:
                    rows.append(dict(zip(cols, map(float, w))))
                except ValueError:
                    pass
    return integ, loop, rows


def fit(t, y):
    n = len(t)
    tm, ym = sum(t) / n, sum(y) / n
    stt = sum((a - tm) ** 2 for a in t)
    slope = sum((a - tm) * (b - ym) for a, b in zip(t, y)) / stt if stt > 0 else 0.0
    rms = math.sqrt(sum((b - ym - slope * (a - tm)) ** 2 for a, b in zip(t, y)) / n)
    return slope, rms


def main(argv):
    teq = 0.5
    if len(argv) > 1 and argv[0] == "--teq":
        teq = float(argv[1])
        argv = argv[2:]
    if not argv:
        argv = ["log.lammps"]
    for path in argv:
        integ, loop, rows = parse(path)
        if not rows:
            print(f"{path}: no thermo output")
            continue
        dt = None
        with open(path) as fh:
            m = re.search(r"^\s*timestep\s+(\S+)", fh.read(), re.M)
            dt = float(m.group(1)) if m else 0.005
        t = [r["Step"] * dt for r in rows]
        print(f"{path}: fix {integ}, loop time {loop} s, {len(rows)} thermo lines")
        for key, name in (("TotEng", "etotal"), ("v_Ht", "Ht")):
            if key not in rows[0]:
                continue
            y = [r[key] for r in rows]
            eq = [(a, b) for a, b in zip(t, y) if a >= teq - 1e-12]
            ta, ya = [a for a, _ in eq], [b for _, b in eq]
            slope, rms = fit(ta, ya)
            print(f"  {name:6s}: E(0) {y[0]:.6f}  melt {ya[0]-y[0]:+.4e}  whole run {y[-1]-y[0]:+.4e}"
                  f" | t >= {teq}: change {ya[-1]-ya[0]:+.4e}  drift {slope:+.4e}/tau"
                  f"  rms {rms:.4e}  max-min {max(ya)-min(ya):.4e}")

if __name__ == "__main__":
    main(sys.argv[1:])
