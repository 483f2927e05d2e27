#!/usr/bin/env python3
"""Stability stress tests of fix pe_jump and fix pe_jump/async.

  /usr/bin/python3 bench/stability/stress.py [--quick] [--studies cfl,long,string,resonance,hard]

Studies (results as JSON in bench/stability/results/, plots doc/stability_*.png;
with --quick both go to bench/work/stability/ instead):
  cfl        largest stable step by bisection against 2/omega_max (numpy) for
             harmonic chains and a 2d spring lattice; fix nve, pe_jump midpoint,
             pe_jump lobatto 3
  long       FPU chain of examples/fpu over many steps: drift of H and H~
  string     nonlinear string (examples/nonlinear-string) with and without adapt
  resonance  slow/fast chain: run_style respa + fix nve against fix pe_jump/async
             over K = 1..100
  hard       close LJ approaches, steps just above the stability limit

Environment: LMP (default bench/work/stability-bin/lmp, run with
LD_LIBRARY_PATH set to its directory). One LAMMPS process at a time.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import time

import numpy as np

sys.dont_write_bytecode = True
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
INPUTS = os.path.join(HERE, "inputs")
RESULTS = os.path.join(HERE, "results")
DOC = os.path.join(ROOT, "doc")
LMP = os.environ.get("LMP", os.path.join(ROOT, "bench", "work", "stability-bin", "lmp"))
WORK = os.path.join(ROOT, "bench", "work", "stability")
QUICK = False


def log(msg):
    print(msg, flush=True)


# ---------------------------------------------------------------------------
# running LAMMPS and reading its log

def lmp(infile, variables, tag, timeout=3600):
    """Run LAMMPS (serial) on infile with -var settings; return parsed log."""
    os.makedirs(WORK, exist_ok=True)
    logf = os.path.join(WORK, f"log.{tag}")
    cmd = [LMP, "-in", infile, "-log", logf, "-screen", "none", "-nocite"]
    for k, v in variables.items():
        cmd += ["-var", k] + (v if isinstance(v, list) else [str(v)])
    env = dict(os.environ, LD_LIBRARY_PATH=os.path.dirname(LMP), OMP_NUM_THREADS="1")
    t0 = time.time()
    try:
        p = subprocess.run(cmd, cwd=WORK, env=env, capture_output=True, text=True, timeout=timeout)
        rc, out = p.returncode, p.stdout + p.stderr
        hung = False
    except subprocess.TimeoutExpired:
        rc, out, hung = -1, "", True
    wall = time.time() - t0
    text = open(logf).read() if os.path.exists(logf) else ""
    r = parse_log(text + "\n" + out)
    r.update(rc=rc, wall=wall, hung=hung, log=logf)
    return r


def parse_log(text):
    """Thermo rows (list of dicts), ERROR line, loop time, nan flag."""
    rows, header = [], None
    error, loop = None, None
    prints = []
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("ERROR") and error is None:
            error = s
        if s.startswith("Step ") or s.startswith("Step\t"):
            header = s.split()
            continue
        if s.startswith("Loop time"):
            loop = float(s.split()[3])
            header = None
            continue
        if header:
            f = s.split()
            if len(f) == len(header):
                try:
                    rows.append({h: float(x) for h, x in zip(header, f)})
                    continue
                except ValueError:
                    pass
            if not s.startswith("WARNING"):
                header = None if not f or not f[0].lstrip("-").isdigit() else header
        if s.startswith("STRESS") or s.startswith("PEJUMP_SUMMARY") or s.startswith("SLOWFAST"):
            prints.append(s)
    nan = bool(re.search(r"\b(nan|-nan|inf|-inf)\b", "\n".join(
        " ".join(str(v) for v in r.values()) for r in rows), re.I)) or \
        any(not all(math.isfinite(v) for v in r.values()) for r in rows)
    return dict(rows=rows, error=error, loop=loop, nan=nan, prints=prints)


# ---------------------------------------------------------------------------
# harmonic networks: data files and the Hessian

def write_network(path, pos, mobile, bonds, kcoef, vel, mass=None, fast=None):
    """2d network. pos (n,2), mobile bool (n), bonds list of (i, j, type),
    kcoef list of (K, r0) per bond type (E = K (r - r0)^2), vel (n,2)."""
    n = len(pos)
    mass = np.ones(n) if mass is None else mass
    fast = np.zeros(n, bool) if fast is None else fast
    types = np.where(mobile, np.where(fast, 3, 1), 2)
    lo, hi = pos.min(0) - 3.0, pos.max(0) + 3.0
    with open(path, "w") as f:
        f.write("PE-JUMP stability network (bench/stability/stress.py)\n\n")
        f.write(f"{n} atoms\n3 atom types\n{len(bonds)} bonds\n{len(kcoef)} bond types\n\n")
        f.write(f"{lo[0]:.6f} {hi[0]:.6f} xlo xhi\n{lo[1]:.6f} {hi[1]:.6f} ylo yhi\n-0.5 0.5 zlo zhi\n\n")
        # per-atom masses are not in atom_style bond: use per-type masses,
        # so a mixed-mass system needs one type per mass (not used here)
        f.write("Masses\n\n1 1.0\n2 1.0\n3 1.0\n\n")
        f.write("Bond Coeffs\n\n")
        for t, (K, r0) in enumerate(kcoef):
            f.write(f"{t+1} {K:.17g} {r0:.17g}\n")
        f.write("\nAtoms # bond\n\n")
        for i in range(n):
            f.write(f"{i+1} 1 {types[i]} {pos[i,0]:.17g} {pos[i,1]:.17g} 0.0\n")
        f.write("\nVelocities\n\n")
        for i in range(n):
            f.write(f"{i+1} {vel[i,0]:.17g} {vel[i,1]:.17g} 0.0\n")
        f.write("\nBonds\n\n")
        for b, (i, j, t) in enumerate(bonds):
            f.write(f"{b+1} {t} {i+1} {j+1}\n")


def hessian(pos, mobile, bonds, kcoef, mass=None):
    """Mass-weighted Hessian of sum K (r - r0)^2 at pos (mobile dofs only).
    At a bond of length r: 2K [e e^T + (1 - r0/r)(I - e e^T)]."""
    n = len(pos)
    H = np.zeros((2 * n, 2 * n))
    for (i, j, t) in bonds:
        K, r0 = kcoef[t - 1]
        d = pos[j] - pos[i]
        r = np.linalg.norm(d)
        e = d / r
        blk = 2 * K * (np.outer(e, e) + (1 - r0 / r) * (np.eye(2) - np.outer(e, e)))
        for a, b, s in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
            H[2 * a:2 * a + 2, 2 * b:2 * b + 2] += s * blk
    dof = np.repeat(mobile, 2)
    H = H[np.ix_(dof, dof)]
    m = np.ones(n) if mass is None else mass
    w = 1 / np.sqrt(np.repeat(m[mobile], 2))
    return H * w[:, None] * w[None, :]


def chain_system(kbonds, seed, amp=1e-3):
    """Chain along x with fixed end atoms, bond i has coefficient kbonds[i]
    (len = N + 1 for N mobile atoms), spacing 1, rest length 1."""
    N = len(kbonds) - 1
    pos = np.zeros((N + 2, 2))
    pos[:, 0] = np.arange(N + 2)
    mobile = np.ones(N + 2, bool)
    mobile[[0, -1]] = False
    ktypes = sorted(set(kbonds))
    kcoef = [(k, 1.0) for k in ktypes]
    bonds = [(i, i + 1, ktypes.index(kbonds[i]) + 1) for i in range(N + 1)]
    rng = np.random.default_rng(seed)
    vel = np.zeros_like(pos)
    vel[mobile, 0] = amp * rng.uniform(-1, 1, N)
    disp = np.zeros_like(pos)
    disp[mobile, 0] = amp * rng.uniform(-1, 1, N)
    # the Hessian at the equilibrium (linear system along x: exact)
    Hx = hessian(pos, mobile, bonds, kcoef)[0::2, 0::2]
    return dict(pos=pos + disp, mobile=mobile, bonds=bonds, kcoef=kcoef, vel=vel, H=Hx)


def square_lattice(nx, ny, k1, k2, seed, amp=1e-4):
    """Square lattice, spacing 1, nearest (E = k1 (r-1)^2) and diagonal
    (E = k2 (r - sqrt2)^2) bonds; the outer ring of atoms is fixed."""
    idx = lambda i, j: i * ny + j
    pos = np.array([(i, j) for i in range(nx) for j in range(ny)], float)
    mobile = np.array([0 < i < nx - 1 and 0 < j < ny - 1 for i in range(nx) for j in range(ny)])
    bonds = []
    for i in range(nx):
        for j in range(ny):
            for (di, dj, t) in ((1, 0, 1), (0, 1, 1), (1, 1, 2), (1, -1, 2)):
                a, b = i + di, j + dj
                if 0 <= a < nx and 0 <= b < ny and (mobile[idx(i, j)] or mobile[idx(a, b)]):
                    bonds.append((idx(i, j), idx(a, b), t))
    kcoef = [(k1, 1.0), (k2, math.sqrt(2.0))]
    rng = np.random.default_rng(seed)
    vel = np.where(mobile[:, None], amp * rng.uniform(-1, 1, pos.shape), 0.0)
    disp = np.where(mobile[:, None], amp * rng.uniform(-1, 1, pos.shape), 0.0)
    H = hessian(pos, mobile, bonds, kcoef)
    return dict(pos=pos + disp, mobile=mobile, bonds=bonds, kcoef=kcoef, vel=vel, H=H)


def triangular_lattice(nx, ny, k1, seed, amp=1e-4):
    """Triangular lattice, spacing 1, nearest-neighbour bonds E = k1 (r-1)^2,
    a frame of fixed atoms (first/last row and column)."""
    h = math.sqrt(3) / 2
    idx = lambda i, j: j * nx + i
    pos = np.array([(i + 0.5 * (j % 2), j * h) for j in range(ny) for i in range(nx)], float)
    mobile = np.array([0 < i < nx - 1 and 0 < j < ny - 1 for j in range(ny) for i in range(nx)])
    bonds = []
    for j in range(ny):
        for i in range(nx):
            nb = [(i + 1, j)]
            if j % 2 == 0:
                nb += [(i, j + 1), (i - 1, j + 1)]
            else:
                nb += [(i, j + 1), (i + 1, j + 1)]
            for (a, b) in nb:
                if 0 <= a < nx and 0 <= b < ny and (mobile[idx(i, j)] or mobile[idx(a, b)]):
                    bonds.append((idx(i, j), idx(a, b), 1))
    kcoef = [(k1, 1.0)]
    rng = np.random.default_rng(seed)
    vel = np.where(mobile[:, None], amp * rng.uniform(-1, 1, pos.shape), 0.0)
    disp = np.where(mobile[:, None], amp * rng.uniform(-1, 1, pos.shape), 0.0)
    H = hessian(pos, mobile, bonds, kcoef)
    return dict(pos=pos + disp, mobile=mobile, bonds=bonds, kcoef=kcoef, vel=vel, H=H)


def network_run(datafile, integ, pjopts, h, nsteps, nth, tag, Ecap=1e300, K=1):
    """One run; returns dict with stable flag and how it ended."""
    r = lmp(os.path.join(INPUTS, "in.network"),
            dict(data=datafile, integrator=integ, pjopts=[pjopts] if pjopts else ["quadrature midpoint"],
                 h=f"{h:.17g}", nsteps=nsteps, nth=nth, Ecap=f"{Ecap:.6g}", K=K), tag)
    rows = r["rows"]
    last = int(rows[-1]["Step"]) if rows else 0
    E0 = rows[0]["v_E"] if rows else float("nan")
    Emax = max((abs(x["v_E"]) for x in rows), default=float("nan"))
    unstable_err = bool(r["error"] and "unstable" in r["error"])
    if r["hung"]:
        outcome = "hang"
    elif r["error"]:
        outcome = "instability error" if unstable_err else "other error"
    elif r["nan"]:
        outcome = "nan"
    elif last < nsteps:
        outcome = "energy cap"
    else:
        outcome = "completed"
    # bounded energy: no growth from the first to the last quarter of the run
    # (near the limit the discrete energy of the top mode is large, ~1/(1 - (h w/2)^2),
    # but bounded; an unstable mode grows exponentially)
    q = max(1, len(rows) // 4)
    e_first = max((abs(x["v_E"]) for x in rows[:q]), default=float("nan"))
    e_last = max((abs(x["v_E"]) for x in rows[-q:]), default=float("nan"))
    growth = e_last / e_first if e_first > 0 else float("nan")
    stable = outcome == "completed" and math.isfinite(Emax) and growth < 10.0
    m = re.search(r"at step (\d+)", r["error"] or "")
    if m:
        last = int(m.group(1))
    if outcome == "completed" and not stable:
        outcome = "energy growth"
    return dict(stable=stable, outcome=outcome, error=r["error"], last_step=last, E0=E0, growth=growth,
                Emax=Emax, nan=r["nan"], wall=r["wall"], rc=r["rc"],
                Hrange=(max(x["v_Ht"] for x in rows) - min(x["v_Ht"] for x in rows)) if rows else None)


# ---------------------------------------------------------------------------
# study 1: CFL sweep

def study_cfl():
    os.makedirs(WORK, exist_ok=True)
    rng = np.random.default_rng(7)
    systems = {}
    systems["chain N=50 uniform"] = chain_system([50.0] * 51, 1)
    if not QUICK:
        systems["chain N=200 uniform"] = chain_system([50.0] * 201, 2)
        kmix = list(np.round(np.exp(rng.uniform(0, math.log(100.0), 101)), 3))
        systems["chain N=100 stiffness 1..100 (log-uniform)"] = chain_system(kmix, 3)
        systems["square 20x20 nn+diag (fixed frame)"] = square_lattice(20, 20, 50.0, 25.0, 4)
        systems["triangular 20x20 (fixed frame)"] = triangular_lattice(20, 20, 50.0, 5)
    rules = [("nve", ""), ("pe_jump", "quadrature midpoint"), ("pe_jump", "quadrature lobatto 3")]
    nsteps = 5000 if QUICK else 20000
    niter = 8 if QUICK else 13
    out = []
    for name, sysd in systems.items():
        lam = float(np.linalg.eigvalsh(sysd["H"]).max())
        htheory = 2 / math.sqrt(lam)
        data = os.path.join(WORK, "cfl_" + re.sub(r"[^A-Za-z0-9]+", "_", name) + ".data")
        write_network(data, sysd["pos"], sysd["mobile"], sysd["bonds"], sysd["kcoef"], sysd["vel"])
        for integ, opts in rules:
            label = integ if integ == "nve" else f"pe_jump {opts.split(' ', 1)[1]}"
            lo, hi = 0.9, 1.12
            # make sure of the bracket
            info_lo = network_run(data, integ, opts, lo * htheory, nsteps, 100, "cfl", Ecap=1e6)
            info_hi = network_run(data, integ, opts, hi * htheory, nsteps, 100, "cfl", Ecap=1e6)
            above = []
            for it in range(niter):
                mid = 0.5 * (lo + hi)
                res = network_run(data, integ, opts, mid * htheory, nsteps, 100, "cfl",
                                  Ecap=1e6 if integ == "nve" else 1e300)
                if res["stable"]:
                    lo = mid
                else:
                    hi = mid
                    above.append(dict(ratio=mid, outcome=res["outcome"], last_step=res["last_step"]))
            rec = dict(system=name, rule=label, natoms_mobile=int(sysd["mobile"].sum()),
                       lambda_max=lam, h_theory=htheory, ratio_lo=lo, ratio_hi=hi,
                       ratio=0.5 * (lo + hi), bracket_ok=bool(info_lo["stable"] and not info_hi["stable"]),
                       unstable_outcomes=sorted(set(a["outcome"] for a in above)),
                       nsteps=nsteps)
            log(f"CFL {name:45s} {label:20s} h_theory {htheory:.6g} measured/theory "
                f"[{lo:.5f}, {hi:.5f}] outcomes above: {rec['unstable_outcomes']}")
            out.append(rec)
    save("cfl", dict(results=out, nsteps=nsteps, iterations=niter))
    plot_cfl(dict(results=out))
    return out


# ---------------------------------------------------------------------------
# study 2: long FPU run

def study_long():
    infile = os.path.join(INPUTS, "in.fpu-long")
    methods = [("pe_jump midpoint", "pe_jump", "quadrature midpoint init kick"),
               ("pe_jump lobatto 3", "pe_jump", "quadrature lobatto 3 init kick"),
               ("fix nve", "nve", "")]
    budget = 25 * 60.0
    target = 10 ** 5 if QUICK else 10 ** 7
    out = dict(methods={}, budget_s=budget, target_steps=target)
    for label, integ, opts in methods:
        v = dict(integrator=integ, pjopts=[opts or "quadrature midpoint"], nthermo=10000, nave=100)
        t = lmp(infile, dict(v, nsteps=100000), "fpu_timing")
        per_step = t["loop"] / 1e5
        n = target if per_step * target <= budget else int(budget / per_step) // 10 ** 5 * 10 ** 5
        log(f"long {label}: 1e5 steps in {t['loop']:.2f} s -> {per_step * 1e7 / 60:.1f} min for 1e7 steps; running {n}")
        r = t if n == 100000 else lmp(infile, dict(v, nsteps=n), "fpu_long_" + label.replace(" ", "_"))
        rows = r["rows"]
        step = np.array([x["Step"] for x in rows])
        H = np.array([x["v_H"] for x in rows])
        Ht = np.array([x["v_Ht"] for x in rows])
        Ha = np.array([x["f_avg[1]"] for x in rows[1:]])
        Hta = np.array([x["f_avg[2]"] for x in rows[1:]])
        out["methods"][label] = dict(
            nsteps=n, loop_s=r["loop"], time_1e5_s=t["loop"], error=r["error"],
            step=step.tolist(), H=H.tolist(), Ht=Ht.tolist(), Havg=Ha.tolist(), Htavg=Hta.tolist(),
            H0=H[0], Ht0=Ht[0],
            max_dH=float(np.max(np.abs(H - H[0]))), max_dHt=float(np.max(np.abs(Ht - Ht[0]))),
            drift_Havg=float(Ha[-1] - Ha[0]), drift_Htavg=float(Hta[-1] - Hta[0]),
            # least-squares slope of the windowed averages per 1e6 steps
            slope_Havg=float(np.polyfit(step[1:], Ha, 1)[0] * 1e6),
            slope_Htavg=float(np.polyfit(step[1:], Hta, 1)[0] * 1e6))
        if not QUICK and per_step * 1e8 <= budget:
            # cheap enough: also 1e8 steps, thermo every 1e5 steps
            r8 = lmp(infile, dict(v, nsteps=10 ** 8, nthermo=100000, nave=1000),
                     "fpu_long8_" + label.replace(" ", "_"))
            rows8 = r8["rows"]
            H8 = np.array([x["v_H"] for x in rows8])
            Ht8 = np.array([x["v_Ht"] for x in rows8])
            Ha8 = np.array([x["f_avg[1]"] for x in rows8[1:]])
            Hta8 = np.array([x["f_avg[2]"] for x in rows8[1:]])
            out["methods"][label]["run_1e8"] = dict(
                loop_s=r8["loop"], error=r8["error"], step=[x["Step"] for x in rows8],
                H=H8.tolist(), Ht=Ht8.tolist(), Havg=Ha8.tolist(), Htavg=Hta8.tolist(),
                max_dH=float(np.max(np.abs(H8 - H8[0]))), max_dHt=float(np.max(np.abs(Ht8 - Ht8[0]))),
                drift_Havg=float(Ha8[-1] - Ha8[0]), drift_Htavg=float(Hta8[-1] - Hta8[0]))
            m8 = out["methods"][label]["run_1e8"]
            log(f"  1e8 steps in {r8['loop']:.1f} s: max|H-H0| {m8['max_dH']:.3e} max|H~-H~0| {m8['max_dHt']:.3e} "
                f"avg drift H {m8['drift_Havg']:.3e} H~ {m8['drift_Htavg']:.3e}")
        m = out["methods"][label]
        log(f"  max|H-H0| {m['max_dH']:.3e} max|H~-H~0| {m['max_dHt']:.3e} "
            f"avg drift H {m['drift_Havg']:.3e} H~ {m['drift_Htavg']:.3e}")
    save("long", out)
    plot_long(out)


def plot_long(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    colors = {"pe_jump midpoint": "C0", "pe_jump lobatto 3": "C2", "fix nve": "C3"}
    for label, m in out["methods"].items():
        c = colors.get(label)
        st = np.array(m["step"])
        ax[0].plot(st, np.array(m["H"]) - m["H0"], ".", ms=2, color=c, label=f"{label}: H = pe+ke")
        for run, ls in ((m, "-"), (m.get("run_1e8"), ":")):
            if run is None or "nve" in label:
                continue
            s = np.array(run["step"])
            d = np.abs(np.array(run["Ht"]) - run["Ht"][0])
            ax[1].loglog(s[1:], np.maximum(d[1:], 1e-17), ls, color=c,
                         label=f"{label}: |H~ - H~0| ({len(s) - 1} samples to {s[-1]:.0e})")
        r8 = m.get("run_1e8")
        if r8:
            s8 = np.array(r8["step"][1:])
            ax[2].plot(s8, np.array(r8["Havg"]) - r8["Havg"][0], "-", lw=0.8, color=c,
                       label=f"{label}: H, window mean")
    ax[0].set_title("1e7 steps, every 1e4 steps: H(n) - H(0)", fontsize=10)
    ax[0].set_xlabel("step (h = 1e-3)")
    ax[1].set_title("pseudo-energy |H~(n) - H~(0)| (solid 1e7, dotted 1e8 run)", fontsize=10)
    ax[1].set_xlabel("step")
    ax[2].set_title("1e8 steps: mean of H over each 1e5-step window, minus the first", fontsize=10)
    ax[2].set_xlabel("step")
    for a in ax:
        a.legend(fontsize=7)
    fig.suptitle("FPU chain (examples/fpu, omega = 50, h = 1e-3): long-run energy and pseudo-energy")
    fig.tight_layout()
    fig.savefig(os.path.join(DOC if not QUICK else WORK, "stability_fpu_long.png"), dpi=110)


def plot_cfl(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    res = out["results"]
    systems = list(dict.fromkeys(r["system"] for r in res))
    rules = list(dict.fromkeys(r["rule"] for r in res))
    fig, ax = plt.subplots(figsize=(9, 3.8))
    w = 0.8 / len(rules)
    for k, rule in enumerate(rules):
        x = np.arange(len(systems)) + (k - (len(rules) - 1) / 2) * w
        y = [next(r["ratio"] - 1 for r in res if r["system"] == s and r["rule"] == rule) for s in systems]
        e = [next((r["ratio_hi"] - r["ratio_lo"]) / 2 for r in res if r["system"] == s and r["rule"] == rule)
             for s in systems]
        ax.bar(x, y, w, yerr=e, label=rule)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xticks(np.arange(len(systems)))
    ax.set_xticklabels([s.replace(" (", "\n(") for s in systems], fontsize=7)
    ax.set_ylabel("measured h_max / (2/omega_max) - 1")
    ax.set_title("largest stable step by bisection (20000 steps) against the linear limit 2/omega_max", fontsize=10)
    ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(DOC if not QUICK else WORK, "stability_cfl.png"), dpi=110)


# ---------------------------------------------------------------------------
# study 3: nonlinear string with and without adapt

def read_efile(path):
    d = np.loadtxt(path, comments="#")
    return dict(step=d[:, 0], t=d[:, 1], dt=d[:, 2], dH=d[:, 7], dHt=d[:, 8])


def string_summary(r):
    txt = " ".join(r["prints"])
    g = lambda pat: float(re.search(pat, txt).group(1)) if re.search(pat, txt) else None
    return dict(dt_lo=g(r"dt in \[([0-9.e+-]+),"), dt_hi=g(r"dt in \[[0-9.e+-]+, ([0-9.e+-]+)\]"),
                steps=g(r"steps (\d+)"), t=g(r" t ([0-9.]+) H0"), evals=g(r"force evaluations ([0-9.]+)"),
                max_dH=g(r"max\|H-H0\|/\|H0\| ([-0-9.e+]+)"), max_dHt=g(r"max\|H~-H~0\|/\|H~0\| ([-0-9.e+]+)"),
                error=r["error"], nan=r["nan"])


def study_string():
    infile = os.path.join(ROOT, "examples", "nonlinear-string", "in.nonlinear-string")
    out = dict(runs=[])
    Tlong = 2.0 if QUICK else 10.0
    for quad in (["midpoint"] if QUICK else ["midpoint", "lobatto 3"]):
        q = [quad]
        ef = os.path.join(WORK, "string_adapt.dat")
        r = lmp(infile, dict(quad=q, adapt="yes", energy="yes", efile=ef, nthermo=1000), "string_adapt")
        e = read_efile(ef)
        dts = e["dt"][1:]
        s = string_summary(r)
        mean_dt = float(s["t"] / s["steps"])
        rec = dict(quad=quad, kind="adapt 3e-4 0.0005 0.0055", T=1.0, **s, dt_min=float(dts.min()),
                   dt_max=float(dts.max()), dt_mean=mean_dt,
                   dt_hist=np.histogram(dts, bins=20)[0].tolist(), dt_series=dts.tolist(),
                   t_series=e["t"][1:].tolist())
        out["runs"].append(rec)
        log(f"string {quad} adapt: steps {s['steps']:.0f} dt [{rec['dt_min']:.5g}, {rec['dt_max']:.5g}] "
            f"mean {mean_dt:.5g} max dH {s['max_dH']} max dHt {s['max_dHt']}")
        for (kind, dt, T) in [("fixed 0.0033 (paper)", 0.0033, 1.0), ("fixed at adapt mean", mean_dt, 1.0),
                              ("fixed at adapt mean", mean_dt, Tlong), ("fixed at adapt max", rec["dt_max"], 1.0),
                              ("fixed at adapt max", rec["dt_max"], Tlong),
                              ("fixed at dtmin", 0.0005, Tlong),
                              ("adapt", None, Tlong)]:
            v = dict(quad=q, nthermo=1000, T=T)
            if dt is None:
                v.update(adapt="yes", energy="yes", efile=os.path.join(WORK, "string_adapt_long.dat"))
            else:
                v.update(dt=f"{dt:.10g}")
            r = lmp(infile, v, "string_fixed")
            s = string_summary(r)
            rr = dict(quad=quad, kind=kind, dt=dt, T=T, **s)
            if dt is None:
                e = read_efile(os.path.join(WORK, "string_adapt_long.dat"))
                k = max(1, len(e["dt"]) // 2000)
                rr.update(dt_min=float(e["dt"][1:].min()), dt_max=float(e["dt"][1:].max()),
                          dt_mean=float(T / s["steps"]), dt_series_long=e["dt"][1::k].tolist(),
                          t_series_long=e["t"][1::k].tolist(), dH_series_long=e["dH"][1::k].tolist(),
                          dHt_series_long=e["dHt"][1::k].tolist())
            out["runs"].append(rr)
            log(f"string {quad} {kind} dt {dt} T {T}: steps {s['steps']} max dH {s['max_dH']} "
                f"max dHt {s['max_dHt']} error {s['error']}")
    save("string", out)
    plot_string(out)


def plot_string(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 3.8))
    for r in out["runs"]:
        if "dt_series" in r:
            ax[0].plot(r["t_series"], r["dt_series"], label=f"adapt, {r['quad']} ({r['steps']:.0f} steps)")
        if "dt_series_long" in r:
            ax[1].semilogy(r["t_series_long"], r["dt_series_long"],
                           label=f"adapt, {r['quad']} ({r['steps']:.0f} steps to t = {r['T']:g})")
    for a in ax:
        a.axhline(0.0033, color="k", ls=":", label="fixed step of the paper, 0.0033")
        a.set_xlabel("t")
        a.set_ylabel("time step (fix vector element 3)")
        a.legend(fontsize=8)
    ax[0].set_title("t in [0, 1] (the paper's run)", fontsize=10)
    ax[1].set_title("t in [0, 10]", fontsize=10)
    fig.suptitle("nonlinear string (alpha 0.99, A 0.3): steps chosen by adapt 3e-4 0.0005 0.0055")
    fig.tight_layout()
    fig.savefig(os.path.join(DOC if not QUICK else WORK, "stability_string_adapt.png"), dpi=110)


# ---------------------------------------------------------------------------
# study 4: resonance of the slow/fast chain over K

def study_resonance():
    sys.path.insert(0, os.path.join(ROOT, "bench"))
    import benchlib as B
    infile = os.path.join(ROOT, "bench", "inputs", "in.springs")
    a, om2, M = 5.0, 2500.0, 8
    springs = "KKKQQQQ"
    rng = np.random.default_rng(2024)
    amp_fast = 0.2 * math.sqrt(10.0 / om2)
    variants = [(springs, np.r_[rng.uniform(-1, 1, 3) * amp_fast, 0, 0, 0],
                 np.r_[0, 0, 0, rng.uniform(-0.5, 0.5, 3)]) for _ in range(M)]
    os.makedirs(WORK, exist_ok=True)
    B.write_table(os.path.join(WORK, "soft.table"), "SOFT", lambda r: (r - a) ** 4,
                  lambda r: -4 * (r - a) ** 3, 1.0, 9.0)
    B.write_chain_data(os.path.join(WORK, "chain.data"), variants, a=a)
    # linear frequencies of the fast segment (wall =K= q1 =K= q2 =K= q3, soft springs quartic)
    k = om2 / 2
    Hf = k * np.array([[2, -1, 0], [-1, 2, -1], [0, -1, 1]], float)
    omegas = np.sqrt(np.linalg.eigvalsh(Hf))
    Ks = [1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 60, 75, 100]
    hS = 0.2
    hF_fixed = 0.002
    T = 10.0 if QUICK else 40.0
    sweeps = [("fixed coarse step hS = 0.2", [(K, hS / K) for K in (Ks[::3] if QUICK else Ks)]),
              ("fixed fine step hF = 0.002", [(K, hF_fixed) for K in (range(1, 101, 9) if QUICK else range(1, 101))])]
    out = dict(omegas=omegas.tolist(), hS=hS, hF=hF_fixed, T=T, copies=M, sweeps={})
    base = dict(data=os.path.join(WORK, "chain.data"), table=os.path.join(WORK, "soft.table"), rc=8.0,
                skin=0.5, a=a, Kb=om2 / 4, out=os.path.join(WORK, "res.dump"))
    for sname, pts in sweeps:
        recs = []
        for (K, hf) in pts:
            Tk = round(T / (K * hf)) * K * hf
            for integ in ("respa", "async"):
                v = dict(base, integrator=integ, K=K, h=f"{hf:.12g}", T=f"{Tk:.12g}", quad="midpoint",
                         nsample=int(round(Tk / (K * hf))))
                r = lmp(infile, v, "res")
                rows = r["rows"]
                if rows:
                    E = np.array([x["c_epot"] + x["c_ekin"] for x in rows])
                    fin = np.isfinite(E)
                    rel = float(np.max(np.abs(E[fin] - E[0])) / abs(E[0])) if fin.all() else float("inf")
                else:
                    rel = float("nan")
                if r["error"] or r["nan"]:
                    rel = float("inf")
                recs.append(dict(K=K, hF=hf, hS=K * hf, integ=integ, rel_err=rel, error=r["error"],
                                 nan=r["nan"], omega_hS=(omegas * K * hf).tolist()))
                log(f"res {sname} K {K:3d} {integ:5s} hS {K * hf:.4g} rel err {rel:.3e} "
                    f"{'ERROR ' + r['error'][:90] if r['error'] else ''}")
        out["sweeps"][sname] = recs
    save("resonance", out)
    plot_resonance(out)


def plot_resonance(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, 2, figsize=(12, 4.2))
    om = np.array(out["omegas"])
    for ax, (sname, recs) in zip(axs, out["sweeps"].items()):
        cap = 1e3
        for integ, mk, lab in (("respa", "o-", "run_style respa 2 K bond 1 pair 2 + fix nve"),
                               ("async", "s-", "fix pe_jump/async K fast (midpoint)")):
            rr = [r for r in recs if r["integ"] == integ]
            K = np.array([r["K"] for r in rr])
            e = np.array([r["rel_err"] for r in rr])
            bad = ~np.isfinite(e)
            ax.semilogy(K[~bad], e[~bad], mk, ms=3, lw=0.8, label=lab)
            ax.semilogy(K[bad], np.full(bad.sum(), cap), "x" if integ == "respa" else "+", ms=8,
                        color=ax.lines[-1].get_color(), label=f"{integ}: unstable / stopped")
        if "fine" in sname:
            hF = out["hF"]
            for w in om:
                for n in range(1, 6):
                    Kr = n * math.pi / (w * hF)
                    if Kr <= 100:
                        ax.axvline(Kr, color="gray", lw=0.5, ls=":")
            ax.set_xlabel("K (coarse step hS = K hF; dotted: omega_j hS = n pi)")
        else:
            ax.set_xlabel("K (fine step hF = hS / K)")
        ax.set_xscale("log")
        ax.set_ylabel("max |H - H0| / |H0| (coarse nodes)")
        ax.set_title(sname, fontsize=10)
        ax.legend(fontsize=7)
    fig.suptitle(f"slow/fast chains (stiff omega_j = {', '.join(f'{w:.1f}' for w in om)}), T = {out['T']}")
    fig.tight_layout()
    fig.savefig(os.path.join(DOC if not QUICK else WORK, "stability_resonance.png"), dpi=110)


# ---------------------------------------------------------------------------
# study 5: hard cases

def lj_outcome(r, tend):
    txt = " ".join(r["prints"])
    m = re.search(r"STRESS done step (\d+) time (\S+) E0 (\S+) Emin (\S+) Emax (\S+) Htmin (\S+) Htmax (\S+) "
                  r"dtmin (\S+) dtmax (\S+) rmin (\S+) Eend (\S+) Htend (\S+)", txt)
    rec = dict(error=r["error"], nan=r["nan"], hung=r["hung"], wall=r["wall"])
    if m:
        vals = [float(x) for x in m.groups()]
        step, t, E0, Emin, Emax, Htmin, Htmax, dtmin, dtmax, rmin, Eend, Htend = vals
        rec.update(steps=step, t=t, E0=E0, dE=max(abs(Emax - E0), abs(Emin - E0)),
                   dE_end=Eend - E0, dHt_end=Htend - E0,
                   dHt=max(abs(Htmax - E0), abs(Htmin - E0)), dtmin=dtmin, dtmax=dtmax, rmin=rmin)
        if not all(math.isfinite(x) for x in vals):
            rec["nan"] = True
    if r["hung"]:
        rec["outcome"] = "hang"
    elif r["error"]:
        rec["outcome"] = "instability error" if "unstable" in r["error"] else "error: " + r["error"][7:110]
    elif rec["nan"]:
        rec["outcome"] = "NaN"
    elif m and rec["dE"] > 100 * max(abs(rec["E0"]), 1.0):
        rec["outcome"] = "blew up (finite numbers)"
    elif m and rec["t"] < tend - 1e-9:
        rec["outcome"] = "stopped early"
    else:
        rec["outcome"] = "finite"
    return rec


def study_hard():
    infile = os.path.join(INPUTS, "in.lj-hard")
    methods = [("fix nve", "nve", ""), ("pe_jump midpoint", "pe_jump", "quadrature midpoint"),
               ("pe_jump lobatto 3", "pe_jump", "quadrature lobatto 3"),
               ("pe_jump lobatto 3 adapt 1e-4 1e-5 0.005", "pe_jump", "quadrature lobatto 3 adapt 1e-4 1e-5 0.005")]
    out = dict(pair=[], liquid=[], cfl=[])
    for (v0, skin) in ([(10, 0.3), (100, 1.5)] if QUICK else
                       [(3, 0.3), (10, 0.3), (30, 0.3), (100, 0.3), (30, 1.5), (100, 1.5)]):
        for label, integ, opts in methods:
            r = lmp(infile, dict(system="pair", v0=v0, integrator=integ, pjopts=[opts or "quadrature midpoint"],
                                 h=0.005, tend=0.5, skin=skin, nmax=100000 if "adapt" in opts else 0),
                    "hard_pair", timeout=600)
            rec = dict(v0=v0, skin=skin, method=label, **lj_outcome(r, 0.5))
            out["pair"].append(rec)
            log(f"hard pair v0 {v0} skin {skin} {label}: {rec['outcome']} t {rec.get('t')} E0 {rec.get('E0')} "
                f"dE_end {rec.get('dE_end')} dHt_end {rec.get('dHt_end')} rmin {rec.get('rmin')} dE {rec.get('dE')} "
                f"dHt {rec.get('dHt')} dt [{rec.get('dtmin')}, {rec.get('dtmax')}]")
    for T0 in ([10] if QUICK else [2, 10, 50]):
        for label, integ, opts in methods:
            r = lmp(infile, dict(system="liquid", T0=T0, integrator=integ, pjopts=[opts or "quadrature midpoint"],
                                 h=0.005, tend=2.0 if QUICK else 10.0, nmax=100000 if "adapt" in opts else 0),
                    "hard_liquid", timeout=900)
            rec = dict(T0=T0, method=label, **lj_outcome(r, 2.0 if QUICK else 10.0))
            out["liquid"].append(rec)
            log(f"hard liquid T0 {T0} {label}: {rec['outcome']} t {rec.get('t')} E0 {rec.get('E0')} "
                f"dE_end {rec.get('dE_end')} dHt_end {rec.get('dHt_end')} dE {rec.get('dE')} dHt {rec.get('dHt')} "
                f"dt [{rec.get('dtmin')}, {rec.get('dtmax')}] wall {rec['wall']:.1f}")
    # (b) just above the stability limit, sync and async
    sysd = chain_system([50.0] * 51, 11)
    hc = 2 / math.sqrt(np.linalg.eigvalsh(sysd["H"]).max())
    data = os.path.join(WORK, "hard_chain.data")
    write_network(data, sysd["pos"], sysd["mobile"], sysd["bonds"], sysd["kcoef"], sysd["vel"])
    for f in (1.05, 1.01, 0.99):
        for opts in ("quadrature midpoint", "quadrature lobatto 3", "quadrature legendre 2"):
            res = network_run(data, "pe_jump", opts, f * hc, 20000, 100, "hard_cfl")
            out["cfl"].append(dict(system="chain N=50 k=100", fix="pe_jump " + opts.split(" ", 1)[1],
                                   h_over_hc=f, **res))
            log(f"hard cfl sync {opts} h/hc {f}: {res['outcome']} at step {res['last_step']} nan {res['nan']} "
                f"wall {res['wall']:.2f} s: {res['error']}")
    # async: stiff segment (fast group) + soft segment, harmonic; chain of 40
    # bonds 0..19 stiff (atoms 1..20 fast, the last one mixed), 20..40 soft:
    # every slow atom has soft springs only
    kb = [2500.0] * 20 + [1.0] * 21
    sysd = chain_system(kb, 12)
    fast = np.zeros(len(sysd["pos"]), bool)
    fast[1:21] = True
    data = os.path.join(WORK, "hard_async.data")
    write_network(data, sysd["pos"], sysd["mobile"], sysd["bonds"], sysd["kcoef"], sysd["vel"], fast=fast)
    Hx = sysd["H"]
    lam_all = np.linalg.eigvalsh(Hx[:20, :20]).max()   # block of the fine-clock atoms
    slow_idx = np.arange(20, 40)      # mobile indices of the slow atoms (atoms 21..40)
    lam_slow = np.linalg.eigvalsh(Hx[np.ix_(slow_idx, slow_idx)]).max()
    hcF, hcS = 2 / math.sqrt(lam_all), 2 / math.sqrt(lam_slow)
    out["async_limits"] = dict(h_c_full=hcF, h_c_slow_block=hcS)
    cases = [("fine step 1.05 x limit, K=4", 4, 1.05 * hcF), ("fine step 1.01 x limit, K=4", 4, 1.01 * hcF),
             ("fine step 0.95 x limit, K=4", 4, 0.95 * hcF),
             ("coarse step 1.05 x slow limit, K=100", 100, 1.05 * hcS / 100),
             ("coarse step 1.5 x slow limit, K=100", 100, 1.5 * hcS / 100),
             ("coarse step 0.5 x slow limit, K=100", 100, 0.5 * hcS / 100)]
    for (name, K, hf) in cases:
        for opts in ("quadrature midpoint", "quadrature lobatto 3"):
            nst = 20000 * K if K <= 4 else 200000
            res = network_run(data, "async", opts, hf, nst, 100 * K, "hard_async", K=K)
            out["cfl"].append(dict(system="chain 20 stiff (k=5000) + 20 soft (k=2)", fix="pe_jump/async " + opts.split(" ", 1)[1],
                                   case=name, K=K, hF=hf, hS=K * hf, **res))
            log(f"hard cfl async {name} {opts}: {res['outcome']} at step {res['last_step']} nan {res['nan']} "
                f"wall {res['wall']:.2f} s: {res['error']}")
    save("hard", out)


def save(name, obj):
    # the quick run keeps its results out of the repository
    where = os.path.join(WORK, "results") if QUICK else RESULTS
    os.makedirs(where, exist_ok=True)
    suffix = "_quick" if QUICK else ""
    with open(os.path.join(where, f"{name}{suffix}.json"), "w") as f:
        json.dump(obj, f, indent=1, default=float)


STUDIES = {"cfl": study_cfl, "long": study_long, "string": study_string,
           "resonance": study_resonance, "hard": study_hard}


def main():
    global QUICK
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--studies", default="cfl,long,string,resonance,hard")
    ap.add_argument("--plot-only", action="store_true", help="redraw the plots from the saved results")
    a = ap.parse_args()
    QUICK = a.quick
    if a.plot_only:
        sfx = "_quick" if QUICK else ""
        plots = dict(cfl=plot_cfl, long=plot_long, string=plot_string, resonance=plot_resonance)
        for s in a.studies.split(","):
            f = os.path.join(os.path.join(WORK, "results") if QUICK else RESULTS, f"{s}{sfx}.json")
            if s in plots and os.path.exists(f):
                plots[s](json.load(open(f)))
        return
    if not os.path.exists(LMP):
        sys.exit(f"no LAMMPS binary at {LMP}: copy build/lmp and build/liblammps.so.0 there")
    for s in a.studies.split(","):
        t0 = time.time()
        log(f"== study {s}")
        STUDIES[s]()
        log(f"== study {s} done in {time.time() - t0:.1f} s")


if __name__ == "__main__":
    main()
