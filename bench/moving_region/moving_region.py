#!/usr/bin/python3
"""Moving fast regions: fix pe_jump/async against what a LAMMPS user would
otherwise run, at the same accuracy, in three scenes whose fine-step region
moves (a running crack, an impact on a bonded lattice, a collision cascade).

    /usr/bin/python3 bench/moving_region/moving_region.py [--lmp build/lmp]
        [--reps 3] [--nice 5] [--scenes crack,impact,cascade] [--quick]
    /usr/bin/python3 bench/moving_region/moving_region.py --report

(bench/moving_region/run.sh runs the first line.) Every run is one MPI
rank, one at a time, with one binary: --lmp and the liblammps.so.0 beside
it are copied to bench/work/moving_region/bin/ at the start and that copy
runs everything. Logs, dumps and the copy go to bench/work/moving_region/
(not kept in git); the results to bench/results/moving_region/report.json
and report.md (--report writes report.md again from the json).

Scenes and methods (inputs in.crack, in.impact, in.cascade beside this
script; their heads describe them):

  crack    running crack in a 2d LJ solid (LAMMPS' examples/crack, closed:
           pre-strain, frozen boundary rows), 8141 atoms, t = 0 .. 12.
  impact   7 atoms hit a bonded 2d triangular lattice (10000 atoms, 30000
           harmonic bonds) at 1.33 times the sound speed, t = 0 .. 25.
           For both: fix nve at a scan of time steps (its largest stable
           step and its best passing one), fix pe_jump at a shorter scan,
           fix pe_jump/async with a static fast group around the place
           where the action starts, a dynamic fast group (`group dynamic`
           following the crack tip / the projectile), a kinetic-energy
           group (impact) and the keyword `fast auto TOL`.
  cascade  collision cascade in an LJ fcc crystal (4000 atoms, PKA of
           2000 epsilon), t = 0 .. 1. Compared with fix nve + fix dt/reset
           (xmax 0.013 .. 0.1, dtmax 0.005), which is what cascades are run
           with; fix pe_jump + dt/reset xmax 0.013; pe_jump/async with a
           static sphere, a dynamic sphere around the PKA and fast auto.

Reference of every scene: fix nve at a small fixed step (crack h/4 =
0.00075, impact h/4 = 0.0025, cascade 5e-5), run once. For the cascade it
also writes the perfect lattice for the Wigner-Seitz defect count.

Time steps: the `timestep` of fix pe_jump/async is the COARSE step h_S
(one LAMMPS step = one coarse step); the inputs take the fine step
h_F = -var h and K and set timestep K h. The script checks the log line of
the fix ("coarse step h_S = ... fine step h_F = ...") of every async run
and stops if it does not match (a binary with the older meaning).

Status: a run is unstable if it stops with a LAMMPS error (lost atoms,
missing bond atoms, the stability guard of pe_jump(/async)), if its energy
is not finite, or if max |E - E(0)| exceeds the scene's energy scale
(blown up). Unstable runs are run once.

Accuracy (analyze.py): max over the thermo lines of |E(t) - E(0)| / scale
(scale |E(0)| for crack, the impact energy for impact, Epka for the
cascade), RMS and max |r - r_ref| of the final unwrapped positions against
the reference, and for the cascade the Wigner-Seitz vacancies and
interstitials. TOLERANCE below, the same for every method of a scene.

Cost: LAMMPS' Loop time (median over --reps rounds; a round runs every
stable configuration once, interleaved, so a change of the load affects all
alike), force evaluations (fix nve: 1 per step; pe_jump(/async): thermo
f_int[5] at the end, which counts the one extra evaluation at each thermo
step), wall per evaluation. /proc/loadavg is recorded before every run.

Comparisons (per scene): "nve best" = the passing fix nve run (cascade:
fix nve + dt/reset) with the smallest median wall time. speed-up =
wall(nve best) / wall(method); evaluation ratio = evals(nve best) /
evals(method); wall/eval ratio = evaluation ratio / speed-up (1: every
evaluation saved is wall time saved; above 1: an evaluation of the method
costs more wall time). "matched" = the fastest fix nve run (cascade: nve +
dt/reset) that is at least as accurate as the method on every measure of
the tolerance, whatever the tolerance, and the speed-up against it.
"""
import argparse
import datetime
import hashlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import analyze as A  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
WORK = os.path.join(ROOT, "bench", "work", "moving_region")
RESULTS = os.path.join(ROOT, "bench", "results", "moving_region")

# The tolerance of each scene, the same for every method (see the README
# and report.md for why these values):
#   dE    max |E(t) - E(0)| / scale over the thermo lines
#   rms   RMS |r - r_ref| of the final positions (length units)
#   defects  the same vacancy and interstitial counts as the reference
TOLERANCE = {
    "crack": {"dE": 4e-4, "rms": 0.1},
    "impact": {"dE": 1e-2, "max": 1e-2},
    "cascade": {"dE": 1e-2, "rms": 0.05, "defects": True},
}

