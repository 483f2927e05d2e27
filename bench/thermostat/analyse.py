#!/usr/bin/env python3
"""Summarise the long fix langevin runs of run.sh: mean temperature (with
the standard error from 10 blocks), mean potential energy per atom, the
jump energy at the start and the end and its largest value, and the
largest difference of the radial distribution function from fix nve's.
usage: analyse.py WORKDIR TAG...   (the first tag is the reference)"""
import sys

import numpy as np


def series(path):
    return np.loadtxt(path, comments="#")    # step, temp, pe (total), jump


def rdf(path):
    rows = [line.split() for line in open(path) if not line.startswith("#")]
    rows = [r for r in rows if len(r) == 4]    # row index, r, g, coord
    return np.array([[float(r[1]), float(r[2])] for r in rows])


def block_error(x, nblocks=10):
    blocks = np.array_split(x, nblocks)
    means = np.array([b.mean() for b in blocks])
    return means.std(ddof=1) / np.sqrt(nblocks)


def main():
    work, tags = sys.argv[1], sys.argv[2:]
    natoms = 256
    ref = rdf(f"{work}/rdf.{tags[0]}.dat")
    print("| integrator | mean T (+- s.e.) | mean pe per atom | jump energy first / last 10% of the run | largest jump energy | max \\|g(r) - g_nve(r)\\| |")
    print("|---|---|---|---|---|---|")
    for tag in tags:
        s = series(f"{work}/series.{tag}.dat")
        t, pe, jump = s[:, 1], s[:, 2] / natoms, s[:, 3]
        n = len(jump) // 10
        g = rdf(f"{work}/rdf.{tag}.dat")
        dg = np.abs(g[:, 1] - ref[:, 1]).max()
        print(f"| {tag} | {t.mean():.4f} +- {block_error(t):.4f} | {pe.mean():.4f} +- "
              f"{block_error(pe):.4f} | {jump[:n].mean():.4g} / {jump[-n:].mean():.4g} | "
              f"{jump.max():.4g} | {dg:.4f} (max g {g[:, 1].max():.3f}) |")


if __name__ == "__main__":
    main()
