#!/usr/bin/python3
"""PE-JUMP cost targets: time the fixes against fix nve on three scenes with
one binary, write bench/results/cost/<label>.json; --report compares labels.

    /usr/bin/python3 bench/cost/cost.py --label before --lmp /path/to/older/build/lmp \\
        [--libdir DIR] [--reps 3] [--quick] [--scenes bonded,lj,springs]
    /usr/bin/python3 bench/cost/cost.py --report [--out FILE] [--labels a,b]

Scenes (one MPI rank, no suffix):
  bonded   2d triangular lattice, every spring a harmonic bond (no pair
           style), stiff inclusion of 10% of the atoms (K x2500), 40000
           atoms, h = 0.005, 4000 steps: nve, pe_jump midpoint / lobatto 3,
           pe_jump/async 50 stiff midpoint / lobatto 3, each also with the
           opt-in atom_modify first + neigh_modify include stiff ("first";
           "first 2d": and fix enforce2d on stiff only)
                                                          (bench/cost/in.bonded_lattice)
  lj       LJ liquid, 32000 atoms, 200 steps: nve, pe_jump midpoint /
           lobatto 3                                      (bench/inputs/in.lj)
  springs  the spring lattice of bench.py (16800 atoms, soft pair table,
           stiff bonds), h = 0.002, 500 fine steps: pe_jump midpoint and
           pe_jump/async 50 midpoint                      (bench/inputs/in.springs)
Every configuration runs --reps times, interleaved (all configurations once,
then again); figures are medians. See bench/cost/README.md.
"""

import argparse
import hashlib
import os
import platform
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
import benchlib as B  # noqa: E402

RESULTS = os.path.join(B.BENCH, "results", "cost")
WORK = os.path.join(B.BENCH, "work", "cost")
WORK_LABEL = None   # bench/work/cost/<label>, set by measure()
CATS = ("Pair", "Bond", "Neigh", "Comm", "Output", "Modify", "Other")

FULL = dict(bonded_nx=200, bonded_ny=200, bonded_h=0.005, bonded_steps=4000, bonded_thermo=1000,
            bonded_ratio=2500.0, lj_ncell=20, lj_steps=200,
            springs_nx=120, springs_ny=140, springs_h=0.002, springs_steps=500, K=50)
QUICK = dict(FULL, bonded_nx=60, bonded_ny=60, bonded_steps=400, bonded_thermo=200,
             lj_ncell=8, lj_steps=50, springs_nx=60, springs_ny=70, springs_steps=200)

# (scene, name, integrator, quadrature, K[, extra input variables])
# "first": the opt-in atom_modify first + neigh_modify include stiff; "2d":
# also fix enforce2d on that group only (LAMMPS then loops over it only)
FIRST = {"first": "stiff"}
FIRST_2D = {"first": "stiff", "e2d": "stiff"}
# "every 50": neigh_modify every 50 (LAMMPS checks the list distances of all
# atoms at coarse nodes only; pe_jump/async checks the atoms it moved on the
# other steps); "every 50 2d": and fix enforce2d on stiff only
EVERY = {"nevery": "50"}
EVERY_2D = {"nevery": "50", "e2d": "stiff"}
CONFIGS = [
    ("bonded", "nve", "nve", None, None),
    ("bonded", "pe_jump midpoint", "pe_jump", "midpoint", None),
    ("bonded", "pe_jump lobatto 3", "pe_jump", "lobatto 3", None),
    ("bonded", "async 50 midpoint", "async", "midpoint", 50),
    ("bonded", "async 50 lobatto 3", "async", "lobatto 3", 50),
    ("bonded", "async 50 midpoint first", "async", "midpoint", 50, FIRST),
    ("bonded", "async 50 lobatto 3 first", "async", "lobatto 3", 50, FIRST),
    ("bonded", "async 50 midpoint first 2d", "async", "midpoint", 50, FIRST_2D),
    ("bonded", "async 50 lobatto 3 first 2d", "async", "lobatto 3", 50, FIRST_2D),
    ("bonded", "pe_jump midpoint every 50", "pe_jump", "midpoint", None, EVERY),
    ("bonded", "pe_jump lobatto 3 every 50", "pe_jump", "lobatto 3", None, EVERY),
    ("bonded", "async 50 midpoint every 50", "async", "midpoint", 50, EVERY),
    ("bonded", "async 50 lobatto 3 every 50", "async", "lobatto 3", 50, EVERY),
    ("bonded", "async 50 midpoint every 50 2d", "async", "midpoint", 50, EVERY_2D),
    ("bonded", "async 50 lobatto 3 every 50 2d", "async", "lobatto 3", 50, EVERY_2D),
    ("lj", "nve", "nve", None, None),
    ("lj", "pe_jump midpoint", "pe_jump", "midpoint", None),
    ("lj", "pe_jump lobatto 3", "pe_jump", "lobatto 3", None),
    ("springs", "pe_jump midpoint", "pe_jump", "midpoint", None),
    ("springs", "async 50 midpoint", "async", "midpoint", 50),
    ("springs", "async 50 midpoint every 50", "async", "midpoint", 50, EVERY),
]

