#!/usr/bin/env bash
# valgrind (memcheck) on every example input of the project with the
# lmp of build/ (tools/setup.sh builds it): prints the error summary of
# each run and exits non-zero if any run has errors. Open MPI's own
# suppression file hides the MPI library's known reports.
set -uo pipefail
cd "$(dirname "$0")/.."
top=$(pwd)
lmp=${LMP:-$top/build/lmp}
supp=""
for f in /usr/share/openmpi/openmpi-valgrind.supp; do [ -f "$f" ] && supp="--suppressions=$f"; done
status=0
for input in examples/*/in.*; do
  dir=$(dirname "$input")
  out=$(cd "$dir" && valgrind --error-exitcode=3 $supp "$lmp" -in "$(basename "$input")" \
    -log none -screen none -nocite 2>&1 >/dev/null)
  rc=$?
  summary=$(echo "$out" | grep "ERROR SUMMARY" | tail -n 1 | sed 's/^==[0-9]*== //')
  echo "$input: $summary"
  [ $rc -eq 3 ] && status=1
done
exit $status
