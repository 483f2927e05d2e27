#!/usr/bin/env python3
"""Plot the energy exchange of the Fermi-Pasta-Ulam example from a LAMMPS log.

    lmp -in in.fpu -var nthermo 10 -log log.fpu.dense
    python3 plot_fpu.py log.fpu.dense fpu.png

Top panel: the oscillatory energies I_1, I_2, I_3 of the stiff springs and
their sum I, with the pseudo-energy variation H~ - H~(0) (as in the figure of
section 3.2 of the pe_jump paper and Fig. I.4.x of Hairer-Lubich-Wanner).
Lower panels: H - H(0) and H~ - H~(0), each on its own scale.
Thermo output every 10 steps resolves the stiff period 2 pi/omega = 0.126;
the reference logs (every 1000 steps) alias it but still show the exchange.
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_thermo(path):
    """Return {column: [values]} of all thermo blocks of a LAMMPS log."""
    data, cols = {}, None
    with open(path) as fh:
        for line in fh:
            words = line.split()
            if not words:
                continue
            if words[0] == "Step":
                cols = words
                for c in cols:
                    data.setdefault(c, [])
                continue
            if cols is None:
                continue
            if words[0] == "Loop" or len(words) != len(cols):
                cols = None if words[0] == "Loop" else cols
                continue
            try:
                vals = [float(w) for w in words]
            except ValueError:
                continue
            for c, v in zip(cols, vals):
                data[c].append(v)
    if not data:
        sys.exit(f"no thermo output found in {path}")
    return data


def main():
    log = sys.argv[1] if len(sys.argv) > 1 else "log.lammps"
    out = sys.argv[2] if len(sys.argv) > 2 else "fpu.png"
    d = read_thermo(log)
    t = d["Time"]
    dHt = [x - d["v_Ht"][0] for x in d["v_Ht"]]
    dH = [x - d["v_H"][0] for x in d["v_H"]]

    fig, (ax1, ax2, ax3) = plt.subplots(3, 1, figsize=(8, 8.5), sharex=True,
                                        gridspec_kw={"height_ratios": [2.2, 1, 1]})
    ax1.plot(t, d["v_I"], lw=0.6, color="k", label=r"$I = I_1+I_2+I_3$")
    ax1.plot(t, d["v_I1"], lw=0.8, label=r"$I_1$")
    ax1.plot(t, d["v_I2"], lw=0.8, label=r"$I_2$")
    ax1.plot(t, d["v_I3"], lw=0.8, label=r"$I_3$")
    ax1.plot(t, dHt, lw=0.8, color="tab:red", label=r"$\tilde H - \tilde H(0)$")
    ax1.set_ylabel("energy")
    ax1.set_ylim(-0.05, 1.15)
    ax1.legend(loc="center right", fontsize=9)
    ax1.set_title(r"FPU chain, $m=3$, $\omega=50$, $h=10^{-3}$: oscillatory energies")

    ax2.plot(t, dH, lw=0.5, color="tab:gray")
    ax2.set_ylabel(r"$H - H(0)$")
    ax2.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    ax2.set_title(r"discrete energy $H$ = pe + ke", fontsize=10)

    ax3.plot(t, dHt, lw=0.5, color="tab:red")
    ax3.set_ylabel(r"$\tilde H - \tilde H(0)$")
    ax3.set_xlabel("time")
    ax3.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    ax3.set_title(r"pseudo-energy $\tilde H$ = pe + f_ID", fontsize=10)

    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out} from {len(t)} thermo lines of {log}")


if __name__ == "__main__":
    main()
