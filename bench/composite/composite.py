#!/usr/bin/python3
"""pe_jump/async against fix nve at its largest stable step (and, on the
split scene, against run_style respa) on composite lattices: a longitudinal
pulse crosses a stiff inclusion; every method must meet the same tolerance,
then wall time and force evaluations are compared.

    /usr/bin/python3 bench/composite/composite.py [--label full] [--reps 3]
        [--timestep-meaning fine|coarse] [--variants inc10,inc01] [--lmp build/lmp]
        [--quick]
        (--variants: any of inc10, inc01, inc10split, inc01split)
    /usr/bin/python3 bench/composite/composite.py --report [--label full]

Scene (in.composite_pulse: the bonded lattice of bench/cost/in.bonded_lattice,
then a dump of the unwrapped end positions): 2d triangular lattice, 200 x 200 =
40000 atoms, spacing 1, periodic; every nearest-neighbour spring a
bond_style harmonic bond E = K (r - 1)^2, soft K = 1, stiff K = 2500 where
both ends are in the inclusion (stiffness ratio 2500); no pair style,
comm_modify cutoff 2.0, fix enforce2d, neigh_modify every 1 delay 0 check
yes, skin 0.2, units lj, mass 1. A central disk of 10 % (variant inc10) or
1 % (inc01) of the atoms is the stiff inclusion (atom type 2 = group stiff,
the fine clock of pe_jump/async). Data file: benchlib.write_lattice_data
(soft_as_bonds, kT = 0, perturb = the pulse).

Split scene (variants inc10split, inc01split; in.composite_split): the same
atoms, pulse and springs with the two kinds of springs in two force styles,
so that run_style respa can put the stiff ones on its inner level: the
stiff springs (both ends in the inclusion) are bonds (bond_style harmonic,
K = 2500), the soft springs a pair_style table spline 20000 of
E = Ksoft (r - 1)^2 (soft.table, written here: 20001 points in r from 0.3
to 1.4, cutoff 1.3, so the next neighbours at sqrt(3) are outside the
cutoff and the skin) between the atoms that are not bonded
(special_bonds lj 0 1 1: bonded pairs are left out of the pair list). Data
file: benchlib.write_lattice_data without soft_as_bonds (the file of the
suite's lattice stage). The other way to split, the soft spring between all
neighbours from the pair style plus a bond of K_stiff - K_soft on the stiff
pairs (special_bonds lj 1 1 1), was not taken: there every stiff spring
would be two interactions (a pair and a bond), the counts of interactions
and so the evaluations of respa and of pe_jump/async (which counts pair
list entries and bonds) would no longer be those of the bonded lattice, and
respa's inner level would hold only a part of the stiff spring. With the
split chosen each spring is one interaction, in one style: the B bonds are
the stiff springs, the P pair list entries the soft springs (checked), and
the set of interactions that touch a stiff atom (the fine ones of
pe_jump/async) is the same as on the bonded lattice.
The cost of a table: its force is interpolated. The file's points are
splined in r, which reproduces E (quadratic) and F (linear) exactly; the
table of the run is splined in r^2 and its interpolation error is below
round-off at 20000 points. Checked before the runs of each split variant
(check_split, stopping the script if it fails): fix nve on the bonded and
on the split lattice with the same atoms gives the same forces at t = 0
(the pulse scene, and a lattice with every atom displaced at random by up
to 0.02 so that every spring, stiff ones too, is stretched), and a fix nve
run at h = 0.01 to t = T (the pulse crosses the inclusion) ends at the same
positions with the same total energy at every thermo row, to 1e-9 relative
(measured on the --quick lattice: round-off, forces to 2e-14 of the
largest force, positions to 2e-13, energies to 1e-13 relative); the pair
list holds exactly the soft springs (LAMMPS' Total # of neighbors).

Pulse: a plane longitudinal Gaussian displacement pulse travelling in +x,
    u_x(x) = A exp(-((x - x0)/w)^2),   v_x = -c du_x/dx,   u_y = v_y = 0,
A = 0.05, w = 4, x0 = 52, everything else at rest (T = 0). c is the
long-wave longitudinal sound speed of the soft triangular lattice with
central springs of constant k = 2 K_soft (E = K (r-1)^2) and mass m:
c = sqrt(9 k / (8 m)) = 1.5. The 10 % inclusion (radius 33.2 about
x = 100) spans x = 66.8 .. 133.2: the pulse starts left of it (its value at
the inclusion's left edge is 1e-6 A) and its centre reaches x = 142 at
t = 60, past the right edge (the pulse is 0.008 A there); the 1 %
inclusion (radius 10.5) is crossed at t ~ 30. Inside the inclusion the
wave travels 50 times faster (c = 75); parts are reflected and scattered.

Methods (one MPI rank, one binary copied to bench/work/composite/bin/):
  reference  fix nve at h = 0.0005 (positions at t = 60); its own error is
             estimated from fix nve at h = 0.001 (Richardson, second order:
             |r_0.001 - r_0.0005| / 3)
  nve        fix nve at h = 0.005, 0.0075, 0.01, 60/5500, 60/5200, 60/5100,
             0.012, 0.0125 (steps that divide t = 60)
  async      fix pe_jump/async K stiff with quadrature midpoint, lobatto 2
             and lobatto 3, fine step h_F = 0.01, 0.005 and 60/5250 =
             0.0114286 (the largest below fix nve's largest stable step
             that gives whole coarse steps for most K), K = 5, 10, 15,
             20, 50 where T/(K h_F) is whole (not 60/5250 with K = 20)
             (coarse step h_S = K h_F; K = 15 is not in the issue's
             list: the position error grows as h_S^2 and passes up to h_S ~
             0.18). lobatto 2 is velocity Verlet on each clock (its primary
             node is the end of the step; like midpoint it still evaluates
             every interaction once more at the end of a step that prints
             thermo output: the same evaluation counts)
  respa      (split scene only) run_style respa 2 n bond 1 pair 2 with
             fix nve: inner step h_in = the async fine steps (0.01, 0.005,
             60/5250, all at or below fix nve's largest stable step,
             0.0115), n = 2, 5, 10, 15, 20, 50 inner steps per outer step
             where T/(n h_in) is whole (not 60/5250 with n = 20); the
             timestep is the outer step n h_in
On the split scene the reference, fix nve and pe_jump/async (the same
settings as above) run on the split lattice too.
A run that stops with a LAMMPS error (missing bond atoms, lost atoms, the
stability guard of pe_jump/async) is unstable, and fails.

Timestep meaning (--timestep-meaning): builds before the coarse-step
rewrite took the `timestep` of pe_jump/async as the FINE step h_F, and run
lengths and thermo intervals counted fine steps (multiples of K): `fine`
runs timestep h_F, T/h_F steps. The current build takes `timestep` as the
COARSE step h_S = K h_F and a run counts coarse steps: `coarse` (default)
runs timestep h_S, T/h_S steps, thermo every (interval/K) steps. The physical
times (t = 60, thermo every 0.5 or the nearest divisor of the run below
it, in whole coarse steps) are the same with both. fix nve is not affected.
Before the runs a probe (async K = 2, one LAMMPS step, on a small lattice)
reads vector element 6 of the fix (1 = the step ended at a coarse node):
0 means the binary takes timestep as the fine step, 1 as the coarse step;
the script stops if that is not the meaning asked for.

Tolerance, the same for every method:
  * max over all atoms of |r - r_ref| at t = 60 <= 2 % of A = 0.001
    (by atom id, unwrapped positions xu yu, minimum image on the difference)
  * energy drift |<etotal>_last tenth - <etotal>_first tenth| / |etotal(0)|
    <= 1e-4 (thermo rows at t <= T/10 and t >= 9T/10; etotal = c_epot +
    c_ekin, at coarse nodes for pe_jump/async)
Cost: LAMMPS' Loop time (median over --reps repetitions, interleaved: all
methods once, then again; unstable ones once), force evaluations in units
of one evaluation of every interaction (fix nve: 1 per step;
pe_jump/async: thermo f_int[5] at the last step; respa: per outer step
n f_B + f_P, since its inner levels evaluate the bonds only, with
f_B = B / (B + P) and f_P = P / (B + P) from the B bonds (stiff springs)
and P soft springs of the data file; P is the size of the pair list,
checked; as for fix nve the setup's evaluation is not counted). The machine
is shared: before each run the script waits (--max-wait, 120 s) until the
other processes use at most --max-others (1.3) cores, and records that load.
Summary per variant: fix nve at its largest step that passes ("nve best"),
the passing async setting with the smallest wall time ("async best"),
speed-up = wall nve best / wall async best, evaluation ratio = evals nve best
/ evals async best (the speed-up the evaluations alone would allow), and
wall/eval = evaluation ratio / speed-up (1: every evaluation saved is wall
time saved). Split variants add the fastest passing respa setting ("respa
best"), the same ratios of async best against respa best, and respa best
against nve best; respa settings that fail are listed as such. The ratios
of a split variant are against fix nve and respa on the split lattice
(whose pair table costs more per spring than a bond: fix nve is about 1.3
times slower there than on the bonded lattice).

Run time: inc10 and inc01 (the default) take about 40 minutes on 2 cores;
the split variants were not added to the default: estimated from single
full-size runs (fix nve h = 0.01 7.6 s, respa h_in = 0.01 n = 2 7.6 s,
the reference 20 times the former), each takes about 25-30 minutes more.

Results: bench/results/composite/<label>.json and <label>.md; logs and
scratch in bench/work/composite/<label>/. --quick: 60 x 60 lattice, t = 12,
fewer settings (respa n = 2, 5, 10; a test of the script; do not keep its
results).
"""