SCENE_TITLE = {"bonded": "bonded lattice", "lj": "LJ liquid", "springs": "spring lattice"}

# (key, description, comparison, limit)
TARGETS = [
    ("lj.midpoint_modify_ratio", "LJ: midpoint Modify per atom-step / nve's", "<=", 1.3),
    ("bonded.midpoint_modify_ratio", "bonded lattice: midpoint Modify per atom-step / nve's", "<=", 1.3),
    ("lj.lobatto3_extra_node", "LJ: lobatto 3 extra node / bare evaluation (Modify diff / Pair of nve)", "<=", 1.15),
    ("bonded.lobatto3_extra_node", "bonded lattice: lobatto 3 extra node / bare evaluation (Modify diff / Bond of nve)", "<=", 1.15),
    ("bonded.lobatto3_wall_ratio", "bonded lattice: lobatto 3 wall / nve", "<=", 2.3),
    ("lj.midpoint_mem_extra", "LJ: midpoint memory - nve [bytes/atom]", "<=", 64.0),
    ("bonded.midpoint_mem_extra", "bonded lattice: midpoint memory - nve [bytes/atom]", "<=", 64.0),
    ("bonded.async_midpoint_wall_per_eval", "bonded lattice: async K=50 midpoint wall/eval ratio", "<=", 1.15),
    ("bonded.async_lobatto3_wall_per_eval", "bonded lattice: async K=50 lobatto 3 wall/eval ratio", "<=", 1.15),
    ("springs.async_midpoint_wall_per_eval", "spring lattice: async K=50 midpoint wall/eval ratio", "<=", 1.15),
    ("bonded.async_midpoint_speedup", "bonded lattice: async K=50 midpoint speed-up over sync", ">=", 5.0),
    ("bonded.async_lobatto3_speedup", "bonded lattice: async K=50 lobatto 3 speed-up over sync", ">=", 5.0),
]
# the same async targets with the opt-in (configurations "... first", "... first 2d")
ASYNC_VARIANTS = (("", ""), (" first", "_first"), (" first 2d", "_first_2d"),
                  (" every 50", "_every50"), (" every 50 2d", "_every50_2d"))
TARGETS.append(("springs.async_midpoint_every50_wall_per_eval",
                "spring lattice: async K=50 midpoint every 50 wall/eval ratio", "<=", 1.15))
for _name, _key in ASYNC_VARIANTS[1:]:
    for _q, _qk in (("midpoint", "midpoint"), ("lobatto 3", "lobatto3")):
        TARGETS.append((f"bonded.async_{_qk}{_key}_wall_per_eval",
                        f"bonded lattice: async K=50 {_q}{_name} wall/eval ratio", "<=", 1.15))
        TARGETS.append((f"bonded.async_{_qk}{_key}_speedup",
                        f"bonded lattice: async K=50 {_q}{_name} speed-up over sync", ">=", 5.0))

