#!/usr/bin/env python3
"""Rerun the examples and compare their output with the reference logs.

For every reference log examples/<example>/log.<date>.<name>.<compiler>.<np>
this tool

* works out how the log was made: the -var settings from the example's
  README.md (a table row or, after the rows, a paragraph that names the log
  and gives `-var ...` in backticks; a backticked command with `-in in.<x>`
  also gives the input, for examples with several inputs; a paragraph ends at
  a blank line, at a line naming another log or at the next list item),
  or a command line `lmp -in in.<x> -var ...` in the README or in the comment
  lines echoed at the top of the log whose -var value matches the suffix of the
  log name, e.g. log...lj-langevin-lobatto3... <- -var rule "lobatto 3");
  a log without suffix is the default run; the number of MPI ranks is <np>;
* copies the example folder into a scratch directory under /tmp (the other
  top-level folders of the repository are linked next to it, so relative
  paths such as ../../potentials keep working) and runs
  [mpirun --oversubscribe --allow-run-as-root -np N] lmp -in in.<x> -var ...
  there, one run at a time;
* compares all thermo tables (every numeric column, every row), the lines
  written by `print` commands that contain numbers, and ERROR and WARNING
  lines (without their source location), and reports per log the number of thermo rows,
  whether the output is identical as printed and, if not, the first step where
  it differs and the largest relative difference per column.

Usage:
    python3 tools/compare_example_logs.py [--examples a,b] [--logs PATTERN]
        [--lmp PATH] [--keep] [--workdir DIR] [--timeout SEC] [--dry-run]

The exit code is 0 only if every compared log is identical as printed.
Standard library only.
"""

import argparse
import fnmatch
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLES = os.path.join(REPO, "examples")

LOG_RE = re.compile(r"^log\.([^.]+)\.(.+)\.([^.]+)\.(\d+)$")
NUM_TOKEN_RE = re.compile(
    r"^[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?$|^[-+]?(?:inf|nan|infinity)$",
    re.IGNORECASE)
