#!/usr/bin/env python3
"""The default quadrature rule of fix pe_jump: every rule on the scenes users run.

One command (about 4 minutes of runs on 2 cores, one LAMMPS process at a time;
224 s on 2026-12-06 with the other core busy):

    /usr/bin/python3 bench/default_rule/default_rule.py --lmp build/lmp

Options:
  --lmp BINARY        LAMMPS with fix pe_jump (default: $LMP, else build/lmp)
  --lammps-src DIR    LAMMPS source tree, for bench/data.chain and
                      examples/deposit/in.deposit.atom
                      (default ~/.cache/pe-jump/lammps-20250204+dfsg.1)
  --scenes A,B,...    only these (lj, crack, fpu, quadratic, string, lattice,
                      cascade, chain, compat, reused); the others keep their results
                      from an earlier run in results.json

For each scene: fix nve (the anchor) and fix pe_jump with quadrature
midpoint, lobatto 2, lobatto 3 and legendre 2 at the scene's usual step:

  evals/step  vector element 5 of the fix over the run / steps (fix nve: 1);
              it includes the extra evaluation that midpoint and Legendre
              rules do on every step that tallies energy (thermo output)
  pos. error  max over atoms of |r - r_ref| at a fixed time, r_ref from
              fix nve at h/8 (FPU: DOP853 on the exact model); the
              reference's own error is estimated from nve at h/4
              (Richardson: |r_h/8 - r_h/4| / 3)
  dE          max over the output steps of |etotal - etotal(0)|
  dH~         max over the output steps of |H~ - H~(0)|, H~ = pe + f_ID
              (the pseudo-energy; for fix nve H~ = etotal)

Scenes:
  lj       examples/lj-liquid made small (864 atoms, shifted lj/cut, dt 0.005)
           from an equilibrated liquid: positions at t = 0.5, energies to t = 10
  crack    bench/moving_region/in.crack (LAMMPS' examples/crack,
           closed: pre-strain instead of a pulled boundary), T = 6, h = 0.003
  fpu      examples/fpu (h = 1e-3): positions at t = 10, energies to t = 200
  string   examples/nonlinear-string (bench/inputs/in.string, dt 0.0033, T = 1)
  lattice  examples/spring-lattice with fix pe_jump (sync, h = 0.02, T = 70)
  cascade  the LJ cascade of bench/moving_region/in.cascade under
           fix dt/reset (xmax 0.013, dtmax 0.005): max |dE|/Epka
  quadratic the chain of examples/fpu with harmonic soft springs: every
           spring quadratic, where the pseudo-energy of midpoint and lobatto 2
           is exact
  chain    LAMMPS' bench/in.chain with fix langevin, 500 steps: cost only
  compat   quick checks of doc/compatibility.md: fix wall/reflect, fix rigid
           beside, compute pe/tally, LAMMPS' examples/deposit
  reused   work-precision results of bench/results/full/*.json (fpu, string,
           lj_wp, chain, lattice, dtreset, lj_cost), re-read, not rerun

Results: bench/results/default_rule/results.json and tables.md (markdown of
the tables of doc/default_rule.md); logs and dumps: bench/work/default_rule/.
"""

import argparse
import math
import os
import re
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
BENCH = os.path.dirname(HERE)
ROOT = os.path.dirname(BENCH)
sys.path.insert(0, BENCH)
import benchlib as B  # noqa: E402  (parse_log, read_dump, chain_reference)

EX = os.path.join(ROOT, "examples")
RES_DIR = os.path.join(BENCH, "results", "default_rule")
WORK = os.path.join(BENCH, "work", "default_rule")
FULL = os.path.join(BENCH, "results", "full")

RULES = ["midpoint", "lobatto 2", "lobatto 3", "legendre 2"]
CONFIGS = [("fix nve", None)] + [(q, q) for q in RULES]
LMP = None


def log(msg):
    print(time.strftime("%H:%M:%S"), msg, flush=True)


def tag(name):
    return re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_")


def run(inp, variables, cwd, logname, check=True):
    """One LAMMPS run; returns benchlib.parse_log of its log plus returncode."""
    os.makedirs(cwd, exist_ok=True)
    cmd = [LMP, "-nocite", "-screen", "none", "-log", logname, "-in", inp]
    for k, v in variables.items():
        cmd += ["-var", k, str(v)]
    t0 = time.time()
    p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    path = os.path.join(cwd, logname)
    res = B.parse_log(path) if os.path.exists(path) else {"error_lines": ["no log"], "thermo": []}
    res["returncode"] = p.returncode
    res["wall"] = time.time() - t0
    res["cmd"] = " ".join(cmd[1:])
    if check and (p.returncode != 0 or res.get("error_lines")):
        raise RuntimeError(f"LAMMPS failed in {cwd}: {' '.join(cmd)}\n{res.get('error_lines')}\n"
                           f"{p.stderr[-2000:]}")
    log(f"  {logname}: {res.get('steps', '?')} steps, {res['wall']:.1f} s, rc {p.returncode}")
    return res


def all_rows(res):
    """Thermo rows of every run of a log (same header), one array."""
    head = res["thermo"][0]["head"]
    rows = [r for t in res["thermo"] for r in t["rows"]]
    return head, np.array(rows)


def integrator_vars(quad, pe_jump="pe_jump"):
    """-var settings of an input that takes fix nve or fix pe_jump with a rule"""
    return {"integrator": "nve"} if quad is None else {"integrator": pe_jump, "quad": quad}