# further figures shown in the report (no target)
EXTRA = [
    ("lj.lobatto3_extra_node_total", "LJ: lobatto 3 extra node / bare evaluation, all timer categories"),
    ("bonded.lobatto3_extra_node_total", "bonded lattice: lobatto 3 extra node / bare evaluation, all timer categories"),
    ("lj.lobatto3_wall_ratio", "LJ: lobatto 3 wall / nve"),
    ("lj.midpoint_wall_ratio", "LJ: midpoint wall / nve"),
    ("bonded.midpoint_wall_ratio", "bonded lattice: midpoint wall / nve"),
    ("lj.lobatto3_mem_extra", "LJ: lobatto 3 memory - nve [bytes/atom]"),
    ("bonded.lobatto3_mem_extra", "bonded lattice: lobatto 3 memory - nve [bytes/atom]"),
    ("bonded.async_midpoint_eval_ratio", "bonded lattice: async/sync evaluations, midpoint"),
    ("bonded.async_lobatto3_eval_ratio", "bonded lattice: async/sync evaluations, lobatto 3"),
    ("springs.async_midpoint_eval_ratio", "spring lattice: async/sync evaluations, midpoint"),
    ("springs.async_midpoint_speedup", "spring lattice: async K=50 midpoint speed-up over sync"),
    ("bonded.async_midpoint_first_2d_wall_per_eval_paired",
     "bonded lattice: async K=50 midpoint first 2d wall/eval, median of the repetitions' ratios"),
    ("bonded.async_lobatto3_first_2d_wall_per_eval_paired",
     "bonded lattice: async K=50 lobatto 3 first 2d wall/eval, median of the repetitions' ratios"),
    ("springs.async_midpoint_every50_wall_per_eval_paired",
     "spring lattice: async K=50 midpoint every 50 wall/eval, median of the repetitions' ratios"),
]


def log(msg):
    print(time.strftime("%H:%M:%S"), msg, flush=True)


def cfg_id(scene, name):
    return f"{scene}/{name}"


def slug(s):
    return s.replace(" ", "_").replace("/", "_")


def file_info(path):
    try:
        st = os.stat(path)
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for blk in iter(lambda: f.read(1 << 20), b""):
                h.update(blk)
        return {"path": path, "mtime": time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(st.st_mtime)) + " UTC",
                "size": st.st_size, "sha256": h.hexdigest()[:16]}
    except OSError:
        return {"path": path, "missing": True}


def read_loadavg():
    with open("/proc/loadavg") as f:
        return f.read().strip()


# ------------------------------------------------------------------ scenes

def prepare(c, scenes):
    """Data files and per-scene run settings in bench/work/cost/<label>/."""
    out = {}
    if "bonded" in scenes:
        wd = os.path.join(WORK_LABEL, "bonded")
        os.makedirs(wd, exist_ok=True)
        info = B.write_lattice_data(os.path.join(wd, "lattice.data"), c["bonded_nx"], c["bonded_ny"],
                                    soft_as_bonds=True)
        info["stiff_bonds"] = info["bonds"] - info["soft"]
        out["bonded"] = dict(wd=wd, inp=os.path.join(HERE, "in.bonded_lattice"), info=info,
                             base=dict(data="lattice.data", ratio=c["bonded_ratio"], h=c["bonded_h"],
                                       nsteps=c["bonded_steps"], nthermo=c["bonded_thermo"], K=c["K"]),
                             h=c["bonded_h"], steps=c["bonded_steps"])
    if "lj" in scenes:
        wd = os.path.join(WORK_LABEL, "lj")
        os.makedirs(wd, exist_ok=True)
        out["lj"] = dict(wd=wd, inp=os.path.join(B.INPUTS, "in.lj"), info={"ncell": c["lj_ncell"]},
                         base=dict(ncell=c["lj_ncell"], nsteps=c["lj_steps"]), h=0.005, steps=c["lj_steps"])
    if "springs" in scenes:
        # as bench.py stage skip / lattice: soft pair table 0.5 (r-1)^2, bonds 2500x stiffer
        wd = os.path.join(WORK_LABEL, "springs")
        os.makedirs(wd, exist_ok=True)
        ks, ratio = 0.5, 2500.0
        B.write_table(os.path.join(wd, "soft.table"), "SOFT", lambda r: ks * (r - 1) ** 2,
                      lambda r: -2 * ks * (r - 1), 0.3, 1.4)
        info = B.write_lattice_data(os.path.join(wd, "lattice.data"), c["springs_nx"], c["springs_ny"])
        h, n = c["springs_h"], c["springs_steps"]
        out["springs"] = dict(wd=wd, inp=os.path.join(B.INPUTS, "in.springs"), info=info,
                              base=dict(data="lattice.data", table="soft.table", rc=1.3, skin=0.2, a=1.0,
                                        Kb=ratio * ks, bnd="p p p", procs="* * 1", T=n * h, h=h,
                                        nsample=1, K=c["K"]),
                              h=h, steps=n)
    return out


