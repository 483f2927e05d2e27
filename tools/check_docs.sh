#!/usr/bin/env bash
# Build the command pages doc/fix_pe_jump.rst and doc/fix_pe_jump_async.rst
# and the page of error details doc/Errors_pe_jump.rst with Sphinx, warnings
# being errors (sphinx-build -W), and run the checks of the LAMMPS manual that
# apply to them:
#
#   1. HTML build, -W (configuration in doc/sphinx/conf.py; :doc: links to
#      LAMMPS pages must be listed in doc/sphinx/lammps_pages.txt)
#   2. anchors and links, LAMMPS' char_check and role_check, index entries of
#      the fix styles, the listed LAMMPS pages (tools/check_doc_links.py), and
#      the links of the error messages to doc/Errors_pe_jump.rst, with their
#      ids in the HTML (tools/check_error_links.py)
#   3. spelling (sphinxcontrib.spelling, American English, with the project's
#      word list doc/sphinx/spelling_wordlist.txt), if the extension and an
#      en_US dictionary are installed; with --require-spelling their absence
#      is a failure
#
#   bash tools/check_docs.sh [--out DIR] [--lammps-doc DIR] [--require-spelling]
#
# --out DIR         where the HTML goes (default build/docs); DIR/html/sphinx/index.html
# --lammps-doc DIR  the doc/src folder of a LAMMPS source tree: check the listed
#                   LAMMPS pages against it (default: the one of the LAMMPS tree
#                   in build/CMakeCache.txt, if there is one)
#
# Needs Debian's python3-sphinx (and for step 3 python3-sphinxcontrib.spelling
# and hunspell-en-us); tools/setup.sh installs them.  Exits non-zero if any
# step fails, also when sphinx-build is missing.
set -uo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
out=$top/build/docs
lammps_doc=""
require_spelling=0
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    --lammps-doc) lammps_doc=$2; shift 2 ;;
    --require-spelling) require_spelling=1; shift ;;
    -h|--help) sed -n '2,/^set /p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "check_docs: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done

if ! command -v sphinx-build >/dev/null 2>&1; then
  echo "check_docs: FAILED: sphinx-build not found; install Debian's python3-sphinx" \
       "(apt-get install python3-sphinx; tools/setup.sh installs it)"
  echo "docs: 0 passed, 1 failed"
  exit 1
fi
# the Python that runs sphinx-build (for the look-up of the spelling extension)
sphinx_python=$(head -1 "$(command -v sphinx-build)" | sed -n 's/^#! *//p' | awk '{print $1}')
if [ -z "$sphinx_python" ] || [ ! -x "$sphinx_python" ] || [ "$(basename "$sphinx_python")" = env ]; then
  sphinx_python=python3
fi

if [ -z "$lammps_doc" ] && [ -f "$top/build/CMakeCache.txt" ]; then
  tree=$(sed -n 's/^LAMMPS_SOURCE_DIR:PATH=//p' "$top/build/CMakeCache.txt")
  for d in "$tree/doc/src" "$tree/../doc/src"; do
    [ -n "$tree" ] && [ -d "$d" ] && { lammps_doc=$(cd "$d" && pwd); break; }
  done
fi

passed=0 failed=0
step() { # name, command...
  local name=$1; shift
  echo "== $name"
  if "$@"; then
    passed=$((passed + 1)); echo "== $name: passed"
  else
    failed=$((failed + 1)); echo "== $name: FAILED"
  fi
}

mkdir -p "$out"
html() {
  rm -rf "$out/html" "$out/doctrees"
  sphinx-build -W --keep-going -q -j 1 -c "$top/doc/sphinx" -d "$out/doctrees" -b html \
    "$top/doc" "$out/html" 2>&1 | tee "$out/html-warnings.log"
  local rc=${PIPESTATUS[0]}
  echo "sphinx-build -b html: exit $rc, $(grep -c 'WARNING\|ERROR' "$out/html-warnings.log") warnings; pages in $out/html"
  return "$rc"
}
step "sphinx-build -W -b html" html

links() {
  python3 "$top/tools/check_doc_links.py" ${lammps_doc:+--lammps-doc "$lammps_doc"}
  local rc=$?
  # the links of the error messages to doc/Errors_pe_jump.rst, and their ids in the HTML
  python3 "$top/tools/check_error_links.py" --html "$out/html" || rc=1
  return "$rc"
}
step "anchors, links, characters, roles, index entries, LAMMPS pages" links

if "$sphinx_python" -c 'import sphinxcontrib.spelling, enchant, sys; sys.exit(0 if enchant.dict_exists("en_US") else 1)' 2>/dev/null; then
  spelling() {
    rm -rf "$out/spelling"
    sphinx-build -W --keep-going -q -j 1 -c "$top/doc/sphinx" -d "$out/doctrees-spelling" -b spelling \
      "$top/doc" "$out/spelling" 2>&1 | tee "$out/spelling-warnings.log"
    local rc=${PIPESTATUS[0]}
    echo "sphinx-build -b spelling: exit $rc, $(grep -c 'Spell check' "$out/spelling-warnings.log") misspelled words" \
         "(a word that is right goes into doc/sphinx/spelling_wordlist.txt)"
    return "$rc"
  }
  step "spelling (en_US + doc/sphinx/spelling_wordlist.txt)" spelling
elif [ $require_spelling = 1 ]; then
  echo "== spelling: FAILED: the spelling check needs sphinxcontrib.spelling and an en_US" \
       "dictionary for $sphinx_python (apt-get install python3-sphinxcontrib.spelling hunspell-en-us)"
  failed=$((failed + 1))
else
  echo "== spelling: NOT RUN: sphinxcontrib.spelling or an en_US dictionary is missing" \
       "(apt-get install python3-sphinxcontrib.spelling hunspell-en-us)"
fi

echo "docs: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