import argparse
import hashlib
import math
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
import benchlib as B  # noqa: E402

RESULTS = os.path.join(B.BENCH, "results", "composite")
WORK = os.path.join(B.BENCH, "work", "composite")
INPUT = os.path.join(HERE, "in.composite_pulse")
INPUT_SPLIT = os.path.join(HERE, "in.composite_split")

FULL = dict(nx=200, ny=200, T=60.0, thermo_dt=0.5, Ksoft=1.0, ratio=2500.0,
            amp=0.05, width=4.0, x0=52.0, h_ref=0.0005, h_check=0.001,
            nve_h=[0.005, 0.0075, 0.01, 60 / 5500, 60 / 5200, 60 / 5100, 0.012, 0.0125],
            fine_h=[0.01, 0.005, 60 / 5250], Ks=[5, 10, 15, 20, 50],
            quads=["midpoint", "lobatto 2", "lobatto 3"],
            respa_n=[2, 5, 10, 15, 20, 50],
            table=dict(rlo=0.3, rhi=1.4, npoints=20001, tabn=20000, rc=1.3),
            check_h=0.01, check_disp=0.02)
QUICK = dict(FULL, nx=60, ny=60, T=12.0, width=2.0, x0=8.0,
             nve_h=[0.005, 0.01, 60 / 5200, 0.0125], fine_h=[0.01], Ks=[5, 10], respa_n=[2, 5, 10])
# variant: inclusion fraction and scene (bonds: every spring a bond,
# in.composite_pulse; split: stiff springs bonds, soft springs a pair table,
# in.composite_split, with run_style respa among the methods)
VARIANTS = {"inc10": dict(frac=0.10, scene="bonds"), "inc01": dict(frac=0.01, scene="bonds"),
            "inc10split": dict(frac=0.10, scene="split"), "inc01split": dict(frac=0.01, scene="split")}
SPLIT_CHECK_TOL = 1e-9  # split scene against the bonded one: max force / position difference,
                        # relative to the largest force / to the pulse amplitude
POS_TOL_REL = 0.02      # max position error / pulse amplitude
DRIFT_TOL = 1e-4        # energy drift / |initial energy|
ISSUE_NVE_H = 0.01      # fix nve's largest stable step according to the issue


def log(msg):
    print(time.strftime("%H:%M:%S"), msg, flush=True)


def fmt(x, nd=3, sci=False):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    return f"{x:.{nd}e}" if sci else f"{x:.{nd}f}"


# ------------------------------------------------------------------ scene