def run_one(sc, scene, name, integ, quad, K, rep, extra=None):
    v = dict(sc["base"])
    v.update(extra or {})
    v["integrator"] = integ
    if quad:
        v["quad"] = quad
    if scene == "springs":
        v["out"] = f"final.{slug(name)}.dump"
    load = read_loadavg()
    r = B.run_lammps(sc["inp"], v, cwd=sc["wd"], log=f"log.{slug(name)}.{rep}")
    head, rows = r.get("thermo_head", []), r.get("thermo_rows", [])
    evals = None
    if "v_evals" in head and rows:
        evals = rows[-1][head.index("v_evals")]
    elif "evals" in r.get("bench", {}):
        evals = r["bench"]["evals"]
    out = {"rep": rep, "loadavg_start": load, "loop_time": r["loop_time"],
           "breakdown": {k: r.get("breakdown", {}).get(k) for k in CATS},
           "memory_mb": r["memory_mb"][1], "natoms": r["natoms"], "steps": r["steps"],
           "evals": evals, "cpu_use": r.get("cpu_use"), "neigh_builds": r.get("neigh_builds"),
           "maxrss_kb": r.get("maxrss_kb"), "log": os.path.join(sc["wd"], f"log.{slug(name)}.{rep}")}
    # conservation check: relative variation of H (nve) or H~ (pe_jump) over the thermo rows
    for col in ("v_Ht", "TotEng"):
        if col in head and len(rows) > 1:
            Hs = [row[head.index(col)] for row in rows]
            out["energy_rel_var"] = max(abs(x - Hs[0]) for x in Hs) / max(abs(Hs[0]), 1e-300)
            break
    return out


def summarize(reps):
    s = {"loop_time": B.median([r["loop_time"] for r in reps]),
         "memory_mb": B.median([r["memory_mb"] for r in reps]),
         "natoms": reps[0]["natoms"], "steps": reps[0]["steps"],
         "evals": B.median([r["evals"] for r in reps]) if all(r["evals"] is not None for r in reps) else None,
         "cpu_use": B.median([r["cpu_use"] if r["cpu_use"] is not None else float("nan") for r in reps]),
         "breakdown": {}}
    for k in CATS:
        vals = [r["breakdown"][k] for r in reps if r["breakdown"].get(k) is not None]
        if vals:
            s["breakdown"][k] = B.median(vals)
    ev = [r.get("energy_rel_var") for r in reps if r.get("energy_rel_var") is not None]
    if ev:
        s["energy_rel_var"] = max(ev)
    return s


# ------------------------------------------------------------------ figures

