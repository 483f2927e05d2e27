#!/usr/bin/env python3
"""Plot the slow/fast Fermi-Pasta-Ulam chain from the trajectory files.

    lmp -in in.fpu-slow-fast                        # writes traj.async.dat
    lmp -in in.fpu-slow-fast -var integrator sync   # writes traj.sync.dat
    python3 plot_slow_fast.py [traj.async.dat traj.sync.dat [fpu-slow-fast.png [tplot]]]

Both files hold "step time q1 .. q6 Ht" at every coarse node t^n = n h_S.
Panels: positions q_1..q_6 of the asynchronous run for t <= tplot (default
20); relative pseudo-energy variation (H~^n - H~^0)/|H~^0| at the coarse
nodes of both runs; max_i |q_i^async - q_i^sync| at the common times.
Prints the max position difference over [0, t] for a few t.
"""
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    d = np.loadtxt(path, comments="#")
    return d[:, 1], d[:, 2:8], d[:, 8]


def main():
    fa = sys.argv[1] if len(sys.argv) > 1 else "traj.async.dat"
    fs = sys.argv[2] if len(sys.argv) > 2 else "traj.sync.dat"
    out = sys.argv[3] if len(sys.argv) > 3 else "fpu-slow-fast.png"
    tplot = float(sys.argv[4]) if len(sys.argv) > 4 else 20.0

    ta, qa, Ha = load(fa)
    ts, qs, Hs = load(fs)
    # common times (the sync file has the same coarse-node times when written
    # with the same hS; otherwise match to 1e-9)
    ia, is_ = [], []
    lookup = {round(t, 9): k for k, t in enumerate(ts)}
    for k, t in enumerate(ta):
        j = lookup.get(round(t, 9))
        if j is not None:
            ia.append(k)
            is_.append(j)
    ia, is_ = np.array(ia), np.array(is_)
    tc = ta[ia]
    diff = np.max(np.abs(qa[ia] - qs[is_]), axis=1)

    dHa = (Ha - Ha[0]) / abs(Ha[0])
    dHs = (Hs - Hs[0]) / abs(Hs[0])
    print(f"{fa}: {len(ta)} coarse nodes, t in [0, {ta[-1]:g}], "
          f"max |H~-H~0|/|H~0| = {np.max(np.abs(dHa)):.3e}")
    print(f"{fs}: {len(ts)} nodes, max |H~-H~0|/|H~0| = {np.max(np.abs(dHs)):.3e}")
    for tmax in (1.0, 10.0, 20.0, 50.0, 100.0):
        sel = tc <= tmax + 1e-9
        if tc[-1] >= tmax - 1e-9:
            print(f"max_i |q_i async - q_i sync| over t in [0, {tmax:g}]: {np.max(diff[sel]):.3e}")
    print(f"max_i |q_i| over the run (async): {np.max(np.abs(qa)):.3f}")

    fig, (ax1, ax2, ax3) = plt.subplots(3, 1, figsize=(8, 9),
                                        gridspec_kw={"height_ratios": [2, 1, 1]})
    sel = ta <= tplot + 1e-9
    labels = ["$q_1$ fast", "$q_2$ fast", "$q_3$ mixed", "$q_4$ slow", "$q_5$ slow", "$q_6$ slow"]
    styles = ["-", "-", "-", "--", "--", "--"]
    for i in range(6):
        ax1.plot(ta[sel], qa[sel, i], styles[i], lw=0.9, label=labels[i])
    ax1.set_xlabel("time")
    ax1.set_ylabel("displacement $q_i$")
    ax1.legend(ncol=3, fontsize=8, loc="upper left")
    ax1.set_title(r"slow/fast FPU chain, fix pe_jump/async, $h_S=0.01$, $h_F=2\cdot10^{-4}$ (K = 50)")

    ax2.plot(ts, dHs, lw=0.6, color="tab:gray", label="sync, $h=h_F$")
    ax2.plot(ta, dHa, lw=0.6, color="tab:red", label="async, coarse nodes")
    ax2.set_ylabel(r"$(\tilde H^n-\tilde H^0)/|\tilde H^0|$")
    ax2.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    ax2.legend(fontsize=8, loc="upper left")
    ax2.set_title("relative pseudo-energy variation (Gauss-Lobatto 5)", fontsize=10)

    ax3.semilogy(tc[1:], diff[1:], lw=0.6, color="tab:blue")
    ax3.set_xlabel("time")
    ax3.set_ylabel(r"$\max_i |q_i^{async}-q_i^{sync}|$")
    ax3.set_title("position difference async (h_S, h_F) vs sync (h_F)", fontsize=10)

    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
