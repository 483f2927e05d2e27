#!/usr/bin/env python3
"""Summary of bench/thermostat/in.lj-light-langevin: fix pe_jump/async with
the light atoms on the fine clock against fix nve at the fine step, both
under fix langevin. Means after the first tenth of the run, standard errors
from 10 blocks; the largest difference of g(r) from fix nve's; the jump
energy in the first and the last tenth. Checks the thermostat target:
each group's mean temperature within 1 % of T = 1, g(r) within 0.01 of fix
nve's, and a jump energy that does not grow (last tenth below twice the
first). The exit code is 1 if a check fails.
usage: light_langevin.py WORKDIR [TAG_NVE TAG ...]   (default nve async)
Every TAG is compared with TAG_NVE; another realisation of fix nve (e.g.
-var seed 5821 -var tag nve2) gives the statistical floor of the g(r)
difference."""
import sys

import numpy as np

TARGET_T, T_TOL, GR_TOL, JUMP_GROWTH = 1.0, 0.01, 0.01, 2.0


def series(path):
    return np.loadtxt(path, comments="#")    # step, T slow, T light, jump energy


def rdf(path):
    rows = [line.split() for line in open(path) if not line.startswith("#")]
    return np.array([[float(r[1]), float(r[2])] for r in rows if len(r) == 4])


def mean_and_error(x, nblocks=10):
    blocks = np.array([b.mean() for b in np.array_split(x, nblocks)])
    return x.mean(), blocks.std(ddof=1) / np.sqrt(nblocks)


def main():
    work = sys.argv[1]
    tags = sys.argv[2:] if len(sys.argv) >= 4 else ["nve", "async"]
    tag_nve = tags[0]
    g_nve = rdf(f"{work}/rdf.{tag_nve}.dat")
    failed = []
    print("| integrator | T slow atoms | T light atoms | g(r): peak, largest difference from nve (r) "
          "| jump energy, first / last tenth (largest) |")
    print("|---|---|---|---|---|")
    for tag in tags:
        s = series(f"{work}/series.{tag}.dat")
        s = s[len(s) // 10:]
        cells = []
        for col, name in ((1, "slow"), (2, "light")):
            m, e = mean_and_error(s[:, col])
            cells.append(f"{m:.4f} +- {e:.4f}")
            if abs(m - TARGET_T) > T_TOL * TARGET_T:
                failed.append(f"{tag}: mean T of the {name} atoms {m:.4f}")
        g = rdf(f"{work}/rdf.{tag}.dat")
        diff = np.abs(g[:, 1] - g_nve[:, 1])
        k = int(diff.argmax())
        cells.append(f"{g[:, 1].max():.3f}, {diff[k]:.4f} (r = {g[k, 0]:.3f})")
        if diff[k] > GR_TOL:
            failed.append(f"{tag}: g(r) {diff[k]:.4f} from fix nve's")
        jump = s[:, 3]
        n = max(1, len(jump) // 10)
        first, last = jump[:n].mean(), jump[-n:].mean()
        jumps = jump.max() > 0.0    # (fix nve: 0)
        cells.append(f"{first:.4g} / {last:.4g} ({jump.max():.4g})" if jumps else "-")
        if jumps and last > JUMP_GROWTH * first:
            failed.append(f"{tag}: jump energy grew from {first:.4g} to {last:.4g}")
        print(f"| {tag} | " + " | ".join(cells) + " |")
    print()
    print("checks: " + ("all met" if not failed else "FAILED: " + "; ".join(failed)))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