def derive(runs):
    """Derived figures from the medians: {scene: {figure: value}}, plus a
    per-configuration table {id: {...}}."""
    med = {k: v["median"] for k, v in runs.items()}
    table = {}
    for cid, m in med.items():
        scene, name = cid.split("/", 1)
        na, ns = m["natoms"], m["steps"]
        row = {"wall": m["loop_time"],
               "modify_ns_atom_step": m["breakdown"].get("Modify", float("nan")) / (na * ns) * 1e9,
               "mem_bytes_atom": m["memory_mb"] * 1048576.0 / na,
               "evals": m["evals"], "evals_per_step": (m["evals"] / ns) if m["evals"] is not None else None}
        nve = med.get(cfg_id(scene, "nve"))
        if nve:
            nrow_mod = nve["breakdown"].get("Modify", float("nan")) / (nve["natoms"] * nve["steps"]) * 1e9
            row["wall_ratio_nve"] = m["loop_time"] / nve["loop_time"]
            row["modify_ratio_nve"] = row["modify_ns_atom_step"] / nrow_mod
            row["mem_extra_bytes_atom"] = row["mem_bytes_atom"] - nve["memory_mb"] * 1048576.0 / nve["natoms"]
        table[cid] = row
    fig = {}
    for scene in SCENE_TITLE:
        f = {}
        nve = med.get(cfg_id(scene, "nve"))
        mid = med.get(cfg_id(scene, "pe_jump midpoint"))
        l3 = med.get(cfg_id(scene, "pe_jump lobatto 3"))
        if nve and mid:
            t = table[cfg_id(scene, "pe_jump midpoint")]
            f["midpoint_modify_ratio"] = t["modify_ratio_nve"]
            f["midpoint_wall_ratio"] = t["wall_ratio_nve"]
            f["midpoint_mem_extra"] = t["mem_extra_bytes_atom"]
        if nve and l3:
            t = table[cfg_id(scene, "pe_jump lobatto 3")]
            f["lobatto3_wall_ratio"] = t["wall_ratio_nve"]
            f["lobatto3_mem_extra"] = t["mem_extra_bytes_atom"]
        if nve and mid and l3:
            bare_cat = "Pair" if scene == "lj" else "Bond"
            bare = nve["breakdown"].get(bare_cat)
            f["lobatto3_extra_node"] = (l3["breakdown"]["Modify"] - mid["breakdown"]["Modify"]) / bare
            # robust to where LAMMPS books the fixes' own force evaluations
            force_cats = ("Pair", "Bond", "Comm", "Modify")
            tot = lambda m: sum(m["breakdown"].get(k) or 0.0 for k in force_cats)  # noqa: E731
            f["lobatto3_extra_node_total"] = (tot(l3) - tot(mid)) / sum(nve["breakdown"].get(k) or 0.0
                                                                       for k in ("Pair", "Bond"))
            f["bare_eval_category"] = bare_cat
        for q, qkey in (("midpoint", "midpoint"), ("lobatto 3", "lobatto3")):
            for vname, vkey in ASYNC_VARIANTS:
                key = qkey + vkey
                # against the synchronous run of the same input (neigh_modify
                # every 50 too) where there is one, else the default one
                sid = cfg_id(scene, f"pe_jump {q}{vname}")
                if sid not in med:
                    sid = cfg_id(scene, f"pe_jump {q}")
                aid = cfg_id(scene, f"async 50 {q}{vname}")
                s, a = med.get(sid), med.get(aid)
                if s and a and s["evals"] and a["evals"]:
                    er = a["evals"] / s["evals"]
                    f[f"async_{key}_eval_ratio"] = er
                    f[f"async_{key}_wall_ratio"] = a["loop_time"] / s["loop_time"]
                    f[f"async_{key}_wall_per_eval"] = (a["loop_time"] / s["loop_time"]) / er
                    f[f"async_{key}_speedup"] = s["loop_time"] / a["loop_time"]
                    # the same from each repetition's pair of runs (interleaved,
                    # so a drift of the machine's speed cancels), median
                    pairs = zip(runs[aid]["reps"], runs[sid]["reps"])
                    f[f"async_{key}_wall_per_eval_paired"] = B.median(
                        [(ra["loop_time"] / rs["loop_time"]) / er for ra, rs in pairs])
        if f:
            fig[scene] = f
    targets = []
    for key, desc, op, lim in TARGETS:
        scene, k = key.split(".")
        val = fig.get(scene, {}).get(k)
        met = None if val is None else (val <= lim if op == "<=" else val >= lim)
        targets.append({"key": key, "desc": desc, "op": op, "limit": lim, "value": val, "met": met})
    return {"table": table, "figures": fig, "targets": targets}


# ------------------------------------------------------------------ measure

