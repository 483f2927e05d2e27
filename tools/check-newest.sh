#!/usr/bin/env bash
# The project against the newest LAMMPS release that Debian has (4 Jul 2026,
# Debian unstable), beside the default one (4 Feb 2025, Debian 13): builds
# it into build-newest/ (or $NEWEST_BUILD), runs the whole test suite there,
# and shows that each release's plugin refuses to load into the other's lmp.
# Run tools/setup.sh first (the default build). A cold build of the newest
# release takes about 40 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
top=$(pwd)
newest=${NEWEST_BUILD:-$top/build-newest}
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
cmake -S . -B "$newest" -G Ninja -D CMAKE_BUILD_TYPE=Release -D PEJUMP_LAMMPS_RELEASE=newest >/dev/null
cmake --build "$newest" -j "$(nproc)"
(cd "$newest" && ctest --output-on-failure -j 2)

# each plugin in the other release's lmp: refused, naming both versions
check=$(mktemp -d)
trap 'rm -rf "$check"' EXIT
status=0
for pair in "$top/build/pejumpplugin.so:$newest/lmp" "$newest/pejumpplugin.so:$top/build/lmp"; do
  plugin=${pair%%:*} lmp=${pair##*:}
  echo "plugin load $plugin" > "$check/in.load"
  out=$("$lmp" -in "$check/in.load" -log none -nocite 2>&1 || true)
  if echo "$out" | grep -q "ERROR: The PE-JUMP plugin was built for LAMMPS version"; then
    echo "refused as it must: $(echo "$out" | grep -o 'built for LAMMPS version [^:]*')"
  else
    echo "NOT refused: $plugin in $lmp"
    status=1
  fi
done
exit $status