def sound_speed(Ksoft, mass=1.0):
    """Long-wave longitudinal sound speed of the triangular lattice with
    nearest-neighbour springs E = Ksoft (r - 1)^2 (spring constant 2 Ksoft)."""
    return math.sqrt(9.0 * 2.0 * Ksoft / (8.0 * mass))


def pulse(amp, width, x0, c):
    """perturb function of benchlib.write_lattice_data: the right-going
    Gaussian displacement pulse u_x = A exp(-((x-x0)/w)^2), v_x = -c du_x/dx
    (exactly zero beyond 20 w: LAMMPS refuses denormal numbers)."""
    def perturb(x, y):
        s = (x - x0) / width
        u = np.where(np.abs(s) < 20.0, amp * np.exp(-s * s), 0.0)
        zero = np.zeros_like(x)
        return u, zero, 2.0 * c * s / width * u, zero
    return perturb


def write_scene(wd, frac, c, scene="bonds", perturb=None, prefix=""):
    """Data file of one variant in wd (bonds: lattice.data, every spring a
    bond; split: split.data, the stiff springs as bonds, and soft.table, the
    soft spring for the pair style); returns benchlib's lattice info, with
    stiff_bonds and soft (springs) and, for split, bond_fraction and
    pair_fraction: the shares of the bonds and of the pairs in all
    interactions. perturb: another perturbation than the pulse (the check)."""
    os.makedirs(wd, exist_ok=True)
    cs = sound_speed(c["Ksoft"])
    perturb = perturb or pulse(c["amp"], c["width"], c["x0"], cs)
    split = scene == "split"
    info = B.write_lattice_data(os.path.join(wd, prefix + ("split.data" if split else "lattice.data")),
                                c["nx"], c["ny"], frac=frac, kT=0.0, soft_as_bonds=not split,
                                perturb=perturb)
    info["stiff_bonds"] = info["bonds"] - (0 if split else info["soft"])
    info["sound_speed"] = cs
    info["scene"] = scene
    if split:
        t, K = c["table"], c["Ksoft"]
        B.write_table(os.path.join(wd, "soft.table"), "SOFT", lambda r: K * (r - 1.0) ** 2,
                      lambda r: -2.0 * K * (r - 1.0), t["rlo"], t["rhi"], n=t["npoints"])
        n = info["stiff_bonds"] + info["soft"]
        info["bond_fraction"] = info["stiff_bonds"] / n
        info["pair_fraction"] = info["soft"] / n
    return info


def random_displacements(amp, seed=4321):
    """perturb function of the check: every atom displaced by a uniform
    random vector in [-amp, amp]^2, at rest (every spring stretched)."""
    def perturb(x, y):
        rng = np.random.default_rng(seed)
        u = rng.uniform(-amp, amp, size=(x.size, 2))
        zero = np.zeros_like(x)
        return u[:, 0], u[:, 1], zero, zero
    return perturb


# ------------------------------------------------------------------ methods

def methods(c, info):
    """The runs of one variant, each a dict: name, integrator, quad, h_F, K
    (respa: h_F the inner step, K the inner steps per outer step, cost the
    force evaluations per outer step)."""
    out = [dict(name=f"nve h={h:.6g}", integrator="nve", quad=None, h_F=h, K=1) for h in c["nve_h"]]
    if info["scene"] == "split":
        for hf in c["fine_h"]:
            for n in c["respa_n"]:
                n_outer = c["T"] / (n * hf)
                if abs(n_outer - round(n_outer)) > 1e-9 * n_outer:
                    continue
                out.append(dict(name=f"respa hin={hf:g} n={n}", integrator="respa", quad=None, h_F=hf, K=n,
                                cost=n * info["bond_fraction"] + info["pair_fraction"]))
    for quad in c["quads"]:
        for hf in c["fine_h"]:
            for K in c["Ks"]:
                n_coarse = c["T"] / (K * hf)
                if abs(n_coarse - round(n_coarse)) > 1e-9 * n_coarse:
                    continue    # (the run would not end at T)
                out.append(dict(name=f"async {quad} hF={hf:g} K={K}", integrator="async",
                                quad=quad, h_F=hf, K=K))
    return out


def thermo_every(n, step, dt):
    """Largest divisor d of n with d * step <= dt (at least 1)."""
    best = 1
    for d in range(1, n + 1):
        if d * step > dt * (1 + 1e-9):
            break
        if n % d == 0:
            best = d
    return best


def run_plan(m, T, thermo_dt, meaning):
    """timestep, run length and thermo interval of method m for the final
    time T under the timestep meaning 'fine' or 'coarse' (fix nve: K = 1;
    its step is made T / round(T / h) so that the run ends exactly at T)."""
    K = m["K"]
    n_coarse = int(round(T / (K * m["h_F"])))
    h_S = T / n_coarse
    if abs(n_coarse * K * m["h_F"] - T) > 1e-9 * T:
        if m["integrator"] != "nve":
            raise ValueError(f"{m['name']}: T = {T} is not a multiple of the coarse step")
    h_F = h_S / K
    d = thermo_every(n_coarse, h_S, thermo_dt)
    if m["integrator"] == "respa" or (meaning == "coarse" and m["integrator"] == "async"):
        # (respa: the timestep is always the outer step)
        timestep, nsteps, nthermo = h_S, n_coarse, d
    else:
        timestep, nsteps, nthermo = h_F, n_coarse * K, d * K
    return dict(h_F=h_F, h_S=h_S, K=K, timestep=timestep, nsteps=nsteps, nthermo=nthermo,
                thermo_dt=d * h_S)


# ------------------------------------------------------------------ running

QUIET = dict(limit=1.3, maxwait=120.0)    # set by measure() from --max-others, --max-wait


def wait_quiet():
    """Wait (up to QUIET maxwait seconds) until the other processes use at
    most QUIET limit cores (benchlib.busy_others over 1 s, none of our runs
    active); returns that load and the seconds waited."""
    t0 = time.time()
    while True:
        busy = B.busy_others(1.0)
        if busy <= QUIET["limit"] or time.time() - t0 >= QUIET["maxwait"]:
            return busy, time.time() - t0
        time.sleep(5)