# async entries: (label, -var settings, [(h_F, K), ...])
SCENES = {
    "crack": {
        "input": "in.crack", "escale": "E0", "scale_name": "|E(0)|", "h": 0.003, "T": 12.0,
        "ref": {"integrator": "nve", "h": 0.00075},
        "nve": [0.003, 0.005, 0.0075, 0.01, 0.012, 0.015, 0.02, 0.025, 0.03, 0.0375, 0.05, 0.06,
                0.075],
        "sync": [0.003, 0.0075, 0.015, 0.03, 0.05],
        "async": [
            ("static R10", {"fast": "static", "R": 10.0}, [(0.003, 5), (0.005, 3), (0.003, 10)]),
            ("band R10", {"fast": "band", "R": 10.0}, [(0.003, 10)]),
            ("dynamic R10 every 50", {"fast": "dynamic", "R": 10.0, "every": 50},
             [(0.003, 5), (0.003, 10)]),
            ("fast auto 0.02", {"fast": "keyword", "tol": 0.02}, [(0.003, 10)]),
            ("fast auto 0.1", {"fast": "keyword", "tol": 0.1}, [(0.003, 10)]),
            ("fast auto 0.2 buffer 1 within 1.2",
             {"fast": "keyword", "tol": 0.2, "buffer": 1, "reach": 1.2}, [(0.003, 10)]),
        ],
    },
    "impact": {
        "input": "in.impact", "escale": "E0", "scale_name": "E(0) (the impact energy)", "h": 0.01,
        "T": 25.0, "ref": {"integrator": "nve", "h": 0.0025},
        "nve": [0.01, 0.02, 0.025, 0.05, 1 / 16, 1 / 12, 0.1, 0.125, 0.2, 0.25, 0.5],
        "sync": [0.01, 0.025, 0.05, 0.1, 0.2],
        "async": [
            ("static R8", {"fast": "static", "R": 8.0},
             [(0.01, 5), (0.01, 10), (0.02, 5), (0.025, 5), (0.01, 20)]),
            ("dynamic R8 every 50", {"fast": "dynamic", "R": 8.0, "every": 50}, [(0.01, 10)]),
            ("kinetic energy > 0.01 every 10", {"fast": "auto", "kthr": 0.01, "every": 10},
             [(0.01, 10)]),
            ("fast auto 0.02", {"fast": "keyword", "tol": 0.02}, [(0.01, 10)]),
            ("fast auto 0.2 buffer 1 within 1.2",
             {"fast": "keyword", "tol": 0.2, "buffer": 1, "reach": 1.2}, [(0.01, 10)]),
        ],
    },
    "cascade": {
        "input": "in.cascade", "escale": "Epka", "scale_name": "Epka", "h": 2e-4, "T": 1.0,
        "ref": {"integrator": "nve", "h": 5e-5, "sites": "yes"},
        "dtreset": [("nve", 0.013), ("nve", 0.018), ("nve", 0.025), ("nve", 0.035), ("nve", 0.05),
                    ("nve", 0.07), ("nve", 0.1), ("sync", 0.013), ("sync", 0.05)],
        "async": [
            ("static R4", {"fast": "static", "R": 4.0}, [(2e-4, 10)]),
            # at h_S = 0.005 atoms outside the sphere move more than half the
            # default skin 0.3 in a coarse step: the fix stops; skin 0.6
            ("static R4 skin 0.6", {"fast": "static", "R": 4.0, "skin": 0.6}, [(5e-4, 10)]),
            ("dynamic R4 every 10", {"fast": "dynamic", "R": 4.0, "every": 10}, [(2e-4, 10)]),
            ("fast auto 0.02", {"fast": "keyword", "tol": 0.02}, [(2e-4, 10)]),
            ("fast auto 0.05 buffer 1 within 1.2",
             {"fast": "keyword", "tol": 0.05, "buffer": 1, "reach": 1.2}, [(2e-4, 10), (5e-4, 10)]),
        ],
    },
}


def g(x):
    return "%.4g" % x


def exact(x):
    return "%.17g" % x


def impact_skin(h, vp=2.0):
    """fix pe_jump stops when an atom moves more than half the skin in a
    step: the projectile moves vp h; skin >= 2.5 vp h (default 0.3)."""
    need = 2.5 * vp * h
    return max(0.3, round(need + 0.05, 1))


