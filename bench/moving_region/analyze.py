#!/usr/bin/env python3
"""Analysis of the moving-fast-region scenes (crack, impact, cascade).

For every run of a scene (a log log.<date>.<scene>-<name>.g++.1 and the
final dump final.<scene>.<name>.dump) it reports

  * wall time: the "Loop time" of the run (seconds, one rank);
  * force evaluations: the thermo column v_evals at the end (fix nve: one per
    step; fix pe_jump(/async): f_int[5], the cumulative evaluation count,
    1 = all interactions evaluated once);
  * energy error: max_t |E(t) - E(0)| / scale over the thermo lines, with
    E = pe + ke (column v_E), and the same for the pseudo-energy
    H~ = pe + f_int of fix pe_jump(/async) (column v_Ht; = E for fix nve),
    which these schemes conserve (at coarse nodes for async; the thermo
    interval is a multiple of K); scale = |E(0)| for crack and impact (for the
    impact E(0) is the kinetic energy put in: the lattice starts at rest
    length), and the PKA energy Epka for the cascade (|E(0)| is the
    cohesive energy there, 150 times larger);
  * distance from the reference run (fix pe_jump at a 4x smaller step):
    RMS and max |r - r_ref| of the unwrapped final positions (xu yu zu),
    atoms matched by ID;
  * cascade only: Wigner-Seitz defects of the final configuration against
    the perfect lattice (sites.cascade.dump): vacant sites, interstitials
    (extra atoms on multiply occupied sites), atoms off their own site, and
    the vacant sites not vacant in the reference.

It writes results.md (a markdown table per scene) and <scene>.png (energy
deviation against time, and the distance from the reference against the
force evaluations). Needs numpy and matplotlib.

  python3 analyze.py                 # all scenes, logs of date 24Nov26
  python3 analyze.py --date 24Nov26 --scenes crack cascade
  python3 analyze.py --runs async-dyn async-auto   # extra run names
"""
import argparse
import glob
import math
import os
import re
import sys

import numpy as np

SCENES = {
    # scene: (default runs in table order, reference run, energy scale)
    "crack": (["nve", "sync", "async", "async-band", "nve-coarse", "sync-coarse",
               "nve-noshift", "async-noshift", "async-dyn", "async-dyn-k5", "async-fastauto",
               "async-fastauto-tol0.1", "async-fastauto-tol0.2", "async-fastauto-near"], "ref", "E0"),
    "impact": (["nve", "sync", "async", "nve-coarse", "sync-coarse", "async-dyn",
                "async-dyn-r12", "async-auto", "async-fastauto",
                "async-fastauto-tol0.1", "async-fastauto-tol0.2", "async-fastauto-near"], "ref", "E0"),
    "cascade": (["nve", "sync", "async", "nve-coarse", "sync-coarse", "async-dyn", "async-dyn-r3",
                 "async-auto", "async-auto-k2", "async-fastauto",
                 "async-fastauto-b1", "async-fastauto-tol0.1",
                 "async-fastauto-tol0.2", "async-fastauto-near",
                 "async-fastauto-near-tol0.02"], "ref", "Epka"),
}


def parse_log(path):
    """Thermo columns of the last run, loop time, steps, the SCENE line and
    the variables given on the command line / in the log."""
    cols, rows, loop, steps, scene = None, [], None, None, None
    epka, changes = None, None
    with open(path) as f:
        lines = f.readlines()
    in_thermo = False
    for line in lines:
        s = line.split()
        if s and s[0] == "Step":
            cols, rows, in_thermo = s, [], True
            continue
        if line.startswith("Loop time"):
            in_thermo = False
            m = re.search(r"Loop time of (\S+) on .* for (\d+) steps", line)
            loop, steps = float(m.group(1)), int(m.group(2))
            continue
        m = re.match(r"Fix pe_jump/async: (\d+) atoms changed clock at (\d+) of (\d+) coarse nodes",
                     line)
        if m:
            changes = [int(g) for g in m.groups()]
        if in_thermo:
            try:
                vals = [float(v) for v in s]
            except ValueError:
                in_thermo = False
                continue
            if len(vals) == len(cols):
                rows.append(vals)
        if line.startswith("SCENE"):
            scene = line.strip()
        m = re.match(r"variable\s+Epka\s+index\s+(\S+)", line)
        if m and epka is None:
            epka = float(m.group(1))
        if line.startswith("ERROR"):
            scene = scene or line.strip()
    data = {c: np.array([r[i] for r in rows]) for i, c in enumerate(cols or [])}
    kasync = next((int(m.group(1)) for m in (re.search(r"pe_jump/async\s+(\d+)\s", l)
                                               for l in lines) if m), None)
    return {"cols": data, "loop": loop, "steps": steps, "scene": scene, "epka": epka, "K": kasync,
            "changes": changes,
            "error": next((l.strip() for l in lines if l.startswith("ERROR")), None)}