def run_one(wd, c, m, plan, tag, ratio, scene="bonds", prefix="", forces=False):
    """Run one method on the scene (bonds or split; data file prefix +
    lattice.data or split.data); returns its record (status ok / unstable,
    timing, evaluations, energy series, end-position dump; forces: also the
    end forces, dump + '.forces')."""
    dump = f"final.{tag}.dump"
    split = scene == "split"
    v = dict(data=prefix + ("split.data" if split else "lattice.data"), Ksoft=c["Ksoft"], ratio=ratio,
             integrator=m["integrator"], K=m["K"], dt=f"{plan['timestep']:.17g}",
             nsteps=plan["nsteps"], nthermo=plan["nthermo"], dump=dump, forces=int(forces))
    if split:
        v.update(table="soft.table", tabkey="SOFT", tabn=c["table"]["tabn"], rc=c["table"]["rc"])
    if m["quad"]:
        v["quad"] = m["quad"]
    busy, waited = wait_quiet()
    load = os.getloadavg()[0]
    # no retries: the binary is a snapshot, and a failed run is a result
    r = B.run_lammps(INPUT_SPLIT if split else INPUT, v, cwd=wd, log=f"log.{tag}", check=False, retries=0)
    rec = {"loadavg_start": load, "others_busy": busy, "waited": waited, "returncode": r["returncode"], "log": os.path.join(wd, f"log.{tag}"),
           "process_wall": r.get("process_wall"), "cpu_use": r.get("cpu_use")}
    err = first_error(rec["log"])
    if r["returncode"] != 0 or err or "loop_time" not in r:
        rec.update(status="unstable", error=err or f"exit status {r['returncode']}, no Loop time")
        return rec
    head, rows = r["thermo_head"], np.array(r["thermo_rows"])
    if m["integrator"] == "async":
        evals = float(rows[-1, head.index("v_evals")])
    elif m["integrator"] == "respa":     # cost per outer step: n bond fractions + the pair fraction
        evals = r["steps"] * m["cost"]
    else:
        evals = float(r["steps"])
    rec.update(status="ok", loop_time=r["loop_time"], steps=r["steps"], natoms=r["natoms"], evals=evals,
               breakdown=r.get("breakdown"), neighbors=r.get("neighbors"),
               time=(rows[:, head.index("Step")] * plan["timestep"]).tolist(),
               etotal=(rows[:, head.index("c_epot")] + rows[:, head.index("c_ekin")]).tolist(),
               pseudo=rows[:, head.index("v_Ht")].tolist(),
               t_end=r["bench"].get("t_end"), at_node=r["bench"].get("at_node"),
               dump=os.path.join(wd, dump))
    return rec


def first_error(path):
    """The first ERROR line of a LAMMPS log (benchlib.parse_log does not
    look for them inside a thermo table, where a run that blows up stops)."""
    try:
        with open(path, errors="replace") as f:
            return next((ln.strip() for ln in f if ln.startswith("ERROR")), None)
    except OSError:
        return None


# ------------------------------------------------------------------ measures

def end_positions(path):
    """Unwrapped end positions (xu, yu) sorted by atom id."""
    d = B.read_dump(path)
    order = np.argsort(d["id"])
    return d["id"][order], np.column_stack((d["xu"][order], d["yu"][order]))


def max_distance(a, b, box):
    """Max over atoms of |r_a - r_b| of two (ids, positions) pairs (the same
    ids; minimum image on the difference)."""
    if not np.array_equal(a[0], b[0]):
        raise RuntimeError("atom ids differ")
    d = a[1] - b[1]
    d -= box * np.round(d / box)
    return float(np.max(np.hypot(d[:, 0], d[:, 1])))


def energy_drift(t, e, T):
    """(<e> over t >= 9T/10 - <e> over t <= T/10) / |e(0)|."""
    t, e = np.asarray(t), np.asarray(e)
    first, last = e[t <= 0.1 * T + 1e-9], e[t >= 0.9 * T - 1e-9]
    return float((last.mean() - first.mean()) / abs(e[0]))


def judge(rec, ref, box, c):
    """Add the error, the drift and pass/fail to an ok record; drop its dump."""
    if rec["status"] != "ok":
        rec["passed"] = False
        return rec
    rec["pos_error"] = max_distance(end_positions(rec["dump"]), ref, box)
    rec["drift"] = energy_drift(rec["time"], rec["etotal"], c["T"])
    rec["passed"] = bool(rec["pos_error"] <= POS_TOL_REL * c["amp"] and abs(rec["drift"]) <= DRIFT_TOL)
    os.remove(rec["dump"])
    return rec


def check_end(m, rec, c):
    """Warnings if the run did not end at T, or (async) not at a coarse node."""
    warn = []
    if rec.get("t_end") is not None and abs(rec["t_end"] - c["T"]) > 1e-6 * c["T"]:
        warn.append(f"ended at t = {rec['t_end']}, not {c['T']}")
    if rec.get("at_node") is not None and rec["at_node"] != 1:
        warn.append("the run did not end at a coarse node")
    for w in warn:
        log(f"  WARNING {m['name']}: {w}")
    return warn


def binary_meaning(c):
    """The binary's meaning of timestep for pe_jump/async: 'fine' if one
    LAMMPS step of a K = 2 run does not end at a coarse node, else 'coarse'."""
    wd = os.path.join(WORK, "probe")
    write_scene(wd, 0.10, dict(c, nx=20, ny=20, x0=5.0, width=1.0))
    m = dict(name="probe", integrator="async", quad="midpoint", h_F=0.01, K=2)
    plan = dict(timestep=0.01, nsteps=1, nthermo=1)
    rec = run_one(wd, c, m, plan, "probe", c["ratio"])
    if rec["status"] != "ok" or rec.get("at_node") is None:
        raise RuntimeError(f"probe run failed: {rec.get('error')} (log {rec['log']})")
    return "coarse" if rec["at_node"] == 1 else "fine"


# ------------------------------------------------------------------ one variant

def end_forces(path):
    """End forces (fx, fy) sorted by atom id."""
    d = B.read_dump(path)
    order = np.argsort(d["id"])
    return d["id"][order], np.column_stack((d["fx"][order], d["fy"][order]))


