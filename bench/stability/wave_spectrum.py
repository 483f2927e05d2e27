#!/usr/bin/env python3
"""Spectral radius of one coarse step of fix pe_jump/async on the
inhomogeneous 1D wave (linear analysis, independent of LAMMPS).

The scheme (midpoint rule; for this linear problem every rule gives the
same scheme) maps the state at a coarse node, (u, v^{n+1/2}, [v]^n) of the
N-1 moving sites, linearly onto the state at the next coarse node. This
script builds that matrix column by column (numpy, the same equations as
wave_reference.py, which reproduces the LAMMPS positions to 1e-12) and
prints its spectral radius rho: rho > 1 means the amplitude grows by the
factor rho per coarse step (the LAMMPS runs of wave_stability.py stop with
the instability error after about log(1e6)/log(rho) coarse steps).

Options:
  --buffer B      B layers of slow sites next to the interface on the fine
                  clock (fix pe_jump/async ... buffer B)
  --variant       remedies that were tried and rejected, kept to reproduce
                  doc/async_stability.md:
                  extrapolate G: add G times the parasitic estimate
                      [v]^n - H (A_{n-1} + A_n)/2 to the slow jumps
                  nodekick G: blend the slow jumps with the node kick
                      H F(q^{n+1})/m (G = 1: slow atoms take leapfrog steps)
  --eigvec        print where the eigenvector of the largest eigenvalue sits

  python3 bench/stability/wave_spectrum.py --N 250 --hs 0.45,0.5,1.0 --K 10,20,30
  python3 bench/stability/wave_spectrum.py --N 250 --hs 0.5 --K 20 --buffer 1
"""

import argparse
import os
import sys

import numpy as np

sys.dont_write_bytecode = True    # no __pycache__ in the repository
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import wave_stability as ws    # noqa: E402


def system(n, buffer=0):
    """Stiffness matrices of the fine and coarse springs, fine-clock mask."""
    dx = 1.0 / n
    m = n - 1    # moving sites 1..n-1 -> rows 0..m-1
    kb = np.array([ws.c_of((b - 0.5) * dx) ** 2 / dx ** 2 for b in range(1, n + 1)])
    nf = ws.nfast(n) + buffer
    fast = np.array([1 <= i <= nf for i in range(1, n)])
    # spring b (1..n) joins sites b-1 and b; fine if it touches a fine site
    fine_spring = np.array([(1 <= b - 1 <= nf) or (1 <= b <= nf) for b in range(1, n + 1)])

    def stiffness(mask):
        s = np.zeros((m, m))
        for b in range(1, n + 1):
            if not mask[b - 1]:
                continue
            ends = [e for e in (b - 1, b) if 1 <= e <= n - 1]
            for e in ends:
                s[e - 1, e - 1] += kb[b - 1]
            if len(ends) == 2:
                s[b - 2, b - 1] -= kb[b - 1]
                s[b - 1, b - 2] -= kb[b - 1]
        return s
    return m, fast, stiffness(fine_spring), stiffness(~fine_spring)


def coarse_step_matrix(n, hs_dx, k, buffer=0, variant=None, gamma=0.0):
    m, fast, sf, sc = system(n, buffer)
    slow = ~fast
    big = hs_dx / n
    hf = big / k
    eye = np.eye(4 * m)    # state: u, v^{n+1/2}, [v]^n, A_{n-1} (slow rows)
    u, vh, jump, aprev = (eye[r * m:(r + 1) * m].copy() for r in range(4))
    start = u.copy()
    facc = np.zeros_like(u)
    for _ in range(k):
        f = -sf @ (u + 0.5 * hf * vh)
        u += hf * vh
        facc[slow] += hf * f[slow]
        jump[fast] = 2.0 * hf * f[fast] - jump[fast]
        vh[fast] += jump[fast]
    a = facc / big - sc @ (start + 0.5 * big * vh)
    new = 2.0 * big * a[slow] - jump[slow]
    if variant == "extrapolate":
        new += gamma * (jump[slow] - 0.5 * big * (aprev[slow] + a[slow]))
    elif variant == "nodekick":
        new = (1.0 - gamma) * new + gamma * big * (-(sf + sc) @ u)[slow]
    jump[slow] = new
    vh[slow] += new
    aprev = np.where(slow[:, None], a, 0.0)
    return np.vstack([u, vh, jump, aprev]), m, fast


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--N", type=int, default=250)
    ap.add_argument("--hs", default="0.45,0.5,1.0", help="coarse steps h_S/dx")
    ap.add_argument("--K", default="10,20,30")
    ap.add_argument("--buffer", default="0", help="comma-separated buffer layers")
    ap.add_argument("--variant", choices=["extrapolate", "nodekick"])
    ap.add_argument("--gamma", default="1.0", help="comma-separated strengths of the variant")
    ap.add_argument("--eigvec", action="store_true")
    args = ap.parse_args()
    for hs in [float(x) for x in args.hs.split(",")]:
        for k in [int(x) for x in args.K.split(",")]:
            if hs / k > 0.1 + 1e-12:
                print(f"N {args.N} h_S {hs} dx K {k}: h_F > 0.1 dx, beyond the fast limit")
                continue
            for b in [int(x) for x in args.buffer.split(",")]:
                for g in ([float(x) for x in args.gamma.split(",")] if args.variant else [0.0]):
                    t, m, fast = coarse_step_matrix(args.N, hs, k, b, args.variant, g)
                    ev, vec = np.linalg.eig(t)
                    top = int(np.argmax(np.abs(ev)))
                    what = f" {args.variant} {g}" if args.variant else ""
                    line = (f"N {args.N} h_S {hs} dx K {k} buffer {b}{what}: rho {abs(ev[top]):.6f}"
                            f" (eigenvalue {ev[top].real:+.6f}{ev[top].imag:+.6f}i)")
                    if args.eigvec:
                        jmp = np.abs(vec[2 * m:3 * m, top])
                        line += (f"; jump eigenvector peaks at site {int(np.argmax(jmp)) + 1}"
                                 f" (fine clock: sites 1..{int(fast.sum())})")
                    print(line, flush=True)


if __name__ == "__main__":
    main()