def read_dump(path):
    """ids, positions (N x 3) sorted by id, and the box bounds (3 x 2)."""
    with open(path) as f:
        lines = f.readlines()
    i = 0
    box, n = [], 0
    while i < len(lines):
        if lines[i].startswith("ITEM: NUMBER OF ATOMS"):
            n = int(lines[i + 1])
        if lines[i].startswith("ITEM: BOX BOUNDS"):
            box = [[float(v) for v in lines[i + k].split()[:2]] for k in (1, 2, 3)]
        if lines[i].startswith("ITEM: ATOMS"):
            cols = lines[i].split()[2:]
            arr = np.loadtxt(lines[i + 1:i + 1 + n], ndmin=2)
            break
        i += 1
    ids = arr[:, cols.index("id")].astype(int)
    pc = [c for c in ("xu", "yu", "zu") if c in cols] or ["x", "y", "z"]
    pos = arr[:, [cols.index(c) for c in pc]]
    order = np.argsort(ids)
    return ids[order], pos[order], np.array(box)


def distance(run, ref):
    ids, p, _ = run
    rid, rp, _ = ref
    common, ia, ib = np.intersect1d(ids, rid, return_indices=True)
    d = np.linalg.norm(p[ia] - rp[ib], axis=1)
    return math.sqrt(np.mean(d * d)), float(d.max()), len(common)


def wigner_seitz(sites, final):
    """Occupation of the perfect-lattice sites by the final atoms (periodic
    box of the sites dump). Returns vacancies, interstitials, atoms not on
    their own (initial) site, and the set of vacant site ids."""
    sid, sp, box = sites
    fid, fp, _ = final
    L = box[:, 1] - box[:, 0]
    # every atom of the final dump must have a site with the same id
    pos = {i: k for k, i in enumerate(sid)}
    own = np.array([pos[i] for i in fid])
    nearest = np.empty(len(fid), dtype=int)
    for a in range(0, len(fid), 256):
        d = fp[a:a + 256, None, :] - sp[None, :, :]
        d -= L * np.round(d / L)
        nearest[a:a + 256] = np.argmin(np.einsum("ijk,ijk->ij", d, d), axis=1)
    occ = np.bincount(nearest, minlength=len(sid))
    vac = int(np.sum(occ == 0))
    inter = int(np.sum(np.maximum(occ - 1, 0)))
    off = int(np.sum(nearest != own))
    return vac, inter, off, set(sid[occ == 0].tolist())


def find(pattern):
    hits = sorted(glob.glob(pattern))
    return hits[-1] if hits else None


