"""Helpers of the PE-JUMP benchmark suite: running LAMMPS, reading its log,
writing data files and tables, reference solutions.

Only numpy (and scipy for the chain references) is needed; run with the
system python (/usr/bin/python3).
"""

import json
import math
import os
import re
import subprocess
import time

import numpy as np

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
INPUTS = os.path.join(BENCH, "inputs")
LMP = os.environ.get("LMP", os.path.join(ROOT, "build", "lmp"))
MPIRUN = ["mpirun", "--oversubscribe", "--allow-run-as-root"]


# ---------------------------------------------------------------- running

def wait_for_binary(maxwait=900):
    """The binary may be rebuilt while we run: wait until it is there."""
    t0 = time.time()
    while not (os.path.isfile(LMP) and os.access(LMP, os.X_OK)):
        if time.time() - t0 > maxwait:
            raise RuntimeError(f"LAMMPS binary {LMP} missing for {maxwait} s")
        time.sleep(10)


def snapshot_binary(dest, settle=60):
    """Copy build/lmp and its liblammps into dest and use the copies from
    now on (the build may be redone while the benchmarks run: one
    invocation must time one binary). Waits until the library has not
    changed for `settle` seconds. Returns a description of the copy."""
    global LMP
    import shutil
    src_dir = os.path.dirname(LMP)
    lib = os.path.join(src_dir, "liblammps.so.0")
    while True:
        wait_for_binary()
        newest = max(os.path.getmtime(LMP), os.path.getmtime(lib) if os.path.exists(lib) else 0)
        if time.time() - newest >= settle:
            break
        time.sleep(10)
    os.makedirs(dest, exist_ok=True)
    shutil.copy2(LMP, os.path.join(dest, "lmp"))
    if os.path.exists(lib):
        shutil.copy2(lib, os.path.join(dest, "liblammps.so.0"))
        os.environ["LD_LIBRARY_PATH"] = dest + ":" + os.environ.get("LD_LIBRARY_PATH", "")
    info = {"source": LMP, "mtime": time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(newest))}
    LMP = os.path.join(dest, "lmp")
    return info


def run_lammps(inp, variables=None, cwd=None, log="log.lammps", np_=1,
               timeout=3600, check=True, retries=2):
    """Run LAMMPS on input file inp with -var settings; return the parsed log.

    The process is wrapped in /usr/bin/time to get its peak resident memory.
    """
    cwd = cwd or os.getcwd()
    os.makedirs(cwd, exist_ok=True)
    cmd = []
    if np_ > 1:
        # every rank under /usr/bin/time, to get the peak memory of each
        cmd += MPIRUN + ["-np", str(np_), "-x", "LD_LIBRARY_PATH", "bash", "-c",
                         'exec /usr/bin/time -f "%M" -o "$0.rank$OMPI_COMM_WORLD_RANK" "$@"',
                         log + ".time"]
    cmd += [LMP, "-nocite", "-screen", "none", "-log", log, "-in", inp]
    for k, v in (variables or {}).items():
        cmd += ["-var", k] + (list(v) if isinstance(v, (list, tuple)) else [str(v)])
    timefile = os.path.join(cwd, log + ".time")
    full = ["/usr/bin/time", "-f", "%M %e %U %S", "-o", timefile] + cmd
    for attempt in range(retries + 1):
        wait_for_binary()
        t0 = time.time()
        p = subprocess.run(full, cwd=cwd, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True, timeout=timeout)
        wall = time.time() - t0
        logpath = os.path.join(cwd, log)
        res = parse_log(logpath) if os.path.exists(logpath) else {"error": "no log"}
        # a binary replaced under our feet shows as an exec failure: retry
        if p.returncode != 0 and attempt < retries and not res.get("error_lines"):
            time.sleep(30)
            continue
        break
    res["returncode"] = p.returncode
    res["process_wall"] = wall
    res["cmd"] = " ".join(cmd)
    try:
        with open(timefile) as f:
            line = f.read().strip().splitlines()[-1].split()
        res["maxrss_kb"] = int(line[0])       # of mpirun itself for np > 1
        res["user_s"] = float(line[2])
        res["sys_s"] = float(line[3])
    except Exception:
        pass
    if np_ > 1:
        rss = []
        for k in range(np_):
            try:
                with open(os.path.join(cwd, f"{log}.time.rank{k}")) as f:
                    rss.append(int(f.read().strip().splitlines()[-1].split()[0]))
            except Exception:
                pass
        res["rank_rss_kb"] = rss
    if check and (p.returncode != 0 or res.get("error_lines")):
        raise RuntimeError(f"LAMMPS failed in {cwd}: {' '.join(cmd)}\n"
                           f"{res.get('error_lines')}\n{p.stderr[-2000:]}")
    return res