def plan(scene, quick=False):
    """The runs of a scene: dicts with tag, label, family, vars, h, K."""
    S = SCENES[scene]
    runs = []
    ref = dict(S["ref"])
    runs.append({"tag": "ref", "label": f"fix nve h = {g(ref['h'])}", "family": "ref",
                 "vars": ref, "h": ref["h"], "K": None})
    if "nve" in S:
        for h in S["nve"]:
            runs.append({"tag": f"nve-h{g(h)}", "label": f"fix nve h = {g(h)}", "family": "nve",
                         "vars": {"integrator": "nve", "h": exact(h)}, "h": h, "K": None})
        for h in S["sync"]:
            v = {"integrator": "sync", "h": exact(h)}
            if scene == "impact" and impact_skin(h) > 0.3:
                v["skin"] = impact_skin(h)
            runs.append({"tag": f"sync-h{g(h)}", "label": f"fix pe_jump h = {g(h)}"
                         + (f" (skin {g(v['skin'])})" if "skin" in v else ""),
                         "family": "sync", "vars": v, "h": h, "K": None})
    for integ, xmax in S.get("dtreset", []):
        fam = "dtreset" if integ == "nve" else "sync-dtreset"
        name = "fix nve" if integ == "nve" else "fix pe_jump"
        runs.append({"tag": f"{integ}-dtreset-x{g(xmax)}",
                     "label": f"{name} + dt/reset xmax {g(xmax)}", "family": fam,
                     "vars": {"integrator": integ, "xmax": xmax}, "h": None, "K": None,
                     "xmax": xmax})
    for label, v, steps in S["async"]:
        for hF, K in steps:
            vv = {"integrator": "async", "h": exact(hF), "K": K}
            vv.update(v)
            slug = label.split(" within")[0].replace(" ", "-").replace(">", "gt")
            runs.append({"tag": f"async-{slug}-K{K}-hF{g(hF)}",
                         "label": f"pe_jump/async K {K} {label}", "family": "async",
                         "vars": vv, "h": hF, "K": K, "h_S": K * hF})
    if quick:
        runs = [r for r in runs if r["family"] in ("ref", "async") or r is runs[1]]
    return runs


def loadavg():
    try:
        with open("/proc/loadavg") as f:
            return f.read().strip()
    except OSError:
        return ""


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def source_name(path):
    """the binary's path relative to the repository, or only its name"""
    rel = os.path.relpath(path, ROOT)
    return rel if not rel.startswith("..") else os.path.basename(path) + " (outside the repository)"


def snapshot_binary(lmp):
    """Copy lmp and the liblammps.so.0 beside it to WORK/bin."""
    src = os.path.abspath(lmp)
    dest = os.path.join(WORK, "bin")
    os.makedirs(dest, exist_ok=True)
    info = {"source": source_name(src)}
    shutil.copy2(src, os.path.join(dest, "lmp"))
    info["lmp_sha256"] = sha256(src)
    lib = os.path.join(os.path.dirname(src), "liblammps.so.0")
    if os.path.exists(lib):
        shutil.copy2(lib, os.path.join(dest, "liblammps.so.0"))
        info["liblammps_sha256"] = sha256(lib)
        info["liblammps_mtime"] = time.strftime("%Y-%m-%d %H:%M:%S",
                                                time.localtime(os.path.getmtime(lib)))
    return os.path.join(dest, "lmp"), info


def lammps_version(logpath):
    try:
        with open(logpath, errors="replace") as f:
            first = f.readline().strip()
        return first
    except OSError:
        return None


def git_head():
    try:
        head = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True).stdout.strip()
        return head
    except OSError:
        return None


def cpu_stat():
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    idle = v[3] + (v[4] if len(v) > 4 else 0)
    return sum(v[:8]), idle


def busy_cores(interval=0.5):
    """Cores used by other processes over `interval` seconds (none of our
    runs is active while this is measured)."""
    t0, i0 = cpu_stat()
    time.sleep(interval)
    t1, i1 = cpu_stat()
    dt = max(t1 - t0, 1)
    return (dt - (i1 - i0)) / dt * (os.cpu_count() or 1)


class Runner:
    def __init__(self, lmp, nice, max_others=1.3, max_wait=60.0):
        self.lmp = lmp
        self.nice = nice
        self.max_others = max_others
        self.max_wait = max_wait
        self.env = dict(os.environ)
        self.env["LD_LIBRARY_PATH"] = os.path.dirname(lmp) + ":" + self.env.get("LD_LIBRARY_PATH", "")
        self.env["OMP_NUM_THREADS"] = "1"

    def run(self, scene, r, rnd):
        wd = os.path.join(WORK, scene)
        os.makedirs(wd, exist_ok=True)
        name = r["tag"] if rnd == 1 else f"{r['tag']}.r{rnd}"
        log = f"log.{scene}-{name}"
        cmd = (["nice", "-n", str(self.nice)] if self.nice else []) + [
            self.lmp, "-nocite", "-screen", "none", "-log", log,
            "-in", os.path.join(HERE, SCENES[scene]["input"])]
        for k, v in r["vars"].items():
            cmd += ["-var", k, str(v)]
        cmd += ["-var", "name", name]
        # wait (at most max_wait s) until the other processes leave a core
        waited, busy = 0.0, busy_cores()
        while busy > self.max_others and waited < self.max_wait:
            time.sleep(4.0)
            waited += 5.0
            busy = busy_cores()
        load = loadavg()
        t0 = time.time()
        try:
            p = subprocess.run(cmd, cwd=wd, env=self.env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE, text=True, timeout=1800)
            rc = p.returncode
        except subprocess.TimeoutExpired:
            rc = "timeout"
        wall = time.time() - t0
        dump = os.path.join(wd, f"final.{scene}.{name}.dump")
        return {"round": rnd, "log": os.path.join(wd, log), "dump": dump, "returncode": rc,
                "loadavg": load, "load1": float(load.split()[0]) if load else None,
                "process_wall": wall, "others_busy": round(busy, 2), "waited": waited,
                "cmd": " ".join(["lmp"] + cmd[cmd.index(self.lmp) + 1:])}