def with_integrator(text, quad):
    """a LAMMPS input with its fix nve lines turned into fix pe_jump with the rule quad"""
    spec = "nve" if quad is None else f"pe_jump quadrature {quad}"
    return re.sub(r"^(fix\s+\S+\s+\S+\s+)nve\s*$", lambda m: m.group(1) + spec, text, flags=re.M)


def energy_stats(res, ecol, htcol, norm):
    head, R = all_rows(res)
    E = R[:, head.index(ecol)]
    Ht = R[:, head.index(htcol)]
    return {"dE_max": float(np.max(np.abs(E - E[0])) / norm),
            "dE_end": float((E[-1] - E[0]) / norm),
            "dHt_max": float(np.max(np.abs(Ht - Ht[0])) / norm),
            "E0": float(E[0]), "samples": int(len(E))}


def bench_line(res, key):
    return float(res["bench"][key])


def read_dump_box(path):
    """write_dump custom output sorted by id, with the box lengths."""
    with open(path) as f:
        lines = f.read().splitlines()
    k = [i for i, ln in enumerate(lines) if ln.startswith("ITEM: BOX BOUNDS")][-1]
    L = [float(lines[k + j].split()[1]) - float(lines[k + j].split()[0]) for j in (1, 2, 3)]
    d = B.read_dump(path)
    d["L"] = L
    return d


def dist(d, r, cols, periodic=()):
    s = 0.0
    for j, c in enumerate(cols):
        dd = d[c] - r[c]
        if j in periodic:
            dd -= r["L"][j] * np.round(dd / r["L"][j])
        s = s + dd * dd
    return np.sqrt(s)


def pos_errors(e):
    """max and 99th percentile over atoms of the position error e."""
    return {"pos_err": float(np.max(e)), "pos_err_p99": float(np.percentile(e, 99))}


def add_ratios(rows, keys=("pos_err", "pos_err_p99", "dE_max", "dHt_max")):
    nve = next(r for r in rows if r["rule"] == "fix nve")
    for r in rows:
        for k in keys:
            if k in r and k in nve and nve[k]:
                r[k + "_vs_nve"] = r[k] / nve[k]


# ------------------------------------------------------------------ scenes

def scene_lj(a):
    wd = os.path.join(WORK, "lj")
    inp = os.path.join(HERE, "in.lj-liquid")
    h, Tpos, Trest, nout = 0.005, 0.5, 9.5, 10
    run(inp, {"integrator": "nve", "Tpos": 5.0, "Trest": 0, "nout": 1000, "save": "liquid_data"},
        wd, "log.equil")
    refs = {}
    for k in (8, 4):
        run(inp, {"integrator": "nve", "start": "liquid_data", "dt": h / k, "Tpos": Tpos, "Trest": 0,
                  "nout": 100 * k, "out": f"ref{k}_pos"}, wd, f"log.ref{k}")
        refs[k] = B.read_dump(os.path.join(wd, f"ref{k}_pos"))
    cols = ("xu", "yu", "zu")
    ref_err = float(np.max(dist(refs[8], refs[4], cols)) / 3.0)
    ref_err_p99 = float(np.percentile(dist(refs[8], refs[4], cols), 99) / 3.0)
    rows = []
    for name, quad in CONFIGS:
        v = {"start": "liquid_data", "dt": h, "Tpos": Tpos, "Trest": Trest, "nout": nout,
             "out": f"pos_{tag(name)}"}
        v.update(integrator_vars(quad))
        r = run(inp, v, wd, f"log.{tag(name)}")
        d = B.read_dump(os.path.join(wd, v["out"]))
        n = bench_line(r, "natoms")
        row = {"rule": name, "evals_per_step": bench_line(r, "evals") / bench_line(r, "steps")}
        row.update(pos_errors(dist(d, refs[8], cols)))
        row.update(energy_stats(r, "TotEng", "v_Ht", n))
        rows.append(row)
    add_ratios(rows)
    return {"desc": "LJ liquid, 864 atoms (fcc 0.8442, 6^3 cells, T = 3.0 on the lattice, 1000 steps of "
                    "fix nve to a liquid), lj/cut 2.5 shifted, dt 0.005; positions at t = 0.5 (100 steps), "
                    "energies every 10 steps to t = 10 (2000 steps), per atom",
            "h": h, "T_pos": Tpos, "T_energy": Tpos + Trest, "ref": "fix nve at h/8",
            "ref_err": ref_err, "ref_err_p99": ref_err_p99, "energy_norm": "per atom", "rows": rows}