def check_split(wd, frac, c, info, meaning):
    """The split scene against the bonded one with the same atoms (fix nve,
    the same input commands otherwise): the forces at t = 0 of the pulse
    scene (only soft springs stretched: the pulse is outside the inclusion)
    and of a lattice with every atom displaced at random by up to
    check_disp in x and y (every spring stretched, stiff ones too), and a
    fix nve run at check_h over the whole time T (the pulse crosses the
    inclusion): end positions, end forces, total energy at every thermo row.
    Also the size of the pair list (LAMMPS' Total # of neighbors, at the
    start and at T) against the number of soft springs. Stops the script if
    the scenes differ by more than SPLIT_CHECK_TOL (forces at t = 0 relative
    to the largest force, positions relative to the pulse amplitude, total
    energies relative to |etotal(0)|) or the pair list is not the soft
    springs. The end forces of the run are reported, not judged: there the
    stiff springs turn the round-off difference of the positions into force
    differences 2 ratio Ksoft = 5000 times larger."""
    ratio = c["ratio"]
    write_scene(wd, frac, c, "bonds")
    disp = random_displacements(c["check_disp"])
    for scene in ("bonds", "split"):
        write_scene(wd, frac, c, scene, perturb=disp, prefix="rand_")
    box = np.array([info["Lx"], info["Ly"]])
    m = dict(name="check", integrator="nve", quad=None, h_F=c["check_h"], K=1)
    out = {}
    for label, prefix, plan in (("pulse_t0", "", dict(timestep=c["check_h"], nsteps=0, nthermo=1)),
                                ("random_t0", "rand_", dict(timestep=c["check_h"], nsteps=0, nthermo=1)),
                                ("pulse_run", "", run_plan(m, c["T"], c["thermo_dt"], meaning))):
        recs = {}
        for scene in ("bonds", "split"):
            rec = run_one(wd, c, m, plan, f"check_{label}_{scene}", ratio, scene, prefix, forces=True)
            if rec["status"] != "ok":
                raise RuntimeError(f"check run {label} {scene} failed: {rec.get('error')} (log {rec['log']})")
            rec["forces"] = end_forces(rec["dump"] + ".forces")
            rec["positions"] = end_positions(rec["dump"])
            os.remove(rec["dump"] + ".forces")
            os.remove(rec["dump"])
            recs[scene] = rec
        fb, fs = recs["bonds"]["forces"], recs["split"]["forces"]
        if not np.array_equal(fb[0], fs[0]):
            raise RuntimeError("atom ids differ")
        eb, es = np.array(recs["bonds"]["etotal"]), np.array(recs["split"]["etotal"])
        out[label] = dict(t=plan["nsteps"] * plan["timestep"], h=plan["timestep"],
                          force_max=float(np.max(np.hypot(fb[1][:, 0], fb[1][:, 1]))),
                          force_diff=float(np.max(np.hypot(*(fb[1] - fs[1]).T))),
                          position_diff=max_distance(recs["bonds"]["positions"], recs["split"]["positions"], box),
                          etotal0=float(eb[0]), etotal_diff=float(np.max(np.abs(eb - es))),
                          pair_list=recs["split"]["neighbors"],
                          loop_time={k: r["loop_time"] for k, r in recs.items()})
        o = out[label]
        log(f"  check {label}: t = {o['t']:g}, max |F| {o['force_max']:.3e}, max |dF| {o['force_diff']:.2e}, "
            f"max |dr| {o['position_diff']:.2e}, max |dE| {o['etotal_diff']:.2e} (E0 {o['etotal0']:.4g}), "
            f"pair list {o['pair_list']} (soft springs {info['soft']})")
        # (forces only at t = 0: at T the stiff springs turn the positions'
        # round-off difference into force differences 2 ratio Ksoft larger)
        bad = [o["t"] == 0 and o["force_diff"] > SPLIT_CHECK_TOL * o["force_max"],
               o["position_diff"] > SPLIT_CHECK_TOL * c["amp"],
               o["etotal_diff"] > SPLIT_CHECK_TOL * abs(o["etotal0"]),
               o["pair_list"] != info["soft"]]
        if any(bad):
            raise RuntimeError(f"the split scene is not the bonded scene ({label}): {o}")
    return out


def reference(wd, c, ratio, meaning, scene="bonds"):
    """fix nve at h_ref (the reference positions) and at h_check (its
    error estimate); returns (positions, description)."""
    out = {}
    pos = {}
    for key in ("h_ref", "h_check"):
        m = dict(name=f"reference nve h={c[key]:g}", integrator="nve", quad=None, h_F=c[key], K=1)
        plan = run_plan(m, c["T"], c["thermo_dt"], meaning)
        rec = run_one(wd, c, m, plan, f"ref_{key}", ratio, scene)
        if rec["status"] != "ok":
            raise RuntimeError(f"reference run failed: {rec.get('error')}")
        pos[key] = end_positions(rec["dump"])
        out[key] = dict(h=plan["h_F"], loop_time=rec["loop_time"], drift=energy_drift(rec["time"], rec["etotal"], c["T"]),
                        etotal0=rec["etotal"][0])
        log(f"  {m['name']}: loop {rec['loop_time']:.2f} s, drift {out[key]['drift']:.2e}")
    return pos, out


