#!/usr/bin/env bash
# Build checks that LAMMPS asks of a package, after tools/setup.sh: the
# styles compile and run
#   serial  with LAMMPS' serial MPI stubs (-D BUILD_MPI=off)
#   bigbig  with 64-bit atom IDs and image flags (-D LAMMPS_SIZES=bigbig)
# Each builds liblammps and lmp into build-<name>/ with only the packages
# its example needs (no tests, no plugin; ccache keeps rebuilds short) and
# runs examples/fpu-slow-fast for a short time with fix pe_jump/async and
# fix pe_jump; a build error or a run that does not end is a failure.
#
#   bash tools/check-configs.sh [serial] [bigbig]     (default: both; JOBS=n: n compile jobs)
set -euo pipefail
cd "$(dirname "$0")/.."
TOP=$PWD
TREE=$(sed -n 's/^LAMMPS_SOURCE_DIR:PATH=//p' build/CMakeCache.txt 2>/dev/null || true)
[ -n "$TREE" ] || { echo "check-configs: run tools/setup.sh first (build/ has the LAMMPS tree)"; exit 1; }
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}

configure_args() {
  case $1 in
    serial) echo "-D BUILD_MPI=off" ;;
    bigbig) echo "-D LAMMPS_SIZES=bigbig" ;;
    *) echo "check-configs: unknown configuration $1" >&2; return 1 ;;
  esac
}

check() {
  local name=$1 dir=$TOP/build-$1 args log
  args=$(configure_args "$name")
  log=$dir/check-configs.log
  mkdir -p "$dir"
  echo "== $name: configure and build ($args)"
  # shellcheck disable=SC2086
  cmake -S . -B "$dir" -G Ninja -D CMAKE_BUILD_TYPE=Release -D LAMMPS_SOURCE_DIR="$TREE" \
    -D PEJUMP_ENABLE_TESTING=off -D PEJUMP_BUILD_PLUGIN=off -D "PEJUMP_PACKAGES=MOLECULE;CLASS2" \
    -D BUILD_OMP=off $args > "$log" 2>&1 || { tail -30 "$log"; return 1; }
  cmake --build "$dir" -j "${JOBS:-$(nproc)}" >> "$log" 2>&1 || { grep -B2 -A8 "error" "$log" | head -60; return 1; }
  local work
  work=$(mktemp -d)
  for integrator in async sync; do
    (cd "$work" && "$dir/lmp" -in "$TOP/examples/fpu-slow-fast/in.fpu-slow-fast" -var integrator $integrator \
      -var T 2.0 -var record no -log log.$integrator -screen none) ||
      { echo "check-configs: $name: the $integrator run failed"; tail -20 "$work/log.$integrator"; return 1; }
    grep -q "^Total wall time" "$work/log.$integrator" ||
      { echo "check-configs: $name: the $integrator run did not end"; return 1; }
    local fix=pe_jump
    [ "$integrator" = async ] && fix=pe_jump/async
    echo "   $name: fix $fix: $(grep -m1 '^Loop time' "$work/log.$integrator")"
  done
  rm -rf "$work"
}

for name in "${@:-serial bigbig}"; do
  for one in $name; do check "$one"; done
done
echo "check-configs: all configurations built and ran"
