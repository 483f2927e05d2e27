#!/usr/bin/env bash
# Memory and undefined-behaviour checks of the PE-JUMP sources: build them
# (not LAMMPS itself) with AddressSanitizer and UndefinedBehaviorSanitizer
# into build-sanitize/, run the whole test suite and every example input
# (shortened), and report the findings that point into src/ or unittest/.
# Run tools/setup.sh first (packages, LAMMPS source). Results: the summary
# at the end; doc/memory_checks.md records a run.
set -euo pipefail
cd "$(dirname "$0")/.."
top=$(pwd)
build=$top/build-sanitize
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
cmake -S . -B "$build" -G Ninja -D CMAKE_BUILD_TYPE=Release -D PEJUMP_SANITIZE=ON >/dev/null
# the build lists the tests by running the test programs
ASAN_OPTIONS=detect_leaks=0 cmake --build "$build" -j "$(nproc)"
logs=$build/sanitize-logs
rm -rf "$logs"
mkdir -p "$logs"
# leaks of MPI and of LAMMPS' own allocations at exit are not the project's
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=0:log_path=$logs/asan"
export UBSAN_OPTIONS="print_stacktrace=1:log_path=$logs/ubsan"
status=0
(cd "$build" && ctest -j 2 --output-on-failure > "$logs/ctest.txt" 2>&1) || status=1
tail -n 3 "$logs/ctest.txt"
for input in examples/*/in.*; do
  dir=$(dirname "$input")
  (cd "$dir" && timeout 900 "$build/lmp" -in "$(basename "$input")" -log none -screen none \
    -nocite) > /dev/null 2>&1 || echo "example $input stopped with an error"
done
findings=$(cat "$logs"/asan.* "$logs"/ubsan.* 2>/dev/null | grep -cE "ERROR: AddressSanitizer|runtime error" || true)
ours=$(cat "$logs"/asan.* "$logs"/ubsan.* 2>/dev/null | grep -E "^ *#[0-9]+ .* in .*(src/(fix_pe_jump|pe_jump_)|unittest/)" | wc -l || true)
echo "sanitizer reports: $findings; frames in the project's sources: $ours"
[ "$findings" = 0 ] || status=1
exit $status