def classify(m, scale_limit=1.0):
    """ok / unstable / error (an error that is not an instability)."""
    err = m.get("error")
    if err and "more than half the neighbor skin" in err:
        return "stopped", err
    if err:
        unstable_words = ("Lost atoms", "Bond atoms", "Bond/react", "momentum jumps grew",
                          "Out of range atoms", "neighbor bins", "Non-numeric", "Neighbor list overflow",
                          "Too many", "unstable", "NaN", "nan")
        if any(w in err for w in unstable_words):
            return "unstable", err
        return "error", err
    if m.get("loop") is None or "dE" not in m:
        return "error", "no Loop time or no thermo output"
    if not m.get("finite", True):
        return "unstable", "energy not finite"
    if m["dE"] > scale_limit:
        return "unstable", f"blew up: max |E - E(0)| = {m['dE']:.3g} x scale"
    return "ok", None


def judge(scene, m, ref):
    """Pass / fail against the scene's tolerance; the list of failed measures."""
    tol = TOLERANCE[scene]
    fails = [k for k in ("dE", "rms", "max") if k in tol and (k not in m or m[k] > tol[k])]
    if tol.get("defects") and (m.get("vac"), m.get("inter")) != (ref.get("vac"), ref.get("inter")):
        fails.append("defects")
    return not fails, fails


def as_accurate(c, m, ref, scene):
    """comparator run c at least as accurate as run m on every measure of
    the tolerance."""
    tol = TOLERANCE[scene]
    for k in ("dE", "rms", "max"):
        if k in tol and c.get(k, 1e99) > m.get(k, 1e99):
            return False
    if tol.get("defects"):
        dc = abs(c.get("vac", 1 << 30) - ref.get("vac", 0)) + abs(c.get("inter", 1 << 30) - ref.get("inter", 0))
        dm = abs(m.get("vac", 1 << 30) - ref.get("vac", 0)) + abs(m.get("inter", 1 << 30) - ref.get("inter", 0))
        if dc > dm:
            return False
    return True


def measure(args):
    lmp, binfo = snapshot_binary(args.lmp)
    runner = Runner(lmp, args.nice, args.max_others, args.max_wait)
    scenes = args.scenes.split(",")
    started = time.time()
    res = {"meta": {"started": datetime.datetime.now().isoformat(timespec="seconds"),
                    "binary": binfo, "git_head": git_head(), "reps": args.reps, "nice": args.nice,
                    "ranks": 1, "nproc": os.cpu_count(), "tolerance": TOLERANCE,
                    "max_others": args.max_others, "max_wait": args.max_wait,
                    "loadavg_start": loadavg(), "quick": args.quick},
           "scenes": {}}
    plans = {s: plan(s, args.quick) for s in scenes}
    recs = {s: {r["tag"]: dict(r, rounds=[]) for r in plans[s]} for s in scenes}
    refs = {}
    # round 1: the references first, then every run; the accuracy is taken here
    for s in scenes:
        r = recs[s]["ref"]
        print(f"[{s}] {r['label']}", flush=True)
        rr = runner.run(s, r, 1)
        r["rounds"].append(rr)
        ref_dump = A.read_dump(rr["dump"])
        sites = None
        if s == "cascade":
            sites = A.read_dump(os.path.join(WORK, s, "sites.cascade.dump"))
        m = A.measures(rr["log"], ref_dump, None, sites, None, SCENES[s]["escale"])
        ref_vac = A.wigner_seitz(sites, ref_dump)[3] if sites is not None else None
        r.update({k: v for k, v in m.items() if k != "cpu"})
        r["status"] = classify(m)[0]
        res["meta"]["lammps"] = lammps_version(rr["log"])
        refs[s] = {"dump": ref_dump, "sites": sites, "vac_set": ref_vac, "rec": r}
    for rnd in range(1, args.reps + 1):
        for s in scenes:
            for tag, r in recs[s].items():
                if r["family"] == "ref" or (rnd > 1 and r["status"] != "ok"):
                    continue
                rr = runner.run(s, r, rnd)
                r["rounds"].append(rr)
                m = A.measures(rr["log"], None, None, None, None, SCENES[s]["escale"])
                rr.update(loop=m.get("loop"), loop_cpu=m.get("loop_cpu"), evals=m.get("evals"),
                          cpu=m.get("cpu"))
                if rnd == 1:
                    dump = A.read_dump(rr["dump"]) if os.path.exists(rr["dump"]) else None
                    R = refs[s]
                    m = A.measures(rr["log"], dump, R["dump"] if dump is not None else None,
                                   R["sites"], R["vac_set"], SCENES[s]["escale"])
                    r.update({k: v for k, v in m.items() if k != "cpu"})
                    r["status"], r["why"] = classify(m)
                    if r["status"] == "ok" and r["family"] == "async":
                        hl = m.get("hline")
                        want = r["K"] * r["h"]
                        if not hl or abs(hl["h_S"] - want) > 1e-9 * want or hl["K"] != r["K"]:
                            sys.exit(f"{s} {tag}: the log does not state h_S = {want} "
                                     f"(found {hl}); this script needs a build in which the "
                                     "timestep of pe_jump/async is the coarse step")
                else:
                    if rr.get("evals") != r.get("evals"):
                        r.setdefault("notes", []).append(
                            f"round {rnd}: evaluations {rr.get('evals')} differ from round 1")
                    if os.path.exists(rr["dump"]):
                        os.remove(rr["dump"])
                print(f"[{s}] round {rnd} {r['label']}: {r['status']}"
                      + (f", loop {rr['loop']:.3f} s" if rr.get("loop") else "")
                      + f", load {rr['loadavg'].split()[0] if rr['loadavg'] else '?'}", flush=True)
    res["meta"]["finished"] = datetime.datetime.now().isoformat(timespec="seconds")
    res["meta"]["duration_s"] = time.time() - started
    res["meta"]["loadavg_end"] = loadavg()
    for s in scenes:
        res["scenes"][s] = summarize(s, recs[s])
    os.makedirs(RESULTS, exist_ok=True)
    out = args.out or os.path.join(RESULTS, "report.json")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        json.dump(res, f, indent=1, default=float)
    md = markdown(res)
    with open(os.path.splitext(out)[0] + ".md", "w") as f:
        f.write(md)
    print(md)