def scene_crack(a):
    wd = os.path.join(WORK, "crack")
    inp = os.path.join(ROOT, "bench", "moving_region", "in.crack")
    h, T = 0.003, 6.0
    refs = {}
    for k in (8, 4):
        run(inp, {"integrator": "nve", "h": h / k, "T": T, "tout": 0.3, "name": f"ref{k}"}, wd, f"log.ref{k}")
        refs[k] = B.read_dump(os.path.join(wd, f"final.crack.ref{k}.dump"))
    cols = ("xu", "yu")
    ref_err = float(np.max(dist(refs[8], refs[4], cols)) / 3.0)
    ref_err_p99 = float(np.percentile(dist(refs[8], refs[4], cols), 99) / 3.0)
    rows = []
    for name, quad in CONFIGS:
        v = {"h": h, "T": T, "tout": 0.06, "name": tag(name)}
        v.update(integrator_vars(quad, "sync"))
        r = run(inp, v, wd, f"log.{tag(name)}")
        d = B.read_dump(os.path.join(wd, f"final.crack.{tag(name)}.dump"))
        head, R = all_rows(r)
        nmob = len(d["id"])
        row = {"rule": name, "evals_per_step": float(R[-1, head.index("v_evals")] / R[-1, 0]),
               "xtip_end": float(R[-1, head.index("v_xtip")])}
        row.update(pos_errors(dist(d, refs[8], cols)))
        row.update(energy_stats(r, "v_E", "v_Ht", nmob))
        rows.append(row)
    add_ratios(rows)
    return {"desc": "crack of bench/moving_region/in.crack (LAMMPS' examples/crack: 2d LJ, 8141 "
                    "atoms, 7537 mobile; closed system: pre-strain 0.10 instead of the pulled boundary, "
                    "pair_modify shift yes), h = 0.003, T = 6 (2000 steps), output every 20 steps; "
                    "energies per mobile atom",
            "h": h, "T": T, "ref": "fix nve at h/8", "ref_err": ref_err, "ref_err_p99": ref_err_p99,
            "energy_norm": "per mobile atom", "rows": rows}


def scene_fpu(a, soft="quartic"):
    wd = os.path.join(WORK, "fpu" if soft == "quartic" else "quadratic")
    inp = os.path.join(HERE, "in.fpu")
    h, Tpos, T = 1e-3, 10.0, 200.0
    om = 50.0
    q0 = np.array([(1 - 1 / om) / math.sqrt(2), (1 + 1 / om) / math.sqrt(2), 0, 0, 0, 0])
    p0 = np.array([0, math.sqrt(2), 0, 0, 0, 0])
    # soft springs: quartic d^4, or (soft harmonic) d^2 = (2/4) d^2 with omega^2 = 2 in chain_reference
    if soft == "quartic":
        qref, _ = B.chain_reference("QKQKQKQ", q0, p0, Tpos, om * om)
    else:
        qref = quadratic_chain_reference(q0, p0, Tpos, om * om)
    rows = []
    for name, quad in CONFIGS:
        v = {"dt": h, "Tpos": Tpos, "T": T, "nout": 10, "soft": soft}
        v.update(integrator_vars(quad))
        r = run(inp, v, wd, f"log.{tag(name)}")
        with open(os.path.join(wd, f"log.{tag(name)}")) as f:
            pos = [ln.split() for ln in f if ln.startswith("POS ")]
        q = np.array([float(x) for x in pos[0][2:8]])
        head, R = all_rows(r)
        H0 = abs(R[0, head.index("v_H")])
        row = {"rule": name, "evals_per_step": bench_line(r, "evals") / bench_line(r, "steps"),
               "pos_err": float(np.max(np.abs(q - qref)))}
        row.update(energy_stats(r, "v_H", "v_Ht", H0))
        rows.append(row)
    add_ratios(rows)
    if soft != "quartic":
        return {"desc": "the chain of examples/fpu with soft harmonic springs (q_{2i+1}-q_{2i})^2 instead of "
                        "the quartic ones (in.fpu -var soft harmonic): every spring quadratic in the positions "
                        "of the 1d chain, h = 1e-3; positions at t = 10 against the exact solution (matrix "
                        "exponential), energies every 10 steps to t = 200, relative to |H(0)|",
                "h": h, "T_pos": Tpos, "T_energy": T, "ref": "exact (eigen-decomposition)", "ref_err": None,
                "energy_norm": "relative to |H(0)|", "rows": rows}
    return {"desc": "FPU chain of examples/fpu (omega 50, GNI initial values), h = 1e-3; positions at t = 10 "
                    "against DOP853 (rtol 1e-13) on the exact model, energies every 10 steps to t = 200 "
                    "(200000 steps), relative to |H(0)|",
            "h": h, "T_pos": Tpos, "T_energy": T, "ref": "DOP853 rtol 1e-13", "ref_err": None,
            "energy_norm": "relative to |H(0)|", "rows": rows}


def quadratic_chain_reference(q0, p0, T, omega2):
    """Exact solution of the linear chain (walls fixed, unit masses): stiff
    springs (omega^2/4) d^2 and soft springs d^2, by the eigenvectors of the
    stiffness matrix."""
    n = len(q0)
    k = np.array([2.0 if i % 2 == 0 else omega2 / 2.0 for i in range(n + 1)])  # spring constants: E = k/2 d^2
    Km = np.zeros((n, n))
    for i in range(n):
        Km[i, i] = k[i] + k[i + 1]
        if i + 1 < n:
            Km[i, i + 1] = Km[i + 1, i] = -k[i + 1]
    w2, V = np.linalg.eigh(Km)
    w = np.sqrt(w2)
    a0, b0 = V.T @ q0, V.T @ p0
    return V @ (a0 * np.cos(w * T) + b0 / w * np.sin(w * T))


