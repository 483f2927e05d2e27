#!/usr/bin/env python3
"""Checks of the command pages that Sphinx does not do (tools/check_docs.sh).

    python3 tools/check_doc_links.py [--lammps-doc DIR]

Run from anywhere; paths are taken from the repository this file is in.
Each check prints one line, "ok: ..." or "FAILED: ..." followed by what is
wrong; the exit status is the number of failed checks (0 = all passed).

* anchors: no label (``.. _name:``) is defined twice in doc/*.rst (LAMMPS'
  rst_anchor_check);
* links from the pages: every relative link target of doc/*.rst
  (```text <target>`_``) is a file of the repository, and an anchor after
  ``#`` in a link to a Markdown file is one of its headings (GitHub's
  heading ids);
* links into the pages: every Markdown link to a page doc/*.rst from
  doc/*.md, README.md and examples/*/README.md names an existing page, and
  an anchor after ``#`` is a section or label of that page;
* characters and roles: LAMMPS' char_check and role_check of its doc
  Makefile (ASCII only; no ``:doc`` without its colons or backquotes; no
  ```text <link>``` without its trailing underscore);
* index: every fix style of src/ (``FixStyle(name, ...)``) has a
  ``.. index:: fix name`` entry in doc/*.rst (as LAMMPS' check-styles.py);
* LAMMPS pages: every page in doc/sphinx/lammps_pages.txt is linked from a
  page; with --lammps-doc (the doc/src folder of a LAMMPS source tree),
  every one exists there.
"""
import argparse
import glob
import os
import re
import sys
import unicodedata

TOP = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
DOC = os.path.join(TOP, 'doc')


def rel(path):
    return os.path.relpath(path, TOP)


def read(path):
    with open(path, encoding='utf-8') as f:
        return f.read()


def github_slugs(md_text):
    """Heading ids as GitHub makes them for a Markdown file."""
    slugs, seen = set(), {}
    in_fence = False
    for line in md_text.splitlines():
        if line.lstrip().startswith('```'):
            in_fence = not in_fence
            continue
        if in_fence:
            continue
        m = re.match(r'^#{1,6}\s+(.*?)\s*#*\s*$', line)
        if not m:
            continue
        title = re.sub(r'`|\*\*|__', '', m.group(1))
        title = re.sub(r'\[([^\]]*)\]\([^)]*\)', r'\1', title)
        slug = ''.join(c for c in title.lower()
                       if c in ' -_' or unicodedata.category(c)[0] in 'LN')
        slug = slug.replace(' ', '-')
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        slugs.add(slug if n == 0 else f'{slug}-{n}')
    for m in re.finditer(r'<a\s+(?:id|name)="([^"]+)"', md_text):
        slugs.add(m.group(1))
    return slugs


def docutils_id(text):
    """docutils' make_id: lower case, runs of other characters -> '-'."""
    text = unicodedata.normalize('NFKD', text).encode('ascii', 'ignore').decode()
    text = re.sub(r'[^a-z0-9]+', '-', text.lower()).strip('-')
    return text