def summarize(scene, recs):
    ref = recs["ref"]
    runs = [r for t, r in recs.items() if t != "ref"]
    for r in runs:
        for k in ("speedup", "speedup_cpu", "eval_ratio", "wall_per_eval_ratio", "matched",
                  "matched_speedup", "matched_speedup_cpu"):
            r.pop(k, None)
        loops = [x["loop"] for x in r["rounds"] if x.get("loop") is not None]
        r["wall_all"] = loops
        r["wall_median"] = statistics.median(loops) if loops else None
        cpus = [x["loop_cpu"] for x in r["rounds"] if x.get("loop_cpu") is not None]
        r["cpu_all"] = cpus
        r["cpu_median"] = statistics.median(cpus) if cpus else None
        r["busy_all"] = [x.get("others_busy") for x in r["rounds"]]
        r["load1_all"] = [x["load1"] for x in r["rounds"]]
        if r["status"] == "ok":
            r["passed"], r["fails"] = judge(scene, r, ref)
            if r.get("evals"):
                r["ms_per_eval"] = 1e3 * r["wall_median"] / r["evals"]
        else:
            r["passed"], r["fails"] = False, [r["status"]]
    comp_family = "dtreset" if scene == "cascade" else "nve"
    comp = [r for r in runs if r["family"] == comp_family]
    stable = [r for r in comp if r["status"] == "ok"]
    passing = [r for r in stable if r["passed"]]
    best = min(passing, key=lambda r: r["wall_median"]) if passing else None
    key = "xmax" if scene == "cascade" else "h"
    summ = {"comparator_family": comp_family,
            "largest_stable": max((r[key] for r in stable), default=None),
            "smallest_unstable": min((r[key] for r in comp if r["status"] != "ok"), default=None),
            "best": best["tag"] if best else None}
    for r in runs:
        if r["status"] != "ok":
            continue
        if best is not None:
            r["speedup"] = best["wall_median"] / r["wall_median"]
            if best.get("cpu_median") and r.get("cpu_median"):
                r["speedup_cpu"] = best["cpu_median"] / r["cpu_median"]
            r["eval_ratio"] = best["evals"] / r["evals"]
            r["wall_per_eval_ratio"] = r["eval_ratio"] / r["speedup"]
        if r["family"] != comp_family:
            cands = [c for c in stable if as_accurate(c, r, ref, scene)]
            if cands:
                c = min(cands, key=lambda c: c["wall_median"])
                r["matched"] = c["tag"]
                r["matched_speedup"] = c["wall_median"] / r["wall_median"]
                if c.get("cpu_median") and r.get("cpu_median"):
                    r["matched_speedup_cpu"] = c["cpu_median"] / r["cpu_median"]
            else:
                r["matched"] = None
    fam = {}
    for r in runs:
        if r["status"] == "ok" and r["passed"] and r["family"] != comp_family:
            f = r["family"]
            if f not in fam or r["wall_median"] < fam[f]["wall_median"]:
                fam[f] = r
    summ["fastest_passing"] = {f: r["tag"] for f, r in fam.items()}
    loads = [x["load1"] for r in runs for x in r["rounds"] if x.get("load1") is not None]
    summ["load1_min"] = min(loads) if loads else None
    summ["load1_max"] = max(loads) if loads else None
    summ["load1_median"] = statistics.median(loads) if loads else None
    busy = [x["others_busy"] for r in runs for x in r["rounds"] if x.get("others_busy") is not None]
    summ["others_busy_max"] = max(busy) if busy else None
    summ["others_busy_median"] = statistics.median(busy) if busy else None
    summ["waited_s"] = sum(x.get("waited", 0) for r in runs for x in r["rounds"])
    for r in [ref] + runs:
        for x in r["rounds"]:
            x.pop("dump", None)
            if os.path.isabs(x.get("log", "")):
                x["log"] = os.path.relpath(x["log"], ROOT)
            if "cmd" in x:
                x["cmd"] = x["cmd"].replace(ROOT + os.sep, "")
    return {"tolerance": TOLERANCE[scene], "reference": ref, "runs": runs, "summary": summ,
            "scene": {k: v for k, v in SCENES[scene].items() if k not in ("async",)}}


