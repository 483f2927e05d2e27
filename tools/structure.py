#!/usr/bin/env python3
"""Structure figures of src/ at a git revision (file and function sizes, members per class).

    python3 tools/structure.py [--rev REV] [--top N] [--members] [--all-functions]

Reads the files of src/ as committed at REV (default HEAD; the working tree
is not read, so uncommitted edits do not count) and prints

* lines: `wc -l` of every file of src/ (src/plugin and dot files included,
  as `git ls-tree` lists them), the number of files, and the lines of
  fix_pe_jump.cpp and fix_pe_jump_async.cpp;
* data members per class (every class or struct defined in a header of
  src/, nested ones as Outer::Inner): the declared names in the class body
  itself (`double a, b;` counts 2, `double x[3];` counts 1); not counted:
  member functions, static constexpr constants (and other static members),
  type aliases (using, typedef), enums, nested struct/class definitions
  (they are counted as classes of their own), friends;
* the longest functions of the .cpp files (and inline ones in the headers),
  length from the first line of the definition (its return type, or the
  template line) to the closing brace, both included;
* "save f, compute, restore f": the places that copy atom->f into a saved
  array and back, found as a copy loop `...[i][k] = f[i][k]` whose reverse
  `f[i][k] = ...[i][k]` follows in the same function;
* declared member functions of src/ classes that nothing in src/ calls (a
  hint of dead code; LAMMPS callbacks marked `override` are left out).

Comments, string and character literals are blanked before anything is
parsed; the parser is a brace matcher, good for the style of these sources
(clang-format), not a C++ front end. Standard library and git only.
"""

import argparse
import re
import subprocess
import sys
import os

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def git(*args):
    return subprocess.run(["git", "-C", REPO] + list(args), check=True,
                          capture_output=True, text=True).stdout


def files_at(rev):
    names = git("ls-tree", "-r", "--name-only", rev, "--", "src").split()
    return {n: git("show", "%s:%s" % (rev, n)) for n in names}