def run_variant(name, var, c, args):
    wd = os.path.join(WORK, args.label, name)
    frac, scene = var["frac"], var["scene"]
    info = write_scene(wd, frac, c, scene)
    box = np.array([info["Lx"], info["Ly"]])
    ratio = c["ratio"]
    log(f"variant {name}: {info['atoms']} atoms, inclusion {info['inclusion']}, c = {info['sound_speed']:.4g}, "
        f"scene {scene}" + (f" ({info['stiff_bonds']} bonds, {info['soft']} pairs: fractions "
                            f"{info['bond_fraction']:.5f}, {info['pair_fraction']:.5f})" if scene == "split" else ""))
    check = check_split(wd, frac, c, info, args.timestep_meaning) if scene == "split" else None
    pos, ref = reference(wd, c, ratio, args.timestep_meaning, scene)
    ref_pos = pos["h_ref"]
    ref["error_estimate"] = max_distance(pos["h_check"], ref_pos, box) / 3.0
    log(f"  reference error estimate {ref['error_estimate']:.2e}")
    ms = methods(c, info)
    runs = {m["name"]: dict(spec=m, plan=run_plan(m, c["T"], c["thermo_dt"], args.timestep_meaning), reps=[])
            for m in ms}
    for rep in range(args.reps):
        for m in ms:
            run = runs[m["name"]]
            if rep > 0 and run["reps"][0]["status"] != "ok":
                continue
            rec = judge(run_one(wd, c, m, run["plan"], f"{slug(m['name'])}.{rep}", ratio, scene),
                        ref_pos, box, c)
            rec["warnings"] = check_end(m, rec, c) if rec["status"] == "ok" else []
            run["reps"].append(rec)
            log(f"  rep {rep} {m['name']:32s} " + (
                f"loop {rec['loop_time']:7.2f} s  evals {rec['evals']:9.1f}  err {rec['pos_error']:.2e}  "
                f"drift {rec['drift']:+.1e}  {'pass' if rec['passed'] else 'FAIL'}  others {rec['others_busy']:.2f}"
                if rec["status"] == "ok" else f"UNSTABLE: {rec['error']}"))
    for run in runs.values():
        run["median"] = summarize(run["reps"])
    return dict(fraction=frac, scene=scene, info=info, split_check=check, reference=ref, runs=runs,
                summary=compare(runs))


def slug(s):
    return s.replace(" ", "_").replace("=", "").replace("/", "_")


def without_series(obj):
    """obj without the thermo series (time, etotal, pseudo) of its runs: the
    drifts and errors judged from them stay, the report reads only those
    (keeps the stored results small)."""
    if isinstance(obj, dict):
        return {k: without_series(v) for k, v in obj.items()
                if not (k in ("time", "etotal", "pseudo") and isinstance(v, list))}
    if isinstance(obj, list):
        return [without_series(v) for v in obj]
    return obj


def summarize(reps):
    """Median wall time; errors and drifts (deterministic: the largest over
    the repetitions, and their spread); pass only if every repetition passed."""
    ok = [r for r in reps if r["status"] == "ok"]
    if not ok:
        return dict(status="unstable", passed=False, error=reps[0].get("error"))
    errs = [r["pos_error"] for r in ok]
    drifts = [r["drift"] for r in ok]
    return dict(status="ok", loop_time=B.median([r["loop_time"] for r in ok]),
                loop_times=[r["loop_time"] for r in ok], evals=ok[0]["evals"],
                pos_error=max(errs), pos_error_spread=max(errs) - min(errs),
                drift=max(drifts, key=abs), passed=all(r["passed"] for r in ok),
                cpu_use=B.median([r["cpu_use"] for r in ok if r.get("cpu_use") is not None] or [float("nan")]))


def ratios(nve, asy):
    """speed-up (wall), evaluation ratio and wall/eval of run asy against
    run nve, from the median wall times; speed-up also as the median of the
    repetitions' ratios (rep k of the one against rep k of the other, run
    close in time) and from the smallest wall times (the least disturbed
    runs on a shared machine)."""
    wn, wa = nve["median"]["loop_time"], asy["median"]["loop_time"]
    en, ea = nve["median"]["evals"], asy["median"]["evals"]
    pairs = [rn["loop_time"] / ra["loop_time"] for rn, ra in zip(nve["reps"], asy["reps"])]
    fastest = min(nve["median"]["loop_times"]) / min(asy["median"]["loop_times"])
    return dict(speedup=wn / wa, eval_ratio=en / ea, wall_per_eval=(en / ea) / (wn / wa),
                speedup_paired=B.median(pairs), speedup_min=fastest, wall_per_eval_min=(en / ea) / fastest)


def compare(runs):
    """nve's largest stable and largest passing step, the fastest passing
    async setting, and the ratios between the two; the same ratios against
    fix nve at h = 0.01 (the issue's largest stable step); on the split
    scene also the fastest passing respa setting, async against it
    (vs_respa) and it against nve's best (respa_vs_nve)."""
    def kind(k):
        return [r for r in runs.values() if r["spec"]["integrator"] == k]
    nve = kind("nve")
    stable = [r for r in nve if r["median"]["status"] == "ok"]
    passing = [r for r in stable if r["median"]["passed"]]
    asy = [r for r in kind("async") if r["median"]["passed"]]
    respa = kind("respa")
    res = [r for r in respa if r["median"]["passed"]]
    s = {"nve_largest_stable_h": max((r["plan"]["h_F"] for r in stable), default=None),
         "nve_smallest_unstable_h": min((r["plan"]["h_F"] for r in nve if r["median"]["status"] != "ok"),
                                        default=None)}
    if respa:
        s["respa_passing"] = len(res)
        s["respa_stable"] = sum(r["median"]["status"] == "ok" for r in respa)
        s["respa_runs"] = len(respa)
        s["respa_max_inner_h"] = max(r["plan"]["h_F"] for r in respa)
    nb = max(passing, key=lambda r: r["plan"]["h_F"]) if passing else None
    ab = min(asy, key=lambda r: r["median"]["loop_time"]) if asy else None
    rb = min(res, key=lambda r: r["median"]["loop_time"]) if res else None
    if rb:
        s["respa_best"] = rb["spec"]["name"]
        if nb:
            s["respa_vs_nve"] = dict(nve=nb["spec"]["name"], **ratios(nb, rb))
    if ab:
        s["async_best"] = ab["spec"]["name"]
        if rb:
            s["vs_respa"] = dict(respa=rb["spec"]["name"], **ratios(rb, ab))
    if not nb or not ab:
        return s
    s.update(nve_best=nb["spec"]["name"], nve_best_h=nb["plan"]["h_F"])
    s.update(ratios(nb, ab))
    n01 = [r for r in passing if abs(r["plan"]["h_F"] - ISSUE_NVE_H) < 1e-12]
    if n01:
        s["vs_issue_nve"] = dict(nve=n01[0]["spec"]["name"], **ratios(n01[0], ab))
    return s


# ------------------------------------------------------------------ output