# ------------------------------------------------------------------ report

def fm(x, f="%.3g"):
    return "-" if x is None else (f % x)


def step_cell(r):
    if r["family"] == "async":
        return f"h_F {g(r['h'])}, h_S {g(r['h_S'])}"
    if r.get("xmax") is not None:
        return f"xmax {g(r['xmax'])}"
    return f"h {g(r['h'])}"


SCENE_TITLES = {"crack": "crack (running crack, 2d LJ, 8141 atoms, t = 0 .. 12)",
                "impact": "impact (bonded 2d lattice, 10000 atoms, t = 0 .. 25)",
                "cascade": "cascade (LJ fcc, 4000 atoms, PKA 2000 epsilon, t = 0 .. 1)"}


def tol_text(scene, S):
    t = TOLERANCE[scene]
    parts = [f"max |E(t) - E(0)| / {S['scene']['scale_name']} <= {g(t['dE'])}"]
    if "rms" in t:
        parts.append(f"RMS |r - r_ref| <= {g(t['rms'])}")
    if "max" in t:
        parts.append(f"max |r - r_ref| <= {g(t['max'])}")
    if t.get("defects"):
        parts.append("the reference's Wigner-Seitz vacancy and interstitial counts")
    return " and ".join(parts)


def markdown(res):
    M = res["meta"]
    L = ["# Moving fast regions: pe_jump/async against fix nve at the same accuracy", "",
         "Written by `bench/moving_region/moving_region.py` (the command and what every column "
         "means: `bench/moving_region/README.md`). Do not edit; run it again.", "",
         f"* run {M['started']} .. {M['finished']} ({M['duration_s'] / 60:.1f} min), git {M['git_head']}, "
         f"{M['ranks']} MPI rank per run, one run at a time, `nice -n {M['nice']}`, "
         f"median of {M['reps']} interleaved rounds (unstable runs once)",
         f"* binary: {M['binary']['source']} (lmp sha256 {M['binary'].get('lmp_sha256', '?')[:12]}, "
         f"liblammps.so.0 sha256 {M['binary'].get('liblammps_sha256', '?')[:12]}, "
         f"built {M['binary'].get('liblammps_mtime', '?')}), {M.get('lammps', '')}",
         f"* machine: {M['nproc']} cores shared with other work; /proc/loadavg at the start "
         f"`{M['loadavg_start']}`, at the end `{M['loadavg_end']}`; the 1-minute load before "
         "each run is in the tables' last column and in report.json", ""]
    if M.get("quick"):
        L += ["**Quick run (test of the script): not the measurement.**", ""]
    L += ["Columns: wall = LAMMPS Loop time, median (min .. max over the rounds); CPU = the "
          "median of Loop time x \"% CPU use\" (LAMMPS' own line; less sensitive to other "
          "processes); evals = force evaluations (fix nve: 1 per step; pe_jump(/async): f_int[5], "
          "with the extra evaluation of each thermo step); ms/eval = wall per evaluation; "
          "dE = max |E(t) - E(0)| / scale over the thermo lines (E = pe + ke, what thermo etotal "
          "shows); dH~ = the same for the pseudo-energy pe + f_int that pe_jump(/async) conserves "
          "(= dE for fix nve); RMS / max dr = distance of the final unwrapped positions from the "
          "reference; fine-clock atoms = pe_jump/async's fast group (static) or the mean number "
          "of atoms on the fine clock at a coarse node (dynamic, fast auto) and the clock "
          "changes of the run; speed-up = wall of the scene's \"nve best\" (the passing fix nve "
          "run, for the cascade fix nve + dt/reset, with the smallest wall median) / wall of the "
          "method (> 1: faster than it); eval ratio = evaluations of nve best / evaluations of the "
          "method; wall/eval ratio = eval ratio / speed-up (> 1: the method's evaluations cost "
          "more wall time each than fix nve's); matched = the fastest fix nve (cascade: nve + "
          "dt/reset) run at least as accurate on every measure of the tolerance, whatever the "
          "tolerance, and the speed-up against it; load = 1-minute load average before the runs "
          "(min .. max); others' cores = cores used by other processes in the half second before a "
          "run.", ""]
    L += ["## In brief", ""]
    for s, S in res["scenes"].items():
        L += summary_lines(s, S)
    L += ["", "\"no clear difference\": the wall and CPU-time medians disagree on the sign, or "
          "the wall times of the repetitions overlap.", ""]
    for s, S in res["scenes"].items():
        L += scene_md(s, S)
    return "\n".join(L) + "\n"