NUM_IN_TEXT_RE = re.compile(
    r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
SRC_LOC_RE = re.compile(r"\s*\((?:src/)?[\w./-]+\.(?:cpp|h):\d+\)\s*$")


# ---------------------------------------------------------------- run specs

def parse_var_args(text):
    """-var settings of one command line -> list of (name, [values])."""
    try:
        toks = shlex.split(text, comments=True)
    except ValueError:
        return None
    out = []
    i = 0
    while i < len(toks):
        if toks[i] in ("-var", "-v"):
            if i + 2 >= len(toks):
                return None
            name, vals, j = toks[i + 1], [], i + 2
            while j < len(toks) and not toks[j].startswith("-"):
                vals.append(toks[j])
                j += 1
            if not vals:
                return None
            out.append((name, vals))
            i = j
        else:
            i += 1
    return out


def command_lines(text, infile):
    """`lmp -in <infile> ...` command lines in a text -> list of var lists."""
    cands = []
    for line in text.splitlines():
        m = re.search(r"\blmp\s+(-in|-i)\s+(\S+)(.*)$", line)
        if not m or os.path.basename(m.group(2)) != infile:
            continue
        rest = m.group(3)
        # a comment on the line starts with '#' outside quotes; shlex handles it
        v = parse_var_args(rest)
        if v is not None:
            cands.append(v)
    return cands


def input_of(text):
    """the input file named by `-in <file>` (or `-i`) in a command, or None."""
    m = re.search(r"(?:^|\s)(?:-in|-i)\s+(\S+)", text)
    return os.path.basename(m.group(1)) if m else None


def paragraph_vars(readme, logname):
    """-var settings given next to a mention of the log in the README.

    -> list of (input file or None, var list); the table rows that name the
    log come first (a row is specific to the log), then the paragraphs. A
    paragraph ends at a blank line, at a line that names another log, or at
    the next list item. A backticked command that names its input with
    `-in in.<x>` gives that input (examples with several inputs)."""
    m = LOG_RE.match(logname)
    stem = "log.%s.%s." % (m.group(1), m.group(2))
    lines = readme.splitlines()
    rows, paras = [], []
    for k, line in enumerate(lines):
        if stem not in line:
            continue
        if line.lstrip().startswith("|"):
            para, found = [line], rows          # a table row: that row only
        else:
            para, found = [], paras
            for l2 in lines[k:]:
                if not l2.strip():
                    break
                if l2 is not line and "log." in l2 and stem not in l2:
                    break
                if l2 is not line and re.match(r"\s*(?:[*+-]|\d+\.)\s", l2):
                    break
                para.append(l2)
        text = "\n".join(para)
        for seg in re.findall(r"`([^`]*-var\s[^`]*)`", text):
            v = parse_var_args(seg)
            if v:
                found.append((input_of(seg), v))
    return rows + paras


def norm(s):
    return re.sub(r"\s+", "", s).lower()


def run_spec(exdir, logname):
    """(input file, list of (name, values), how it was found) or an error."""
    m = LOG_RE.match(logname)
    name = m.group(2)
    ex = os.path.basename(exdir)
    inputs = sorted(f for f in os.listdir(exdir) if f.startswith("in."))
    if not inputs:
        return None, None, "no in.* file"
    infile = "in." + ex if ("in." + ex) in inputs else inputs[0]
    if name == ex:
        suffix = ""
    elif name.startswith(ex + "-"):
        suffix = name[len(ex) + 1:]
    else:
        suffix = name
    readme_path = os.path.join(exdir, "README.md")
    readme = open(readme_path, errors="replace").read() \
        if os.path.exists(readme_path) else ""

    para = paragraph_vars(readme, logname)
    if para:
        given, vars_ = para[0]
        if given is not None:
            if given not in inputs:
                return None, None, "the README names input %s, which is not here" % given
            infile = given
        return infile, vars_, "README text next to the log name"
    if suffix == "":
        return infile, [], "default run (no suffix in the log name)"
    # command lines of the README and of the input's comments echoed in the log
    logtext = open(os.path.join(exdir, logname), errors="replace").read()
    header = "\n".join(l for l in logtext.splitlines() if l.startswith("#"))
    cands = command_lines(readme, infile) + command_lines(header, infile)
    matches = []
    for v in cands:
        for vname, vals in v:
            val = norm(" ".join(vals))
            if suffix.lower() in (val, norm(vname) + val, norm(vname) + "-" + val):
                matches.append(v)
                break
    if matches:
        matches.sort(key=len)
        return infile, matches[0], "README/log command line matching '%s'" % suffix
    intext = open(os.path.join(exdir, infile), errors="replace").read()
    if re.search(r"^\s*variable\s+integrator\s+index", intext, re.M) \
            and re.fullmatch(r"[\w]+", suffix):
        return infile, [("integrator", [suffix])], \
            "guess: -var integrator %s" % suffix
    return infile, None, "cannot tell how the log was made (suffix '%s')" % suffix


# ---------------------------------------------------------------- log parsing

def print_templates(intext):
    """Regexes matching the output lines of the `print` commands of an input."""
    text = re.sub(r"&\s*\n", " ", intext)
    temps = []
    for m in re.finditer(r'\bprint\s+("""(.*?)"""|"([^"\n]*)"|\'([^\'\n]*)\')',
                         text, re.S):
        s = next(g for g in m.groups()[1:] if g is not None)
        for line in s.splitlines():
            pat, lit, i = [], 0, 0
            while i < len(line):
                c = line[i]
                if c == "$" and i + 1 < len(line):
                    n = line[i + 1]
                    if n == "{":
                        j = line.find("}", i)
                        i = len(line) if j < 0 else j + 1
                    elif n == "(":
                        depth, j = 0, i + 1
                        while j < len(line):
                            if line[j] == "(":
                                depth += 1
                            elif line[j] == ")":
                                depth -= 1
                                if depth == 0:
                                    break
                            j += 1
                        i = j + 1
                    else:
                        i += 2
                    pat.append("(.*?)")
                else:
                    pat.append(re.escape(c))
                    lit += 1
                    i += 1
            if lit >= 4:
                temps.append(re.compile("".join(pat)))
    return temps


def is_num(t):
    return bool(NUM_TOKEN_RE.match(t))


def parse_log(path, temps):
    """thermo tables, print lines with numbers, ERROR and WARNING lines of a log."""
    tables, prints, errors = [], [], []
    cur = None
    expect_header = False
    try:
        lines = open(path, errors="replace").read().splitlines()
    except OSError:
        lines = []
    for line in lines:
        toks = line.split()
        if expect_header:
            expect_header = False
            if toks and not all(is_num(t) for t in toks):
                cur = {"header": toks, "rows": []}
                tables.append(cur)
                continue
        if line.startswith("Per MPI rank memory allocation"):
            expect_header = True
            cur = None
            continue
        if cur is not None:
            if line.startswith("Loop time of"):
                cur = None
                continue
            if len(toks) == len(cur["header"]) and all(is_num(t) for t in toks):
                cur["rows"].append(toks)
                continue
        if line.startswith("ERROR"):
            errors.append(SRC_LOC_RE.sub("", line))
            cur = None
            continue
        if line.startswith("WARNING"):    # (inside a thermo table too)
            errors.append(SRC_LOC_RE.sub("", line))
            continue
        if cur is None and NUM_IN_TEXT_RE.search(line) and \
                any(t.fullmatch(line.rstrip()) for t in temps):
            prints.append(line.rstrip())
    return tables, prints, errors


# ---------------------------------------------------------------- comparing

def to_float(t):
    try:
        return float(t)
    except ValueError:
        return float("nan")


def reldiff(a, b):
    if a == b:
        return 0.0
    if math.isnan(a) and math.isnan(b):
        return 0.0
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf
    return abs(a - b) / max(abs(a), abs(b))


def compare_text_lines(ref, new):
    """print/ERROR lines: (n identical, list of messages, max rel diff)."""
    msgs, worst, same = [], 0.0, 0
    for k in range(max(len(ref), len(new))):
        if k >= len(ref) or k >= len(new):
            msgs.append("line %d only in %s" % (k + 1, "new" if k >= len(ref) else "reference"))
            worst = math.inf
            continue
        a, b = ref[k], new[k]
        if a == b:
            same += 1
            continue
        if NUM_IN_TEXT_RE.sub("#", a) != NUM_IN_TEXT_RE.sub("#", b):
            msgs.append("text differs:\n      ref: %s\n      new: %s" % (a, b))
            worst = math.inf
            continue
        na = [float(x) for x in NUM_IN_TEXT_RE.findall(a)]
        nb = [float(x) for x in NUM_IN_TEXT_RE.findall(b)]
        d = max((reldiff(x, y) for x, y in zip(na, nb)), default=0.0)
        worst = max(worst, d)
        msgs.append("max rel diff %.3g:\n      ref: %s\n      new: %s" % (d, a, b))
    return same, msgs, worst


def compare_tables(ref, new):
    """dict with rows, identical flag, first difference, per-column maxima."""
    res = {"rows_ref": sum(len(t["rows"]) for t in ref),
           "rows_new": sum(len(t["rows"]) for t in new),
           "first": None, "colmax": {}, "notes": []}
    if len(ref) != len(new):
        res["notes"].append("%d thermo tables in the reference, %d in the new log"
                            % (len(ref), len(new)))
    multi = len(ref) > 1

    def where(ti, row, header):
        s = ("step %s" % row[header.index("Step")]) if "Step" in header \
            else "row %s" % row[0]
        return ("run %d %s" % (ti + 1, s)) if multi else s

    for ti in range(min(len(ref), len(new))):
        hr, hn = ref[ti]["header"], new[ti]["header"]
        if hr != hn:
            res["notes"].append("run %d: thermo columns differ: %s / %s"
                                % (ti + 1, " ".join(hr), " ".join(hn)))
            if res["first"] is None:
                res["first"] = "run %d header" % (ti + 1)
        cols = [(c, hr.index(c), hn.index(c)) for c in hr if c in hn]
        rr, rn = ref[ti]["rows"], new[ti]["rows"]
        for k in range(min(len(rr), len(rn))):
            a, b = rr[k], rn[k]
            if a != b and res["first"] is None:
                res["first"] = where(ti, a, hr)
            for c, ia, ib in cols:
                d = reldiff(to_float(a[ia]), to_float(b[ib]))
                if a[ia] != b[ib] and d == 0.0:
                    d = 0.0          # e.g. 0 against -0: differs as printed only
                res["colmax"][c] = max(res["colmax"].get(c, 0.0), d)
        if len(rr) != len(rn):
            res["notes"].append("run %d: %d thermo rows in the reference, %d new"
                                % (ti + 1, len(rr), len(rn)))
            if res["first"] is None:
                k = min(len(rr), len(rn))
                longer = rr if len(rr) > len(rn) else rn
                res["first"] = where(ti, longer[k], hr) + \
                    (" (missing in new)" if len(rr) > len(rn) else " (extra in new)")
    if res["first"] is None and len(ref) != len(new):
        res["first"] = "run %d" % (min(len(ref), len(new)) + 1)
    return res


# ---------------------------------------------------------------- running

def make_scratch(root, ex):
    """root/examples/<ex> as a copy, the other top-level entries as links."""
    os.makedirs(os.path.join(root, "examples"), exist_ok=True)
    for e in os.listdir(REPO):
        if e in ("examples",) or e.startswith("."):
            continue
        dst = os.path.join(root, e)
        if not os.path.lexists(dst):
            os.symlink(os.path.join(REPO, e), dst)
    rundir = os.path.join(root, "examples", ex)
    shutil.copytree(os.path.join(EXAMPLES, ex), rundir, symlinks=True)
    return rundir


def build_cmd(lmp, infile, vars_, np_, newlog):
    cmd = [lmp, "-in", infile]
    for name, vals in vars_:
        cmd += ["-var", name] + list(vals)
    cmd += ["-log", newlog]
    if np_ > 1:
        cmd = ["mpirun", "--oversubscribe", "--allow-run-as-root",
               "-np", str(np_)] + cmd
    return cmd


def binary_stamp(lmp):
    """mtimes of the binary and of the liblammps next to it (rebuild check)."""
    d = os.path.dirname(os.path.realpath(lmp))
    files = [lmp] + sorted(os.path.join(d, f) for f in os.listdir(d)
                           if f.startswith("liblammps") and ".so" in f)
    out = []
    for f in files:
        try:
            out.append((f, os.stat(f).st_mtime))
        except OSError:
            out.append((f, None))
    return tuple(out)


def fmt_d(d):
    if d == 0:
        return "0"
    if math.isinf(d):
        return "inf"
    return "%.2e" % d


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--examples", help="comma-separated example folders (default: all)")
    ap.add_argument("--logs", help="only logs whose file name matches this glob")
    ap.add_argument("--lmp", default="build/lmp",
                    help="LAMMPS binary (default build/lmp, relative to the repository)")
    ap.add_argument("--workdir", help="scratch directory (default: new one under /tmp)")
    ap.add_argument("--keep", action="store_true", help="keep the scratch directory")
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds per run")
    ap.add_argument("--dry-run", action="store_true",
                    help="only print the commands that would be run")
    ap.add_argument("-q", "--quiet", action="store_true",
                    help="no per-line details of print/ERROR differences")
    args = ap.parse_args()

    lmp = args.lmp
    if not os.path.isabs(lmp):
        lmp = os.path.join(REPO, lmp) if os.path.exists(os.path.join(REPO, lmp)) \
            else os.path.abspath(lmp)
    if not args.dry_run and not os.access(lmp, os.X_OK):
        sys.exit("no LAMMPS binary at %s" % lmp)

    exs = sorted(d for d in os.listdir(EXAMPLES)
                 if os.path.isdir(os.path.join(EXAMPLES, d)))
    if args.examples:
        want = [e.strip().strip("/") for e in args.examples.split(",") if e.strip()]
        bad = [e for e in want if e not in exs]
        if bad:
            sys.exit("unknown example(s): %s (have: %s)" % (", ".join(bad), ", ".join(exs)))
        exs = want

    own_tmp = args.workdir is None
    if args.dry_run:
        work = args.workdir or "(none, dry run)"
    else:
        work = args.workdir or tempfile.mkdtemp(prefix="compare_example_logs.",
                                                dir="/tmp")
        os.makedirs(work, exist_ok=True)
    print("lmp: %s\nscratch: %s\n" % (lmp, work))

    summary = []
    all_ok = True
    stamp0 = None if args.dry_run else binary_stamp(lmp)
    if stamp0:
        print("binary: " + ", ".join("%s %s" % (os.path.basename(f),
              time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(t)) if t else "?")
              for f, t in stamp0) + "\n")
    rebuilt = False
    for ex in exs:
        exdir = os.path.join(EXAMPLES, ex)
        logs = sorted(f for f in os.listdir(exdir) if LOG_RE.match(f))
        if args.logs:
            logs = [f for f in logs if fnmatch.fnmatch(f, args.logs)]
        for logname in logs:
            np_ = int(LOG_RE.match(logname).group(4))
            infile, vars_, how = run_spec(exdir, logname)
            print("=== %s/%s (np %d)" % (ex, logname, np_))
            if vars_ is None:
                print("  SKIPPED: %s" % how)
                summary.append((ex, logname, np_, "-", "no run spec", "-", "-"))
                all_ok = False
                continue
            newlog = "log.new." + logname
            cmd = build_cmd(lmp, infile, vars_, np_, newlog)
            print("  how: %s" % how)
            print("  run: %s" % " ".join(shlex.quote(c) for c in cmd))
            if args.dry_run:
                continue
            root = os.path.join(work, logname)
            if os.path.exists(root):
                shutil.rmtree(root)
            rundir = make_scratch(root, ex)
            if not rebuilt and binary_stamp(lmp) != stamp0:
                rebuilt = True
                print("  WARNING: the LAMMPS binary or library changed since the "
                      "start; this and later runs use the new build")
            t0 = time.time()
            with open(os.path.join(rundir, "screen." + logname), "w") as out:
                try:
                    rc = subprocess.run(cmd, cwd=rundir, stdout=out,
                                        stderr=subprocess.STDOUT,
                                        timeout=args.timeout).returncode
                except subprocess.TimeoutExpired:
                    rc = "timeout"
            dt = time.time() - t0
            temps = print_templates(open(os.path.join(exdir, infile),
                                         errors="replace").read())
            rt, rp, re_ = parse_log(os.path.join(exdir, logname), temps)
            nt, npr, ne = parse_log(os.path.join(rundir, newlog), temps)
            res = compare_tables(rt, nt)
            psame, pmsgs, pworst = compare_text_lines(rp, npr)
            esame, emsgs, eworst = compare_text_lines(re_, ne)
            tab_same = res["first"] is None and not res["notes"]
            ok = tab_same and not pmsgs and not emsgs
            if rc not in (0,) and not re_:
                ok = False
            all_ok &= ok
            print("  exit status %s, %.1f s" % (rc, dt))
            print("  thermo rows: %d reference, %d new; %s"
                  % (res["rows_ref"], res["rows_new"],
                     "identical as printed" if tab_same else
                     "differ from %s" % res["first"]))
            for n in res["notes"]:
                print("  note: %s" % n)
            nz = [(c, d) for c, d in res["colmax"].items() if d > 0]
            if not tab_same:
                if nz:
                    print("  largest relative difference per column:")
                    print("    " + ", ".join("%s %s" % (c, fmt_d(d)) for c, d in nz))
                    zero = [c for c, d in res["colmax"].items() if d == 0]
                    if zero:
                        print("    equal in every row: " + " ".join(zero))
            print("  print lines with numbers: %d reference, %d new, %d identical"
                  % (len(rp), len(npr), psame))
            if not args.quiet:
                for msg in pmsgs:
                    print("    " + msg)
            if re_ or ne:
                print("  ERROR and WARNING lines: %d reference, %d new, %d identical "
                      "(source location ignored)" % (len(re_), len(ne), esame))
                if not args.quiet:
                    for msg in emsgs:
                        print("    " + msg)
            if rc not in (0,) and not re_:
                print("  the new run failed; see %s" %
                      os.path.join(rundir, "screen." + logname))
            tworst = max([d for _, d in nz], default=0.0)
            worst = max(tworst, pworst if pmsgs else 0.0)
            wcol = ("print" if pmsgs and pworst > tworst else
                    max(nz, key=lambda cd: cd[1])[0] if nz else
                    ("print" if pmsgs else ""))
            summary.append((ex, logname, np_, "%d/%d" % (res["rows_ref"], res["rows_new"]),
                            "yes" if ok else "NO",
                            "-" if ok else (res["first"] or
                                            ("print lines" if pmsgs else "ERROR line")),
                            ("%s (%s)" % (fmt_d(worst), wcol)) if wcol else
                            ("0" if ok else "-")))
            print()

    if not args.dry_run:
        print("example | log | np | rows ref/new | identical | first difference | largest rel. diff")
        for row in summary:
            print(" | ".join(str(x) for x in row))
        if rebuilt or binary_stamp(lmp) != stamp0:
            all_ok = False
            print("\nWARNING: the binary was rebuilt during this comparison; "
                  "the results mix two builds")
        print("\nall identical as printed" if all_ok else "\nsome logs differ")
    if own_tmp and not args.keep and not args.dry_run:
        shutil.rmtree(work, ignore_errors=True)
    elif not args.dry_run:
        print("scratch kept: %s" % work)
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