def scene_string(a):
    wd = os.path.join(WORK, "string")
    inp = os.path.join(BENCH, "inputs", "in.string")
    h, T = 0.0033, 1.0
    refs = {}
    for k in (16, 8):
        run(inp, {"integrator": "nve", "dt": h / k, "T": T, "nsample": 10, "out": f"ref{k}.dump"},
            wd, f"log.ref{k}")
        refs[k] = B.read_dump(os.path.join(wd, f"ref{k}.dump"))
    cols = ("x", "y")
    ref_err = float(np.max(dist(refs[16], refs[8], cols)) / 3.0)
    ref_err_p99 = float(np.percentile(dist(refs[16], refs[8], cols), 99) / 3.0)
    rows = []
    for name, quad in CONFIGS:
        v = {"dt": h, "T": T, "nsample": 31, "out": f"final.{tag(name)}.dump"}
        v.update(integrator_vars(quad))
        r = run(inp, v, wd, f"log.{tag(name)}")
        d = B.read_dump(os.path.join(wd, v["out"]))
        head, R = all_rows(r)
        H0 = abs(R[0, head.index("v_H")])
        row = {"rule": name, "evals_per_step": bench_line(r, "evals") / bench_line(r, "steps")}
        row.update(pos_errors(dist(d, refs[16], cols)))
        row.update(energy_stats(r, "v_H", "v_Ht", H0))
        rows.append(row)
    add_ratios(rows)
    return {"desc": "nonlinear string of examples/nonlinear-string (alpha 0.99, A 0.3, 101 nodes; "
                    "bench/inputs/in.string), dt 0.0033 (303 steps to t = 1), output every 10 steps; "
                    "positions at t = 1, energies relative to |H(0)|",
            "h": h, "T": T, "ref": "fix nve at h/16", "ref_err": ref_err, "ref_err_p99": ref_err_p99,
            "energy_norm": "relative to |H(0)|", "rows": rows}


def scene_lattice(a):
    wd = os.path.join(WORK, "lattice")
    inp = os.path.join(EX, "spring-lattice", "in.spring-lattice")
    hS, K = 0.2, 10          # fix pe_jump and fix nve step: hS/K = 0.02
    refs = {}
    for k in (8, 4):
        run(inp, {"integrator": "nve", "hS": hS / k, "K": K, "tout": 7.0, "check": "yes"}, wd, f"log.ref{k}")
        os.replace(os.path.join(wd, "check.final.dump"), os.path.join(wd, f"final.ref{k}.dump"))
        refs[k] = read_dump_box(os.path.join(wd, f"final.ref{k}.dump"))
    cols = ("x", "y")
    ref_err = float(np.max(dist(refs[8], refs[4], cols, periodic=(1,))) / 3.0)
    ref_err_p99 = float(np.percentile(dist(refs[8], refs[4], cols, periodic=(1,)), 99) / 3.0)
    rows = []
    for name, quad in CONFIGS:
        v = {"hS": hS, "K": K, "tout": 0.2, "check": "yes"}
        v.update(integrator_vars(quad, "sync"))
        r = run(inp, v, wd, f"log.{tag(name)}")
        os.replace(os.path.join(wd, "check.final.dump"), os.path.join(wd, f"final.{tag(name)}.dump"))
        d = read_dump_box(os.path.join(wd, f"final.{tag(name)}.dump"))
        head, R = all_rows(r)
        H0 = abs(R[0, head.index("v_H")])
        row = {"rule": name, "evals_per_step": float(R[-1, head.index("v_evals")] / R[-1, 0])}
        row.update(pos_errors(dist(d, refs[8], cols, periodic=(1,))))
        row.update(energy_stats(r, "v_H", "v_Ht", H0))
        rows.append(row)
    add_ratios(rows)
    return {"desc": "spring lattice of examples/spring-lattice with fix pe_jump (-var integrator sync): "
                    "2d triangular lattice of harmonic bonds (12800 atoms, stiff inclusion k 100), "
                    "longitudinal pulse, h = 0.02, T = 70 (3500 steps), output every 10 steps; "
                    "energies relative to |H(0)|",
            "h": hS / K, "T": 70.0, "ref": "fix nve at h/8", "ref_err": ref_err, "ref_err_p99": ref_err_p99,
            "energy_norm": "relative to |H(0)|", "rows": rows}


def scene_cascade(a):
    wd = os.path.join(WORK, "cascade")
    inp = os.path.join(HERE, "in.cascade-dtreset")
    Epka, xmax = 2000.0, 0.013
    cfgs = [("fix nve", "nve", None, None, xmax),
            ("midpoint", "pe_jump", "midpoint", "no", xmax),
            ("midpoint compensate yes", "pe_jump", "midpoint", "yes", xmax),
            ("lobatto 2", "pe_jump", "lobatto 2", "no", xmax),
            ("lobatto 2 compensate yes", "pe_jump", "lobatto 2", "yes", xmax),
            ("lobatto 3", "pe_jump", "lobatto 3", "no", xmax),
            ("lobatto 3 compensate yes", "pe_jump", "lobatto 3", "yes", xmax),
            ("legendre 2 compensate yes", "pe_jump", "legendre 2", "yes", xmax),
            # the same evaluations as lobatto 3: half the distance per step
            ("fix nve, xmax/2", "nve", None, None, xmax / 2),
            ("midpoint, xmax/2", "pe_jump", "midpoint", "no", xmax / 2),
            ("lobatto 2 compensate yes, xmax/2", "pe_jump", "lobatto 2", "yes", xmax / 2)]
    rows = []
    for name, integ, quad, comp, xm in cfgs:
        v = {"integrator": integ, "xmax": xm, "dtmax": 0.005, "T": 1.0, "nout": 10, "Epka": Epka}
        if quad:
            v.update(quad=quad, comp=comp)
        r = run(inp, v, wd, f"log.{tag(name)}")
        head, R = all_rows(r)
        dt = R[:, head.index("Dt")]
        row = {"rule": name, "xmax": xm, "steps": bench_line(r, "steps"), "time": bench_line(r, "time"),
               "evals": bench_line(r, "evals"),
               "evals_per_step": bench_line(r, "evals") / bench_line(r, "steps"),
               "dt_min": float(dt.min()), "dt_max": float(dt.max())}
        row.update(energy_stats(r, "v_E", "v_Ht", Epka))
        rows.append(row)
    add_ratios(rows, ("dE_max",))
    return {"desc": "LJ cascade of bench/moving_region/in.cascade (4000 atoms, fcc 1.07, lj/cut 2.5 "
                    "shifted, T0 0.01, PKA 2000 epsilon) under fix dt/reset 1 NULL 0.005 0.013 units box "
                    "(first step 2e-4), t = 0 to 1, output every 10 steps; energies divided by Epka",
            "Epka": Epka, "xmax": xmax, "dtmax": 0.005, "energy_norm": "per Epka", "rows": rows}