def verdict(r, best):
    """faster / slower / no clear difference: the wall and CPU medians must
    agree, and the wall ranges of the repetitions must not overlap."""
    sw, sc = r.get("speedup"), r.get("speedup_cpu")
    if sw is None:
        return "-"
    apart = (max(r["wall_all"]) < min(best["wall_all"]) or min(r["wall_all"]) > max(best["wall_all"]))
    if sw > 1 and (sc is None or sc > 1) and apart:
        return "faster"
    if sw < 1 and (sc is None or sc < 1) and apart:
        return "slower"
    return "no clear difference"


def family_name(f):
    return {"sync": "fix pe_jump", "sync-dtreset": "fix pe_jump + dt/reset",
            "async": "fix pe_jump/async"}.get(f, f)


def summary_lines(s, S):
    sm = S["summary"]
    by = {r["tag"]: r for r in S["runs"]}
    best = by.get(sm["best"])
    cname = "fix nve + dt/reset" if s == "cascade" else "fix nve"
    if not best:
        return [f"* {s}: no {cname} run passes the tolerance"]
    L = [f"* **{s}**: {cname} best = {best['label']} ({best['wall_median']:.3f} s, "
         f"{best['evals']:.0f} evaluations)"]
    for f in ("sync", "sync-dtreset", "async"):
        tag = sm.get("fastest_passing", {}).get(f)
        if tag:
            r = by[tag]
            L.append(f"  * fastest passing {family_name(f)}: {r['label']} ({step_cell(r)}), "
                     f"{r['wall_median']:.3f} s: speed-up {r['speedup']:.2f}x (CPU time "
                     f"{fm(r.get('speedup_cpu'), '%.2fx')}), {r['evals']:.0f} evaluations "
                     f"(ratio {r['eval_ratio']:.2f}), wall/eval ratio {r['wall_per_eval_ratio']:.2f}: "
                     f"{verdict(r, best)}")
        elif f == "async":
            L.append("  * no fix pe_jump/async run passes the tolerance")
    return L


