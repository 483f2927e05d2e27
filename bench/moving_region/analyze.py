#!/usr/bin/env python3
"""Measures of one run of the moving-region scenes (crack, impact, cascade).

Used by moving_region.py (the driver); also a command of its own, which
prints the measures of runs from their logs and final dumps:

    python3 analyze.py LOG [LOG ...] [--ref REF_DUMP] [--sites SITES_DUMP]
                       [--scale E0|Epka]

For one run (a LAMMPS log and the final dump final.<scene>.<name>.dump that
the input writes, `id xu yu zu` sorted by id):

  * loop time: the sum of the "Loop time" lines of the log (seconds; a run
    under fix dt/reset is two LAMMPS runs, the halted one and the last step
    that ends at T), and its CPU time (Loop time x "% CPU use" of each loop:
    less sensitive to other processes on the machine);
  * force evaluations: the thermo column v_evals at the end (fix nve: one
    per step; fix pe_jump(/async): f_int[5], the cumulative evaluation
    count, 1 = all interactions evaluated once);
  * energy error: max_t |E(t) - E(0)| / scale over the thermo lines, with
    E = pe + ke (column v_E), and the same for the pseudo-energy
    H~ = pe + f_int of fix pe_jump(/async) (column v_Ht; = E for fix nve),
    which these schemes conserve (at coarse nodes for async). scale = |E(0)|
    for crack and impact (for the impact E(0) is the kinetic energy put in:
    the lattice starts at rest length), and the PKA energy Epka for the
    cascade (|E(0)| is the cohesive energy there, 14 times Epka);
  * distance from a reference run: RMS and max |r - r_ref| of the unwrapped
    final positions, atoms matched by id;
  * cascade: Wigner-Seitz defects of the final configuration against the
    perfect lattice (sites.cascade.dump): vacant sites, interstitials (extra
    atoms on multiply occupied sites), atoms off their own site, and the
    vacant sites that are not vacant in the reference.

numpy only.
"""
import argparse
import math
import re
import sys

import numpy as np


def parse_log(path):
    """Thermo columns of all runs of the log (the first row of a run that
    repeats the last row of the one before is dropped), the summed loop
    time and step count, the ERROR line, the pe_jump/async step line, the
    clock-change line and Epka."""
    cols, rows = None, []
    loop, steps, nloops, loops = 0.0, 0, 0, []
    epka, changes, hline, cpu = None, None, None, []
    with open(path, errors="replace") as f:
        lines = f.readlines()
    in_thermo = False
    for line in lines:
        s = line.split()
        if s and s[0] == "Step":
            if cols is not None and s != cols:
                rows = []          # another thermo style: keep the last one
            cols, in_thermo = s, True
            continue
        if line.startswith("Loop time"):
            in_thermo = False
            m = re.search(r"Loop time of (\S+) on .* for (\d+) steps", line)
            loop += float(m.group(1))
            loops.append(float(m.group(1)))
            steps += int(m.group(2))
            nloops += 1
            continue
        m = re.search(r"(\S+)% CPU use", line)
        if m:
            cpu.append(float(m.group(1)))
        m = re.match(r"Fix pe_jump/async: (\d+) atoms changed clock at (\d+) of (\d+) coarse nodes", line)
        if m:
            changes = [int(g) for g in m.groups()]
        m = re.match(r"Fix pe_jump/async: coarse step h_S = (\S+) \(the time step\), "
                     r"fine step h_F = h_S/K = (\S+) \(K = (\d+)\)", line)
        if m:
            hline = {"h_S": float(m.group(1)), "h_F": float(m.group(2)), "K": int(m.group(3))}
        m = re.match(r"variable\s+Epka\s+index\s+(\S+)", line)
        if m and epka is None:
            epka = float(m.group(1))
        if in_thermo:
            try:
                vals = [float(v) for v in s]
            except ValueError:
                in_thermo = False
                continue
            if len(vals) == len(cols):
                if rows and vals[0] == rows[-1][0]:
                    continue       # the first row of a continued run
                rows.append(vals)
    data = {c: np.array([r[i] for r in rows]) for i, c in enumerate(cols or [])}
    error = next((l.strip() for l in lines if l.startswith("ERROR")), None)
    # CPU time of the loops: Loop time x "% CPU use" (LAMMPS prints one per loop)
    loop_cpu = (sum(t * c / 100.0 for t, c in zip(loops, cpu)) if loops and len(cpu) == len(loops)
                else None)
    return {"cols": data, "loop": loop if nloops else None, "steps": steps, "nloops": nloops,
            "loop_cpu": loop_cpu,
            "epka": epka, "changes": changes, "hline": hline, "cpu": cpu, "error": error}