def scene_chain(a):
    data = os.path.join(a.lammps_src, "bench", "data.chain")
    if not os.path.exists(data):
        return {"skipped": f"{data} not found"}
    wd = os.path.join(WORK, "chain")
    inp = os.path.join(HERE, "in.chain-langevin")
    rows = []
    for name, quad in CONFIGS:
        v = {"data": data, "nsteps": 500, "nout": 100}
        v.update(integrator_vars(quad))
        r = run(inp, v, wd, f"log.{tag(name)}", check=False)
        row = {"rule": name, "runs": r["returncode"] == 0 and not r.get("error_lines"),
               "error": (r.get("error_lines") or [None])[0]}
        if row["runs"]:
            row.update(evals_per_step=bench_line(r, "evals") / bench_line(r, "steps"),
                       T_mean_second_half=bench_line(r, "Tmean2"))
        rows.append(row)
    return {"desc": "LAMMPS' bench/in.chain (32000 atoms of FENE bead-spring melt, fix langevin 1.0 1.0 10.0, "
                    "dt 0.012), 500 steps, thermo every 100 steps: cost and whether it runs; mean T over "
                    "steps 250-500 only as a sanity check (the temperature study is bench/thermostat)",
            "rows": rows}


def outcome(r, path):
    """refused (with its ERROR line, searched in the whole log: benchlib's
    parser skips the lines of an interrupted thermo table) or runs."""
    if r["returncode"] != 0 or r.get("error_lines"):
        with open(path, errors="replace") as f:
            errs = [ln.strip() for ln in f if ln.startswith("ERROR")]
        return "refused", (errs or r.get("error_lines") or ["(no ERROR line)"])[0]
    return "runs", None