def scene_md(s, S):
    sm = S["summary"]
    ref = S["reference"]
    runs = S["runs"]
    by = {r["tag"]: r for r in runs}
    best = by.get(sm["best"])
    key = "xmax" if s == "cascade" else "h"
    cname = "fix nve + dt/reset" if s == "cascade" else "fix nve"
    L = [f"## {SCENE_TITLES[s]}", "",
         f"Tolerance (every method): {tol_text(s, S)}.", "",
         f"Reference: {ref['label']} ({ref['steps']} steps, dE {fm(ref.get('dE'), '%.2e')}"
         + (f", {ref.get('vac')} vacancies, {ref.get('inter')} interstitials" if 'vac' in ref else "")
         + f"). {cname}: largest stable {key} {fm(sm['largest_stable'], '%.4g')}, smallest unstable "
         f"{fm(sm['smallest_unstable'], '%.4g')} (of the scanned ones); best passing (\"nve best\"): "
         + (f"{best['label']}, {best['wall_median']:.3f} s, {best['evals']:.0f} evaluations."
            if best else "none (no speed-ups below)."), "",
         "Accuracy and cost:", ""]
    defects = s == "cascade"
    hdr = ["method", "step", "status", "wall (s)", "CPU (s)", "evals", "ms/eval", "dE", "dH~",
           "RMS dr", "max dr"] + (["vac / int"] if defects else []) + ["fine-clock atoms", "pass"]
    L += ["| " + " | ".join(hdr) + " |", "|" + "---|" * len(hdr)]
    for r in runs:
        if r["status"] != "ok":
            why = (r.get("why") or "").replace("|", "/")
            why = why.split(" (src/")[0][:110]
            cells = [r["label"], step_cell(r), f"{r['status']}: {why}", "-", "-",
                     fm(r.get("evals"), "%.0f") + " (at the stop)", "-", "-", "-", "-", "-"]
            cells += (["-"] if defects else []) + ["-", "fail"]
            L.append("| " + " | ".join(cells) + " |")
            continue
        wl = r["wall_all"]
        wall = (f"{r['wall_median']:.3f} ({min(wl):.3f} .. {max(wl):.3f})" if len(wl) > 1
                else f"{r['wall_median']:.3f}")
        fca = "-"
        if r["family"] == "async":
            fca = fm(r.get("fine_clock_atoms"), "%.0f")
            if r.get("clock_changes") is not None:
                fca += f" ({r['clock_changes']} changes)"
        passed = "pass" if r["passed"] else "fail (" + ", ".join(r["fails"]) + ")"
        if r is best:
            passed += ", nve best"
        cells = [r["label"], step_cell(r), "ok", wall, fm(r.get("cpu_median"), "%.3f"),
                 fm(r.get("evals"), "%.0f"), fm(r.get("ms_per_eval"), "%.3f"), fm(r["dE"], "%.2e"),
                 fm(r.get("dHt"), "%.2e"), fm(r.get("rms"), "%.2e"), fm(r.get("max"), "%.2e")]
        if defects:
            cells += [f"{r.get('vac')} / {r.get('inter')}"]
        cells += [fca, passed]
        L.append("| " + " | ".join(cells) + " |")
    L += ["", f"Against {cname} best (speed-up = its wall median / this one; CPU: the same with "
          "the CPU-time medians) and against the fastest " + cname + " run at least as accurate "
          "on every measure of the tolerance (\"matched\"):", ""]
    hdr = ["method", "step", "pass", "speed-up", "speed-up (CPU)", "eval ratio", "wall/eval ratio",
           "matched: " + cname + " run", "speed-up vs matched", "load (1 min)", "others' cores"]
    L += ["| " + " | ".join(hdr) + " |", "|" + "---|" * len(hdr)]
    for r in runs:
        loads = [x for x in r.get("load1_all", []) if x is not None]
        lo = f"{min(loads):.2f} .. {max(loads):.2f}" if loads else "-"
        busy = [x for x in r.get("busy_all", []) if x is not None]
        bz = f"{min(busy):.2f} .. {max(busy):.2f}" if busy else "-"
        if r["status"] != "ok":
            L.append("| " + " | ".join([r["label"], step_cell(r), r["status"]] + ["-"] * 6 + [lo, bz]) + " |")
            continue
        passed = "pass" if r["passed"] else "fail"
        mt, ms = "-", "-"
        if "matched" in r:
            if r["matched"]:
                mt = step_cell(by[r["matched"]])
                ms = f"{r['matched_speedup']:.2f}x (CPU {fm(r.get('matched_speedup_cpu'), '%.2fx')})"
            else:
                mt = "none as accurate"
        L.append("| " + " | ".join([r["label"], step_cell(r), passed, fm(r.get("speedup"), "%.2fx"),
                                    fm(r.get("speedup_cpu"), "%.2fx"), fm(r.get("eval_ratio"), "%.2f"),
                                    fm(r.get("wall_per_eval_ratio"), "%.2f"), mt, ms, lo, bz]) + " |")
    L.append("")
    L += summary_lines(s, S)
    notes = [f"{r['label']}: {n}" for r in runs for n in r.get("notes", [])]
    L += [f"* {n}" for n in notes]
    L += [f"* 1-minute load average before the runs: {fm(sm['load1_min'], '%.2f')} .. "
          f"{fm(sm['load1_max'], '%.2f')} (median {fm(sm['load1_median'], '%.2f')}); cores used by "
          f"other processes just before a run: median {fm(sm.get('others_busy_median'), '%.2f')}, "
          f"max {fm(sm.get('others_busy_max'), '%.2f')}; waited {sm.get('waited_s', 0):.0f} s for them", ""]
    return L


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lmp", default=os.environ.get("LMP", os.path.join(ROOT, "build", "lmp")),
                    help="LAMMPS binary (copied with the liblammps.so.0 beside it)")
    ap.add_argument("--reps", type=int, default=3, help="rounds (timing repetitions)")
    ap.add_argument("--nice", type=int, default=5, help="nice level of the runs (0: none)")
    ap.add_argument("--scenes", default="crack,impact,cascade")
    ap.add_argument("--max-others", type=float, default=1.3,
                    help="before each run wait until other processes use at most this many cores")
    ap.add_argument("--max-wait", type=float, default=60.0, help="... but at most this many seconds")
    ap.add_argument("--quick", action="store_true",
                    help="test of the script: one nve run per scene, the references, async, 1 round")
    ap.add_argument("--out", help="json path (default bench/results/moving_region/report.json; "
                                  "the .md beside it)")
    ap.add_argument("--report", action="store_true", help="write report.md again from report.json")
    a = ap.parse_args()
    if a.report:
        out = a.out or os.path.join(RESULTS, "report.json")
        with open(out) as f:
            res = json.load(f)
        # the comparisons again (with the TOLERANCE of this script)
        res["meta"]["tolerance"] = TOLERANCE
        src = res["meta"]["binary"].get("source", "")
        if os.path.isabs(src):
            res["meta"]["binary"]["source"] = source_name(src)
        for s, S in res["scenes"].items():
            recs = {"ref": S["reference"]}
            recs.update({r["tag"]: r for r in S["runs"]})
            res["scenes"][s] = summarize(s, recs)
        with open(out, "w") as f:
            json.dump(res, f, indent=1, default=float)
        with open(os.path.splitext(out)[0] + ".md", "w") as f:
            f.write(markdown(res))
        return 0
    if a.quick:
        a.reps = 1
        if not a.out:
            a.out = os.path.join(WORK, "quick", "report.json")
            os.makedirs(os.path.dirname(a.out), exist_ok=True)
    measure(a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