_num = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def parse_log(path):
    """Loop time, timing breakdown, CPU use, memory, thermo tables and
    'BENCH key value ...' lines of a LAMMPS log file (last run wins for
    the per-run values; 'runs' keeps all of them)."""
    with open(path, errors="replace") as f:
        lines = f.read().splitlines()
    res = {"runs": [], "thermo": [], "bench": {}, "error_lines": []}
    cur = None
    i = 0
    while i < len(lines):
        ln = lines[i]
        if ln.startswith("ERROR") or " ERROR:" in ln[:20]:
            res["error_lines"].append(ln)
        if ln.startswith("Per MPI rank memory allocation"):
            m = re.findall(_num, ln.split("=")[1])
            cur = {"memory_mb": [float(x) for x in m[:3]]}
            res["runs"].append(cur)
            # thermo header follows
            j = i + 1
            while j < len(lines) and not lines[j].split()[:1] == ["Step"]:
                j += 1
            if j < len(lines):
                head = lines[j].split()
                rows = []
                k = j + 1
                while k < len(lines) and not lines[k].startswith("Loop time"):
                    parts = lines[k].split()
                    if len(parts) == len(head):
                        try:
                            rows.append([float(x) for x in parts])
                        except ValueError:
                            pass
                    k += 1
                cur["thermo_head"] = head
                cur["thermo"] = rows
                res["thermo"].append({"head": head, "rows": rows})
                i = k
                continue
        m = re.match(r"Loop time of (" + _num + r") on (\d+) procs for (\d+) steps with (\d+) atoms", ln)
        if m and cur is not None:
            cur["loop_time"] = float(m.group(1))
            cur["procs"] = int(m.group(2))
            cur["steps"] = int(m.group(3))
            cur["natoms"] = int(m.group(4))
        m = re.match(r"(" + _num + r")% CPU use", ln)
        if m and cur is not None:
            cur["cpu_use"] = float(m.group(1))
        m = re.match(r"(Pair|Bond|Kspace|Neigh|Comm|Output|Modify|Other)\s*\|(.*)", ln)
        if m and cur is not None:
            vals = [x for x in m.group(2).split("|")]
            try:
                cur.setdefault("breakdown", {})[m.group(1)] = float(vals[1])
            except (ValueError, IndexError):
                pass
        m = re.match(r"Total # of neighbors = (\d+)", ln)
        if m and cur is not None:
            cur["neighbors"] = int(m.group(1))
        m = re.match(r"Neighbor list builds = (\d+)", ln)
        if m and cur is not None:
            cur["neigh_builds"] = int(m.group(1))
        if ln.startswith("BENCH "):
            parts = ln.split()[1:]
            for k in range(0, len(parts) - 1, 2):
                try:
                    res["bench"][parts[k]] = float(parts[k + 1])
                except ValueError:
                    res["bench"][parts[k]] = parts[k + 1]
        i += 1
    runs = [r for r in res["runs"] if "loop_time" in r]
    if runs:
        last = runs[-1]
        for k in ("loop_time", "steps", "natoms", "cpu_use", "breakdown",
                  "memory_mb", "neighbors", "neigh_builds", "procs"):
            if k in last:
                res[k] = last[k]
        if "thermo" in last:
            res["thermo_head"] = last["thermo_head"]
            res["thermo_rows"] = last["thermo"]
    return res


def thermo_column(res, name):
    head = res["thermo_head"]
    j = head.index(name)
    return np.array([r[j] for r in res["thermo_rows"]])


