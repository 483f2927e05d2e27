#!/usr/bin/python3
"""Write doc/benchmarks.md and doc/bench_*.png from bench/results/<mode>/.

    /usr/bin/python3 bench/report.py [--quick]
"""

import argparse
import math
import os
import sys

import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as B  # noqa: E402

DOC = os.path.join(B.ROOT, "doc")


def fmt(x, d=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    if x == 0:
        return "0"
    if abs(x) >= 1e4 or abs(x) < 1e-3:
        return f"{x:.{d-1}e}"
    return f"{x:.{d}g}"


def met(ok):
    return "**met**" if ok else "**missed**"


def interp_cost(points, err, key, ekey="err"):
    """Cost (points[key]) of a curve at error err (points[ekey]), log-log
    interpolation between the bracketing points (extrapolated from the
    nearest two if err is outside the curve; flagged)."""
    pts = sorted(((p[ekey], p[key]) for p in points if p[ekey] > 0), key=lambda t: t[0])
    if len(pts) < 2:
        return None, True
    le = np.log([p[0] for p in pts])
    lc = np.log([p[1] for p in pts])
    x = math.log(err)
    if x < le[0]:
        i, extra = 0, True
    elif x > le[-1]:
        i, extra = len(pts) - 2, True
    else:
        i = max(0, min(len(pts) - 2, int(np.searchsorted(le, x)) - 1))
        extra = False
    if le[i + 1] == le[i]:
        return float(np.exp(lc[i])), extra
    t = (x - le[i]) / (le[i + 1] - le[i])
    return float(np.exp(lc[i] + t * (lc[i + 1] - lc[i]))), extra


def groups(points):
    out = {}
    for p in points:
        out.setdefault(p["label"], []).append(p)
    for v in out.values():
        v.sort(key=lambda p: p["h"])
    return out


STYLE = {}


def style(label):
    if label not in STYLE:
        markers = "osD^v<>pPX*hd"
        n = len(STYLE)
        cmap = plt.get_cmap("tab20")
        STYLE[label] = dict(marker=markers[n % len(markers)], color=cmap((2 * n) % 20 + (n // 10) % 2),
                            linestyle=["-", "--", ":"][(n // 10) % 3], markersize=5)
    return STYLE[label]


def wp_plot(name, title, points, xkeys=("evals", "loop_time"), ekey="err", elabel="error",
            extra_panel=None, note=None):
    STYLE.clear()
    g = groups(points)
    npan = len(xkeys) + (1 if extra_panel else 0)
    fig, axs = plt.subplots(1, npan, figsize=(5.2 * npan, 4.4))
    axs = np.atleast_1d(axs)
    xl = {"evals": "force evaluations (1 = one full evaluation)", "loop_time": "wall time of the run [s] (median)"}
    for ax, xk in zip(axs, xkeys):
        for lab, ps in g.items():
            xs = [p[xk] for p in ps]
            ys = [p[ekey] for p in ps]
            ax.loglog(xs, ys, label=lab, **style(lab))
        ax.set_xlabel(xl.get(xk, xk))
        ax.set_ylabel(elabel)
        ax.grid(True, which="both", alpha=0.3)
    if extra_panel:
        ax = axs[-1]
        k2, lab2 = extra_panel
        for lab, ps in g.items():
            xs = [p["evals"] for p in ps]
            ys = [max(p[k2], 1e-16) for p in ps]
            ax.loglog(xs, ys, label=lab, **style(lab))
        ax.set_xlabel(xl["evals"])
        ax.set_ylabel(lab2)
        ax.grid(True, which="both", alpha=0.3)
    axs[0].legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=10)
    if note:
        fig.text(0.01, 0.01, note, fontsize=7)
    fig.tight_layout(rect=(0, 0.03, 1, 0.95))
    path = os.path.join(DOC, f"bench_{name}.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return f"bench_{name}.png"


def wp_table(points, cols):
    head = "| " + " | ".join(c[0] for c in cols) + " |\n|" + "---|" * len(cols) + "\n"
    rows = []
    for p in sorted(points, key=lambda p: (p["label"], -p["h"])):
        rows.append("| " + " | ".join(c[1](p) for c in cols) + " |")
    return head + "\n".join(rows) + "\n"


def quiet_text(d):
    q = d.get("quiet", [])
    if not q:
        return ""
    return ", ".join(f"{x['label']}: others {x['others_busy_cores']:.2f} cores" for x in q)


def cpu_range(points):
    c = [p["cpu_use"] for p in points if p.get("cpu_use") == p.get("cpu_use")]
    return (min(c), max(c)) if c else (float("nan"), float("nan"))


# ===================================================================== sections

def sec_lj_cost(R, targets, misses):
    d = R.get("lj_cost")
    if not d:
        return ""
    t = {x["name"]: x for x in d["table"]}
    nve = t["fix nve"]
    out = ["## 1. Per-step cost on the LJ liquid\n"]
    if d.get("rerun_of_noisy"):
        out.append("The first measurement of this stage was noisy; these are the numbers of its repetition by "
                   "the `retime` stage.\n")
    out.append(f"{nve['natoms']} atoms (fcc 0.8442, {d['ncell']}^3 cells), `lj/cut 2.5`, T = 1.44 on the lattice, "
               f"`neighbor 0.3 bin`, `neigh_modify every 1 delay 0 check yes`, dt = 0.005, {d['steps']} steps, "
               f"thermo output at the first and last step only (`bench/inputs/in.lj`). Every configuration ran "
               f"{d['reps']} times, interleaved (all configurations once, then again), and the table shows medians of "
               f"the LAMMPS `Loop time`. Force evaluations are the fix's vector element 5 over the run "
               f"(fix nve: one per step). The last step of a Legendre rule (and midpoint) costs one extra "
               f"evaluation for the energy output; that is in the counts. The force evaluations a fix does itself at the extra "
               f"quadrature nodes are booked by LAMMPS under Modify, not Pair. Machine state: {quiet_text(d)}.\n")
    out.append("| integrator | evals / step | loop time [s] | ratio to fix nve | target | | Pair [s] | Neigh [s] | Comm [s] | Modify [s] | Other [s] | CPU use |")
    out.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for row in d["table"]:
        ratio = row["loop_time"] / nve["loop_time"]
        q = row["quad"] or ""
        tgt, ok = "", None
        if q == "midpoint":
            tgt = "<= 1.05"
            ok = ratio <= 1.05
        elif q.startswith("lobatto"):
            n = int(q.split()[1])
            tgt = f"<= {1.05 * (n - 1):.2f}"
            ok = ratio <= 1.05 * (n - 1)
        elif q.startswith("legendre"):
            n = int(q.split()[1])
            tgt = f"(N = {n}: {1.05 * n:.2f})"
        bd = row["breakdown"]
        out.append(f"| {row['name']} | {row['evals'] / row['steps']:.4f} | {row['loop_time']:.3f} | {ratio:.3f} | {tgt} | "
                   f"{'' if ok is None else met(ok)} | {bd.get('Pair', 0):.3f} | {bd.get('Neigh', 0):.3f} | {bd.get('Comm', 0):.3f} | "
                   f"{bd.get('Modify', 0):.3f} | {bd.get('Other', 0):.3f} | {row['cpu_use']:.1f}% |")
        if ok is not None:
            targets.append((f"LJ liquid ({nve['natoms']} atoms): {row['name']} per step vs fix nve",
                            tgt, f"{ratio:.3f} (wall), {row['evals'] / row['steps'] / 1.0:.3f} evals/step", ok))
            if not ok:
                misses.append(row["name"])
    out.append("")
    # explain the split
    mid = t.get("pe_jump midpoint")
    if mid:
        dm = mid["breakdown"].get("Modify", 0) - nve["breakdown"].get("Modify", 0)
        dp = mid["breakdown"].get("Pair", 0) - nve["breakdown"].get("Pair", 0)
        dn = mid["breakdown"].get("Neigh", 0) - nve["breakdown"].get("Neigh", 0)
        tot = mid["loop_time"] - nve["loop_time"]
        out.append(f"Where the midpoint rule's extra time goes (medians, pe_jump midpoint minus fix nve): "
                   f"total {tot:+.3f} s = Modify {dm:+.3f} s + Pair {dp:+.3f} s + Neigh {dn:+.3f} s + rest. "
                   f"Modify is the integrator itself: fix nve {nve['breakdown'].get('Modify', 0):.3f} s, "
                   f"pe_jump midpoint {mid['breakdown'].get('Modify', 0):.3f} s, i.e. "
                   f"{1e9 * mid['breakdown'].get('Modify', 0) / mid['steps'] / mid['natoms']:.1f} ns per atom and step "
                   f"against {1e9 * nve['breakdown'].get('Modify', 0) / nve['steps'] / nve['natoms']:.1f} ns. "
                   f"The midpoint rule does {mid['evals'] - mid['steps']:.0f} extra evaluation(s) in {mid['steps']} "
                   f"steps (energy and virial at the last step, for the thermo output), "
                   f"{100.0 * (mid['evals'] - mid['steps']) / mid['steps']:.1f}% of the force work. "
                   f"Neighbor list builds: fix nve {nve.get('neigh_builds')}, pe_jump midpoint {mid.get('neigh_builds')}.\n")
    return "\n".join(out) + "\n"


def sec_mpi(R):
    d = R.get("mpi")
    if not d:
        return ""
    out = ["## 2. MPI: 1 and 2 ranks on the 2 cores\n"]
    if d.get("rerun_of_noisy"):
        out.append("The first measurement of this stage ran while other processes used the machine "
                   f"({quiet_text({'quiet': d['first_attempt_quiet']})}); the `retime` stage repeated it at the end "
                   "and these are the numbers of the repetition.\n")
    out.append(f"Same LJ input, {d['steps']} steps, {d['reps']} interleaved repetitions, medians. Memory: "
               f"LAMMPS' `Per MPI rank memory allocation` (average over ranks) times the number of ranks, "
               f"per atom; and the peak resident set of each rank process (`/usr/bin/time`, includes the "
               f"executable, MPI and libraries). Machine state: {quiet_text(d)}.\n")
    out.append("| integrator | ranks | loop time [s] | speedup 1 -> 2 | LAMMPS memory [bytes/atom] | peak RSS per rank [MB] | final pe | CPU use |")
    out.append("|---|---|---|---|---|---|---|---|")
    t = {(x["integ"], x["quad"], x["np"]): x for x in d["table"]}
    for x in d["table"]:
        one = t.get((x["integ"], x["quad"], 1))
        sp = one["loop_time"] / x["loop_time"] if one else float("nan")
        rss = x.get("rank_rss_kb") or ([x["maxrss_kb"]] if x.get("maxrss_kb") else [])
        name = "fix nve" if x["integ"] == "nve" else f"pe_jump {x['quad']}"
        out.append(f"| {name} | {x['np']} | {x['loop_time']:.3f} | {sp:.2f} | {x['bytes_per_atom']:.0f} | "
                   f"{', '.join(f'{r / 1024:.0f}' for r in rss)} | {x['final_pe']:.10g} | {x['cpu_use']:.1f}% |")
    out.append("")
    n1 = t.get(("nve", None, 1))
    m1 = t.get(("pe_jump", "midpoint", 1))
    l1 = t.get(("pe_jump", "lobatto 3", 1))
    if n1 and m1 and l1:
        agree = []
        for (i, q) in (("nve", None), ("pe_jump", "midpoint"), ("pe_jump", "lobatto 3")):
            a, b = t.get((i, q, 1)), t.get((i, q, 2))
            if a and b:
                agree.append(abs(a["final_pe"] - b["final_pe"]) / abs(a["final_pe"]))
        out.append(f"The fix's own per-atom state shows in the memory: pe_jump midpoint needs "
                   f"{m1['bytes_per_atom'] - n1['bytes_per_atom']:.0f} bytes/atom more than fix nve, lobatto 3 "
                   f"{l1['bytes_per_atom'] - n1['bytes_per_atom']:.0f} (it also keeps the start-node force). "
                   f"The final potential energy after {d['steps']} steps is the same on 1 and 2 ranks to a relative "
                   f"{max(agree):.1e} (thermo output with 14 significant digits).\n")
    return "\n".join(out) + "\n"


def sec_fpu(R):
    d = R.get("fpu")
    if not d:
        return ""
    pts = d["points"]
    png = wp_plot("fpu", f"FPU chain (omega = {d['omega']:g}), positions at t = {d['T']:g} vs DOP853 reference",
                  pts, extra_panel=("eHt", "max |H~ - H~0|/|H0| (fix nve, respa: H)"),
                  elabel="max |q - q_ref|")
    out = ["## 3. Work-precision: Fermi-Pasta-Ulam chain\n"]
    out.append(f"The chain of `examples/fpu` (Hairer-Lubich-Wanner; 6 moving masses between walls, alternating "
               f"soft quartic springs and stiff harmonic springs, omega = {d['omega']:g}, their initial values). "
               f"For `run_style respa` the stiff springs must be a different force style from the soft ones: "
               f"every integrator here runs `bench/inputs/in.springs`, where the stiff springs are bonds "
               f"(`bond_style harmonic`) and the soft ones a `pair_style table` (spline, 20000 points) of "
               f"(r - a)^4 between the neighbours that are not bonded; respa puts bonds on the inner level. "
               f"Error: max over the atoms of |q_i(T) - q_i,ref(T)|, T = {d['T']:g}, against scipy's DOP853 "
               f"(rtol 1e-13) on the exact quartic model (so the table's interpolation error is inside the "
               f"error floor). Third panel: conservation of the pseudo-energy H~ (fix pe_jump) or of H "
               f"(fix nve, respa), max over 50 samples. pe_jump/async is not applicable: every moving atom "
               f"touches a stiff spring, so there are no slow atoms. Wall times of a 8-atom system are "
               f"LAMMPS' per-step overhead, not force work. {d['reps']} repetitions, medians.\n")
    out.append(f"![FPU work-precision]({png})\n")
    out.append(wp_table(pts, [("method", lambda p: p["label"]), ("h", lambda p: f"{p['h']:g}"),
                              ("evals", lambda p: f"{p['evals']:.0f}"), ("wall [s]", lambda p: f"{p['loop_time']:.4f}"),
                              ("max position error", lambda p: fmt(p["err"])),
                              ("max rel. dH", lambda p: fmt(p["eH"])), ("max rel. dH~", lambda p: fmt(p["eHt"]))]))
    return "\n".join(out) + "\n"


def sec_string(R):
    d = R.get("string")
    if not d:
        return ""
    pts = d["points"]
    png = wp_plot("string", "Nonlinear string (alpha 0.99, A 0.3), positions at t = 1 vs reference",
                  pts, extra_panel=("eHt", "max |H~ - H~0|/|H~0| (fix nve: H)"), elabel="max |q - q_ref|")
    out = ["## 4. Work-precision: nonlinear string\n"]
    out.append(f"`bench/inputs/in.string` = the setup of `examples/nonlinear-string` (alpha = 0.99, amplitude 0.3, "
               f"101 nodes) with a choice of integrator. Reference: pe_jump legendre 5 at h = {d['href']:g} "
               f"(its own error, estimated from the run at 2h by Richardson, is {fmt(d['ref_err'])}). Error: max "
               f"over the nodes of the distance to the reference at t = 1. One force style only (bonds): "
               f"`run_style respa` cannot split it; the string is homogeneous: no slow/fast split for "
               f"pe_jump/async. {d['reps']} repetitions, medians; 101 atoms, so wall times are per-step overhead.\n")
    out.append(f"![string work-precision]({png})\n")
    out.append(wp_table(pts, [("method", lambda p: p["label"]), ("h", lambda p: f"{p['h']:g}"),
                              ("evals", lambda p: f"{p['evals']:.0f}"), ("wall [s]", lambda p: f"{p['loop_time']:.4f}"),
                              ("max position error", lambda p: fmt(p["err"])),
                              ("max rel. dH", lambda p: fmt(p["eH"])), ("max rel. dH~", lambda p: fmt(p["eHt"]))]))
    return "\n".join(out) + "\n"


def async_overhead_rows(pts, sync_label, async_prefix):
    """(label, h, eval ratio, wall ratio, wall/eval) of async against sync
    (same quadrature when the async label names one) at the same fine step."""
    g = groups(pts)
    rows = []
    for lab, ps in g.items():
        if not lab.startswith(async_prefix):
            continue
        q = [k for k in g if k.startswith("pe_jump ") and lab.endswith(k[len("pe_jump "):])]
        sync = {p["h"]: p for p in g.get(q[0] if q else sync_label, [])}
        for p in ps:
            s = sync.get(p["h"])
            if not s:
                continue
            er = p["evals"] / s["evals"]
            wr = p["loop_time"] / s["loop_time"]
            rows.append((lab, p["h"], er, wr, wr / er))
    return rows


TOL_ERR, TOL_DE = 1e-3, 1e-3
TOL_METHODS = ("fix nve", "respa", "pe_jump", "async")


def energy_dev(p):
    """max |dE|/E of the tolerance: H = pe + ke for every method (the
    pseudo-energy H~ of the fixes, which they conserve, is shown beside it)."""
    return p["eH"]


def tol_section(pts, scene, targets):
    """Fastest configuration (median wall time) of each method within the
    tolerance position error <= TOL_ERR and max |dE|/E <= TOL_DE; a target
    row async against respa. These are the speed-ups a user sees."""
    where = lambda p: f"{p['label']}, " + (f"N = {p['N']}" if "N" in p else f"h = {p['h']:g}")  # noqa: E731
    out = [f"Fastest configuration of each method within one tolerance for all: position error <= {TOL_ERR:g} "
           f"and max |dE|/E <= {TOL_DE:g}, with E = pe + ke (etotal) for every method; the pseudo-energy H~ "
           f"that pe_jump and pe_jump/async conserve (for async at coarse nodes) is shown beside it. Of the "
           f"points above, the one with the smallest median wall time. respa's evaluations are "
           f"(K x bonds + pairs)/(bonds + pairs) per outer step. These are the speed-ups a user gets "
           f"(fix nve at its largest step within the tolerance, respa at the same tolerance), unlike the "
           f"ratios to pe_jump at the same fine step below, which are overhead figures.\n",
           "| method | fastest passing configuration | wall [s] | evals | position error | max \\|dE\\|/E (pe + ke) | max rel. dH~ | points passing |",
           "|---|---|---|---|---|---|---|---|"]
    best = {}
    for m in TOL_METHODS:
        ps = [p for p in pts if p["label"].startswith(m)]
        ok = [p for p in ps if p["err"] <= TOL_ERR and energy_dev(p) <= TOL_DE]
        if not ps:
            continue
        if not ok:
            out.append(f"| {m} | none (smallest error {fmt(min(p['err'] for p in ps))}, smallest max \\|dE\\|/E "
                       f"{fmt(min(energy_dev(p) for p in ps))}) | | | | | | 0 of {len(ps)} |")
            continue
        b = min(ok, key=lambda p: p["loop_time"])
        best[m] = b
        out.append(f"| {m} | {where(b)} | {b['loop_time']:.4f} | {b['evals']:.1f} | {fmt(b['err'])} | "
                   f"{fmt(energy_dev(b))} | {fmt(b['eHt'])} | {len(ok)} of {len(ps)} |")
    out.append("")
    a, r = best.get("async"), best.get("respa")
    name = f"{scene}: async at least as fast as respa under pos err <= {TOL_ERR:g} and max \\|dE\\|/E <= {TOL_DE:g}"
    if a and r:
        sp = r["loop_time"] / a["loop_time"]
        out.append(f"async against respa within the tolerance: wall time async/respa = "
                   f"{a['loop_time'] / r['loop_time']:.3f} (respa/async = {sp:.3f}), evaluations async/respa = "
                   f"{a['evals'] / r['evals']:.3f}.\n")
        if sp < 1:
            out.append(f"Why async loses here: its fastest passing point ({where(a)}) does {a['evals']:.1f} "
                       f"evaluations in {a['loop_time']:.4f} s ({1e3 * a['loop_time'] / a['evals']:.3f} ms per "
                       f"evaluation), respa's ({where(r)}) {r['evals']:.1f} in {r['loop_time']:.4f} s "
                       f"({1e3 * r['loop_time'] / r['evals']:.3f} ms per evaluation).\n")
        alt = [p for p in pts if p["label"].startswith("async") and p["err"] <= TOL_ERR and p["eHt"] <= TOL_DE]
        alt = min(alt, key=lambda p: p["loop_time"]) if alt else None
        if alt is not a:
            out.append("Judged on its pseudo-energy H~ instead (which it conserves; pe + ke differs from it by the "
                       "jump energy, which oscillates but does not accumulate), async's fastest passing point "
                       "would be " +
                       (f"{where(alt)}: {alt['loop_time']:.4f} s, {alt['evals']:.1f} evaluations, respa/async = "
                        f"{r['loop_time'] / alt['loop_time']:.3f}. The target above does not count this.\n"
                        if alt else "none.\n"))
        targets.append((name, ">= 1 (wall respa / async)",
                        f"{sp:.2f}: {where(a)} {a['loop_time']:.3f} s, {a['evals']:.0f} evals; "
                        f"{where(r)} {r['loop_time']:.3f} s, {r['evals']:.0f} evals", sp >= 1))
    elif a:
        out.append("No respa configuration is within the tolerance, so async is the faster of the two there.\n")
        targets.append((name, ">= 1 (wall respa / async)",
                        f"no respa point passes; {where(a)} {a['loop_time']:.3f} s, {a['evals']:.0f} evals", True))
    elif any(p["label"].startswith("async") for p in pts):
        targets.append((name, ">= 1 (wall respa / async)", "no async point passes", False))
    return "\n".join(out) + "\n"


def sec_chain(R, targets):
    d = R.get("chain")
    if not d:
        return ""
    pts = d["points"]
    c = d["counts"]
    png = wp_plot("chain", f"Slow/fast chain: {c['atoms']} atoms ({d['copies']} copies), positions at t = {d['T']:g}",
                  pts, elabel="max |q - q_ref|")
    out = ["## 5. Work-precision: slow/fast chain, " + f"{c['atoms']} atoms\n"]
    out.append(f"The chain of paper section 4.3.1 (`examples/fpu-slow-fast`): 3 stiff harmonic springs "
               f"(wall - q1 - q2 - q3), then 4 soft quartic springs (q3 - q4 - ... - wall); q1, q2 fast, q3 mixed, "
               f"q4..q6 slow. **Choice: {d['copies']} copies of the paper's chain side by side** (2d, copies "
               f"apart in y beyond the cutoff), {c['atoms']} atoms of which {c['mobile']} move, {c['bonds']} stiff "
               f"bonds and {c['soft']} soft pair springs. Copies rather than one long chain because (i) the "
               f"slow/fast structure per atom, hence the cost ratio N_a/N_s of the paper, stays the paper's, "
               f"(ii) the reference can then be computed exactly: the copies cycle through {d['variants']} random "
               f"initial states (fast displacements q1..q3 uniform in +-0.2 sqrt(10)/omega, slow velocities "
               f"p4..p6 uniform in +-0.5: the energies of the paper's example), each integrated by DOP853 at "
               f"rtol 1e-13. **Stiffness: omega^2 = {d['omega2']:g}** instead of the paper's 10: with omega^2 = 10 "
               f"the 'fast' frequencies (1.0, 2.8, 4.0) are no faster than the quartic springs' (about 1-3 at "
               f"these amplitudes), so there is nothing for a multirate method to gain; omega = 50 (as in the "
               f"FPU chain) separates the time scales by about 30. Stiff springs are bonds, soft springs a pair "
               f"table (as in section 3), so respa can put the stiff springs on the inner level. Error: max over "
               f"all moving atoms of |q - q_ref| at t = {d['T']:g}. The respa force-evaluation count is "
               f"(K x bonds + pairs)/(bonds + pairs) per outer step. {d['reps']} repetitions, medians.\n")
    out.append(f"![chain work-precision]({png})\n")
    out.append(wp_table(pts, [("method", lambda p: p["label"]), ("h (fine)", lambda p: f"{p['h']:g}"),
                              ("evals", lambda p: f"{p['evals']:.0f}"), ("wall [s]", lambda p: f"{p['loop_time']:.3f}"),
                              ("error", lambda p: fmt(p["err"])), ("error fast atoms", lambda p: fmt(p["err_fast"])),
                              ("error slow atoms", lambda p: fmt(p["err_slow"])),
                              ("max rel. dH~ (async: at coarse nodes)", lambda p: fmt(p["eHt"])),
                              ("Modify [s]", lambda p: f"{p['breakdown'].get('Modify', 0):.3f}"),
                              ("CPU", lambda p: f"{p['cpu_use']:.0f}%")]))
    out.append(tol_section(pts, "Slow/fast chain", targets))
    # target: at equal error async faster than nve and respa
    g = groups(pts)
    lines = ["\nAt equal error (log-log interpolation of the other curve's wall time at the async point's error; "
             "'extrap.' = outside that curve's range):\n",
             "| async point | error | wall [s] | fix nve at that error [s] | best respa at that error [s] | speedup vs nve | vs respa |",
             "|---|---|---|---|---|---|---|"]
    best = None
    for lab, ps in g.items():
        if not lab.startswith("async"):
            continue
        for p in ps:
            tn, xn = interp_cost(g["fix nve"], p["err"], "loop_time")
            rs = [(interp_cost(v, p["err"], "loop_time"), k) for k, v in g.items() if k.startswith("respa")]
            rs = [(x[0][0], x[0][1], x[1]) for x in rs if x[0][0]]
            tr, xr, kr = min(rs) if rs else (None, True, "")
            sn, sr = tn / p["loop_time"], tr / p["loop_time"] if tr else float("nan")
            lines.append(f"| {lab}, h = {p['h']:g} | {fmt(p['err'])} | {p['loop_time']:.3f} | {tn:.3f}{' extrap.' if xn else ''} | "
                         f"{tr:.3f} ({kr}){' extrap.' if xr else ''} | {sn:.2f} | {sr:.2f} |")
            score = min(sn, sr)
            if best is None or score > best[0]:
                best = (score, lab, p["h"], sn, sr)
    out.append("\n".join(lines) + "\n")
    if best:
        ok = best[3] > 1 and best[4] > 1
        targets.append(("Slow/fast chain: async faster than fix nve and respa at equal error",
                        "> 1 and > 1", f"best: {best[1]} h={best[2]:g}: {best[3]:.2f}x vs nve, {best[4]:.2f}x vs respa", ok))
    rows = async_overhead_rows(pts, "pe_jump midpoint", "async")
    if rows:
        out.append("Overhead of async: async against sync (pe_jump midpoint) at the same fine step, "
                   "force-evaluation ratio, wall-clock ratio, and their quotient (target: within 10% of 1). "
                   "These measure what the fix costs per evaluation it saves, not a speed-up for users "
                   "(those are against fix nve and respa, above):\n")
        out.append("The paper's cost ratio for this chain is eta = (1 + m/((m+1)K))/(1 + m/(m+1)), m = 3; the measured "
                   "evaluation ratio also holds the sync run's extra energy evaluations at its thermo output.\n")
        out.append("| async | h | evals async/sync | paper's eta | wall async/sync | wall ratio / evals ratio |\n|---|---|---|---|---|---|")
        for r in rows:
            K = int(r[0].split("K=")[1].split()[0])
            eta = (1 + 3.0 / (4 * K)) / (1 + 3.0 / 4)
            out.append(f"| {r[0]} | {r[1]:g} | {r[2]:.3f} | {eta:.3f} | {r[3]:.3f} | {r[4]:.2f} |")
        out.append("")
        k = [r for r in rows if r[0] == "async K=10"]
        if k:
            worst = max(k, key=lambda r: abs(r[4] - 1))
            targets.append(("Slow/fast chain (overhead): async K=10 wall-clock ratio to sync within 10% of its evaluation ratio",
                            "0.9 .. 1.1", f"{worst[4]:.2f} (evals {worst[2]:.3f}, wall {worst[3]:.3f})",
                            abs(worst[4] - 1) <= 0.1))
    return "\n".join(out) + "\n"


def sec_wave(R, targets):
    d = R.get("wave")
    if not d:
        return ""
    pts = d["points"]
    for p in pts:
        p["label_h"] = p["label"]
    png = wp_plot("wave", f"Inhomogeneous wave: max error against the exact solution at t = {d['T']:g} (N = "
                  + ", ".join(str(n) for n in sorted({p['N'] for p in pts})) + ")", pts,
                  elabel="max_i |u_i - u(x_i, T)|", extra_panel=("eH", "max |H - H0|/|H0| (samples)"))
    out = ["## 6. Work-precision: inhomogeneous wave against the exact solution\n"]
    out.append("Paper section 4.3.2 (`examples/wave-inhomogeneous`): c = 10 on (0, 0.5), 1 on (0.5, 1), N "
               "intervals, u0 = 0.01 exp(-(20(x-0.2))^2), v0 = -c1 u0' (doc/theory.md, section 6: the paper's printed "
               "v0 is inconsistent with its exact solution). The stiff springs (c1) are bonds, the soft ones (c2) a "
               "pair table (`in.springs`), so that respa can split them. Each curve refines N (and the steps with "
               "dx); the stable async pair h_S = 0.5 dx, h_F = 0.05 dx (K = 10), and h_S = 0.5 dx, "
               "h_F = 0.1 dx (K = 5). The error against the exact solution contains the space discretisation "
               "error, which dominates at these N (the same for all integrators at the same N); the cost to reach "
               f"it is what differs. {d['reps']} repetitions, medians. Right panel: energy H = pe + ke (sampled at "
               "5 times; for async at coarse nodes).\n")
    out.append(f"![wave work-precision]({png})\n")
    out.append(wp_table(pts, [("method", lambda p: p["label"]), ("N", lambda p: str(p["N"])),
                              ("evals", lambda p: f"{p['evals']:.0f}"), ("wall [s]", lambda p: f"{p['loop_time']:.4f}"),
                              ("error vs exact", lambda p: fmt(p["err"], 4)),
                              ("max rel. dH", lambda p: fmt(p["eH"])), ("max rel. dH~", lambda p: fmt(p["eHt"]))]))
    out.append(tol_section(pts, "Inhomogeneous wave", targets))
    # async vs sync at the same N and fine step
    g = {}
    for p in pts:
        g[(p["label"], p["N"])] = p
    rows = []
    for p in pts:
        if p["label"].startswith("async K=10"):
            s = g.get(("pe_jump h=0.05dx", p["N"]))
            if s:
                rows.append((p["N"], p["evals"] / s["evals"], p["loop_time"] / s["loop_time"], p["err"] / s["err"]))
    if rows:
        out.append("Overhead of async: async K = 10 (0.5 dx / 0.05 dx) against pe_jump at h = 0.05 dx, same N "
                   "(what the fix costs per evaluation it saves, not a speed-up for users):\n")
        out.append("| N | evals async/sync | wall async/sync | wall ratio / evals ratio | error async/sync |\n|---|---|---|---|---|")
        for r in rows:
            out.append(f"| {r[0]} | {r[1]:.3f} | {r[2]:.3f} | {r[2] / r[1]:.2f} | {r[3]:.3f} |")
        out.append("")
        big = max(rows, key=lambda r: r[0])
        targets.append((f"Wave N={big[0]} (overhead): async K=10 wall-clock ratio to sync within 10% of its evaluation ratio",
                        "0.9 .. 1.1", f"{big[2] / big[1]:.2f} (evals {big[1]:.3f}, wall {big[2]:.3f})",
                        abs(big[2] / big[1] - 1) <= 0.1))
    return "\n".join(out) + "\n"


def sec_lattice(R, targets, misses):
    d = R.get("lattice")
    if not d:
        return ""
    pts = d["points"]
    info = d["info"]
    png = wp_plot("lattice", f"Spring lattice, {info['atoms']} atoms, stiff inclusion {info['inclusion']} atoms "
                  f"(stiffness x{d['stiffness_ratio']:g}), positions at t = {d['T']:g}", pts, elabel="max |r - r_ref|")
    out = ["## 7. Work-precision: 2d spring lattice with a stiff inclusion (K = 50)\n"]
    out.append(f"Triangular lattice (spacing 1, periodic, unit masses), {info['atoms']} atoms; a central disk of "
               f"{info['inclusion']} atoms ({100.0 * info['inclusion'] / info['atoms']:.1f}%) is the fast group. Springs "
               f"between two inclusion atoms are {d['stiffness_ratio']:g} times stiffer (frequency ratio "
               f"{math.sqrt(d['stiffness_ratio']):.0f}): {info['bonds']} bonds; all other nearest-neighbour springs "
               f"({info['soft']}) are the soft pair table. Initial state: lattice positions, Gaussian velocities "
               f"with kT = 1e-4 in every atom (equipartition: every mode equally excited). With K = "
               f"{math.sqrt(d['stiffness_ratio']):.0f} = the frequency ratio, omega h is the same in both regions, so the "
               f"async error is about the sync error (see the inclusion/matrix columns). Reference: pe_jump midpoint "
               f"at h = {d['href']:g} (Richardson estimate of its error {fmt(d['ref_err'])}). Error: max over atoms of "
               f"|r - r_ref| at t = {d['T']:g}. {d['reps']} repetitions, medians. This scene is `bench/inputs/in.springs` "
               f"on a data file from `benchlib.write_lattice_data` (not `examples/spring-lattice`, which did not "
               f"exist when this was written, and whose springs are all bonds so respa could not split them).\n")
    out.append(f"![lattice work-precision]({png})\n")
    out.append(wp_table(pts, [("method", lambda p: p["label"]), ("h (fine)", lambda p: f"{p['h']:g}"),
                              ("evals", lambda p: f"{p['evals']:.1f}"), ("wall [s]", lambda p: f"{p['loop_time']:.3f}"),
                              ("error", lambda p: fmt(p["err"])), ("inclusion", lambda p: fmt(p["err_inclusion"])),
                              ("matrix", lambda p: fmt(p["err_matrix"])), ("max rel. dH~", lambda p: fmt(p["eHt"])),
                              ("Pair [s]", lambda p: f"{p['breakdown'].get('Pair', 0):.3f}"),
                              ("Bond [s]", lambda p: f"{p['breakdown'].get('Bond', 0):.3f}"),
                              ("Modify [s]", lambda p: f"{p['breakdown'].get('Modify', 0):.3f}"),
                              ("Comm [s]", lambda p: f"{p['breakdown'].get('Comm', 0):.3f}"),
                              ("CPU", lambda p: f"{p['cpu_use']:.0f}%")]))
    g = groups(pts)
    sync = g.get("pe_jump midpoint (sync)", [])
    lines = ["\nAsync K = 50 against sync (pe_jump midpoint) at the same accuracy (sync's wall time and evaluations "
             "interpolated log-log at the async point's error). sync/async compares the two fixes; what a user "
             "gains is in the last two columns, against fix nve and the faster respa at that error:\n",
             "| async K=50 h_F | error | evals | wall [s] | sync evals at that error | sync wall at that error [s] | sync/async (evals) | sync/async (wall) | fix nve at that error [s] | best respa at that error [s] | nve/async (wall) | respa/async (wall) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    res = []
    for p in g.get("async K=50", []):
        ts, xs = interp_cost(sync, p["err"], "loop_time")
        es, _ = interp_cost(sync, p["err"], "evals")
        tn, xn = interp_cost(g.get("fix nve", []), p["err"], "loop_time")
        rs = [(interp_cost(v, p["err"], "loop_time"), k) for k, v in g.items() if k.startswith("respa")]
        rs = [(x[0][0], x[0][1], x[1]) for x in rs if x[0][0]]
        tr, xr, kr = min(rs) if rs else (None, True, "")
        res.append((p, ts, es, xs))
        lines.append(f"| {p['h']:g} | {fmt(p['err'])} | {p['evals']:.1f} | {p['loop_time']:.3f} | {es:.1f} | "
                     f"{ts:.3f}{' extrap.' if xs else ''} | {es / p['evals']:.2f} | {ts / p['loop_time']:.2f} | "
                     f"{fmt(tn)}{' extrap.' if tn and xn else ''} | "
                     f"{fmt(tr)}{f' ({kr})' if tr else ''}{' extrap.' if tr and xr else ''} | "
                     f"{(tn / p['loop_time']) if tn else float('nan'):.2f} | {(tr / p['loop_time']) if tr else float('nan'):.2f} |")
    out.append("\n".join(lines) + "\n")
    if res:
        bestw = max(r[1] / r[0]["loop_time"] for r in res)
        beste = max(r[2] / r[0]["evals"] for r in res)
        out.append(f"Against pe_jump at the same accuracy (fix against fix, not a speed-up for users: those are "
                   f"the last columns): at most {bestw:.2f}x in wall time, {beste:.2f}x in evaluations.\n")
    rows = async_overhead_rows(pts, "pe_jump midpoint (sync)", "async")
    if rows:
        out.append("Overhead of async: async against sync at the same fine step (target: wall ratio within 10% of "
                   "evaluation ratio; not a speed-up for users):\n")
        out.append("| async | h_F | evals async/sync | wall async/sync | wall ratio / evals ratio |\n|---|---|---|---|---|")
        for r in rows:
            out.append(f"| {r[0]} | {r[1]:g} | {r[2]:.3f} | {r[3]:.3f} | {r[4]:.2f} |")
        out.append("")
        k50 = [r for r in rows if r[0] == "async K=50"]
        if k50:
            worst = max(k50, key=lambda r: abs(r[4] - 1))
            targets.append(("Lattice (overhead): async K=50 wall-clock ratio to sync within 10% of its evaluation ratio",
                            "0.9 .. 1.1", f"{worst[4]:.2f} (evals {worst[2]:.3f}, wall {worst[3]:.3f})",
                            abs(worst[4] - 1) <= 0.1))
            if abs(worst[4] - 1) > 0.1:
                misses.append("async overhead")
    return "\n".join(out) + "\n"


def sec_lj_wp(R):
    d = R.get("lj_wp")
    if not d:
        return ""
    pts = d["points"]
    n = pts[0]["natoms"]
    png = wp_plot("lj", f"LJ liquid, {n} atoms: positions at t = {d['T']:g} vs reference", pts,
                  elabel="max |r - r_ref|")
    out = ["## 8. Work-precision: LJ liquid\n"]
    out.append(f"The liquid of section 1 ({n} atoms) after 1000 steps from the lattice (written with "
               f"`write_data`), then t = {d['T']:g} with each integrator. Reference: fix nve at h = {d['href']:g} "
               f"(Richardson estimate of its error {fmt(d['ref_err'])}). Error: max over atoms of the distance of "
               f"the unwrapped positions. The liquid is chaotic, so errors are amplified by about exp(lambda t) "
               f"alike for every method; `lj/cut` without smoothing has a force jump at the cutoff. One force "
               f"style: no respa split, no slow/fast split. {d['reps']} repetitions, medians.\n")
    out.append(f"![LJ work-precision]({png})\n")
    out.append(wp_table(pts, [("method", lambda p: p["label"]), ("h", lambda p: f"{p['h']:g}"),
                              ("evals", lambda p: f"{p['evals']:.0f}"), ("wall [s]", lambda p: f"{p['loop_time']:.3f}"),
                              ("max position error", lambda p: fmt(p["err"])),
                              ("rel. change of etotal", lambda p: fmt(p["eH"]))]))
    g = groups(pts)
    nv = {p["h"]: p for p in g.get("fix nve", [])}
    ratios = [(lab, p["h"], p["err"] / nv[p["h"]]["err"]) for lab, ps in g.items() if lab != "fix nve"
              for p in ps if p["h"] in nv]
    if ratios:
        out.append("Error relative to fix nve at the same step: " +
                   "; ".join(f"{lab} h={h:g}: {r:.2f}" for lab, h, r in ratios) + ".\n")
    return "\n".join(out) + "\n"


def sec_dtreset(R):
    d = R.get("dtreset")
    if not d:
        return ""
    out = ["## 9. Variable steps: fix dt/reset\n"]
    out.append("Both integrators must see exactly the same step sequence. Each input therefore holds two "
               "identical, non-interacting copies of the system, one integrated by fix nve and one by fix pe_jump, "
               "and a single `fix dt/reset` (computed from the atoms of one copy, 'driver') sets the step of both. "
               "FPU: `bench/inputs/in.dtreset-fpu` (omega = 50, `fix dt/reset 1 NULL 2e-3 1.5e-3 units box`); LJ: "
               "`bench/inputs/in.dtreset-lj` (shifted lj/cut so that the energy is continuous, copies overlap "
               "with `neigh_modify exclude type 1 2`, 1000 steps of fix nve at dt = 0.005 first, then "
               "`fix dt/reset 1 NULL 0.008 0.015 units box`). H = pe + ke of each copy, H~ = pe + f_ID of the "
               "pe_jump copy, all relative to |H(0)|.\n")
    keys = [k for k in d if k.startswith("fpu")] + (["lj"] if "lj" in d else [])
    fig, axs = plt.subplots(2, len(keys), figsize=(4.6 * len(keys), 6.4), squeeze=False)
    rows = ["| system | dt/reset driver | pe_jump rule | steps | dt range | fix nve: H(end) - H(0) | fix nve: max abs | pe_jump: H(end) - H(0) | pe_jump: max abs | pe_jump: H~(end) - H~(0) | H~: max abs |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for j, k in enumerate(keys):
        v = d[k]
        a = np.array(v["data"])
        t, dt = a[:, 1], a[:, 2]
        H1, H2, Ht = a[:, 3], a[:, 4], a[:, 5]
        s = abs(H1[0])
        e1, e2, et = (H1 - H1[0]) / s, (H2 - H2[0]) / s, (Ht - Ht[0]) / s
        ax = axs[0, j]
        ax.plot(t, e1, label="fix nve: H")
        ax.plot(t, e2, label="pe_jump: H")
        ax.plot(t, et, label="pe_jump: H~")
        ax.set_title(f"{'FPU' if k.startswith('fpu') else 'LJ liquid'}: driver {v['drive']}, pe_jump {v['quad']}", fontsize=9)
        ax.set_xlabel("time")
        ax.set_ylabel("(E - E(0))/|H(0)|")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        axs[1, j].plot(t, dt, lw=0.6)
        axs[1, j].set_xlabel("time")
        axs[1, j].set_ylabel("dt (every 100th step)")
        axs[1, j].grid(alpha=0.3)
        rows.append(f"| {'FPU chain' if k.startswith('fpu') else 'LJ liquid'} | {v['drive']} | {v['quad']} | {int(a[-1, 0])} | "
                    f"{dt.min():.3g} .. {dt.max():.3g} | {fmt(e1[-1])} | {fmt(np.max(np.abs(e1)))} | {fmt(e2[-1])} | "
                    f"{fmt(np.max(np.abs(e2)))} | {fmt(et[-1])} | {fmt(np.max(np.abs(et)))} |")
    fig.tight_layout()
    fig.savefig(os.path.join(DOC, "bench_dtreset.png"), dpi=110)
    plt.close(fig)
    out.append("\n".join(rows) + "\n")
    out.append("![energy under fix dt/reset](bench_dtreset.png)\n")
    summ = []
    for k in keys:
        v = d[k]
        a = np.array(v["data"])
        s0 = abs(a[0, 3])
        e1 = np.max(np.abs(a[:, 3] - a[0, 3])) / s0
        e2 = np.max(np.abs(a[:, 4] - a[0, 4])) / s0
        et = np.max(np.abs(a[:, 5] - a[0, 5])) / s0
        summ.append(f"{'FPU' if k.startswith('fpu') else 'LJ'} (driver {v['drive']}, {v['quad']}): fix nve's H "
                    f"{e1:.2g}, pe_jump's H {e2:.2g}, its H~ {et:.2g}")
    out.append("Largest relative excursion over the run, " + "; ".join(summ) + ". H of pe_jump differs from "
               "H~ by the jump energy, which oscillates with the step changes but does not accumulate; H~ is "
               "conserved up to the quadrature error of the rule (exact for lobatto 3 on the quartic FPU chain).\n")
    return "\n".join(out) + "\n"


def ms(x, n):
    return f"{1e3 * x / n:.3f}"


def sec_skip(R):
    d = R.get("skip")
    if not d and not any(k in R for k in ("fpu", "string")):
        return ""
    out = ["## 10. Skip what a scene does not need\n"]
    out.append("What the fixes leave out, shown with counts (vector element 5 of the fix, noise-free) and timings "
               "(LAMMPS `Loop time` and its breakdown, medians of interleaved repetitions): energies and virial "
               "only on output steps (10.1), the Lobatto start node and the Verlet loop's own evaluation as "
               "quadrature nodes (10.2), slow interactions skipped on fine steps by pe_jump/async (10.3), and "
               "`quadrature auto` against the fixed rules (10.4).\n")
    if d:
        out.append(_skip_lj(d))
        out.append(_skip_async(d))
    out.append(_skip_auto(R))
    return "\n".join(x for x in out if x) + "\n"


def _skip_lj(d):
    L = d["lj"]
    N = L["steps"]
    t = {(x["rule"], x["thermo"]): x for x in L["table"]}
    rules = []
    for x in L["table"]:
        if x["rule"] not in rules:
            rules.append(x["rule"])
    nve_e = t[("fix nve", "end")]
    out = ["### 10.1 Energies and virial cost nothing on steps without output\n"]
    out.append(f"LJ liquid of section 1 (`bench/inputs/in.lj`, {nve_e['natoms']} atoms, {N} steps), run twice per "
               f"integrator: `thermo {N}` (energy and pressure at the last step only; step 0 is the setup) and "
               f"`thermo 1` (`pe` and `press` at every step, so the Verlet loop asks every step for energy and "
               f"virial). With E_end and E_every the force evaluations of the two runs and o_end = 1, o_every = {N} "
               f"the output steps, the evaluations per step without output are k and those added per output "
               f"step x: E = {N} k + o x, two equations for two unknowns (fix nve has no counter: its count is "
               f"the step number, 1 per step by definition). Times per step are medians over {d['reps']} "
               f"repetitions; 'extra per output step' = (loop time every - loop time end)/({N} - 1). "
               f"Machine state: {quiet_text(L)}.\n")
    out.append("| integrator | evals, thermo end | evals, thermo every | k: evals / step without output | x: extra evals / output step | increments per step (thermo every) | loop / step, end [ms] | loop / step, every [ms] | extra per output step [ms] | Pair / step end / every [ms] | Modify / step end / every [ms] | Output / step every [ms] | CPU use |")
    out.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    kx = {}
    for rule in rules:
        e, v = t.get((rule, "end")), t.get((rule, "every"))
        if not (e and v):
            continue
        if e["integ"] == "nve":
            k, x = 1.0, 0.0
        else:
            x = (v["evals"] - e["evals"]) / (v["outputs"] - e["outputs"])
            k = (e["evals"] - e["outputs"] * x) / N
        kx[rule] = (k, x, e, v)
        dt = (v["loop_time"] - e["loop_time"]) / (N - 1)
        incs = f"{v['inc_min']:.6g}" if v["inc_min"] == v["inc_max"] else f"{v['inc_min']:.6g} .. {v['inc_max']:.6g}"
        be, bv = e["breakdown"], v["breakdown"]
        out.append(f"| {rule} | {e['evals']:.6g} | {v['evals']:.6g} | {k:.6g} | {x:.6g} | "
                   f"{incs if e['integ'] != 'nve' else '(1 by definition)'} | {ms(e['loop_time'], N)} | "
                   f"{ms(v['loop_time'], N)} | {1e3 * dt:+.3f} | {ms(be.get('Pair', 0), N)} / {ms(bv.get('Pair', 0), N)} | "
                   f"{ms(be.get('Modify', 0), N)} / {ms(bv.get('Modify', 0), N)} | {ms(bv.get('Output', 0), N)} | "
                   f"{min(e['cpu_use'], v['cpu_use']):.0f}% |")
    out.append("")
    pay = [r for r, (k, x, e, v) in kx.items() if x > 0.5]
    free = [r for r, (k, x, e, v) in kx.items() if abs(x) < 1e-9 and e["integ"] != "nve"]
    txt = []
    if free:
        txt.append("no extra evaluation on output steps for " + ", ".join(free) +
                   " (their last node is the end node q^{n+1}, evaluated by the Verlet loop, which tallies "
                   "energy and virial there when output asks for them)")
    if pay:
        txt.append(", ".join(f"{r} {kx[r][1]:.6g}" for r in pay) + " extra evaluation(s) per output step "
                   "(no node at q^{n+1}: the fix evaluates all interactions once more at the end positions so that "
                   "`pe` and `press` belong to the current positions; on the other steps it does not)")
    if txt:
        out.append("Counts: " + "; ".join(txt) + ". On steps without output every rule does exactly its "
                   "k evaluations; the energy of the last step of the `thermo end` runs is the only extra one "
                   "there. This is the cost table of `doc/fix_pe_jump.rst` (Legendre rules and midpoint pay 1 "
                   "per output step, Lobatto rules 0), i.e. energies and virial are computed only when output "
                   "asks for them, never on the other steps.\n")
    if "fix nve" in kx:
        e, v = kx["fix nve"][2], kx["fix nve"][3]
        dp = (v["breakdown"].get("Pair", 0) - e["breakdown"].get("Pair", 0)) / (N - 1)
        out.append(f"Timings: with fix nve, asking for energy and virial at every step costs "
                   f"{1e3 * (v['loop_time'] - e['loop_time']) / (N - 1):+.3f} ms per output step, of which "
                   f"{1e3 * dp:+.3f} ms in Pair (the pair style tallying energy and virial) and "
                   f"{ms(v['breakdown'].get('Output', 0), N)} ms in Output, against "
                   f"{ms(e['loop_time'], N)} ms for a step without output. For the rules that pay an extra "
                   f"evaluation the difference shows in Modify (the fix's own evaluations): "
                   + ", ".join(f"{r} {1e3 * (kx[r][3]['breakdown'].get('Modify', 0) - kx[r][2]['breakdown'].get('Modify', 0)) / (N - 1):+.3f} ms"
                               for r in pay) +
                   f" per output step, about one evaluation (fix nve's Pair time per step: "
                   f"{ms(e['breakdown'].get('Pair', 0), N)} ms). Time differences of a few percent are within "
                   f"the noise of this machine (see the CPU use column).\n")
    # 10.2: nodes
    out.append("### 10.2 Lobatto reuses its start node; the Verlet loop's evaluation is one of the nodes\n")
    out.append(f"The `thermo end` runs of 10.1: k (evaluations per step without output) against the number of "
               f"nodes of each rule. The Verlet loop evaluates the forces once per step (LAMMPS books it under "
               f"Pair); every further evaluation is the fix's (booked under Modify). If the Verlet loop's "
               f"evaluation were not a node, every rule would need its nodes plus one; if Lobatto did not reuse "
               f"its start node (the end node of the previous step), lobatto N would need N. Last two columns: "
               f"the fix's Modify time per own evaluation (Modify of the rule minus Modify of fix nve, divided by "
               f"k - 1) against the Pair time per step of fix nve (one evaluation by the Verlet loop).\n")
    out.append("| rule | nodes | k: evals / step | of which Verlet's own | by the fix | expected k | Pair / step [ms] | Modify / step [ms] | Modify per fix evaluation [ms] | fix nve Pair / step [ms] |")
    out.append("|---|---|---|---|---|---|---|---|---|---|")
    nve_pair = nve_e["breakdown"].get("Pair", 0) / N
    nve_mod = nve_e["breakdown"].get("Modify", 0)
    ok = True
    for rule, (k, x, e, v) in kx.items():
        if e["integ"] == "nve":
            continue
        ok = ok and abs(k - e["expect"]) < 1e-9
        per = (e["breakdown"].get("Modify", 0) - nve_mod) / (N * (k - 1)) if k > 1.5 else None
        out.append(f"| {rule} | {e['nodes']} | {k:.6g} | 1 | {k - 1:.6g} | {e['expect']} | "
                   f"{ms(e['breakdown'].get('Pair', 0), N)} | {ms(e['breakdown'].get('Modify', 0), N)} | "
                   f"{'' if per is None else f'{1e3 * per:.3f}'} | {1e3 * nve_pair:.3f} |")
    out.append("")
    pairs = [x[2]["breakdown"].get("Pair", 0) / N for x in kx.values()]
    fixev = [(x[2]["breakdown"].get("Modify", 0) - nve_mod) / (N * (x[0] - 1)) for x in kx.values() if x[0] > 1.5]
    out.append(("Every count equals its expectation: " if ok else "**Not every count equals its expectation** "
                "(see the table): ") +
               "lobatto N does N - 1 evaluations per step for N nodes, legendre N and midpoint N for N nodes. "
               f"The Pair time per step (the Verlet loop's one evaluation) is {1e3 * min(pairs):.3f} to "
               f"{1e3 * max(pairs):.3f} ms for every rule and fix nve, whatever the number of nodes, so the Verlet "
               "loop's evaluation is one of the nodes and is not repeated by the fix" +
               (f"; a fix evaluation costs {1e3 * min(fixev):.3f} to {1e3 * max(fixev):.3f} ms under Modify, about "
                "what the Verlet loop's costs (the fix skips the neighbor list check, booked under Neigh)"
                if fixev else "") + ". Differences of 10-20% between these times are the noise of a shared "
               "machine (CPU use column of 10.1); the counts are exact.\n")
    return "\n".join(out) + "\n"


def _skip_async(d):
    A = d.get("async")
    if not A:
        return ""
    out = ["### 10.3 pe_jump/async skips the slow interactions on fine steps\n"]
    sc = A["scenes"]
    desc = []
    for name, v in sc.items():
        fr, cn = v["frac"], v["counts"]
        desc.append(f"**{name}** ({cn['atoms']} atoms, {v['steps']} fine steps, i.e. {v['steps']} / K coarse "
                    f"steps of async): {fr['all']} interactions "
                    f"({cn['bonds']} bonds, {fr['pairs']} neighbor pairs), {fr['fine']} of them fine (involving an "
                    f"atom of the fast group): f = {fr['fine'] / fr['all']:.6f}")
    out.append(f"The slow/fast chain of section 5 and the lattice of section 7 (smaller copies), h_F = {A['h']:g}, "
               f"thermo output at the last step only. The fix does not print its interaction fractions, so f (the "
               f"fraction of interactions in the fine subset) is counted from the data file: bonds plus the "
               f"nearest-neighbour soft springs (the only pairs within cutoff + skin; LAMMPS' `Total # of "
               f"neighbors` is checked against it). " + "; ".join(desc) + ". One LAMMPS step of async is one "
               f"coarse step h_S = K h_F, so a run of async has 1/K of sync's steps. Predicted evaluations "
               f"(`doc/fix_pe_jump_async.rst`): coarse steps x n x (f K + (1 - f)) for async (per coarse step "
               f"the fine interactions at each of the K fine steps, the others once), steps x n for sync, with "
               f"n the evaluations per step of the rule (1 for midpoint, 2 for lobatto 3), plus 1 for the energy "
               f"at the output step (async, every rule; sync: Legendre rules and midpoint only). Per-step columns "
               f"are per fine step (h_F) for both fixes: async's totals divided by K x its coarse steps. "
               f"'vs sync' columns are overhead figures (same fine step), not speed-ups for users. "
               f"{d['reps']} repetitions, medians. Machine state: {quiet_text(A)}.\n")
    out.append("| scene | method | neighbors (LAMMPS / data) | evals measured | evals predicted | measured - predicted | evals / fine step | evals vs sync | loop / fine step [ms] | wall vs sync | Pair + Bond / fine step [ms] | Modify / fine step [ms] | CPU use |")
    out.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    worst = 0.0
    for x in A["table"]:
        sync = [y for y in A["table"] if y["scene"] == x["scene"] and y["integ"] == "pe_jump" and y["quad"] == x["quad"]]
        s = sync[0] if sync else None
        n = x.get("fine_steps", x["steps"])      # fine steps (results before the coarse-step build: steps)
        bd = x["breakdown"]
        diff = x["evals"] - x["pred_evals"]
        worst = max(worst, abs(diff))
        out.append(f"| {x['scene']} | {x['label']} | {x.get('neighbors')} / {sc[x['scene']]['frac']['pairs']} | "
                   f"{x['evals']:.6f} | {x['pred_evals']:.6f} | {diff:+.1e} | {x['evals'] / n:.6f} | "
                   f"{(x['evals'] / s['evals']) if s else float('nan'):.3f} | {ms(x['loop_time'], n)} | "
                   f"{(x['loop_time'] / s['loop_time']) if s else float('nan'):.3f} | "
                   f"{ms(bd.get('Pair', 0) + bd.get('Bond', 0), n)} | {ms(bd.get('Modify', 0), n)} | {x['cpu_use']:.0f}% |")
    out.append("")
    exact = worst < 6e-7
    out.append(f"Measured and predicted evaluation counts agree to {worst:.1e} "
               + ("(within the 6 decimals of the printed count) " if exact else "(**more than the 6 printed decimals "
                  "allow**) ") +
               f"for every K, both rules and both scenes: on a fine step the fix evaluates only the fine "
               f"interactions, and the coarse ones once per coarse step at each of the rule's nodes, so the cost "
               f"per coarse step is n (f K + (1 - f)), per fine step n (f + (1 - f)/K), never below n f. Pair + "
               f"Bond holds every evaluation: the Verlet loop's, of the coarse interactions at the primary coarse "
               f"node, and the fix's fine evaluations, which it books as Pair, Bond and Comm time; Modify is the "
               f"fix's own work.\n")
    k1 = [(x, [y for y in A["table"] if y["scene"] == x["scene"] and y["integ"] == "pe_jump"
               and y["quad"] == x["quad"]][0]) for x in A["table"] if x["integ"] == "async" and x["K"] == 1]
    kmax = []
    for scn in sc:
        xs = [x for x in A["table"] if x["scene"] == scn and x["integ"] == "async" and x["quad"] == "midpoint"]
        ss = [y for y in A["table"] if y["scene"] == scn and y["integ"] == "pe_jump" and y["quad"] == "midpoint"]
        if xs and ss:
            kmax.append((max(xs, key=lambda x: x["K"]), ss[0]))
    if k1:
        out.append("K = 1 does exactly the evaluations of sync (every step is a coarse step), but takes " +
                   ", ".join(f"{x['loop_time'] / s_['loop_time']:.2f}x sync's wall time on the {x['scene']} (Modify "
                             f"{ms(x['breakdown'].get('Modify', 0), x['steps'])} against "
                             f"{ms(s_['breakdown'].get('Modify', 0), s_['steps'])} ms per step)" for x, s_ in k1) +
                   ": with K = 1 the fix still swaps the split neighbor and bond lists and evaluates the fine "
                   "interactions in a force pass of its own (the Verlet loop's evaluates the coarse ones), two "
                   "passes per step where sync needs one. For K > 1 the force time falls with the count; "
                   "wall ratio / evaluation ratio to sync at the largest K: " +
                   ", ".join(f"{x['scene']} {x['label']} {(x['loop_time'] / s_['loop_time']) / (x['evals'] / s_['evals']):.2f}"
                             for x, s_ in kmax) +
                   " (1: the wall time falls as the evaluations; above 1, the fix's own time per fine step, "
                   "Modify, falls less than the evaluations; section 12).\n")
    return "\n".join(out) + "\n"


def _skip_auto(R):
    rows, rows2, verdict, pe = [], [], [], []
    nwin_all = 0
    for key, scene in (("fpu", "FPU chain"), ("string", "nonlinear string")):
        if key not in R:
            continue
        g = groups(R[key]["points"])
        fixed = {lab: ps for lab, ps in g.items() if lab.startswith("pe_jump ") and not lab.startswith("pe_jump auto")}
        for lab, ps in g.items():
            if not lab.startswith("pe_jump auto"):
                continue
            nwin = 0
            for p in sorted(ps, key=lambda p: -p["h"]):
                cand = []
                for fl, fps in fixed.items():
                    cst, xt = interp_cost(fps, p["err"], "evals")
                    if cst:
                        cand.append((xt, cst, fl))
                xt, cst, fl = min(cand, key=lambda c: c[1])
                win = p["evals"] < cst
                nwin += win
                rows.append(f"| {scene} | {lab} | {p['h']:g} | {fmt(p['err'])} | {p['evals']:.0f} | {fl}"
                            f"{' (extrap.)' if xt else ''} | {cst:.0f} | {p['evals'] / cst:.2f} |")
                # pseudo-energy: at the same h (same position error), cheapest fixed rule at least as good
                same = [(q["evals"], fl2, q["eHt"]) for fl2, fps in fixed.items() for q in fps
                        if abs(q["h"] - p["h"]) < 1e-12 * p["h"] and q["eHt"] <= p["eHt"]]
                if same:
                    ev, fl2, e2 = min(same)
                    pe.append((p["evals"] / ev, e2 / p["eHt"]))
                    rows2.append(f"| {scene} | {lab} | {p['h']:g} | {fmt(p['eHt'])} | {p['evals']:.0f} | {fl2} | "
                                 f"{fmt(e2)} | {ev:.0f} | {p['evals'] / ev:.2f} |")
                else:
                    rows2.append(f"| {scene} | {lab} | {p['h']:g} | {fmt(p['eHt'])} | {p['evals']:.0f} | none | | | |")
            nwin_all += nwin
            verdict.append(f"{scene}: auto needs fewer evaluations than the best fixed rule at {nwin} of {len(ps)} "
                           f"error levels")
    if not rows:
        return ""
    out = ["### 10.4 quadrature auto against the fixed rules\n"]
    out.append("From the work-precision runs of sections 3 and 4 (points `pe_jump auto TOL`). Position error: at "
               "each auto point's error, the evaluations every fixed pe_jump rule needs, interpolated log-log on "
               "its points (as for the other equal-error comparisons; 'extrap.' = the error lies just outside that "
               "rule's points and its cost is extrapolated from the nearest two), and the cheapest of them:\n")
    out.append("| scene | auto | h | position error | auto evals | best fixed rule at that error | its evals | auto / best |")
    out.append("|---|---|---|---|---|---|---|---|")
    out += rows
    out.append("")
    out.append("Pseudo-energy, which is what TOL controls: at the same h (the same position error, which is set by "
               "the step, not by the rule), the cheapest fixed rule whose max |H~ - H~0|/|H~0| over the run is at "
               "most auto's:\n")
    out.append("| scene | auto | h | auto max rel. dH~ | auto evals | cheapest fixed rule with dH~ <= auto's | its dH~ | its evals | auto / it |")
    out.append("|---|---|---|---|---|---|---|---|---|")
    out += rows2
    out.append("")
    txt = "**Does auto beat every fixed rule?** On the position error: " + "; ".join(verdict) + ". "
    if nwin_all == 0:
        txt += ("No: on these scenes the position error is set by the time step and is about the same for every "
                "rule at a given h, so the cheapest rule for a position error is a 1-evaluation rule (midpoint, "
                "lobatto 2), and auto, which pays for its bound on the pseudo-energy defect, needs about "
                f"{min(float(r.split('|')[-2]) for r in rows):.2f}x to {max(float(r.split('|')[-2]) for r in rows):.2f}x "
                "their evaluations. ")
    if pe:
        cheaper = sum(1 for a, b in pe if a < 1.0)
        txt += (f"On the pseudo-energy (second table), auto is cheaper than the cheapest fixed rule that conserves "
                f"H~ at least as well at {cheaper} of {len(pe)} points, by {100 * (1 - max(a for a, b in pe)):.0f}% "
                f"to {100 * (1 - min(a for a, b in pe)):.0f}% of the evaluations, while that fixed rule's drift is "
                f"{min(b for a, b in pe):.2g}x to {max(b for a, b in pe):.2g}x auto's (auto stops refining as soon "
                "as a step's defect is below TOL; the fixed rule is exact or nearly so on every step). So auto "
                "saves a few percent of the evaluations against the cheapest fixed rule that holds its drift, "
                "and that fixed rule conserves H~ up to orders of magnitude better for those few percent more; "
                "auto does not beat every fixed rule on the work-precision plots.")
    out.append(txt + "\n")
    return "\n".join(out) + "\n"


def sec_profile(R):
    d = R.get("profile")
    if not d or d.get("skipped"):
        return ""
    out = ["## 11. Profiles\n"]
    out.append("`perf record` of single runs (whole process, setup included): LJ 100 steps, 32000 atoms; "
               "lattice (section 7) h = 0.002 to t = 8, async K = 50; chain (section 5, 100000 atoms) h = 0.002 "
               "to t = 2, async K = 10. Self time per symbol, symbols above 1%:\n")
    for k, rows in d.items():
        if k.endswith("_loop") or not isinstance(rows, list):
            continue
        lt = d.get(k + "_loop")
        out.append(f"**{k}**" + (f" (loop {lt:.2f} s)" if lt else "") + ": " +
                   "; ".join(f"{pct:.1f}% `{sym}`" for pct, sym in rows[:12]) + "\n")
    return "\n".join(out) + "\n"


def per_atom_ns(p, keys, natoms=None):
    n = natoms or p["natoms"]
    return 1e9 * sum(p["breakdown"].get(k, 0.0) for k in keys) / (p["steps"] * n)


def sec_findings(R):
    """Observations computed from the results: overhead of the fixes per
    atom and step, async overhead, respa energy, LJ error constant, memory."""
    out = ["## 12. Findings: where the time goes, and what looks wrong\n"]
    # A: per-step overhead of pe_jump midpoint against fix nve, all scenes
    rows = []
    if "lj_cost" in R:
        t = {x["name"]: x for x in R["lj_cost"]["table"]}
        n, m = t["fix nve"], t.get("pe_jump midpoint")
        if m:
            rows.append(("LJ liquid", n["natoms"], n, m, n["natoms"]))
    for scene, key, lab_s, hsel in (("lattice", "lattice", "pe_jump midpoint (sync)", 0.002),
                                    ("slow/fast chain", "chain", "pe_jump midpoint", 0.002)):
        if key in R:
            g = groups(R[key]["points"])
            n = [p for p in g.get("fix nve", []) if abs(p["h"] - hsel) < 1e-12]
            m = [p for p in g.get(lab_s, []) if abs(p["h"] - hsel) < 1e-12]
            if n and m:
                nat = R[key]["counts"]["mobile"] if key == "chain" else n[0]["natoms"]
                rows.append((scene, n[0]["natoms"], n[0], m[0], nat))
    if "wave" in R:
        pts = R["wave"]["points"]
        N = max(p["N"] for p in pts)
        n = [p for p in pts if p["N"] == N and p["label"] == "fix nve h=0.1dx"]
        m = [p for p in pts if p["N"] == N and p["label"] == "pe_jump h=0.1dx"]
        if n and m:
            rows.append((f"wave N={N}", n[0]["natoms"], n[0], m[0], n[0]["natoms"]))
    if rows:
        out.append("**Per-step overhead of fix pe_jump (midpoint) against fix nve at the same step.** "
                   "Force work = (Pair + Bond + Neigh) time per atom and step of fix nve; Modify = the "
                   "integrator's own time per integrated atom and step. The extra work of the fix is a "
                   "fixed cost per atom, so its relative weight depends on how cheap the force field is:\n")
        out.append("| scene | atoms | force work, fix nve [ns/atom/step] | Modify fix nve [ns/atom/step] | Modify pe_jump [ns/atom/step] | wall pe_jump / fix nve |")
        out.append("|---|---|---|---|---|---|")
        for scene, nat, n, m, nint in rows:
            fw = per_atom_ns(n, ("Pair", "Bond", "Neigh"))
            out.append(f"| {scene} | {nat} | {fw:.1f} | {per_atom_ns(n, ('Modify',), nint):.1f} | "
                       f"{per_atom_ns(m, ('Modify',), nint):.1f} | {m['loop_time'] / n['loop_time']:.2f} |")
        out.append("\nOn the LJ liquid the force work is large and the midpoint target holds; on spring "
                   "networks (a few tens of ns of force work per atom) the same per-atom cost of the fix "
                   "makes `fix pe_jump` slower per step than `fix nve`, although it does the same number of "
                   "force evaluations.\n")
    # B: async overhead
    lines, ratios = [], []
    for key, lab_s, lab_a in (("lattice", "pe_jump midpoint (sync)", "async K=50"),
                              ("chain", "pe_jump midpoint", "async K=10")):
        if key not in R:
            continue
        g = groups(R[key]["points"])
        for a in g.get(lab_a, []):
            s = [p for p in g.get(lab_s, []) if p["h"] == a["h"]]
            n = [p for p in g.get("fix nve", []) if p["h"] == a["h"]]
            rs = [p for k, v in g.items() if k.startswith("respa") and k.endswith(lab_a.split()[-1])
                  for p in v if p["h"] == a["h"]]
            if not (s and n):
                continue
            s, n = s[0], n[0]
            af = a.get("fine_steps", a["steps"])     # async's fine steps (older results: steps)
            frac = (R[key]["info"]["inclusion"] / R[key]["info"]["atoms"]) if key == "lattice" else 0.5
            ratios.append((key, lab_a, a["h"], a["breakdown"].get("Modify", 0) / af / (s["breakdown"].get("Modify", 0) / s["steps"]),
                           a["breakdown"].get("Modify", 0) / af / (n["breakdown"].get("Modify", 0) / n["steps"]), frac,
                           (a["loop_time"] / s["loop_time"]) / (a["evals"] / s["evals"])))
            lines.append(f"| {key} | {lab_a}, h_F = {a['h']:g} | {a['evals'] / s['evals']:.3f} | "
                         f"{a['loop_time'] / s['loop_time']:.3f} | {1e3 * a['breakdown'].get('Modify', 0) / af:.3f} | "
                         f"{1e3 * s['breakdown'].get('Modify', 0) / s['steps']:.3f} | {1e3 * n['breakdown'].get('Modify', 0) / n['steps']:.3f} | "
                         f"{(1e3 * rs[0]['breakdown'].get('Modify', 0) / (rs[0]['steps'] * rs[0]['K'])) if rs else float('nan'):.3f} | "
                         f"{1e3 * (a['breakdown'].get('Pair', 0) + a['breakdown'].get('Bond', 0)) / af:.3f} |")
    if lines:
        out.append("**Overhead of fix pe_jump/async per fine step.** Modify time per fine step of async (its "
                   "totals over K x its coarse steps: one LAMMPS step of async is one coarse step), "
                   "sync (pe_jump midpoint at h_F) and fix nve (at h_F), per inner step of respa with the same "
                   "K (its Modify holds the inner-level fix nve updates of all atoms), and the force time (Pair "
                   "+ Bond) of async per fine step. In ms. The ratios to sync are overhead figures, not "
                   "speed-ups for users:\n")
        out.append("| scene | async | evals async/sync | wall async/sync | Modify async | Modify sync | Modify fix nve | Modify respa (per inner step) | Pair+Bond async |")
        out.append("|---|---|---|---|---|---|---|---|---|")
        out += lines
        txt = "; ".join(f"{k} ({la}): {r1:.2f}x the Modify time of a synchronous step and {r2:.2f}x that of "
                        f"fix nve (both integrate all atoms), with {100 * fr:.0f}% of the integrated atoms in the fast group"
                        for k, la, h, r1, r2, fr, q in ratios if h == max(x[2] for x in ratios if x[0] == k))
        quot = {}
        for x in ratios:
            quot.setdefault(x[0], []).append(x[6])
        qtxt = ", ".join(f"{k} {min(v):.2f}-{max(v):.2f}" for k, v in quot.items())
        above = [k for k, v in quot.items() if max(v) > 1.0]
        prof = R.get("profile", {})
        old_prof = R.get("meta", {}).get("stages", {}).get("profile", {}).get("async_step") != "coarse"
        checks = "; ".join(f"{pct:.1f}% of the {k.split('_')[0]} run" for k in ("lattice_async", "chain_async")
                           for pct, sym in prof.get(k, []) if sym.endswith("Neighbor::check_distance"))
        if checks and old_prof:
            checks += ", profiles of the older build"
        out.append("\nThe force work of async (Pair + Bond) drops with its evaluation count; its own "
                   f"time per fine step (Modify): {txt}. Wall ratio / evaluation ratio to sync: {qtxt} "
                   "(1: the wall time falls as the evaluations). On fine steps the fix visits only the "
                   "atoms that move (the fine-clock atoms and the slow atoms in a fine interaction: "
                   "`FixPEJumpAsync::fine_step`, `move_moving` and `finish_fine_step` loop over the moving "
                   "atoms), and once per coarse step every atom of the group (`hold_until` for the interior slow "
                   "atoms, `coarse_quadrature_sum`, `slow_jumps`). " +
                   (f"What keeps the wall-clock ratio above the evaluation ratio ({', '.join(above)}): "
                    if above else "Where the wall-clock ratio is above the evaluation ratio, the causes are: ") +
                   "(1) LAMMPS' own per-step work over all atoms, which a fix cannot skip: the "
                   f"neighbor-list distance check (`Neighbor::check_distance`: {checks or 'see the profiles'}), "
                   "force clearing (memset) and the output machinery; (2) on the chain, fine-clock and slow "
                   "atoms alternate in memory (per chain of six, three fine-clock atoms and one slow atom in "
                   "a fine interaction move on fine steps), so the loops over two thirds of the atoms still "
                   "stream nearly every cache line of x, v, f and the fix's arrays: the per-atom work is "
                   "memory-bound, and the saving per fine step follows the fraction of moving atoms, not the "
                   "evaluation ratio; (3) the pass over all atoms at every coarse node. respa updates all "
                   "atoms at every inner step, at the cost of fix nve.\n")
    prof = R.get("profile", {})
    old_prof = R.get("meta", {}).get("stages", {}).get("profile", {}).get("async_step") != "coarse"
    for k in ("chain_async", "lattice_async"):
        if prof.get(k):
            out.append(f"Profile `{k}` ({'older build, one LAMMPS step = one fine step; ' if old_prof else ''}"
                       "perf, self time, top symbols): " +
                       "; ".join(f"{pct:.1f}% `{sym}`" for pct, sym in prof[k][:10]) + ".\n")
    # C: respa energy on the wave
    if "wave" in R:
        pts = R["wave"]["points"]
        rr = [p for p in pts if p["label"].startswith("respa")]
        nv = [p for p in pts if p["label"].startswith("fix nve")]
        if rr and nv:
            out.append(f"**run_style respa on the wave does not conserve energy**: max |H - H0|/|H0| = "
                       f"{min(p['eH'] for p in rr):.3g} .. {max(p['eH'] for p in rr):.3g} for every N and both K, "
                       f"against {max(p['eH'] for p in nv):.2g} for fix nve and {max(p['eHt'] for p in pts if p['label'].startswith('async')):.2g} "
                       f"for the pseudo-energy of pe_jump/async (checked independently from the final positions "
                       f"and velocities). The outer (soft) impulses kick the stiff region every h_S = 0.5 dx, "
                       f"i.e. omega_fast h_S = 10, deep in the resonance range of impulse multiple time "
                       f"stepping; the positions' max error is not affected at t = 0.5.\n")
    # D: LJ error constant
    if "lj_wp" in R:
        g = groups(R["lj_wp"]["points"])
        nv = {p["h"]: p for p in g.get("fix nve", [])}
        rat = {lab: np.median([p["err"] / nv[p["h"]]["err"] for p in ps if p["h"] in nv])
               for lab, ps in g.items() if lab != "fix nve"}
        if rat:
            out.append("**LJ liquid: position error of pe_jump against fix nve at the same step** (median over "
                       "the steps): " + ", ".join(f"{lab} {r:.2f}x" for lab, r in rat.items()) +
                       ". Lobatto 2 (the trapezoidal rule) with the half-kick start is velocity Verlet, and "
                       "reproduces it; the midpoint rule has a larger error constant on this scene, so at equal "
                       "accuracy it needs a smaller step than fix nve. On the spring networks (sections 5-7) "
                       "the errors of pe_jump midpoint and fix nve are equal.\n")
    # auto TOL: per-step defect bound accumulates
    for key in ("fpu", "string"):
        if key in R:
            g = groups(R[key]["points"])
            au = [lab for lab in g if lab.startswith("pe_jump auto")]
            for lab in au:
                ps = g[lab]
                tol = float(lab.split()[-1])
                out.append(f"**quadrature auto on the {'FPU chain' if key == 'fpu' else 'nonlinear string'}** ({lab}): "
                           "the pseudo-energy error over the run grows as the step shrinks, "
                           + ", ".join(f"h = {p['h']:g}: {p['eHt']:.2g} after {p['steps']:.0f} steps"
                                       for p in sorted(ps, key=lambda p: -p['h'])) +
                           f": TOL = {tol:g} bounds the defect of each step, so the drift over a run is up to TOL "
                           "times the number of steps; a user who wants a bound on the run must scale TOL with h.\n")
    # E: memory
    if "mpi" in R:
        t = {(x["integ"], x["quad"], x["np"]): x for x in R["mpi"]["table"]}
        n1, m1 = t.get(("nve", None, 1)), t.get(("pe_jump", "midpoint", 1))
        if n1 and m1:
            out.append(f"**Memory**: on {n1['natoms']} LJ atoms, 1 rank, LAMMPS reports {n1['memory_mb'][1]:.2f} MB for "
                       f"fix nve and {m1['memory_mb'][1]:.2f} MB for pe_jump midpoint: "
                       f"{m1['bytes_per_atom'] - n1['bytes_per_atom']:.0f} bytes per atom more "
                       f"({(m1['bytes_per_atom'] - n1['bytes_per_atom']) / 8:.0f} doubles per owned atom). "
                       f"`FixPEJump::memory_usage()` counts 2 per-atom arrays (free-flight velocity, jump) and 4 "
                       f"work arrays (fsum, fsample, xsave, fsave) of 3 doubles, all sized to atom->nmax (owned + "
                       f"ghost atoms); with the midpoint rule there are no extra nodes, so xsave and fsave are "
                       f"not needed.\n")
    return "\n".join(out) + "\n"


# stages with pe_jump/async rows, and where the report shows them
ASYNC_STAGES = {"chain": "section 5", "wave": "section 6", "lattice": "section 7", "skip": "section 10.3",
                "profile": "section 11 and the profiles quoted in 12"}


def async_build_text(stages):
    """Which stages' pe_jump/async rows come from the coarse-step build (bench.py
    marks the stages it runs: async_step = coarse) and which are older."""
    coarse = [k for k in ASYNC_STAGES if stages.get(k, {}).get("async_step") == "coarse"]
    older = [k for k in ASYNC_STAGES if k in stages and k not in coarse]
    bins = sorted({stages[k].get("binary_mtime") for k in coarse if stages[k].get("binary_mtime")})
    txt = ("**Which build the pe_jump/async figures come from.** One LAMMPS step of pe_jump/async is one "
           "coarse step h_S = K h_F (as the outer step of run_style respa); the tables give its fine step "
           "h_F as h, and its evaluation counts are vector element 5 of the fix as for pe_jump. ")
    if coarse:
        txt += ("The stages " + ", ".join(f"{k} ({ASYNC_STAGES[k]})" for k in coarse) + " were run with the "
                "coarse-step build" + (f" (binary built {', '.join(bins)})" if bins else "") + ". ")
    if older:
        txt += ("The pe_jump/async rows of the stages " + ", ".join(f"{k} ({ASYNC_STAGES[k]})" for k in older) +
                " are older: a build in which one LAMMPS step was one fine step, not this code's. ")
    txt += ("Ratios of pe_jump/async to fix pe_jump at the same fine step are overhead figures (what the fix "
            "costs per evaluation it saves), not speed-ups a user gets; those are against fix nve at its "
            "largest step within the accuracy asked for and run_style respa at equal error (sections 5 and 6: "
            "fastest configuration within the tolerance; section 5: at equal error; section 7: last columns).\n")
    return txt



# ------------------------------------------- the studies run beside bench.py

# (file under bench/results, title): the reports of the studies that
# bench/run_all.sh runs after bench.py with the same binary
STUDIES = [("composite/full.md", "Composite lattices against fix nve at its largest stable step"),
           ("composite/split.md", "Composite lattices split for run_style respa"),
           ("moving_region/report.md", "Moving fast regions: crack, impact, cascade"),
           ("cost/report.md", "Overhead of pe_jump/async on 1, 2 and 4 ranks")]


def study_json(rel):
    path = os.path.join(B.BENCH, "results", rel)
    return B.load_json(path) if os.path.exists(path) else None


def liblammps_sha(path):
    import hashlib
    if not os.path.exists(path):
        return None
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def binary_check():
    """Which liblammps.so.0 each study names (sha256), against the copy
    bench/run_all.sh made: one line for the report's head."""
    ref = liblammps_sha(os.path.join(B.BENCH, "work", "binary", "liblammps.so.0"))
    named = {}
    c = study_json("composite/full.json")
    if c:
        named["composite"] = c["binary"]["liblammps"].get("sha256")
    c = study_json("composite/split.json")
    if c:
        named["composite split"] = c["binary"]["liblammps"].get("sha256")
    c = study_json("cost/current.json")
    if c:
        named["cost"] = c["binary"]["liblammps"].get("sha256")
    c = study_json("moving_region/report.json")
    if c:
        named["moving regions"] = c["meta"]["binary"].get("liblammps_sha256")
    if not ref:
        return "The copy of the binary that `bench/run_all.sh` makes is not here, so the studies' binaries are not checked.\n"
    same = [k for k, v in named.items() if v and ref.startswith(v[:16])]
    other = [k for k in named if k not in same]
    text = (f"The studies beside bench.py ({', '.join(same) or 'none'}) name the same `liblammps.so.0` "
            f"(sha256 {ref[:16]}).")
    if other:
        text += f" **Warning: {', '.join(other)} name another binary: rerun them with `bench/run_all.sh`.**"
    return text + "\n"


def passing(pts, prefix):
    ok = [p for p in pts if p["label"].startswith(prefix) and p["err"] <= TOL_ERR and energy_dev(p) <= TOL_DE]
    return min(ok, key=lambda p: p["loop_time"]) if ok else None


def rows_paper_scenes(R):
    rows = []
    for key, scene in (("chain", "slow/fast chain"), ("wave", "inhomogeneous wave")):
        d = R.get(key)
        if not d:
            continue
        a = passing(d["points"], "async")
        for user in ("fix nve", "respa"):
            u = passing(d["points"], user)
            if not u and not a:
                continue
            sp = f"{u['loop_time'] / a['loop_time']:.2f}" if (u and a) else ("async only" if a else "0 (async fails)")
            ev = f"{a['evals'] / u['evals']:.2f}" if (u and a) else ""
            rows.append((scene, user, u["label"] + (f", h = {u['h']:g}" if "h" in u else "") if u else "none passes",
                         f"{a['label']}, h = {a['h']:g}" if a else "none passes", sp, "", ev))
    return rows


def rows_composite():
    rows = []
    for rel in ("composite/full.json", "composite/split.json"):
        c = study_json(rel)
        if not c:
            continue
        for name, v in c["variants"].items():
            sm = v["summary"]
            scene = f"composite lattice {100 * v['fraction']:g} % stiff" + (" (split)" if "split" in name else "")
            rows.append((scene, "fix nve", sm["nve_best"], sm["async_best"], f"{sm['speedup']:.2f}",
                         f"{sm['speedup_paired']:.2f}", f"{1.0 / sm['eval_ratio']:.3f}"))
            if sm.get("vs_respa"):
                r = sm["vs_respa"]
                rows.append((scene, "run_style respa", r["respa"], sm["async_best"], f"{r['speedup']:.2f}",
                             f"{r['speedup_paired']:.2f}", f"{1.0 / r['eval_ratio']:.3f}"))
    return rows


def rows_moving():
    rows = []
    c = study_json("moving_region/report.json")
    if not c:
        return rows
    for scene, v in c["scenes"].items():
        runs = {r["tag"]: r for r in v["runs"]}
        sm = v["summary"]
        u, a = runs.get(sm.get("best")), runs.get(sm.get("fastest_passing", {}).get("async"))
        user = "fix nve + fix dt/reset" if sm.get("comparator_family") != "nve" else "fix nve"
        if u and a:
            rows.append((scene, user, u["label"], a["label"], f"{u['wall_median'] / a['wall_median']:.2f}", "",
                         f"{a['evals'] / u['evals']:.2f}"))
        elif u:
            rows.append((scene, user, u["label"], "none passes", "0 (async fails)", "", ""))
    return rows


def sec_against_users(R):
    rows = rows_paper_scenes(R) + rows_composite() + rows_moving()
    if not rows:
        return ""
    out = ["## pe_jump/async against what a user runs instead\n",
           "Every scene of this report on which pe_jump/async applies, against the method a LAMMPS user "
           "would run instead at the same accuracy: fix nve at its largest step that meets the scene's "
           "tolerance, fix nve + fix dt/reset on the cascade, run_style respa where it can split the forces. "
           "Speed-up = wall time of the user's fastest passing setting / pe_jump/async's fastest passing "
           "setting (medians; 'paired': median of the per-repetition ratios, where the study pairs them). "
           "Below 1 pe_jump/async loses. Evaluation ratio = pe_jump/async's force evaluations / the user's. "
           "Tolerances: the paper's scenes (sections 5 and 6) position error <= "
           f"{TOL_ERR:g} and max |dE|/E <= {TOL_DE:g} with E = pe + ke; the composite lattices and the moving "
           "regions those of their studies (appended at the end of this report).\n",
           "| scene | against | user's fastest passing setting | pe_jump/async's fastest passing setting | "
           "speed-up | paired | evaluation ratio |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append("| " + " | ".join(r) + " |")
    out.append("")
    return "\n".join(out) + "\n"


def embed_studies():
    out = []
    for rel, title in STUDIES:
        path = os.path.join(B.BENCH, "results", rel)
        if not os.path.exists(path):
            out.append(f"## {title}\n\nNot run: `bench/results/{rel}` is missing.\n")
            continue
        with open(path) as f:
            lines = f.read().splitlines()
        # one heading level down, the study's own title replaced
        body = [("#" + ln) if ln.startswith("#") else ln for ln in lines[1:]]
        out.append(f"## {title}\n\nFrom `bench/results/{rel}`.\n\n" + "\n".join(body) + "\n")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    mode = "quick" if args.quick else "full"
    rd = os.path.join(B.BENCH, "results", mode)
    global DOC
    if args.quick:
        # the quick check must not overwrite the report of the full run
        DOC = os.path.join(rd, "report")
        os.makedirs(DOC, exist_ok=True)
    R = {}
    for f in os.listdir(rd):
        if f.endswith(".json"):
            R[f[:-5]] = B.load_json(os.path.join(rd, f))
    targets, misses = [], []
    body = []
    if mode == "full":
        body.append(sec_against_users(R))
    body.append(sec_lj_cost(R, targets, misses))
    body.append(sec_mpi(R))
    body.append(sec_fpu(R))
    body.append(sec_string(R))
    body.append(sec_chain(R, targets))
    body.append(sec_wave(R, targets))
    body.append(sec_lattice(R, targets, misses))
    body.append(sec_lj_wp(R))
    body.append(sec_dtreset(R))
    body.append(sec_skip(R))
    body.append(sec_profile(R))
    body.append(sec_findings(R))
    if mode == "full":
        body.append(embed_studies())
    meta = R.get("meta", {})
    head = ["# PE-JUMP benchmarks\n"]
    if mode == "quick":
        head.append("> **Quick mode** (`bench/run_all.sh --quick`): smaller systems, fewer steps and repetitions. "
                    "The numbers below check the pipeline; the targets refer to the full run, whose report is "
                    "`doc/benchmarks.md`.\n")
    head.append("Generated by `bash bench/run_all.sh` (see `bench/README.md`) from the results in "
                f"`bench/results/{mode}/`; every number and plot below comes from that run. LAMMPS 4 Feb 2025 "
                "with fix pe_jump and fix pe_jump/async (`build/lmp`), one MPI rank unless stated, on a 2-core "
                f"machine ({meta.get('uname', '')}). Wall times are LAMMPS' `Loop time` (the run, without setup), "
                "medians of repeated runs made in one invocation of the script, interleaved so that the machine's "
                "state affects all configurations alike. Force evaluations are the noise-free cost: vector "
                "element 5 of the fixes (1 = one full force evaluation; fix nve does 1 per step). Each section "
                "names the load of the other processes measured before and after it (from /proc/stat while none "
                "of our runs was active) and the tables give LAMMPS' `% CPU use` of the runs: 100% means the run "
                "had a core to itself.\n")
    b = meta.get("binary", {})
    if b:
        src = b.get("source", "build/lmp")
        src = os.path.relpath(src, B.ROOT) if src.startswith(B.ROOT) else src
        head.append(f"Binary: a copy of `{src}` and its `liblammps.so.0` built {b.get('mtime')} (git HEAD "
                    f"{meta.get('git_head', '?')}{'; src/ had uncommitted changes' if meta.get('git_src_dirty') else ''}), "
                    "taken at the start so that a rebuild during the run cannot mix binaries.\n")
    head.append("LAMMPS' timer categories: from 2026-11-24 on, the extra force evaluations of the fixes "
                "are stamped as Pair, Bond, Kspace and Comm time, as the Verlet loop's own; in a run made "
                "with an earlier binary the Modify time includes them.\n")
    stages = meta.get("stages", {})
    bins = {v.get("binary_mtime") for v in stages.values() if v.get("binary_mtime")}
    if len(bins) > 1:
        head.append("**Warning: the stages below were run with different binaries** (" +
                    ", ".join(f"{k}: {v.get('binary_mtime')}" for k, v in stages.items()) + ").\n")
    if stages:
        head.append("Stage run times: " + ", ".join(f"{k} {v['seconds']:.0f} s" for k, v in stages.items()) + ".\n")
    head.append(async_build_text(stages))
    if mode == "full":
        head.append(binary_check())
    notes = os.path.join(B.BENCH, f"notes_{mode}_head.md")
    if os.path.exists(notes):
        with open(notes) as f:
            head.append(f.read())
    head.append("## Targets\n")
    head.append("| target | required | measured | |\n|---|---|---|---|")
    for name, req, meas, ok in targets:
        head.append(f"| {name} | {req} | {meas} | {met(ok)} |")
    head.append("")
    text = "\n".join(head) + "\n" + "\n".join(b for b in body if b)
    extra = os.path.join(B.BENCH, f"notes_{mode}.md")
    if os.path.exists(extra):
        with open(extra) as f:
            text += "\n" + f.read()
    with open(os.path.join(DOC, "benchmarks.md"), "w") as f:
        f.write(text)
    print("wrote", os.path.join(DOC, "benchmarks.md"))


if __name__ == "__main__":
    main()