def scene_compat(a):
    wd = os.path.join(WORK, "compat")
    inp = os.path.join(HERE, "in.compat")
    run(os.path.join(HERE, "in.lj-liquid"),
        {"integrator": "nve", "Tpos": 5.0, "Trest": 0, "nout": 1000, "save": "liquid_data"}, wd, "log.equil")
    out = {}
    for case, nsteps in (("wall", 2000), ("rigid", 1000), ("tally", 200)):
        rows = []
        for name, quad in CONFIGS:
            v = {"case": case, "start": "liquid_data", "nsteps": nsteps, "nout": 10}
            v.update(integrator_vars(quad))
            r = run(inp, v, wd, f"log.{case}.{tag(name)}", check=False)
            st, err = outcome(r, os.path.join(wd, f"log.{case}.{tag(name)}"))
            row = {"rule": name, "outcome": st, "error": err}
            if st == "runs":
                head, R = all_rows(r)
                n = bench_line(r, "natoms")
                E = R[:, head.index("v_E")]
                row.update(dE_end_per_atom=float((E[-1] - E[0]) / n),
                           E_spread_per_atom=float((E.max() - E.min()) / n),
                           body_atoms=bench_line(r, "body"))
                if case == "tally":
                    ev, pt = R[:, head.index("E_vdwl")], R[:, head.index("v_tally")]
                    row["max_rel_pe_tally_minus_evdwl"] = float(np.max(np.abs(pt - ev) / np.abs(ev)))
            rows.append(row)
        out[case] = rows
    # LAMMPS' examples/deposit/in.deposit.atom, both fix nve swapped, 2000 of its 10000 steps
    src = os.path.join(a.lammps_src, "examples", "deposit", "in.deposit.atom")
    if os.path.exists(src):
        with open(src) as f:
            text = f.read()
        rows = []
        for name, quad in CONFIGS:
            t = with_integrator(text, quad)
            t = re.sub(r"^run\s+10000\s*$", "run             2000", t, flags=re.M)
            fn = os.path.join(wd, f"in.deposit.{tag(name)}")
            with open(fn, "w") as f:
                f.write(t)
            r = run(fn, {}, wd, f"log.deposit.{tag(name)}", check=False)
            st, err = outcome(r, os.path.join(wd, f"log.deposit.{tag(name)}"))
            row = {"rule": name, "outcome": st, "error": err}
            if st == "runs":
                head, R = all_rows(r)
                row.update({c: float(R[-1, head.index(c)]) for c in ("Step", "Atoms", "Temp", "E_pair",
                                                                     "TotEng")})
            rows.append(row)
        nve = rows[0]
        for row in rows:
            if row["outcome"] == "runs":
                row["epair_minus_nve"] = row["E_pair"] - nve["E_pair"]
        # the first thermo step (every 100) where the temperature of the
        # deposited atoms differs from fix nve's by more than 1e-8
        hn, Rn = all_rows(B.parse_log(os.path.join(wd, "log.deposit.fix_nve")))
        for name, row in zip([c[0] for c in CONFIGS], rows):
            if row["outcome"] != "runs" or name == "fix nve":
                continue
            h2, R2 = all_rows(B.parse_log(os.path.join(wd, f"log.deposit.{tag(name)}")))
            dT = np.abs(R2[:, h2.index("Temp")] - Rn[:, hn.index("Temp")])
            off = np.nonzero(dT > 1e-8)[0]
            row["first_step_off_nve"] = float(Rn[off[0], 0]) if len(off) else None
        # the first atom inserted under a force: its velocity after the step
        # of its insertion (step 701 of the example: atom 358), fix nve
        # against lobatto 2. Deposited with vz = -1 lattice units of fcc 1.0
        # (lattice spacing 4^(1/3)) at the example's dt 0.005
        vins, hdep = -4.0 ** (1.0 / 3.0), 0.005
        kick = {}
        for name, quad in CONFIGS[:3]:
            if quad == "midpoint":
                continue
            t = with_integrator(text, quad)
            t = re.sub(r"^run\s+10000\s*$", f"run 700\ndump dd all custom 1 kick.{tag(name)}.dump id vz fz\n"
                       "dump_modify dd sort id format float %.15g\nrun 1", t, flags=re.M)
            fn = os.path.join(wd, f"in.deposit-kick.{tag(name)}")
            with open(fn, "w") as f:
                f.write(t)
            run(fn, {}, wd, f"log.deposit-kick.{tag(name)}")
            with open(os.path.join(wd, f"kick.{tag(name)}.dump")) as f:
                blocks = f.read().split("ITEM: TIMESTEP")[1:]
            ids = [set(int(ln.split()[0]) for ln in b.split("ITEM: ATOMS")[1].splitlines()[1:] if ln.strip())
                   for b in blocks]
            new = sorted(ids[1] - ids[0])
            last = {int(ln.split()[0]): ln.split() for ln in blocks[1].split("ITEM: ATOMS")[1].splitlines()[1:]
                    if ln.strip()}
            if new:
                i = new[0]
                vz, fz = float(last[i][1]), float(last[i][2])
                kick[name] = {"atom": i, "step": int(blocks[1].split()[0]), "vz": vz, "fz": fz, "vz_inserted": vins,
                              "kick_over_h_f": (vz - vins) / (hdep * fz)}
        out["deposit_first_kick"] = kick
        out["deposit"] = rows
        out["deposit_source"] = src
    return {"desc": "864-atom LJ liquid (in.lj-liquid, equilibrated): wall = boundary p p f with fix "
                    "wall/reflect zlo EDGE zhi EDGE, 2000 steps; rigid = the atoms within 1.3 of the box "
                    "centre in fix rigid single, the others in the integrator, 1000 steps; tally = compute "
                    "pe/tally all, 200 steps; deposit = LAMMPS' examples/deposit/in.deposit.atom with both "
                    "fix nve replaced, 2000 steps. Energies per atom (pe + compute ke)",
            **out}


# ------------------------------------------------------------- reused results

def interp_loglog(x, xs, ys):
    """log-log interpolation of y(x) on points (xs, ys); flag extrapolation."""
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    o = np.argsort(xs)
    xs, ys = xs[o], ys[o]
    lx, ly = np.log(xs), np.log(ys)
    ext = x < xs[0] * (1 - 1e-9) or x > xs[-1] * (1 + 1e-9)
    if x <= xs[0]:
        i = 0
    elif x >= xs[-1]:
        i = len(xs) - 2
    else:
        i = int(np.searchsorted(xs, x)) - 1
    t = (math.log(x) - lx[i]) / (lx[i + 1] - lx[i])
    return float(math.exp(ly[i] + t * (ly[i + 1] - ly[i]))), bool(ext)


def scene_reused(a):
    out = {"source": "bench/results/full/*.json (bench/run_all.sh; fpu, string, chain, lattice, lj_wp and "
                     "dtreset measured with the binary of 2026-11-22, lj_cost with that of 2026-11-24)"}
    wp = {}
    for stage, nve_label in (("fpu", "fix nve"), ("string", "fix nve"), ("lj_wp", "fix nve"),
                             ("chain", "fix nve"), ("lattice", "fix nve")):
        path = os.path.join(FULL, stage + ".json")
        if not os.path.exists(path):
            continue
        d = B.load_json(path)
        pts = d["points"]
        nve = sorted([p for p in pts if p["label"] == nve_label], key=lambda p: p["h"])
        rows = []
        for p in pts:
            lab = p["label"]
            if not (lab == "fix nve" or lab.startswith("pe_jump")):
                continue
            same_h = next((q for q in nve if abs(q["h"] - p["h"]) < 1e-12), None)
            err_nve_cost, ext = interp_loglog(p["evals"], [q["evals"] for q in nve], [q["err"] for q in nve])
            rows.append({"rule": lab.replace("pe_jump ", "").replace(" (sync)", ""), "h": p["h"],
                         "evals": p["evals"], "steps": p.get("steps"),
                         "err": p["err"], "eH": p.get("eH"), "eHt": p.get("eHt"),
                         "err_vs_nve_same_h": p["err"] / same_h["err"] if same_h else None,
                         "err_vs_nve_same_evals": p["err"] / err_nve_cost, "same_evals_extrapolated": ext})
        wp[stage] = {"T": d.get("T"), "rows": rows}
    out["work_precision"] = wp
    path = os.path.join(FULL, "dtreset.json")
    if os.path.exists(path):
        d = B.load_json(path)
        dt = {}
        for k, v in d.items():
            D = np.array(v["data"])
            H1, H2, Ht = D[:, 3], D[:, 4], D[:, 5]
            n0 = abs(H1[0])
            dt[k] = {"drive": v["drive"], "quad": v["quad"], "steps": v["steps"],
                     "nve_dH_max": float(np.max(np.abs(H1 - H1[0])) / n0),
                     "pj_dH_max": float(np.max(np.abs(H2 - H2[0])) / n0),
                     "pj_dHt_max": float(np.max(np.abs(Ht - Ht[0])) / n0)}
        out["dtreset"] = dt
    path = os.path.join(FULL, "lj_cost.json")
    if os.path.exists(path):
        d = B.load_json(path)
        t0 = next(p["loop_time"] for p in d["table"] if p["name"] == "fix nve")
        out["lj_cost"] = {"natoms": d["table"][0]["natoms"], "steps": d["steps"],
                          "rows": [{"rule": p["name"].replace("pe_jump ", ""),
                                    "evals_per_step": p["evals"] / p["steps"],
                                    "wall_vs_nve": p["loop_time"] / t0,
                                    "modify_s": p["breakdown"].get("Modify")} for p in d["table"]]}
    return out