def rst_ids(rst_text):
    """Ids of the sections and labels of a page (as docutils and GitHub make them)."""
    ids = set()
    lines = rst_text.splitlines()
    for i in range(1, len(lines)):
        under = lines[i]
        if (len(under) >= 3 and len(set(under)) == 1 and under[0] in '=-~^"\'`#*+:.'
                and lines[i - 1].strip() and len(under) >= len(lines[i - 1].rstrip())):
            ids.add(docutils_id(lines[i - 1]))
    for m in re.finditer(r'^\.\. _([^:]+):\s*$', rst_text, re.M):
        ids.add(docutils_id(m.group(1)))
    return ids


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--lammps-doc', help='doc/src folder of a LAMMPS source tree')
    args = ap.parse_args()

    pages = sorted(glob.glob(os.path.join(DOC, '*.rst')))
    failed = 0

    def report(name, problems):
        nonlocal failed
        if problems:
            failed += 1
            print(f'FAILED: {name}')
            for p in problems:
                print(f'  {p}')
        else:
            print(f'ok: {name}')

    # anchors defined twice
    labels, problems = {}, []
    for page in pages:
        for n, line in enumerate(read(page).splitlines(), 1):
            m = re.match(r'^\.\. _(.*):$', line)
            if m:
                labels.setdefault(m.group(1), []).append(f'{rel(page)}:{n}')
    for label, where in sorted(labels.items()):
        if len(where) > 1:
            problems.append(f'label {label} defined {len(where)} times: {", ".join(where)}')
    report(f'anchors ({len(labels)} labels, none defined twice)', problems)

    # links from the pages
    problems, count = [], 0
    for page in pages:
        text = read(page)
        for m in re.finditer(r'`[^`<]*<([^`>]+)>`__?', text):
            target = m.group(1).strip()
            if re.match(r'^[a-z][a-z0-9+.-]*:', target) or target.startswith('/'):
                continue  # absolute URLs are not checked (no network)
            count += 1
            line = text.count('\n', 0, m.start()) + 1
            path, _, anchor = target.partition('#')
            full = os.path.normpath(os.path.join(os.path.dirname(page), path))
            if not os.path.exists(full):
                problems.append(f'{rel(page)}:{line}: {target}: no file {rel(full)}')
            elif anchor and full.endswith('.md') and anchor not in github_slugs(read(full)):
                problems.append(f'{rel(page)}:{line}: {target}: no heading #{anchor} in {rel(full)}')
    report(f'links from the pages ({count} relative links)', problems)

    # links into the pages
    sources = (glob.glob(os.path.join(DOC, '*.md')) + [os.path.join(TOP, 'README.md')]
               + glob.glob(os.path.join(TOP, 'examples', '*', 'README.md')))
    problems, count = [], 0
    for src in sorted(s for s in sources if os.path.exists(s)):
        text = read(src)
        for m in re.finditer(r'\]\((?![a-z][a-z0-9+.-]*:)([^)\s]*\.rst(?:#[^)\s]*)?)\)', text):
            count += 1
            line = text.count('\n', 0, m.start()) + 1
            path, _, anchor = m.group(1).partition('#')
            full = os.path.normpath(os.path.join(os.path.dirname(src), path))
            if not os.path.exists(full):
                problems.append(f'{rel(src)}:{line}: {m.group(1)}: no file {rel(full)}')
            elif anchor and anchor not in rst_ids(read(full)):
                problems.append(f'{rel(src)}:{line}: {m.group(1)}: no section or label #{anchor}')
    report(f'links into the pages ({count} links)', problems)

    # LAMMPS' char_check and role_check
    checks = [(r'[^ -~]', 'a character that is not printable ASCII'),
              (r' :[a-z]+`', 'a role without its closing colon'),
              (r' `[^`]+<[a-z][^`]+`[^_]', 'a link without its trailing underscore'),
              (r':(ref|doc):[^`]', 'a :ref: or :doc: without its backquote'),
              (r'(ref|doc)`[^`]', 'a ref or doc role without its colon')]
    problems = []
    for page in pages:
        for n, line in enumerate(read(page).splitlines(), 1):
            for pattern, what in checks:
                if re.search(pattern, line):
                    problems.append(f'{rel(page)}:{n}: {what}: {line.strip()}')
    report("characters and roles (LAMMPS' char_check, role_check)", problems)

    # index entries of the fix styles
    styles = set()
    for header in glob.glob(os.path.join(TOP, 'src', '**', '*.h'), recursive=True):
        styles.update(re.findall(r'^FixStyle\(([^,\s]+)\s*,', read(header), re.M))
    indexed = set()
    for page in pages:
        indexed.update(re.findall(r'^\.\. index:: fix (\S+)\s*$', read(page), re.M))
    problems = [f'fix style {s} has no ".. index:: fix {s}" in doc/*.rst'
                for s in sorted(styles - indexed)]
    report(f'index entries ({len(styles)} fix styles in src/)', problems)

    # the LAMMPS pages that :doc: links lead to
    listed = []
    for line in read(os.path.join(DOC, 'sphinx', 'lammps_pages.txt')).splitlines():
        line = line.split('#', 1)[0].strip()
        if line:
            listed.append(line)
    linked = set()
    for page in pages:
        for m in re.finditer(r':doc:`([^`]*)`', read(page)):
            target = re.search(r'<([^>]*)>\s*$', m.group(1))
            linked.add((target.group(1) if target else m.group(1)).strip())
    report(f'LAMMPS pages in doc/sphinx/lammps_pages.txt ({len(listed)}) linked from a page',
           [f'{p}: linked from no page' for p in sorted(set(listed) - linked)])
    if args.lammps_doc:
        if not os.path.isdir(args.lammps_doc):
            report('LAMMPS pages', [f'{args.lammps_doc} is not a folder'])
        else:
            problems = [f'{p}: no {p}.rst in {args.lammps_doc}' for p in listed
                        if not os.path.exists(os.path.join(args.lammps_doc, p + '.rst'))]
            report(f'LAMMPS pages ({len(listed)} in doc/sphinx/lammps_pages.txt exist in '
                   f'{args.lammps_doc})', problems)
    else:
        print('note: LAMMPS pages not checked against a LAMMPS manual (no --lammps-doc)')
    return failed


if __name__ == '__main__':
    sys.exit(main())
