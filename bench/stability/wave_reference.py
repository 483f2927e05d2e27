#!/usr/bin/env python3
"""Independent check of fix pe_jump/async on the inhomogeneous 1D wave.

Re-implements the asynchronous scheme of the paper (section "Asynchronous
scheme", equations for fast, mixed and slow particles) for the linear chain
of wave_stability.py in plain Python (midpoint rule, kick initialisation
as documented for the fix: [v]^0 = h F(q0)/m with h = h_F for fast-group
atoms and h = h_S for slow atoms), runs LAMMPS on the same input, and
prints the largest difference of the displacements after NCOARSE coarse
steps, together with the largest jump energy of the Python run (to compare
growth and stability with the LAMMPS study).

  python3 bench/stability/wave_reference.py --hs 0.5 --K 10 --ncoarse 200
"""

import argparse
import os
import subprocess
import sys

sys.dont_write_bytecode = True    # no __pycache__ in the repository
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import wave_stability as ws    # noqa: E402


def python_scheme(n, hs_dx, k, ncoarse, every=0):
    dx = 1.0 / n
    hf = hs_dx * dx / k
    big = k * hf
    nf = ws.nfast(n)
    # site i = 0..n; spring b = 1..n joins sites b-1 and b
    stiff = [0.0] + [ws.c_of((b - 0.5) * dx) ** 2 / dx ** 2 for b in range(1, n + 1)]
    fast = [1 <= i <= nf for i in range(n + 1)]
    moving = [1 <= i <= n - 1 for i in range(n + 1)]
    slow = [moving[i] and not fast[i] for i in range(n + 1)]
    fine_bond = [False] + [fast[b - 1] or fast[b] for b in range(1, n + 1)]

    def forces(u, which):
        f = [0.0] * (n + 1)
        for b in range(1, n + 1):
            if which is not None and fine_bond[b] != which:
                continue
            t = stiff[b] * (u[b] - u[b - 1])
            f[b] -= t
            f[b - 1] += t
        return f

    u = [ws.u0(i * dx) if moving[i] else 0.0 for i in range(n + 1)]
    v = [ws.v0(i * dx) if moving[i] else 0.0 for i in range(n + 1)]
    f0 = forces(u, None)
    jump = [0.0] * (n + 1)
    vh = [0.0] * (n + 1)
    for i in range(n + 1):
        if moving[i]:
            jump[i] = (big if slow[i] else hf) * f0[i]
            vh[i] = v[i] + 0.5 * jump[i]

    def jump_energy():
        return sum(0.125 * jump[i] ** 2 for i in range(n + 1) if moving[i])

    jmax = jump_energy()
    for step in range(ncoarse):
        start = list(u)
        facc = [0.0] * (n + 1)
        for m in range(k):
            mid = [u[i] + 0.5 * hf * vh[i] if moving[i] else u[i] for i in range(n + 1)]
            fs = forces(mid, True)
            for i in range(n + 1):
                if not moving[i]:
                    continue
                u[i] += hf * vh[i]
                if slow[i]:
                    facc[i] += hf * fs[i]
                else:
                    jump[i] = 2.0 * hf * fs[i] - jump[i]
                    vh[i] += jump[i]
        cmid = [start[i] + 0.5 * big * vh[i] if slow[i] else u[i] for i in range(n + 1)]
        fc = forces(cmid, False)
        for i in range(n + 1):
            if slow[i]:
                jump[i] = 2.0 * big * (facc[i] / big + fc[i]) - jump[i]
                vh[i] += jump[i]
        jmax = max(jmax, jump_energy())
        if every and (step + 1) % every == 0:
            print(f"python: coarse step {step + 1}: jump energy {jump_energy():.6g}", flush=True)
    return u, jmax


def lammps_run(lmp, workdir, n, hs_dx, k, ncoarse):
    os.makedirs(workdir, exist_ok=True)
    data = os.path.join(workdir, f"wave_N{n}_a1.data")
    ws.write_data(data, n, 1.0)
    inp = os.path.join(workdir, f"in.ref_hs{hs_dx:g}_K{k}")
    ws.write_input(inp, os.path.basename(data), n, 1.0, hs_dx, k, ncoarse, "")
    dump = f"ref_hs{hs_dx:g}_K{k}.dump"
    with open(inp, "a") as f:
        f.write(f"write_dump all custom {dump} id x modify sort id format float %.17g\n")
    ws.wait_for_binary(lmp)
    subprocess.run([lmp, "-nocite", "-in", os.path.basename(inp), "-log",
                    f"log.ref_hs{hs_dx:g}_K{k}", "-screen", "none"], cwd=workdir, check=True)
    u = [0.0] * (n + 1)
    with open(os.path.join(workdir, dump)) as f:
        lines = f.read().splitlines()
    start = lines.index("ITEM: ATOMS id x") + 1
    for line in lines[start:]:
        ident, x = line.split()
        i = int(ident) - 1
        u[i] = float(x) - i
    return u


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--lmp", default=os.path.join(here, "..", "..", "build", "lmp"))
    ap.add_argument("--N", type=int, default=250)
    ap.add_argument("--hs", type=float, default=0.5)
    ap.add_argument("--K", type=int, default=10)
    ap.add_argument("--ncoarse", type=int, default=200)
    ap.add_argument("--workdir", default="wave_reference_runs")
    ap.add_argument("--no-lammps", action="store_true", help="only the Python scheme")
    ap.add_argument("--every", type=int, default=0,
                    help="print the jump energy of the Python run every this many coarse steps")
    args = ap.parse_args()

    u_py, jmax = python_scheme(args.N, args.hs, args.K, args.ncoarse, args.every)
    umax = max(abs(x) for x in u_py)
    print(f"python: N {args.N} h_S {args.hs:g} dx K {args.K}, {args.ncoarse} coarse steps: "
          f"max |u| {umax:.6g}, largest jump energy {jmax:.6g}")
    if args.no_lammps:
        return
    u_lmp = lammps_run(os.path.abspath(args.lmp), args.workdir, args.N, args.hs, args.K,
                       args.ncoarse)
    diff = max(abs(a - b) for a, b in zip(u_py, u_lmp))
    print(f"lammps vs python: max |u_lammps - u_python| = {diff:.3e} (max |u| {umax:.3e})")


if __name__ == "__main__":
    main()
