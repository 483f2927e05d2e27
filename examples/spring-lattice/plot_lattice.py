#!/usr/bin/env python3
"""Pictures of the spring-lattice example from its dump file.

    lmp -in in.spring-lattice -var dump yes          # writes dump.async.lattice
    python3 plot_lattice.py [dump.async.lattice [lattice-classes.png [lattice-wave.png [times [hF]]]]]

lattice-classes.png: the lattice at t = 0 coloured by the class that
fix pe_jump/async gives every atom (per-atom output f_ID: 0 slow, 1 mixed,
2 fast, -1 not in the fix group = walls), with a zoom on the interface.
lattice-wave.png: the displacement magnitude |u| of every atom at a few
times (default: every dumped frame from t = 0 to 70 in steps of 14 time
units, given as a comma-separated list of times that are in the dump; hF,
default 0.02, converts dump steps to times); the inclusion outline is
drawn in white. Needs numpy and matplotlib.
"""
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402


def read_dump(path):
    """list of (step, box, columns, array) of a LAMMPS custom dump"""
    frames = []
    with open(path) as fh:
        lines = fh.read().split("\n")
    i = 0
    while i < len(lines):
        if lines[i].startswith("ITEM: TIMESTEP"):
            step = int(lines[i + 1])
            n = int(lines[i + 3])
            box = [tuple(map(float, lines[i + 5 + k].split()[:2])) for k in range(3)]
            cols = lines[i + 8].split()[2:]
            arr = np.array([[float(w) for w in lines[j].split()] for j in range(i + 9, i + 9 + n)])
            frames.append((step, box, cols, arr))
            i += 9 + n
        else:
            i += 1
    return frames


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "dump.async.lattice"
    out1 = sys.argv[2] if len(sys.argv) > 2 else "lattice-classes.png"
    out2 = sys.argv[3] if len(sys.argv) > 3 else "lattice-wave.png"
    want = [float(t) for t in sys.argv[4].split(",")] if len(sys.argv) > 4 else [0, 14, 28, 42, 56, 70]
    frames = read_dump(path)
    step0, box, cols, a0 = frames[0]
    c = {name: k for k, name in enumerate(cols)}
    x, y, cls = a0[:, c["x"]], a0[:, c["y"]], a0[:, c["v_cls"]]
    (xlo, xhi), (ylo, yhi) = box[0], box[1]
    counts = {k: int(np.sum(cls == k)) for k in (-1, 0, 1, 2)}
    print(f"{path}: {len(a0)} atoms; walls {counts[-1]}, slow {counts[0]}, mixed {counts[1]}, "
          f"fast {counts[2]}")

    # inclusion outline from the fast-group atoms (mixed + fast)
    inc = cls >= 1
    xc, yc = x[inc].mean(), y[inc].mean()
    R = np.sqrt(np.max((x[inc] - xc) ** 2 + (y[inc] - yc) ** 2))

    cmap = ListedColormap(["0.55", "tab:blue", "tab:purple", "tab:red"])
    names = ["wall (not in fix group)", "slow", "mixed", "fast"]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [2.2, 1]})
    for ax, ms in ((ax1, 2.5), (ax2, 14)):
        ax.scatter(x, y, c=cls, cmap=cmap, vmin=-1.5, vmax=2.5, s=ms, linewidths=0)
        ax.set_aspect("equal")
    ax1.set_xlim(xlo, xhi)
    ax1.set_ylim(ylo, yhi)
    ax1.set_title(f"classes of fix pe_jump/async (t = 0): {counts[0]} slow, {counts[1]} mixed, "
                  f"{counts[2]} fast, {counts[-1]} wall atoms", fontsize=10)
    zx, zy = xc + R * 0.70, yc + R * 0.70
    ax2.set_xlim(zx - 6, zx + 6)
    ax2.set_ylim(zy - 6, zy + 6)
    ax2.set_title("zoom on the interface", fontsize=10)
    ax1.add_patch(plt.Rectangle((zx - 6, zy - 6), 12, 12, fill=False, lw=0.8))
    handles = [plt.Line2D([], [], marker="o", ls="", color=cmap(k), label=names[k]) for k in range(4)]
    ax2.legend(handles=handles, fontsize=8, loc="lower left", framealpha=0.9)
    fig.tight_layout()
    fig.savefig(out1, dpi=100)
    print(f"wrote {out1}")

    # wave crossing: |u| at the requested times
    sel = []
    # the dump interval in time is not in the file: take it from the thermo
    # default (tout = 7 at h_F = 0.02 -> 350 steps); pass times that are dumped
    hF = 0.02 if len(sys.argv) <= 5 else float(sys.argv[5])
    for step, box_, cols_, arr in frames:
        t = step * hF
        if any(abs(t - w) < 1e-6 for w in want):
            sel.append((t, arr))
    vmax = 0.05
    ncol = 2
    nrow = (len(sel) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(12, 2.75 * nrow + 0.6), squeeze=False)
    th = np.linspace(0, 2 * np.pi, 200)
    for k, (t, arr) in enumerate(sel):
        ax = axes[k // ncol][k % ncol]
        # colour the field at the lattice sites (x - dx, y - dy), so the
        # picture is not distorted by the (small) displacements
        xs = arr[:, c["x"]] - arr[:, c["c_dsp[1]"]]
        ys = arr[:, c["y"]] - arr[:, c["c_dsp[2]"]]
        sc = ax.tripcolor(xs, ys, arr[:, c["c_dsp[4]"]], shading="gouraud", cmap="viridis",
                          vmin=0, vmax=vmax, rasterized=True)
        ax.plot(xc + R * np.cos(th), yc + R * np.sin(th), color="w", lw=0.7)
        ax.set_aspect("equal")
        ax.set_xlim(xlo, xhi)
        ax.set_ylim(ylo, yhi)
        ax.set_title(f"t = {t:g}", fontsize=9)
        print(f"t = {t:g}: max |u| = {arr[:, c['c_dsp[4]']].max():.4f}, "
              f"mean |u| in the inclusion = {arr[inc, c['c_dsp[4]']].mean():.4f}")
    for k in range(len(sel), nrow * ncol):
        axes[k // ncol][k % ncol].axis("off")
    fig.suptitle("displacement magnitude |u| (pulse amplitude 0.05), fix pe_jump/async, "
                 "h_S = 0.2, h_F = 0.02; white circle: stiff inclusion", fontsize=10)
    fig.colorbar(sc, ax=axes, shrink=0.8, label="|u|")
    fig.savefig(out2, dpi=110)
    print(f"wrote {out2}")


if __name__ == "__main__":
    main()