def read_dump(path):
    """ids, positions (N x 3) sorted by id, and the box bounds (3 x 2)."""
    with open(path) as f:
        lines = f.readlines()
    i, box, n = 0, [], 0
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
    """RMS and max |r - r_ref| over the atoms common to both, their count."""
    ids, p, _ = run
    rid, rp, _ = ref
    common, ia, ib = np.intersect1d(ids, rid, return_indices=True)
    d = np.linalg.norm(p[ia] - rp[ib], axis=1)
    return math.sqrt(float(np.mean(d * d))), float(d.max()), len(common)


def wigner_seitz(sites, final):
    """Occupation of the perfect-lattice sites by the final atoms (periodic
    box of the sites dump). Returns vacancies, interstitials, atoms not on
    their own (initial) site, and the set of vacant site ids."""
    sid, sp, box = sites
    fid, fp, _ = final
    L = box[:, 1] - box[:, 0]
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


def energy_errors(L, escale):
    """max |E - E(0)| / scale and the same for H~; scale |E(0)| ('E0') or
    Epka ('Epka'); None if the log has no thermo rows."""
    c = L["cols"]
    if "v_E" not in c or len(c["v_E"]) == 0:
        return None
    E = c["v_E"]
    scale = L["epka"] if escale == "Epka" else abs(E[0])
    Ht = c.get("v_Ht", E)
    return {"dE": float(np.max(np.abs(E - E[0])) / scale),
            "dHt": float(np.max(np.abs(Ht - Ht[0])) / scale),
            "scale": float(scale), "E0": float(E[0]),
            "finite": bool(np.all(np.isfinite(E)) and np.all(np.isfinite(Ht)))}


def measures(log, dump=None, ref=None, sites=None, ref_vacant=None, escale="E0"):
    """All measures of one run as a dict (see the module docstring)."""
    L = parse_log(log)
    out = {"loop": L["loop"], "loop_cpu": L["loop_cpu"], "steps": L["steps"], "error": L["error"], "hline": L["hline"],
           "cpu": L["cpu"]}
    c = L["cols"]
    if "v_evals" in c and len(c["v_evals"]):
        out["evals"] = float(c["v_evals"][-1])
        out["t_end"] = float(c["Time"][-1])
    e = energy_errors(L, escale)
    if e:
        out.update(e)
    if L["changes"]:
        out["clock_changes"], out["change_nodes"], out["coarse_nodes"] = L["changes"]
    if "f_clk" in c and len(c["f_clk"]):
        out["fine_clock_atoms"] = float(c["f_clk"][-1])
    elif "v_nfast" in c and len(c["v_nfast"]):
        out["fine_clock_atoms"] = float(c["v_nfast"][0])
    if dump is not None and ref is not None:
        out["rms"], out["max"], out["n_matched"] = distance(dump, ref)
    if sites is not None and dump is not None:
        vac, inter, off, vset = wigner_seitz(sites, dump)
        out.update(vac=vac, inter=inter, off=off)
        if ref_vacant is not None:
            out["vac_not_ref"] = len(vset - ref_vacant)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("logs", nargs="+")
    ap.add_argument("--ref", help="final dump of the reference run")
    ap.add_argument("--sites", help="sites.cascade.dump (Wigner-Seitz)")
    ap.add_argument("--scale", default="E0", choices=("E0", "Epka"))
    a = ap.parse_args()
    ref = read_dump(a.ref) if a.ref else None
    sites = read_dump(a.sites) if a.sites else None
    ref_vac = wigner_seitz(sites, ref)[3] if sites is not None and ref is not None else None
    for lg in a.logs:
        m = re.search(r"^SCENE (\S+) \S+ name (\S+)", open(lg, errors="replace").read(), re.M)
        dump = None
        if m:
            try:
                dump = read_dump(f"final.{m.group(1)}.{m.group(2)}.dump")
            except OSError:
                pass
        r = measures(lg, dump, ref, sites, ref_vac, a.scale)
        print(lg, {k: v for k, v in r.items() if k not in ("cpu",)})
    return 0


if __name__ == "__main__":
    sys.exit(main())
