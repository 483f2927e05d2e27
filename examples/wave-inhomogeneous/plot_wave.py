#!/usr/bin/env python3
"""Errors and figure of the inhomogeneous wave example from its dumps.

    lmp -in in.wave-inhomogeneous -var dump yes                   # dump.async.wave
    lmp -in in.wave-inhomogeneous -var dump yes -var integrator sync
    python3 plot_wave.py [--N 250] [--hS_dx 0.5] [--K 10] [--async dump.async.wave]
                         [--sync dump.sync.wave] [--png wave-inhomogeneous.png]

(--N, --hS_dx, --K must be those of the runs: the dump steps are converted
to times with the runs' time steps, h_S = hS_dx/N for the async run, whose
LAMMPS step is one coarse step, and h_F = h_S/K for the sync run.)

The dumps hold "id x" every tout; node i = id - 1 has u_i = x - i.
For every dumped time the script prints max_i |u_i - u(x_i, t)| against

  * the exact solution u of the wave equation (the paper's reflection
    series, the same formula as the atom-style variables of the input), and
  * the exact solution of the semi-discrete system of ODEs (eq.
    discrete_wave: u'' = -A u, solved by diagonalising A), which measures
    the time-integration error alone, without the space discretisation.

It plots u against x at the dumped times: the PDE solution, the
semi-discrete solution and the asynchronous run. Needs numpy and matplotlib.
"""
import argparse
import os

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

C1, C2 = 10.0, 1.0


def g(s):
    """u0 extended by zero outside (0, 0.5)"""
    return np.where((s > 0) & (s < 0.5), 0.01 * np.exp(-400.0 * (s - 0.2) ** 2), 0.0)


def g_prime(s):
    return np.where((s > 0) & (s < 0.5), -8.0 * (s - 0.2) * np.exp(-400.0 * (s - 0.2) ** 2), 0.0)


def u_pde(x, t, kmax=None):
    """the paper's exact solution (valid until the first reflection at x = 1)"""
    r = (C2 - C1) / (C1 + C2)
    if kmax is None:
        kmax = int(np.ceil(C1 * t + 0.5))
    left = np.zeros_like(x)
    right = np.zeros_like(x)
    for k in range(kmax + 1):
        left += r ** k * (g(x + k - C1 * t) - g(k - x - C1 * t))
        right += r ** k * g((C1 / C2) * (x - 0.5) + k + 0.5 - C1 * t)
    return np.where(x <= 0.5, left, 2.0 * C1 / (C1 + C2) * right)


class SemiDiscrete:
    """exact solution of u_i'' = (w_{i-1/2}^2 (u_{i-1}-u_i) - w_{i+1/2}^2 (u_i-u_{i+1}))"""

    def __init__(self, N):
        dx = 1.0 / N
        xm = (np.arange(1, N + 1) - 0.5) * dx          # x_{i-1/2}, i = 1..N
        w2 = (np.where(xm <= 0.5, C1, C2) / dx) ** 2
        A = np.diag(w2[:-1] + w2[1:]) - np.diag(w2[1:-1], 1) - np.diag(w2[1:-1], -1)
        lam, self.V = np.linalg.eigh(A)
        self.om = np.sqrt(lam)
        self.x = np.arange(1, N) * dx
        self.a = self.V.T @ g(self.x)
        self.b = self.V.T @ (-C1 * g_prime(self.x)) / self.om

    def __call__(self, t):
        return self.V @ (self.a * np.cos(self.om * t) + self.b * np.sin(self.om * t))


def read_dump(path):
    """{time step: u of the nodes 1..N-1}, and the step -> time map is up to the caller"""
    frames = {}
    with open(path) as fh:
        lines = fh.read().split("\n")
    i = 0
    while i < len(lines):
        if lines[i].startswith("ITEM: TIMESTEP"):
            step = int(lines[i + 1])
            n = int(lines[i + 3])
            data = np.array([[float(w) for w in lines[j].split()] for j in range(i + 9, i + 9 + n)])
            data = data[np.argsort(data[:, 0])]
            node = data[:, 0] - 1
            frames[step] = (node, data[:, 1] - node)
            i += 9 + n
        else:
            i += 1
    return frames


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--N", type=int, default=250)
    ap.add_argument("--hS_dx", type=float, default=0.5, help="h_S/dx of the runs (default 0.5)")
    ap.add_argument("--K", type=int, default=10, help="K of the runs (default 10)")
    ap.add_argument("--async", dest="fa", default="dump.async.wave")
    ap.add_argument("--sync", dest="fs", default="dump.sync.wave")
    ap.add_argument("--png", default="wave-inhomogeneous.png")
    opts = ap.parse_args()
    N = opts.N
    hS = opts.hS_dx / N
    hF = hS / opts.K
    dt = {"async": hS, "sync": hF}    # the LAMMPS time step of each run
    sd = SemiDiscrete(N)
    # frames keyed by their time t = step * dt (rounded, to match the runs)
    runs = [(name, {round(st * dt[name], 9): fr for st, fr in read_dump(f).items()})
            for name, f in (("async", opts.fa), ("sync", opts.fs)) if os.path.exists(f)]
    if not runs:
        raise SystemExit("no dump files found")

    times = sorted(set.intersection(*(set(fr) for _, fr in runs)))
    print(f"N = {N}, dx = {1.0 / N:g}; max over the nodes of |u_i - reference|")
    head = "| t |" + "".join(f" {n} vs PDE | {n} vs ODE |" for n, _ in runs)
    print(head)
    print("|---" * (1 + 2 * len(runs)) + "|")
    for t in times:
        cells = []
        for name, fr in runs:
            node, u = fr[t]
            inner = (node > 0) & (node < N)
            x = node[inner] / N
            e_pde = np.max(np.abs(u[inner] - u_pde(x, t)))
            e_ode = np.max(np.abs(u[inner] - sd(t)))
            cells += [f"{e_pde:.3e}", f"{e_ode:.3e}"]
        print(f"| {t:.2f} | " + " | ".join(cells) + " |")

    nplot = len(times)
    fig, axes = plt.subplots(nplot, 1, figsize=(8, 1.7 * nplot + 0.6), sharex=True)
    xf = np.linspace(0.0, 1.0, 4001)
    name, fr = runs[0]
    for ax, t in zip(np.atleast_1d(axes), times):
        node, u = fr[t]
        ax.plot(xf, u_pde(xf, t), color="k", lw=0.8, label="exact (PDE)")
        ax.plot(sd.x, sd(t), color="tab:green", lw=0.8, label="exact semi-discrete (ODE)")
        ax.plot(node / N, u, ".", ms=2.5, color="tab:red", label=f"fix pe_jump/{name}" if name == "async" else "fix pe_jump")
        ax.axvline(0.5, color="gray", lw=0.5, ls=":")
        ax.set_ylabel(f"u, t = {t:.1f}")
    np.atleast_1d(axes)[0].legend(fontsize=7, loc="upper right")
    np.atleast_1d(axes)[0].set_title(
        f"inhomogeneous wave, N = {N}, c = 10 | c = 1, h_S = {opts.hS_dx:g} dx, "
        f"h_F = h_S/{opts.K}", fontsize=10)
    np.atleast_1d(axes)[-1].set_xlabel("x")
    fig.tight_layout()
    fig.savefig(opts.png, dpi=110)
    print(f"wrote {opts.png}")


if __name__ == "__main__":
    main()
