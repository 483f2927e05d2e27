#!/usr/bin/env python3
"""Check the links that the error and warning messages of src/ give to doc/Errors_pe_jump.rst.

    python3 tools/check_error_links.py [--html DIR]

The messages append PEJump::errorurl(N) (src/pe_jump_errors.h), which
gives "; see doc/Errors_pe_jump.rst#pejump-errNN". This script fails
(exit status 1) if

* a call of errorurl() in src/ has no literal code (errorurl(3), not
  errorurl(code)), so that the codes can be read from the sources;
* the suffix of src/pe_jump_errors.h is not of the form the checks below
  assume (page path, then "#", an id prefix and the code with two digits);
* a code used in src/ has no section on the page: no label
  ".. _pejump_errNN:" whose HTML id (docutils' make_id, as Sphinx makes
  it: lower case, "_" to "-") is the anchor of the link;
* a label of the page is defined twice, or the labels are not in the
  order of their codes (the page keeps them in a stable order);
* the list at the top of the page does not reference every section;
* with --html DIR (the output of sphinx-build -b html doc DIR, as
  tools/check_docs.sh makes it), the built page has no element with the
  id of a link.

Sections that no message links to (a message removed; codes are not
reused) are listed as a note. Run from anywhere; ctest runs it as
PEJump.ErrorLinksResolve.
"""
import argparse
import glob
import os
import re
import sys
import unicodedata

TOP = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
HEADER = os.path.join(TOP, 'src', 'pe_jump_errors.h')


def read(path):
    with open(path, encoding='utf-8') as f:
        return f.read()


def without_comments(code):
    """C++ comments blanked (newlines kept); string literals left as they are."""
    def blank(m):
        s = m.group(0)
        return s if s[0] in '"\'' else re.sub(r'[^\n]', ' ', s)
    return re.sub(r'"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'|//[^\n]*|/\*.*?\*/', blank, code,
                  flags=re.S)


def docutils_id(text):
    """docutils' make_id: lower case, runs of other characters -> '-'."""
    text = unicodedata.normalize('NFKD', text).encode('ascii', 'ignore').decode()
    return re.sub(r'[^a-z0-9]+', '-', text.lower()).strip('-')


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--html', help='output folder of sphinx-build -b html doc DIR')
    args = ap.parse_args()
    problems = []

    # the form of the link
    m = re.search(r'"; see ([^"#]+)#([a-z-]+)\{:02d\}"', read(HEADER))
    if not m:
        print(f'FAILED: no suffix "; see PAGE#PREFIX{{:02d}}" in {os.path.relpath(HEADER, TOP)}')
        return 1
    page_rel, prefix = m.group(1), m.group(2)
    page = os.path.join(TOP, page_rel)
    if not os.path.isfile(page):
        print(f'FAILED: the messages link to {page_rel}, which does not exist')
        return 1

    # the codes the sources use
    used = {}
    sources = sorted(glob.glob(os.path.join(TOP, 'src', '**', '*.cpp'), recursive=True)
                     + glob.glob(os.path.join(TOP, 'src', '**', '*.h'), recursive=True))
    for path in sources:
        text = without_comments(read(path))
        for call in re.finditer(r'\berrorurl\s*\(([^()]*)\)', text):
            where = f'{os.path.relpath(path, TOP)}:{text.count(chr(10), 0, call.start()) + 1}'
            arg = call.group(1).strip()
            if re.fullmatch(r'\d+', arg):
                used.setdefault(int(arg), []).append(where)
            elif not (path == HEADER and arg == 'int code'):
                problems.append(f'{where}: errorurl({arg}): give the code as a number')

    # the sections of the page
    text = read(page)
    labels = re.findall(r'^\.\. _([^:\s]+):\s*$', text, re.M)
    ids = {}
    for label in labels:
        if label in ids:
            problems.append(f'{page_rel}: label {label} defined twice')
        ids[label] = docutils_id(label)
    label_of_code = '[-_]'.join(re.escape(part) for part in prefix.split('-')) + r'(\d+)'
    codes = [int(mm.group(1)) for label in labels for mm in [re.fullmatch(label_of_code, label)]
             if mm]
    if codes != sorted(codes):
        problems.append(f'{page_rel}: the sections are not in the order of their codes: {codes}')
    anchors = set(ids.values())
    for code, where in sorted(used.items()):
        anchor = f'{prefix}{code:02d}'
        if anchor not in anchors:
            problems.append(f'{", ".join(where)}: errorurl({code}) links to {page_rel}#{anchor}, '
                            f'but the page has no label whose id is {anchor}')
    refs = set(re.findall(r':ref:`[^`]*<([^<>`]+)>`', text.split('\n.. _', 1)[0]))
    for label in labels:
        if label not in refs:
            problems.append(f'{page_rel}: the list at the top does not reference {label}')

    # the built page
    if args.html:
        built = os.path.join(args.html, os.path.splitext(os.path.basename(page_rel))[0] + '.html')
        if not os.path.isfile(built):
            problems.append(f'no built page {built}')
        else:
            html_ids = set(re.findall(r'\bid="([^"]+)"', read(built)))
            for code in sorted(used):
                anchor = f'{prefix}{code:02d}'
                if anchor not in html_ids:
                    problems.append(f'{built}: no element with id="{anchor}" (errorurl({code}))')

    unused = sorted(set(codes) - set(used))
    if unused:
        print('note: sections no message links to: '
              + ', '.join(f'{prefix}{c:02d}' for c in unused))
    if problems:
        print('FAILED: error links')
        for p in problems:
            print(f'  {p}')
        return 1
    print(f'ok: error links ({sum(len(w) for w in used.values())} calls of errorurl() with '
          f'{len(used)} codes in src/, {len(labels)} sections in {page_rel}'
          + (', ids in the built page' if args.html else '') + ')')
    return 0


if __name__ == '__main__':
    sys.exit(main())