# ------------------------------------------------------------------- tables

def g(x):
    return "-" if x is None else f"{x:.3g}"


def tables(res):
    out = []
    accuracy_scenes = [("lj", "LJ liquid (864 atoms, h 0.005)"), ("crack", "crack (h 0.003, T 6)"),
                       ("fpu", "FPU chain (h 1e-3)"), ("string", "nonlinear string (h 0.0033)"),
                       ("lattice", "spring lattice (h 0.02)"),
                       ("quadratic", "harmonic chain (FPU, soft springs quadratic)")]
    out.append("### Accuracy per cost at the scene's step\n")
    out.append("| scene | rule | evals/step | position error (max) | x nve | 99th pct x nve | max dE | x nve "
               "| max dH~ | x nve |")
    out.append("|---|---|---|---|---|---|---|---|---|---|")
    for key, title in accuracy_scenes:
        s = res.get(key)
        if not s:
            continue
        for r in s["rows"]:
            p99 = f"{r['pos_err_p99_vs_nve']:.2f}" if "pos_err_p99_vs_nve" in r else "-"
            out.append(f"| {title} | {r['rule']} | {r['evals_per_step']:.2f} | {r['pos_err']:.2e} | "
                       f"{r.get('pos_err_vs_nve', 1):.2f} | {p99} | {r['dE_max']:.2e} | "
                       f"{r.get('dE_max_vs_nve', 1):.2f} | {r['dHt_max']:.2e} | {r.get('dHt_max_vs_nve', 1):.2g} |")
    out.append("")
    for key, title in accuracy_scenes:
        s = res.get(key)
        if s:
            out.append(f"* {title}: {s['desc']}; reference {s['ref']}"
                       + (f" (its own error, |r_ref - r_(2 h_ref)|/3: max {s['ref_err']:.1e}, 99th percentile "
                          f"{s['ref_err_p99']:.1e})" if s.get("ref_err") else "") + ".")
    out.append("")
    s = res.get("cascade")
    if s:
        out.append("### Cascade under fix dt/reset\n")
        out.append("| run | xmax | steps | evals/step | evals | max abs dE / Epka | x nve | E(end) - E(0) / Epka "
                   "| max abs dH~ / Epka | dt range |")
        out.append("|---|---|---|---|---|---|---|---|---|---|")
        for r in s["rows"]:
            out.append(f"| {r['rule']} | {r['xmax']:.4g} | {r['steps']:.0f} | {r['evals_per_step']:.2f} | "
                       f"{r['evals']:.0f} | {r['dE_max']:.2e} | {r.get('dE_max_vs_nve', 1):.2f} | "
                       f"{r['dE_end']:.1e} | {r['dHt_max']:.1e} | {r['dt_min']:.2g} .. {r['dt_max']:.2g} |")
        out.append("")
        out.append(f"* {s['desc']}.\n")
    s = res.get("chain")
    if s and "rows" in s:
        out.append("### LAMMPS' bench/in.chain with fix langevin (500 steps)\n")
        out.append("| rule | runs | evals/step | mean T, steps 250-500 |")
        out.append("|---|---|---|---|")
        for r in s["rows"]:
            out.append(f"| {r['rule']} | {'yes' if r['runs'] else 'no: ' + str(r['error'])} | "
                       f"{r.get('evals_per_step', float('nan')):.3f} | {r.get('T_mean_second_half', float('nan')):.3f} |")
        out.append("")
    s = res.get("compat")
    if s:
        out.append("### Quick checks beside other fixes and computes\n")
        out.append("| case | rule | outcome | measured |")
        out.append("|---|---|---|---|")
        for case in ("wall", "rigid", "tally", "deposit"):
            for r in s.get(case, []):
                if r["outcome"] == "refused":
                    m = r["error"].split("(src/")[0]
                    m = (m[:160] + " ...") if len(m) > 160 else m
                elif case == "wall":
                    m = f"etotal drift {r['dE_end_per_atom']:+.1e} per atom in 2000 steps"
                elif case == "rigid":
                    m = f"etotal spread {r['E_spread_per_atom']:.1e} per atom in 1000 steps ({r['body_atoms']:.0f} atoms in the body)"
                elif case == "tally":
                    m = f"max abs(pe/tally - evdwl)/abs(evdwl) {r['max_rel_pe_tally_minus_evdwl']:.1e}"
                else:
                    m = (f"{r['Atoms']:.0f} atoms at step {r['Step']:.0f}, T {r['Temp']:.4f}, epair "
                         f"{r['E_pair']:.5f} ({r['epair_minus_nve']:+.1e} from nve)")
                    if r.get("first_step_off_nve") is not None:
                        m += f"; T of the deposited atoms off nve's from step {r['first_step_off_nve']:.0f}"
                out.append(f"| {case} | {r['rule']} | {r['outcome']} | {m} |")
        out.append("")
        for name, k in s.get("deposit_first_kick", {}).items():
            out.append(f"* deposit, {name}: atom {k['atom']} inserted at step {k['step']} with vz "
                       f"{k['vz_inserted']:.6f} under fz {k['fz']:.4f} leaves that step with vz {k['vz']:.6f} = "
                       f"vz_inserted + {k['kick_over_h_f']:.3f} h fz / m")
        out.append("")
    s = res.get("reused")
    if s:
        out.append("### Reused work-precision results (bench/results/full)\n")
        out.append("| scene | rule | h | evals | position error | x nve same h | x nve same evals | "
                   "max rel dH | max rel dH~ |")
        out.append("|---|---|---|---|---|---|---|---|---|")
        keep = {"fix nve", "midpoint", "lobatto 2", "lobatto 3", "legendre 2"}
        names = {"fpu": "FPU chain (in.springs, T 10)", "string": "nonlinear string (T 1)",
                 "lj_wp": "LJ liquid, 32000 atoms (t 0.5)", "chain": "slow/fast chain, 100000 atoms",
                 "lattice": "lattice with stiff inclusion, 16800 atoms"}
        for stage, d in s["work_precision"].items():
            for r in sorted(d["rows"], key=lambda r: (list(sorted(keep)).index(r["rule"]) if r["rule"] in keep
                                                       else 99, -r["h"])):
                if r["rule"] not in keep:
                    continue
                out.append(f"| {names.get(stage, stage)} | {r['rule']} | {r['h']:g} | {r['evals']:.0f} | {r['err']:.2e} | "
                           f"{g(r['err_vs_nve_same_h'])} | {r['err_vs_nve_same_evals']:.2f}"
                           f"{' (extrap.)' if r['same_evals_extrapolated'] else ''} | {g(r['eH'])} | {g(r['eHt'])} |")
        out.append("")
        if "dtreset" in s:
            out.append("| dt/reset run (bench/results/full/dtreset.json) | steps | fix nve max rel dH | pe_jump max rel dH | pe_jump max rel dH~ |")
            out.append("|---|---|---|---|---|")
            for k, r in s["dtreset"].items():
                out.append(f"| {k} (pe_jump {r['quad']}, step from {r['drive']}) | {r['steps']} | {r['nve_dH_max']:.2e} | "
                           f"{r['pj_dH_max']:.2e} | {r['pj_dHt_max']:.2e} |")
            out.append("")
        if "lj_cost" in s:
            out.append(f"| LJ {s['lj_cost']['natoms']} atoms, {s['lj_cost']['steps']} steps (lj_cost.json) | evals/step | wall / fix nve | Modify [s] |")
            out.append("|---|---|---|---|")
            for r in s["lj_cost"]["rows"]:
                out.append(f"| {r['rule']} | {r['evals_per_step']:.3f} | {r['wall_vs_nve']:.3f} | {r['modify_s']:.3f} |")
            out.append("")
    return "\n".join(out) + "\n"