def read_dump(path):
    """write_dump custom output: array sorted by id, columns as in the file."""
    with open(path) as f:
        lines = f.read().splitlines()
    k = [i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS")][-1]
    cols = lines[k].split()[2:]
    data = np.array([[float(x) for x in l.split()] for l in lines[k + 1:] if l.strip()])
    return {c: data[:, j] for j, c in enumerate(cols)}


# ---------------------------------------------------------------- load / quietness

def loadavg():
    return os.getloadavg()


def busy_others(sample=1.0):
    """CPU seconds per second used by all processes (from /proc/stat) over
    a short window; with nothing of ours running this is the others' load."""
    def snap():
        with open("/proc/stat") as f:
            v = [float(x) for x in f.readline().split()[1:]]
        idle = v[3] + v[4]
        return sum(v), idle
    t0, i0 = snap()
    time.sleep(sample)
    t1, i1 = snap()
    ncpu = os.cpu_count() or 1
    return ncpu * (1.0 - (i1 - i0) / max(t1 - t0, 1e-9))


# ---------------------------------------------------------------- files

def write_table(path, key, energy, force, rlo, rhi, n=20001):
    """LAMMPS pair_style table file with n points evenly spaced in r."""
    r = np.linspace(rlo, rhi, n)
    with open(path, "w") as f:
        f.write(f"# written by bench/benchlib.py\n\n{key}\nN {n} R {rlo:.17g} {rhi:.17g}\n\n")
        for i, ri in enumerate(r):
            f.write(f"{i+1} {ri:.17g} {energy(ri):.17g} {force(ri):.17g}\n")


def write_chain_data(path, chains, a=5.0, spacing=9.0):
    """Chains along x in 2d, copy c at y = c*spacing.

    chains: list of (springs, q, p) with springs a string over the 2m+1
    springs from the left wall to the right wall, 'K' = stiff (bond),
    'Q' = soft (pair); q, p: displacements and velocities of the 2m
    mobile atoms. Atom types 1 slow, 2 fast (touches a stiff spring),
    3 wall. Returns the numbers of atoms, bonds and soft springs."""
    atoms, vels, bonds = [], [], []
    nsoft = 0
    aid = 0
    for c, (springs, q, p) in enumerate(chains):
        n = len(springs) - 1           # mobile atoms
        ids = list(range(aid + 1, aid + n + 3))   # wall, mobile..., wall
        y = c * spacing
        for i in range(n + 2):
            if i == 0 or i == n + 1:
                typ, x, v = 3, i * a, 0.0
            else:
                fast = springs[i - 1] == "K" or springs[i] == "K"
                typ = 2 if fast else 1
                x, v = i * a + q[i - 1], p[i - 1]
            atoms.append((ids[i], c + 1, typ, x, y))
            vels.append((ids[i], v))
        for j, s in enumerate(springs):
            if s == "K":
                bonds.append((ids[j], ids[j + 1]))
            else:
                nsoft += 1
        aid += n + 2
    ny = len(chains)
    with open(path, "w") as f:
        f.write("PE-JUMP benchmark chains (bench/benchlib.py)\n\n")
        f.write(f"{len(atoms)} atoms\n3 atom types\n{len(bonds)} bonds\n1 bond types\n\n")
        nmob = len(chains[0][0]) - 1
        f.write(f"{-a:.6f} {(nmob + 2) * a:.6f} xlo xhi\n")
        f.write(f"{-spacing/2:.6f} {(ny - 0.5) * spacing:.6f} ylo yhi\n-0.5 0.5 zlo zhi\n\n")
        f.write("Atoms # bond\n\n")
        for (i, mol, t, x, y) in atoms:
            f.write(f"{i} {mol} {t} {x:.17g} {y:.17g} 0.0\n")
        f.write("\nVelocities\n\n")
        for (i, v) in vels:
            f.write(f"{i} {v:.17g} 0.0 0.0\n")
        f.write("\nBonds\n\n")
        for k, (i, j) in enumerate(bonds):
            f.write(f"{k+1} 1 {i} {j}\n")
    return {"atoms": len(atoms), "bonds": len(bonds), "soft": nsoft,
            "mobile": sum(1 for x in atoms if x[2] != 3)}


def write_lattice_data(path, nx, ny, frac=0.10, kT=1e-4, seed=12345, soft_as_bonds=False,
                       perturb=None):
    """2d triangular spring lattice (spacing 1, periodic, nx*ny atoms, ny
    even) with a central disk holding a fraction frac of the atoms: the
    stiff inclusion. Springs between two inclusion atoms are bonds (stiff),
    all other nearest-neighbour springs are soft (pair table). Atom types:
    1 outside (slow), 2 inclusion (fast group). Velocities: Gaussian with
    variance kT (unit masses), zero total momentum; positions on the lattice.

    soft_as_bonds=True: the soft springs are bonds too (bond type 1, the
    stiff ones bond type 2, "2 bond types"), for a lattice without a pair
    style (bench/cost); the default writes the file as before.

    perturb: None, or a function (x, y) -> (ux, uy, vx, vy) of the arrays of
    lattice positions, added to the positions and velocities after the
    inclusion is chosen (bench/composite: a travelling pulse, with kT=0)."""
    assert ny % 2 == 0
    rng = np.random.default_rng(seed)
    h = math.sqrt(3.0) / 2.0
    Lx, Ly = float(nx), ny * h
    ii, jj = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    x = (ii + 0.5 * (jj % 2) + 0.25).ravel()
    y = (jj * h + 0.5 * h).ravel()
    n = x.size
    r = np.hypot(x - Lx / 2, y - Ly / 2)
    ninc = int(round(frac * n))
    R = np.sort(r)[ninc - 1] + 1e-9
    inc = r <= R
    # nearest neighbours with periodic images
    bonds, soft = [], 0
    for i in range(nx):
        for j in range(ny):
            a = i * ny + j
            odd = j % 2
            # right neighbour, and the two upper neighbours
            nbrs = [((i + 1) % nx, j)]
            if odd:
                nbrs += [(i, (j + 1) % ny), ((i + 1) % nx, (j + 1) % ny)]
            else:
                nbrs += [((i - 1) % nx, (j + 1) % ny), (i, (j + 1) % ny)]
            for (k, l) in nbrs:
                b = k * ny + l
                if inc[a] and inc[b]:
                    bonds.append((a + 1, b + 1, 2 if soft_as_bonds else 1))
                else:
                    soft += 1
                    if soft_as_bonds:
                        bonds.append((a + 1, b + 1, 1))
    v = rng.normal(0.0, math.sqrt(kT), size=(n, 2))
    v -= v.mean(axis=0)
    typ = np.where(inc, 2, 1)
    if perturb is not None:
        ux, uy, vx, vy = perturb(x, y)
        x, y = x + ux, y + uy
        v = v + np.column_stack((vx, vy))
    with open(path, "w") as f:
        f.write("PE-JUMP benchmark: triangular spring lattice with a stiff inclusion (bench/benchlib.py)\n\n")
        f.write(f"{n} atoms\n3 atom types\n{len(bonds)} bonds\n{2 if soft_as_bonds else 1} bond types\n\n")
        f.write(f"0 {Lx:.17g} xlo xhi\n0 {Ly:.17g} ylo yhi\n-0.5 0.5 zlo zhi\n\n")
        f.write("Atoms # bond\n\n")
        for a in range(n):
            f.write(f"{a+1} 1 {typ[a]} {x[a]:.17g} {y[a]:.17g} 0.0\n")
        f.write("\nVelocities\n\n")
        for a in range(n):
            f.write(f"{a+1} {v[a,0]:.17g} {v[a,1]:.17g} 0.0\n")
        f.write("\nBonds\n\n")
        for k, (a, b, t) in enumerate(bonds):
            f.write(f"{k+1} {t} {a} {b}\n")
    return {"atoms": n, "inclusion": int(inc.sum()), "bonds": len(bonds), "soft": soft,
            "Lx": Lx, "Ly": Ly}


# ---------------------------------------------------------------- references

def chain_reference(springs, q0, p0, T, omega2, soft_power=4, rtol=1e-13):
    """Exact-model reference of one chain (walls fixed): stiff springs
    (omega^2/4) d^2, soft springs d^soft_power; DOP853 at tight tolerance."""
    from scipy.integrate import solve_ivp
    springs = list(springs)
    n = len(springs) - 1
    stiff = np.array([s == "K" for s in springs])

    def rhs(t, y):
        q = np.concatenate(([0.0], y[:n], [0.0]))
        d = np.diff(q)                              # spring extensions
        tension = np.where(stiff, 0.5 * omega2 * d, soft_power * d ** (soft_power - 1))
        f = tension[1:] - tension[:-1]              # force on mobile atom i
        return np.concatenate((y[n:], f))

    y0 = np.concatenate((q0, p0))
    sol = solve_ivp(rhs, (0.0, T), y0, method="DOP853", rtol=rtol, atol=1e-15)
    return sol.y[:n, -1], sol.y[n:, -1]


def wave_exact(x, t, c1=10.0, c2=1.0):
    """Exact solution of the paper's inhomogeneous wave (section 4.3.2)
    with u0 = 0.01 exp(-(20(x-0.2))^2) on (0, 0.5), v0 = -c1 u0'."""
    def g(s):
        return np.where((s > 0) & (s < 0.5), 0.01 * np.exp(-400.0 * (s - 0.2) ** 2), 0.0)
    r = (c2 - c1) / (c1 + c2)
    kmax = int(math.ceil(c1 * t + 0.5)) + 1
    uL = sum(r ** k * (g(x + k - c1 * t) - g(k - x - c1 * t)) for k in range(kmax + 1))
    uR = 2 * c1 / (c1 + c2) * sum(r ** k * g((c1 / c2) * (x - 0.5) + k + 0.5 - c1 * t)
                                  for k in range(kmax + 1))
    return np.where(x <= 0.5, uL, uR)


def median(xs):
    return float(np.median(np.asarray(xs, dtype=float)))


def save_json(path, obj):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(obj, f, indent=1, default=float)


def load_json(path):
    with open(path) as f:
        return json.load(f)