def markdown(res):
    c = res["settings"]
    L = [f"# pe_jump/async against fix nve on composite lattices: {res['label']}\n",
         f"`bench/composite/composite.py`, {res['time']}, git {res['git_head'].split()[0]}"
         f"{' (src dirty)' if res['git_src_dirty'] else ''}, liblammps.so.0 sha256 "
         f"{res['binary']['liblammps'].get('sha256')} (build {res['binary']['snapshot'].get('mtime')}), "
         f"timestep meaning `{res['timestep_meaning']}`, "
         f"{res['reps']} repetitions, one MPI rank, {res['duration_s']:.0f} s; {others_load(res)}.\n",
         f"Lattice {c['nx']} x {c['ny']}, stiffness ratio {c['ratio']:g}, pulse A = {c['amp']}, w = {c['width']}, "
         f"x0 = {c['x0']}, t = {c['T']:g}. Pass: max position error <= {POS_TOL_REL * c['amp']:g} and "
         f"|energy drift| <= {DRIFT_TOL:g}. Wall = median Loop time [s] over the repetitions.\n"]
    for vname, v in res["variants"].items():
        ref, s = v["reference"], v["summary"]
        L.append(f"## {vname}: inclusion {v['info']['inclusion']} of {v['info']['atoms']} atoms\n")
        if v.get("scene") == "split":
            L += split_lines(v, c)
        L.append(f"Reference: fix nve h = {ref['h_ref']['h']:g} (loop {ref['h_ref']['loop_time']:.1f} s), "
                 f"its error estimated {ref['error_estimate']:.1e} (against h = {ref['h_check']['h']:g}). "
                 f"fix nve: largest stable step {fmt(s.get('nve_largest_stable_h'), 6)}, smallest unstable "
                 f"{fmt(s.get('nve_smallest_unstable_h'), 6)}.\n")
        L.append("| method | h_F | K | h_S | wall [s] | min wall [s] | evals | max pos. error | drift | pass | "
                 "speed-up vs nve best |")
        L.append("|---|---|---|---|---|---|---|---|---|---|---|")
        wn = None
        if s.get("nve_best"):
            wn = v["runs"][s["nve_best"]]["median"]["loop_time"]
        for name, r in v["runs"].items():
            p, m = r["plan"], r["median"]
            if m["status"] != "ok":
                L.append(f"| {name} | {p['h_F']:.6g} | {p['K']} | {p['h_S']:.6g} | unstable | | | | | fail | |")
                continue
            L.append(f"| {name} | {p['h_F']:.6g} | {p['K']} | {p['h_S']:.6g} | {m['loop_time']:.2f} | "
                     f"{min(m['loop_times']):.2f} | "
                     f"{m['evals']:.0f} | {m['pos_error']:.2e} | {m['drift']:+.1e} | "
                     f"{'pass' if m['passed'] else '**fail**'} | "
                     f"{fmt(wn / m['loop_time'], 2) if wn else 'n/a'} |")
        L.append("")
        rows = []
        if s.get("async_best") and s.get("nve_best"):
            rows.append((s["nve_best"] + " (nve best)", s))
            if s.get("vs_issue_nve"):
                rows.append((s["vs_issue_nve"]["nve"] + " (the issue's nve step)", s["vs_issue_nve"]))
        if s.get("vs_respa"):
            rows.append((s["vs_respa"]["respa"] + " (respa best)", s["vs_respa"]))
        if "respa_runs" in s:
            L.append(f"nve best: {s.get('nve_best', 'none passed')}; fastest passing async: "
                     f"{s.get('async_best', 'none passed')}; fastest passing respa: "
                     f"{s.get('respa_best', 'none passed')} ({s['respa_passing']} of {s['respa_runs']} respa "
                     f"settings pass, {s['respa_stable']} are stable; respa inner steps up to "
                     f"{s['respa_max_inner_h']:.6g}, fix nve's largest stable step "
                     f"{fmt(s.get('nve_largest_stable_h'), 6)}).\n")
        elif rows:
            L.append(f"nve best: {s['nve_best']}; fastest passing async: {s['async_best']}.\n")
        if rows:
            if "respa_runs" in s:
                L.append("Speed-up of the fastest passing async setting against:\n")
            L.append("| against | speed-up (medians) | paired | from the fastest runs | evaluation ratio | "
                     "wall/eval (medians) | wall/eval (fastest runs) |")
            L.append("|---|---|---|---|---|---|---|")
            for who, t in rows:
                L.append(f"| {who} | {t['speedup']:.2f} | {t['speedup_paired']:.2f} | {t['speedup_min']:.2f} | "
                         f"{t['eval_ratio']:.2f} | {t['wall_per_eval']:.2f} | {t['wall_per_eval_min']:.2f} |")
            L.append("")
        else:
            L.append("No passing fix nve or async setting: no speed-up.\n")
        if s.get("respa_vs_nve"):
            t = s["respa_vs_nve"]
            L.append(f"{s['respa_best']} (respa best) against {t['nve']} (nve best): speed-up {t['speedup']:.2f} "
                     f"(paired {t['speedup_paired']:.2f}, fastest runs {t['speedup_min']:.2f}), evaluation ratio "
                     f"{t['eval_ratio']:.2f}, wall/eval {t['wall_per_eval']:.2f}.\n")
    return "\n".join(L)


