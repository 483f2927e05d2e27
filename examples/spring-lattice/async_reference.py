#!/usr/bin/env python3
"""Independent numpy implementation of the asynchronous scheme of the paper
(section 4, two-step form, midpoint rule, `init kick`) for this lattice,
to check fix pe_jump/async against it and to tell a scheme property from an
implementation bug.

    lmp -in in.spring-lattice -var check yes -var quad midpoint \\
        -var nx 60 -var ny 20 -var R 8 -var hS 0.4 -var T 4
    python3 async_reference.py check.t0.data 0.4 10 10 check.final.dump
        -> max |x_LAMMPS - x_reference| after 10 coarse steps
    python3 async_reference.py check.t0.data 0.4 10 400
        -> jump energy (1/8) sum |[v]|^2 every 20 coarse steps

Arguments: data file written by the input at t = 0 (positions and
velocities of the pulse), h_S, K, number of coarse steps, and optionally
the LAMMPS dump of the final positions to compare with. Force constants:
km = 1, ki = 100 (bond types 1 and 2); walls = the atoms within 0.25 of the
left and 0.75 of the right box edge, as in the input; y is periodic.

The scheme, per coarse step [t^n, t^n + h_S] with h_F = h_S/K:
  for m = 0..K-1: forces of the fine bonds (those with an atom of the fast
    group) at the fine midpoint, fast-group atoms at q + h_F/2 v^{+},
    slow atoms on their coarse free flight q_S^n + (m + 1/2) h_F v_S^{+};
    fast-group atoms: q += h_F v^{+}, v^{+} <- v^{-} + 2 h_F F/m, v^{-} <- old v^{+};
    slow atoms accumulate h_F F;
  slow atoms: forces of the coarse bonds at q_S^n + h_S/2 v_S^{+};
    q_S += h_S v_S^{+}, v_S^{+} <- v_S^{-} + 2 (accumulated + h_S F_coarse)/m.
  start: v^{-/+} = v0 -/+ (h/2) F(q0)/m with each atom's own step h.
Only numpy is needed.
"""
import sys

import numpy as np


def read_data(path):
    lines = open(path).read().split("\n")
    box = {}
    for line in lines:
        w = line.split()
        if len(w) == 4 and w[2] == "xlo":
            box["x"] = (float(w[0]), float(w[1]))
        if len(w) == 4 and w[2] == "ylo":
            box["y"] = (float(w[0]), float(w[1]))

    def section(name):
        i = next(k for k, line in enumerate(lines) if line.startswith(name))
        out, j = [], i + 2
        while j < len(lines) and lines[j].strip():
            out.append(lines[j].split())
            j += 1
        return out

    atoms, vel, bonds = section("Atoms"), section("Velocities"), section("Bonds")
    n = len(atoms)
    x, v, typ = np.zeros((n, 2)), np.zeros((n, 2)), np.zeros(n, int)
    for a in atoms:
        i = int(a[0]) - 1
        typ[i] = int(a[2])
        x[i] = [float(a[3]), float(a[4])]
    for a in vel:
        v[int(a[0]) - 1] = [float(a[1]), float(a[2])]
    b = np.array([[int(w[1]), int(w[2]) - 1, int(w[3]) - 1] for w in bonds])
    return x, v, typ, b, box


def main(argv):
    data, hS, K, ncoarse = argv[0], float(argv[1]), int(argv[2]), int(argv[3])
    km, ki = 1.0, 100.0
    x, v, typ, b, box = read_data(data)
    Ly = box["y"][1] - box["y"][0]
    xlo, xhi = box["x"]
    wall = (x[:, 0] < xlo + 0.25) | (x[:, 0] > xhi - 0.75)
    fastg = (typ == 2) & ~wall
    slow = ~fastg & ~wall
    Kb = np.where(b[:, 0] == 1, km / 2, ki / 2)
    I, J = b[:, 1], b[:, 2]
    fine = fastg[I] | fastg[J]
    hF = hS / K

    def force(pos, sel):
        d = pos[J] - pos[I]
        d[:, 1] -= Ly * np.round(d[:, 1] / Ly)
        r = np.sqrt((d ** 2).sum(1))
        fb = (2 * Kb * (r - 1.0) / r)[:, None] * d
        fb[~sel] = 0.0
        f = np.zeros_like(pos)
        np.add.at(f, I, fb)
        np.add.at(f, J, -fb)
        return f

    f0 = force(x, np.ones(len(b), bool))
    h = np.where(fastg, hF, hS)[:, None]
    vm, vp = v - 0.5 * h * f0, v + 0.5 * h * f0
    vm[wall] = vp[wall] = 0.0
    q = x.copy()
    every = max(1, min(20, ncoarse // 10))
    for nc in range(ncoarse):
        qS0 = q.copy()
        facc = np.zeros_like(q)
        for m in range(K):
            mid = q.copy()
            mid[fastg] = q[fastg] + 0.5 * hF * vp[fastg]
            mid[slow] = qS0[slow] + (m + 0.5) * hF * vp[slow]
            f = force(mid, fine)
            q[fastg] += hF * vp[fastg]
            vnew = vm[fastg] + 2 * hF * f[fastg]
            vm[fastg] = vp[fastg]
            vp[fastg] = vnew
            facc[slow] += hF * f[slow]
        mid = q.copy()
        mid[slow] = qS0[slow] + 0.5 * hS * vp[slow]
        fS = force(mid, ~fine)
        q[slow] = qS0[slow] + hS * vp[slow]
        vnew = vm[slow] + 2 * (facc[slow] + hS * fS[slow])
        vm[slow] = vp[slow]
        vp[slow] = vnew
        if (nc + 1) % every == 0 or nc == ncoarse - 1:
            je = 0.125 * ((vp - vm) ** 2).sum()
            print(f"coarse step {nc + 1}: jump energy {je:.6e}", flush=True)
            if not np.isfinite(je) or je > 1e6:
                break
    if len(argv) > 4:
        d = np.loadtxt(argv[4], skiprows=9)
        d = d[np.argsort(d[:, 0])]
        print(f"max |x_LAMMPS - x_reference| after {ncoarse} coarse steps: "
              f"{np.abs(d[:, 1:3] - q).max():.3e}")


if __name__ == "__main__":
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    main(sys.argv[1:])