SCENES = {"lj": scene_lj, "crack": scene_crack, "fpu": scene_fpu,
          "quadratic": lambda a: scene_fpu(a, soft="harmonic"), "string": scene_string,
          "lattice": scene_lattice, "cascade": scene_cascade, "chain": scene_chain,
          "compat": scene_compat, "reused": scene_reused}


def main():
    global LMP
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lmp", default=os.environ.get("LMP", os.path.join(ROOT, "build", "lmp")))
    ap.add_argument("--lammps-src", default=os.path.expanduser("~/.cache/pe-jump/lammps-20250204+dfsg.1"))
    ap.add_argument("--scenes", default=",".join(SCENES))
    a = ap.parse_args()
    LMP = os.path.abspath(a.lmp)
    os.makedirs(RES_DIR, exist_ok=True)
    os.makedirs(WORK, exist_ok=True)
    path = os.path.join(RES_DIR, "results.json")
    res = B.load_json(path) if os.path.exists(path) else {}
    head = subprocess.run(["git", "-C", ROOT, "log", "-1", "--format=%h %s"], stdout=subprocess.PIPE,
                          text=True).stdout.strip()
    for name in a.scenes.split(","):
        log(f"scene {name}")
        t0 = time.time()
        res[name] = SCENES[name](a)
        res[name]["seconds"] = round(time.time() - t0, 1)
        res[name]["run"] = {"binary": LMP, "git_head": head, "finished": time.strftime("%Y-%m-%d %H:%M:%S"),
                            "loadavg_end": [round(x, 2) for x in B.loadavg()]}
        B.save_json(path, res)
        with open(os.path.join(RES_DIR, "tables.md"), "w") as f:
            f.write("<!-- generated by bench/default_rule/default_rule.py from results.json -->\n\n"
                    + tables(res))
    log(f"results in {path}")


if __name__ == "__main__":
    main()