def split_lines(v, c):
    """Markdown: the split scene, its interaction counts and its check."""
    info, chk = v["info"], v.get("split_check") or {}
    L = [f"Split scene (`in.composite_split`): the {info['stiff_bonds']} stiff springs are bonds, the "
         f"{info['soft']} soft springs a pair_style table (spline, {c['table']['tabn']} points, cutoff "
         f"{c['table']['rc']:g}) between the atoms that are not bonded; the same atoms, pulse and forces as "
         f"the bonded lattice. respa: `run_style respa 2 n bond 1 pair 2`, h_F = inner step, K = n, h_S = "
         f"outer step; its evaluations per outer step are n * {info['bond_fraction']:.5f} + "
         f"{info['pair_fraction']:.5f} (the bonds' and the pairs' shares of the "
         f"{info['stiff_bonds'] + info['soft']} interactions).\n"]
    if chk:
        L.append("Check against the bonded lattice (fix nve, the same atoms):\n")
        L.append("| case | t | max abs(F) | max abs(F split - F bonds) | max abs(r split - r bonds) | "
                 "max abs(E split - E bonds) / abs(E(0)) | pair list / soft springs |")
        L.append("|---|---|---|---|---|---|---|")
        names = {"pulse_t0": "pulse, t = 0", "random_t0": f"random displacements <= {c['check_disp']:g}, t = 0",
                 "pulse_run": f"pulse, fix nve h = {chk.get('pulse_run', {}).get('h', 0):g} to T"}
        for k, o in chk.items():
            L.append(f"| {names.get(k, k)} | {o['t']:g} | {o['force_max']:.3e} | {o['force_diff']:.1e} | "
                     f"{o['position_diff']:.1e} | {o['etotal_diff'] / abs(o['etotal0']):.1e} | "
                     f"{o['pair_list']} / {info['soft']} |")
        L.append("")
    return L


def others_load(res):
    """The other processes' CPU use before the timed runs, in words."""
    recs = [rec for v in res["variants"].values() for r in v["runs"].values() for rec in r["reps"]
            if rec["status"] == "ok"]
    busy = [rec["others_busy"] for rec in recs]
    noisy = sum(b > res["quiet"]["limit"] for b in busy)
    return (f"other processes used {min(busy):.2f}-{max(busy):.2f} cores before the timed runs "
            f"(median {B.median(busy):.2f}; {noisy} of {len(busy)} runs started above {res['quiet']['limit']:g} "
            f"after waiting {res['quiet']['maxwait']:g} s), waits {sum(rec['waited'] for rec in recs):.0f} s in all")


def binary_info(snapshot):
    info = {"snapshot": snapshot}
    for key, fn in (("lmp", "lmp"), ("liblammps", "liblammps.so.0")):
        p = os.path.join(os.path.dirname(B.LMP), fn)
        if os.path.exists(p):
            with open(p, "rb") as f:
                info[key] = {"path": p, "sha256": hashlib.sha256(f.read()).hexdigest()[:16]}
        else:
            info[key] = {"path": p, "missing": True}
    return info


def git_state():
    head = subprocess.run(["git", "-C", B.ROOT, "log", "-1", "--format=%h %s"], capture_output=True,
                          text=True).stdout.strip()
    dirty = bool(subprocess.run(["git", "-C", B.ROOT, "status", "--porcelain", "src"], capture_output=True,
                                text=True).stdout.strip())
    return head, dirty


def measure(args):
    c = dict(QUICK if args.quick else FULL)
    QUIET.update(limit=args.max_others, maxwait=10.0 if args.quick else args.max_wait)
    B.LMP = os.path.abspath(args.lmp)
    snap = B.snapshot_binary(os.path.join(WORK, "bin"), settle=5 if args.quick else 60)
    head, dirty = git_state()
    meaning = binary_meaning(c)
    log(f"label {args.label}: binary {B.LMP} (from {snap['source']}, {snap['mtime']}), "
        f"timestep meaning {args.timestep_meaning} (the binary's: {meaning}), {args.reps} repetitions")
    if meaning != args.timestep_meaning:
        sys.exit(f"the binary takes the timestep of pe_jump/async as the {meaning} step: "
                 f"run with --timestep-meaning {meaning}")
    t0 = time.time()
    variants = {v: run_variant(v, VARIANTS[v], c, args) for v in args.variants.split(",")}
    res = dict(label=args.label, time=time.strftime("%Y-%m-%d %H:%M:%S"), quick=args.quick, reps=args.reps,
               timestep_meaning=args.timestep_meaning, settings=c, binary=binary_info(snap),
               git_head=head, git_src_dirty=dirty, host={"ncpu": os.cpu_count()},
               tolerance={"pos_error": POS_TOL_REL * c["amp"], "drift": DRIFT_TOL}, quiet=dict(QUIET),
               duration_s=time.time() - t0, variants=variants)
    B.save_json(os.path.join(RESULTS, f"{args.label}.json"), without_series(res))
    text = markdown(res)
    with open(os.path.join(RESULTS, f"{args.label}.md"), "w") as f:
        f.write(text)
    log(f"wrote {RESULTS}/{args.label}.json and .md")
    print(text)


def report(args):
    """Summaries and markdown again from a stored JSON (no runs)."""
    path = os.path.join(RESULTS, f"{args.label}.json")
    res = B.load_json(path)
    for v in res["variants"].values():
        v["summary"] = compare(v["runs"])
    B.save_json(path, without_series(res))
    text = markdown(res)
    with open(os.path.join(RESULTS, f"{args.label}.md"), "w") as f:
        f.write(text)
    print(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--label", default=None, help="name of the results (default: full, or quick with --quick)")
    ap.add_argument("--lmp", default=B.LMP, help="LAMMPS binary (copied with its liblammps.so.0)")
    ap.add_argument("--reps", type=int, default=3, help="repetitions of each stable run (timing)")
    ap.add_argument("--timestep-meaning", choices=("fine", "coarse"), default="coarse",
                    help="what `timestep` of pe_jump/async sets: the coarse step (current build) or the fine step "
                         "(builds before the coarse-step rewrite)")
    ap.add_argument("--variants", default="inc10,inc01",
                    help="inclusion variants: inc10 (10 %%), inc01 (1 %%), bonded lattice; inc10split, "
                         "inc01split: the split lattice (stiff springs bonds, soft springs a pair table), "
                         "with run_style respa")
    ap.add_argument("--quick", action="store_true", help="small lattice, t = 12, few settings (test of the script)")
    ap.add_argument("--max-others", type=float, default=1.3,
                    help="before each run wait until the other processes use at most this many cores")
    ap.add_argument("--max-wait", type=float, default=120.0, help="... but at most this many seconds")
    ap.add_argument("--report", action="store_true",
                    help="no runs: summaries and markdown again from results/composite/<label>.json")
    args = ap.parse_args()
    args.label = args.label or ("quick" if args.quick else "full")
    if args.report:
        report(args)
    else:
        measure(args)


if __name__ == "__main__":
    main()