def blank_comments(text):
    """comments and literals -> spaces (newlines kept, so lines stay)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * max(0, j - i - 2) + c)
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def blank_preprocessor(text):
    return "\n".join("" if l.lstrip().startswith("#") else l for l in text.split("\n"))


def match_brace(text, i):
    """index of the brace that closes the one at i."""
    depth = 0
    for j in range(i, len(text)):
        if text[j] == "{":
            depth += 1
        elif text[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(text) - 1


def split_top(s, sep=","):
    """split at sep outside (), [], {}, <>."""
    parts, depth, cur = [], 0, []
    for c in s:
        if c in "([{<":
            depth += 1
        elif c in ")]}>":
            depth -= 1
        if c == sep and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(c)
    parts.append("".join(cur))
    return parts


def strip_templates(s):
    """remove <...> argument lists (nested), keep the rest."""
    prev = None
    while prev != s:
        prev = s
        s = re.sub(r"<[^<>]*>", "", s)
    return s


CLASS_HEAD = re.compile(r"\b(class|struct)\s+(\w+)\s*(?:final\s*)?(?::[^;{]*)?\{")


def class_bodies(text, outer=""):
    """(qualified name, body text) of the classes defined in text (nested too)."""
    out, pos = [], 0
    while True:
        m = CLASS_HEAD.search(text, pos)
        if not m:
            return out
        if re.search(r"\benum\s*$", text[:m.start()]):        # enum class X {
            pos = match_brace(text, m.end() - 1) + 1
            continue
        open_ = m.end() - 1
        close = match_brace(text, open_)
        name = (outer + "::" if outer else "") + m.group(2)
        body = text[open_ + 1:close]
        out.append((name, body))
        out.extend(class_bodies(body, name))
        pos = close + 1


def member_statements(body):
    """the statements of a class body at its own level: nested braces that
    are function bodies or nested definitions end a statement; brace
    initialisers stay in it."""
    stmts, cur, i, n = [], [], 0, len(body)
    while i < n:
        c = body[i]
        if c == "{":
            j = match_brace(body, i)
            head = "".join(cur).strip()
            if re.search(r"\b(class|struct|union|enum)\b[^=()]*$", head) \
                    and not re.search(r"=\s*$", head):
                # a nested definition: skip it and what follows up to ';'
                k = body.find(";", j)
                tail = body[j + 1:k if k >= 0 else n].strip()
                stmts.append(("nested", head, tail))
                cur = []
                i = (k if k >= 0 else n - 1) + 1
                continue
            if re.search(r"\)\s*(const|override|final|noexcept|\s)*$", head) \
                    or re.search(r"\)\s*:.*$", head, re.S):
                stmts.append(("stmt", head + " {}", ""))     # inline function
                cur = []
                i = j + 1
                continue
            cur.append(body[i:j + 1])                        # brace initialiser
            i = j + 1
            continue
        if c == ";":
            stmts.append(("stmt", "".join(cur).strip(), ""))
            cur = []
        else:
            cur.append(c)
        i += 1
    return stmts


def data_members(body):
    """declared data member names of one class body."""
    names = []
    for kind, s, tail in member_statements(body):
        if kind == "nested":
            # struct X {...} a, b;  declares members of the outer class too
            if tail and not s.startswith("enum"):
                names += [t.strip() for t in split_top(tail) if t.strip()]
            continue
        s = re.sub(r"\b(public|protected|private)\s*:", " ", s).strip()
        if not s:
            continue
        first = s.split()[0]
        if first in ("using", "typedef", "friend", "static", "template", "enum") \
                or s.startswith("static"):
            continue
        if re.search(r"\boperator\b", s):
            continue
        decl = strip_templates(s)
        # initialisers go: "= ..." and "{...}"
        decl = re.sub(r"\{[^{}]*\}", "", decl)
        parts = split_top(decl)
        first_part = parts[0].split("=")[0]
        if "(" in first_part:
            # a function (or function pointer member: (*name)(...))
            if not re.search(r"\(\s*\*\s*\w+\s*\)\s*\(", first_part):
                continue
        for p in parts:
            p = p.split("=")[0].strip()
            p = re.sub(r"\[[^\]]*\]", "", p).strip()
            m = re.search(r"(\w+)\s*$", p) or re.search(r"\(\s*\*\s*(\w+)\s*\)", p)
            if m:
                names.append(m.group(1))
    return names


FUNC_HEAD = re.compile(r"(\w[\w:~<>,\s\*&]*?)\s*\(")


def functions(text, fname):
    """(name, first line, last line) of the function definitions of a file:
    a brace block whose head (since the last ';', '}' or namespace '{')
    has a parameter list; namespace and class blocks are entered."""
    out = []
    lineno = lambda k: text.count("\n", 0, k) + 1

    def scan(lo, hi, scope):
        i, start = lo, lo
        while i < hi:
            c = text[i]
            if c in ";}":
                start = i + 1
            elif c == "{":
                j = match_brace(text, i)
                head = text[start:i]
                hs = head.strip()
                if re.search(r"\)\s*:", hs) and re.search(r"\w\s*$", hs) \
                        and not re.search(r"\b(const|override|noexcept|final)\s*$", hs):
                    i = j + 1          # name{...} in a constructor's initialiser list
                    continue
                mcls = re.search(r"\b(class|struct)\s+(\w+)[^;{()]*$", hs)
                if re.match(r"^(namespace\b|extern\b)", hs) or hs == "":
                    scan(i + 1, j, scope)
                elif mcls and "(" not in hs:
                    scan(i + 1, j, scope + [mcls.group(2)])
                elif "(" in hs and not re.search(r"\b(enum|union)\b", hs) \
                        and not re.search(r"=\s*$", hs):
                    sig = re.sub(r"\s+", " ", hs)
                    core = sig.split("(")[0]
                    # constructor initialiser lists: name before the first '('
                    m = re.search(r"([\w:~]+)\s*$", core)
                    name = m.group(1) if m else core
                    if scope and "::" not in name:
                        name = "::".join(scope) + "::" + name
                    first = lineno(start + len(head) - len(head.lstrip()))
                    out.append((name, first, lineno(j), fname))
                start = j + 1
                i = j
            i += 1

    scan(0, len(text), [])
    return out


F_EXPR = r"(?:[\w.]+(?:->|\.))*f"          # f, atom->f, nodes.atom->f
SAVES = [r"memcpy\(\s*&(\w+(?:\.\w+)*)\[0\]\[0\]\s*,\s*&%s\[0\]\[0\]" % F_EXPR,
         r"\b(\w+(?:\.\w+)*)\[\w+\]\[\w+\]\s*=\s*%s\[\w+\]\[\w+\]\s*;" % F_EXPR,
         r"copy_forces\(\s*%s\s*,\s*(\w+(?:\.\w+)*)\s*\)" % F_EXPR]
RESTORES = [r"memcpy\(\s*&%s\[0\]\[0\]\s*,\s*&(\w+(?:\.\w+)*)\[0\]\[0\]" % F_EXPR,
            r"\b%s\[\w+\]\[\w+\]\s*=\s*(\w+(?:\.\w+)*)\[\w+\]\[\w+\]\s*;" % F_EXPR,
            r"copy_forces\(\s*(\w+(?:\.\w+)*)\s*,\s*%s\s*\)" % F_EXPR]


def save_restore(text, funcs):
    """places that copy the forces f into an array and later back: within
    one function, or saved by a class's constructor and restored by its
    destructor (a guard object)."""
    lines = text.split("\n")
    saved, restored = {}, {}
    for name, a, b, fname in funcs:
        body = "\n".join(lines[a - 1:b])
        saved[name] = {m.group(1).split(".")[-1] for r in SAVES for m in re.finditer(r, body)}
        restored[name] = {m.group(1).split(".")[-1] for r in RESTORES
                          for m in re.finditer(r, body)}
    found = []
    for name in saved:
        both = saved[name] & restored[name]
        if both:
            found.append("%s (%s)" % (name, ", ".join(sorted(both))))
        parts = name.split("::")
        if len(parts) >= 2 and parts[-1] == parts[-2]:
            dtor = "::".join(parts[:-1] + ["~" + parts[-1]])
            guard = saved[name] & restored.get(dtor, set())
            if guard:
                found.append("%s and %s (%s)" % (name, dtor, ", ".join(sorted(guard))))
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rev", default="HEAD", help="git revision (default HEAD)")
    ap.add_argument("--top", type=int, default=5, help="longest functions shown")
    ap.add_argument("--members", action="store_true",
                    help="list the counted member names of every class")
    args = ap.parse_args()

    rev = git("rev-parse", "--short", args.rev).strip()
    files = files_at(args.rev)
    clean = {n: blank_preprocessor(blank_comments(t)) for n, t in files.items()}

    top = [n for n in files if re.fullmatch(r"src/[^/]+\.(cpp|h)", n)]
    total = sum(files[n].count("\n") for n in top)
    print("revision %s" % rev)
    print("lines in src/*.cpp src/*.h (wc -l): %d in %d files" % (total, len(top)))
    for n in sorted(set(files) - set(top)):
        print("  not counted: %s (%d lines)" % (n, files[n].count("\n")))
    for n in ("src/fix_pe_jump.cpp", "src/fix_pe_jump_async.cpp"):
        if n in files:
            print("  %s: %d" % (n, files[n].count("\n")))

    print("\ndata members (declared names in the class body):")
    classes = []
    for n in sorted(clean):
        if n.endswith(".h"):
            for cname, body in class_bodies(clean[n]):
                classes.append((cname, data_members(body), n))
    for cname, names, n in classes:
        print("  %-34s %3d  (%s)" % (cname, len(names), os.path.basename(n)))
        if args.members:
            print("      " + ", ".join(names))

    funcs = []
    for n in sorted(clean):
        if n.endswith((".cpp", ".h")):
            funcs += functions(clean[n], os.path.basename(n))
    funcs.sort(key=lambda f: -(f[2] - f[1] + 1))
    print("\nlongest functions (first line of the definition to the closing brace):")
    for name, a, b, fname in funcs[:args.top]:
        print("  %-44s %4d  (%s:%d-%d)" % (name, b - a + 1, fname, a, b))

    sr = []
    for n in sorted(clean):
        if n.endswith(".cpp"):
            sr += save_restore(clean[n], [f for f in funcs if f[3] == os.path.basename(n)])
    print("\n\"save f, compute, restore f\" written out: %d" % len(sr))
    for s in sr:
        print("  " + s)

    # member functions declared in the headers that nothing calls: the
    # mentions "name(" in src/ less the declarations in class bodies and the
    # out-of-class definitions
    declared = {}
    for n, t in clean.items():
        if n.endswith(".h"):
            for cname, body in class_bodies(t):
                for kind, st, _ in member_statements(body):
                    if kind != "stmt" or "(" not in st or re.search(r"\boperator\b", st):
                        continue
                    st2 = re.sub(r"\b(public|protected|private)\s*:", " ", st)
                    m = re.search(r"(~?\w+)\s*\(", strip_templates(st2))
                    if not m or m.group(1).startswith("~") \
                            or m.group(1) == cname.split("::")[-1]:
                        continue
                    d = declared.setdefault(m.group(1), [0, False])
                    d[0] += 1
                    d[1] |= bool(re.search(r"\boverride\b", st2))
    alltext = "\n".join(clean.values())
    defined = {}
    for name, a, b, fname in funcs:
        if fname.endswith(".cpp"):
            short = name.split("::")[-1]
            defined[short] = defined.get(short, 0) + 1
    unused = []
    for name, (ndecl, override) in sorted(declared.items()):
        if override:
            continue                        # LAMMPS calls it
        mentions = len(re.findall(r"(?<!\w)%s\s*\(" % re.escape(name), alltext))
        if mentions - ndecl - defined.get(name, 0) <= 0:
            unused.append(name)
    print("\nmember functions declared but not called in src/: %s"
          % (", ".join(unused) if unused else "none"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