def measure(args):
    global WORK_LABEL
    c = dict(QUICK if args.quick else FULL)
    lmp = os.path.abspath(args.lmp)
    libdir = os.path.abspath(args.libdir or os.path.dirname(lmp))
    B.LMP = lmp
    os.environ["LD_LIBRARY_PATH"] = libdir + (":" + os.environ["LD_LIBRARY_PATH"]
                                              if os.environ.get("LD_LIBRARY_PATH") else "")
    WORK_LABEL = os.path.join(WORK, args.label)
    os.makedirs(WORK_LABEL, exist_ok=True)
    scenes = args.scenes.split(",")
    binary = {"lmp": file_info(lmp), "liblammps": file_info(os.path.join(libdir, "liblammps.so.0")),
              "libdir": libdir}
    try:
        head = subprocess.run(["git", "-C", B.ROOT, "log", "-1", "--format=%h %s"], capture_output=True,
                              text=True).stdout.strip()
        dirty = bool(subprocess.run(["git", "-C", B.ROOT, "status", "--porcelain", "src"], capture_output=True,
                                    text=True).stdout.strip())
    except Exception:
        head, dirty = "?", None
    sc = prepare(c, scenes)
    configs = [cf for cf in CONFIGS if cf[0] in scenes]
    log(f"label {args.label}: {len(configs)} configurations x {args.reps} repetitions, binary {lmp}")
    runs = {cfg_id(s, n): {"scene": s, "name": n, "integrator": i, "quad": q, "K": K,
                           "vars": (cf[5] if len(cf) > 5 else {}), "reps": []}
            for cf in configs for (s, n, i, q, K) in [cf[:5]]}
    t0 = time.time()
    for rep in range(args.reps):
        for cf in configs:
            (s, n, i, q, K), extra = cf[:5], (cf[5] if len(cf) > 5 else None)
            r = run_one(sc[s], s, n, i, q, K, rep, extra)
            runs[cfg_id(s, n)]["reps"].append(r)
            bd = r["breakdown"]
            log(f"  {s:8s} {n:20s} rep {rep}: loop {r['loop_time']:8.3f} s  Modify {bd.get('Modify') or 0:7.3f}"
                f"  evals {r['evals']}  CPU {r['cpu_use']}%  load {r['loadavg_start'].split()[0]}")
    for v in runs.values():
        v["median"] = summarize(v["reps"])
    res = {"label": args.label, "time": time.strftime("%Y-%m-%d %H:%M:%S"), "quick": args.quick,
           "reps": args.reps, "settings": c, "binary": binary, "git_head": head, "git_src_dirty": dirty,
           "host": {"uname": " ".join(platform.uname()), "ncpu": os.cpu_count()},
           "duration_s": round(time.time() - t0, 1),
           "scenes": {k: {"info": v["info"], "h": v["h"], "steps": v["steps"], "input": os.path.relpath(v["inp"], B.ROOT),
                          "vars": v["base"]} for k, v in sc.items()},
           "runs": runs}
    res.update(derive(runs))
    out = os.path.join(RESULTS, f"{args.label}.json")
    B.save_json(out, res)
    log(f"wrote {out}")
    for t in res["targets"]:
        v = "n/a" if t["value"] is None else f"{t['value']:.3f}"
        log(f"  {t['desc']:80s} {v:>9s} {t['op']} {t['limit']:g}  {'met' if t['met'] else 'MISSED' if t['met'] is not None else ''}")


# ------------------------------------------------------------------ report

def fmt(x, nd=3):
    if x is None:
        return "n/a"
    if isinstance(x, float) and x != x:
        return "n/a"
    return f"{x:.{nd}f}"