def analyze_scene(scene, runs, ref_name, escale, date, out_md):
    logs, dumps = {}, {}
    prefix = scene + "."
    for name in runs + [ref_name]:
        lg = find(f"log.{date}.{scene}-{name}.g++.1")
        if lg is None:
            continue
        logs[name] = parse_log(lg)
        dp = f"final.{prefix}{name}.dump"
        if os.path.exists(dp):
            dumps[name] = read_dump(dp)
    if not logs:
        print(f"{scene}: no logs of date {date}", file=sys.stderr)
        return
    ref = dumps.get(ref_name)
    sites = read_dump("sites.cascade.dump") if scene == "cascade" and os.path.exists("sites.cascade.dump") else None
    ref_vac = None
    if sites is not None and ref is not None:
        ref_vac = wigner_seitz(sites, ref)
    # nve at the fine step: the wall-time unit
    t_nve = logs["nve"]["loop"] if "nve" in logs and logs["nve"]["loop"] else None

    rows, series = [], {}
    for name in runs + [ref_name]:
        if name not in logs:
            continue
        L = logs[name]
        c = L["cols"]
        if L["loop"] is None or "v_E" not in c or len(c["v_E"]) == 0:
            err = L["error"] or "no thermo"
            m = re.search(r"at step (\d+): the momentum jumps grew (\S+)-fold", err)
            rows.append([name, (f"failed: unstable at step {m.group(1)}, growth {m.group(2)}"
                                if m else "failed: " + err[:100])])
            continue
        E = c["v_E"]
        if escale == "Epka":
            scale, sname = L["epka"], "Epka"
        else:
            scale, sname = abs(E[0]), "abs E(0)"
        dE = np.abs(E - E[0]) / scale
        Ht = c.get("v_Ht", E)
        dHt = np.abs(Ht - Ht[0]) / scale
        series[name] = (c["Time"], dE)
        evals = c["v_evals"][-1]
        h = (c["Time"][-1] - c["Time"][0]) / max(L["steps"], 1)
        row = {"run": name, "h": h, "steps": L["steps"], "loop": L["loop"],
               "tratio": L["loop"] / t_nve if t_nve else float("nan"),
               "evals": evals, "dE": dE.max(), "dHt": dHt.max(), "E0": E[0], "scale": sname}
        if name in dumps and ref is not None and name != ref_name:
            rms, mx, n = distance(dumps[name], ref)
            row.update(rms=rms, max=mx)
        if sites is not None and name in dumps:
            vac, inter, off, vset = wigner_seitz(sites, dumps[name])
            row.update(vac=vac, inter=inter, off=off)
            if ref_vac is not None:
                row["vac_not_ref"] = len(vset - ref_vac[3])
        if "v_nfast" in c:
            row["nfast"] = int(c["v_nfast"][0])
        rows.append(row)

    hdr = ["run", "h", "steps", "loop time (s)", "time / nve", "force evals",
           f"max dE / {rows[0]['scale'] if isinstance(rows[0], dict) else 'scale'}",
           "max dH~ / same",
           "RMS dr vs ref", "max dr vs ref"]
    if sites is not None:
        hdr += ["vacancies", "interstitials", "atoms off site", "vacancies not in ref"]
    lines = [f"### {scene}", "", "| " + " | ".join(hdr) + " |", "|" + "---|" * len(hdr)]
    for r in rows:
        if not isinstance(r, dict):
            lines.append(f"| {r[0]} | {r[1]} |" + " |" * (len(hdr) - 2))
            continue
        f = lambda k, fmt: (fmt % r[k]) if k in r else "-"
        cells = [r["run"], "%g" % r["h"], str(r["steps"]), "%.3f" % r["loop"],
                 "%.2f" % r["tratio"], "%.1f" % r["evals"], "%.2e" % r["dE"], "%.2e" % r["dHt"],
                 f("rms", "%.3e"), f("max", "%.3e")]
        if sites is not None:
            cells += [f("vac", "%d"), f("inter", "%d"), f("off", "%d"), f("vac_not_ref", "%d")]
        lines.append("| " + " | ".join(cells) + " |")
    lines.append("")
    # dynamic fast groups: clock changes and the pseudo-energy (thermo column
    # f_clk = running mean over the coarse nodes of the number of fine-clock
    # atoms; the fix's log line "N atoms changed clock at C of M coarse nodes")
    clk = [n for n in runs if n in logs and "f_clk" in logs[n]["cols"]
           and len(logs[n]["cols"]["f_clk"])]
    if clk:
        lines += [f"clock changes ({scene}; static async for comparison; 'end' = last thermo line,"
                  " the step of the failure for unstable runs)", "",
                  "| run | K | end step | fine-clock atoms / node | clock changes / node |"
                  " max dE | max dH~ | dH~ at end | status |", "|---|---|---|---|---|---|---|---|---|"]
        for name in ["async"] + clk:
            if name not in logs:
                continue
            L = logs[name]
            c = L["cols"]
            E, Ht = c["v_E"], c.get("v_Ht", c["v_E"])
            scale = L["epka"] if escale == "Epka" else abs(E[0])
            nf = "%.1f" % c["f_clk"][-1] if "f_clk" in c else "%d" % int(c["v_nfast"][0])
            ch = "%.2f" % (L["changes"][0] / L["changes"][2]) if L["changes"] else "0"
            err = L["error"]
            status = "ok"
            if err:
                m = re.search(r"at step (\d+): the momentum jumps grew (\S+)-fold", err)
                status = (f"unstable at step {m.group(1)}, growth {m.group(2)}" if m
                          else err.split(":", 1)[1].strip()[:60])
            lines.append(f"| {name} | {L['K']} | {int(c['Step'][-1])} | {nf} | {ch} | "
                         f"{np.abs(E - E[0]).max() / scale:.2e} | {np.abs(Ht - Ht[0]).max() / scale:.2e} | "
                         f"{(Ht[-1] - Ht[0]) / scale:+.2e} | {status} |")
        lines.append("")
    text = "\n".join(lines)
    print(text)
    out_md.write(text + "\n")

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, (t, dE) in series.items():
        ax[0].semilogy(t[1:], np.maximum(dE[1:], 1e-16), label=name)
    ax[0].set_xlabel("time (LJ units)")
    ax[0].set_ylabel(f"|E(t) - E(0)| / {rows[0]['scale'] if isinstance(rows[0], dict) else 'scale'}")
    ax[0].set_title(f"{scene}: energy deviation")
    ax[0].legend(fontsize=8)
    for r in rows:
        if isinstance(r, dict) and "rms" in r:
            ax[1].loglog(r["evals"], r["rms"], "o")
            ax[1].annotate(r["run"], (r["evals"], r["rms"]), fontsize=8,
                           xytext=(4, 4), textcoords="offset points")
    ax[1].set_xlabel("force evaluations")
    ax[1].set_ylabel("RMS |r - r_ref| at the end")
    ax[1].set_title(f"{scene}: distance from the reference (pe_jump, h/4)")
    fig.tight_layout()
    fig.savefig(f"{scene}.png", dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--date", default="24Nov26")
    ap.add_argument("--scenes", nargs="+", default=list(SCENES))
    ap.add_argument("--runs", nargs="*", default=[], help="extra run names (e.g. async-dyn)")
    ap.add_argument("--out", default="results.md")
    a = ap.parse_args()
    with open(a.out, "w") as out:
        for s in a.scenes:
            runs, ref, escale = SCENES[s]
            analyze_scene(s, runs + a.runs, ref, escale, a.date, out)


if __name__ == "__main__":
    main()
