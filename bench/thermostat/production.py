#!/usr/bin/env python3
"""Mean temperature of fix pe_jump under thermostats on production-size
inputs, against fix nve with the same thermostat: LAMMPS' bench/in.chain
(32000 FENE beads, dt 0.012) and a 2048-atom LJ liquid (dt 0.005), each
run for NSTEPS steps with one binary. Two runs go at once (the figures are
means of the trajectory, not timings).

  python3 bench/thermostat/production.py --lmp build/lmp --label after
  python3 bench/thermostat/production.py --report [--labels before,after]

--reanalyse reads the series files of an earlier run of the same label
again instead of running. Results: bench/results/thermostat/<label>.json; the report (markdown) goes
to stdout or --out FILE. Mean T and pe per atom are over the samples after
the first 10 % of the run, with standard errors from 10 blocks."""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
LAMMPS_TREE = os.path.expanduser("~/.cache/pe-jump/lammps-20250204+dfsg.1")

SYSTEMS = {
    "chain": {"input": "in.chain-thermostat", "natoms": 32000, "thermostats": {
        "langevin": "langevin 1.0 1.0 10.0 904297",
        "csvr": "temp/csvr 1.0 1.0 10.0 904297",
        "berendsen": "temp/berendsen 1.0 1.0 10.0"}},
    "lj": {"input": "in.lj-thermostat", "natoms": 2048, "thermostats": {
        "langevin": "langevin 1.0 1.0 1.0 48279",
        "langevin10": "langevin 1.0 1.0 10.0 48279",
        "csvr": "temp/csvr 1.0 1.0 1.0 48279",
        "berendsen": "temp/berendsen 1.0 1.0 1.0"}},
}
INTEGRATORS = ["nve", "midpoint", "lobatto 2", "lobatto 3", "legendre 2"]


def fix_of(rule):
    return "nve" if rule == "nve" else "pe_jump quadrature " + rule


def block_error(x, nblocks=10):
    means = np.array([b.mean() for b in np.array_split(x, nblocks)])
    return float(means.std(ddof=1) / np.sqrt(nblocks))


def run_one(args, system, thermostat, rule, work):
    spec = SYSTEMS[system]
    tag = f"{system}.{thermostat}.{rule.replace(' ', '')}"
    cmd = [os.path.abspath(args.lmp), "-in", os.path.join(HERE, spec["input"]), "-var", "fix", fix_of(rule),
           "-var", "thermostat", spec["thermostats"][thermostat], "-var", "nsteps",
           str(args.steps), "-var", "tag", tag, "-var", "jumpsrc",
           "0.0" if rule == "nve" else "f_1[2]", "-log", f"log.{tag}", "-screen", "none",
           "-nocite"]
    if system == "chain":
        cmd += ["-var", "data", os.path.join(args.lammps, "bench", "data.chain")]
    if not args.reanalyse:
        env = dict(os.environ, OMP_NUM_THREADS="1")
        subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True)
    # a run that stopped with an ERROR is analysed up to there
    log = os.path.join(work, f"log.{tag}")
    errors = [line.strip() for line in open(log) if line.startswith("ERROR")] \
        if os.path.exists(log) else []
    s = np.loadtxt(os.path.join(work, f"series.{tag}.dat"), comments="#")
    steps = int(s[-1, 0] - s[0, 0] + (s[1, 0] - s[0, 0]))    # sampled steps
    s = s[len(s) // 10:]
    t, pe, jump = s[:, 1], s[:, 2] / spec["natoms"], s[:, 3]
    n = max(1, len(jump) // 10)
    return tag, {"system": system, "thermostat": thermostat, "rule": rule,
                 "T": float(t.mean()), "T_se": block_error(t), "pe": float(pe.mean()),
                 "pe_se": block_error(pe), "jump_first": float(jump[:n].mean()),
                 "jump_last": float(jump[-n:].mean()), "steps": steps,
                 "error": errors[0] if errors else ""}


def measure(args):
    work = os.path.join(ROOT, "bench", "work", "thermostat-production", args.label)
    os.makedirs(work, exist_ok=True)
    jobs = [(s, th, r) for s in args.systems for th in SYSTEMS[s]["thermostats"]
            if th in args.thermostats for r in args.rules]
    results = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for tag, res in pool.map(lambda j: run_one(args, *j, work), jobs):
            results[tag] = res
            print(tag, res, flush=True)
    out = os.path.join(ROOT, "bench", "results", "thermostat", args.label + ".json")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    old = json.load(open(out)) if os.path.exists(out) else {}
    old.update(results)
    meta = {"lmp": os.path.realpath(args.lmp), "steps": args.steps}
    old["_meta"] = meta
    json.dump(old, open(out, "w"), indent=1, sort_keys=True)


def report(args):
    labels = args.labels.split(",")
    data = {lab: json.load(open(os.path.join(ROOT, "bench", "results", "thermostat",
                                             lab + ".json"))) for lab in labels}
    lines = ["| system | thermostat | integrator | " +
             " | ".join(f"mean T {lab} (T / T_nve - 1)" for lab in labels) +
             " | jump energy first / last 10 % (" + labels[-1] + ") |",
             "|---|---|---|" + "---|" * len(labels) + "---|"]
    keys = sorted({k for d in data.values() for k in d if not k.startswith("_")})
    for key in keys:
        system, thermostat, _ = key.split(".", 2)
        cells = []
        for lab in labels:
            r = data[lab].get(key)
            nve = data[lab].get(f"{system}.{thermostat}.nve")
            if not r or "T" not in r:
                cells.append("-")
                continue
            rel = "" if (not nve or r["rule"] == "nve") else \
                f" ({100 * (r['T'] / nve['T'] - 1):+.2f} %)"
            stop = ", stopped by an ERROR" if r.get("error") else ""
            cells.append(f"{r['T']:.4f} +- {r['T_se']:.4f}{rel} ({r['steps']} steps{stop})")
        last = data[labels[-1]].get(key, {})
        jumps = "-" if last.get("rule", "nve") == "nve" or "T" not in last else \
            f"{last['jump_first']:.4g} / {last['jump_last']:.4g}"
        rule = (data[labels[-1]].get(key) or data[labels[0]].get(key))["rule"]
        lines.append(f"| {system} | {thermostat} | {rule} | " + " | ".join(cells) +
                     f" | {jumps} |")
    text = "\n".join(lines) + "\n"
    if args.out:
        open(args.out, "w").write(text)
    else:
        sys.stdout.write(text)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--lmp", default=os.path.join(ROOT, "build", "lmp"))
    p.add_argument("--lammps", default=LAMMPS_TREE, help="LAMMPS source tree (bench/data.chain)")
    p.add_argument("--label", default="after")
    p.add_argument("--steps", type=int, default=100000)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--systems", default="chain,lj")
    p.add_argument("--thermostats", default="langevin,csvr,berendsen")
    p.add_argument("--rules", default=",".join(INTEGRATORS))
    p.add_argument("--reanalyse", action="store_true",
                   help="do not run: analyse the series files of the label's work directory")
    p.add_argument("--report", action="store_true")
    p.add_argument("--labels", default="before,after")
    p.add_argument("--out")
    args = p.parse_args()
    if args.report:
        report(args)
        return
    args.systems = args.systems.split(",")
    args.thermostats = args.thermostats.split(",")
    args.rules = args.rules.split(",")
    measure(args)


if __name__ == "__main__":
    main()