def report(args):
    labels = args.labels.split(",") if args.labels else None
    data = {}
    if os.path.isdir(RESULTS):
        for fn in sorted(os.listdir(RESULTS)):
            if fn.endswith(".json"):
                lab = fn[:-5]
                if labels is None or lab in labels:
                    data[lab] = B.load_json(os.path.join(RESULTS, fn))
    if labels:
        data = {k: data[k] for k in labels if k in data}
    # "before" first, then the others in time order
    order = sorted(data, key=lambda k: (k != "before", data[k].get("time", "")))
    L = []
    L.append("# PE-JUMP cost targets\n")
    L.append("Generated by `bench/cost/cost.py --report` from `bench/results/cost/*.json` "
             "(see `bench/cost/README.md`). One MPI rank; medians of interleaved repetitions.\n")
    L.append("| label | date | binary (lmp / liblammps.so.0) | git HEAD | reps | quick | 1-min load at run starts (min-max) |")
    L.append("|---|---|---|---|---|---|---|")
    for lab in order:
        d = data[lab]
        b = d.get("binary", {})
        loads = [float(r["loadavg_start"].split()[0]) for v in d["runs"].values() for r in v["reps"]]
        L.append(f"| {lab} | {d.get('time')} | `{b.get('lmp', {}).get('path')}` ({b.get('liblammps', {}).get('mtime', '?')}, "
                 f"sha256 {b.get('liblammps', {}).get('sha256', '?')}) | {(d.get('git_head') or '?').split()[0]}"
                 f"{' (src dirty)' if d.get('git_src_dirty') else ''} | {d.get('reps')} | {d.get('quick')} | "
                 f"{min(loads):.2f}-{max(loads):.2f} |")
    L.append("")
    L.append("## Targets\n")
    L.append("| figure | target | " + " | ".join(order) + " |")
    L.append("|---|---|" + "---|" * len(order))
    for key, desc, op, lim in TARGETS:
        cells = []
        for lab in order:
            t = next((t for t in data[lab]["targets"] if t["key"] == key), None)
            if t is None or t["value"] is None:
                cells.append("n/a")
            else:
                cells.append(f"{fmt(t['value'], 1 if 'mem' in key else 3)} {'met' if t['met'] else '**missed**'}")
        L.append(f"| {desc} | {op} {lim:g} | " + " | ".join(cells) + " |")
    L.append("")
    L.append("Other figures:\n")
    L.append("| figure | " + " | ".join(order) + " |")
    L.append("|---|" + "---|" * len(order))
    # (from the stored runs: figures added to derive() later show for older labels too)
    figures = {lab: derive(data[lab]["runs"])["figures"] for lab in order}
    for key, desc in EXTRA:
        scene, k = key.split(".")
        cells = [fmt(figures[lab].get(scene, {}).get(k), 1 if "mem" in key else 3) for lab in order]
        L.append(f"| {desc} | " + " | ".join(cells) + " |")
    L.append("")
    for scene, title in SCENE_TITLE.items():
        if not any(scene in data[lab].get("scenes", {}) for lab in order):
            continue
        L.append(f"## {title}\n")
        for lab in order:
            s = data[lab].get("scenes", {}).get(scene)
            if s:
                L.append(f"* {lab}: {s['input']}, {s['steps']} steps, h = {s['h']:g}, info {s['info']}")
        L.append("")
        L.append("| label | configuration | loop [s] | wall/nve | evals/step | Modify [ns/atom-step] | Modify/nve | "
                 "Pair [s] | Bond [s] | Neigh [s] | Comm [s] | Output [s] | Modify [s] | Other [s] | "
                 "memory [B/atom] | - nve | max rel. var. of H / H~ | CPU |")
        L.append("|" + "---|" * 18)
        for lab in order:
            d = data[lab]
            for cid, v in d["runs"].items():
                if v["scene"] != scene:
                    continue
                m, t = v["median"], d["table"][cid]
                bd = m["breakdown"]
                L.append(f"| {lab} | {v['name']} | {fmt(m['loop_time'])} | {fmt(t.get('wall_ratio_nve'))} | "
                         f"{fmt(t['evals_per_step'], 4)} | {fmt(t['modify_ns_atom_step'], 1)} | "
                         f"{fmt(t.get('modify_ratio_nve'))} | "
                         + " | ".join(fmt(bd.get(k)) for k in CATS)
                         + f" | {fmt(t['mem_bytes_atom'], 0)} | {fmt(t.get('mem_extra_bytes_atom'), 0)} | "
                         f"{'%.1e' % m['energy_rel_var'] if m.get('energy_rel_var') is not None else 'n/a'} | "
                         f"{fmt(m.get('cpu_use'), 1)}% |")
        L.append("")
    L.append("Figures: Modify per atom-step = Modify time / (atoms x steps); extra node = (Modify of lobatto 3 - "
             "Modify of midpoint) / (Bond time of fix nve, Pair time for LJ): the cost of the one extra quadrature "
             "node per step against one bare force evaluation; the 'all timer categories' variant takes "
             "Pair + Bond + Comm + Modify instead of Modify (it does not depend on whether LAMMPS books the "
             "fix's own force evaluations under Modify or under Pair/Bond); async wall/eval = (wall async / "
             "wall sync) / (evals async / evals sync), at the same fine step, from the medians (the targets) or, "
             "'median of the repetitions' ratios', from each repetition's async and sync run (run one after "
             "the other) and then the median; speed-up = wall sync / wall async. "
             "Memory: LAMMPS' 'Per MPI rank memory allocation' (avg) per atom.\n")
    text = "\n".join(L)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
        print(f"wrote {args.out}")
    else:
        print(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--label", help="name of this measurement (before, after, ...)")
    ap.add_argument("--lmp", default=os.path.join(B.ROOT, "build", "lmp"), help="LAMMPS binary")
    ap.add_argument("--libdir", default=None, help="LD_LIBRARY_PATH for it (default: the binary's directory)")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="small systems and few steps (test of the script)")
    ap.add_argument("--scenes", default="bonded,lj,springs")
    ap.add_argument("--report", action="store_true", help="write the markdown comparison of all labels")
    ap.add_argument("--labels", default=None, help="--report: only these labels (comma separated)")
    ap.add_argument("--out", default=None, help="--report: output file (default stdout)")
    args = ap.parse_args()
    if args.report:
        report(args)
        return
    if not args.label:
        ap.error("--label is required (or --report)")
    measure(args)


if __name__ == "__main__":
    main()
