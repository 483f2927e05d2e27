#!/usr/bin/env bash
# Long fix langevin runs (10^6 steps each) of fix nve, fix pe_jump (midpoint)
# and fix pe_jump quadrature lobatto 3 on a 256-atom LJ liquid, then the
# summary of analyse.py. About 6 minutes on one core.
#   bash bench/thermostat/run.sh [NSTEPS]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
lmp=${LMP:-$here/../../build/lmp}
nsteps=${1:-1000000}
work=$here/../work/thermostat
mkdir -p "$work"
cd "$work"
for fix in nve pe_jump "pe_jump quadrature lobatto 3"; do
  tag=$(echo "$fix" | tr -d ' ' | sed 's/quadrature/_/')
  "$lmp" -in "$here/in.lj-langevin-long" -var fix "$fix" -var tag "$tag" -var nsteps "$nsteps" \
    -log "log.$tag" -screen none -nocite
done
${PYTHON:-/usr/bin/python3} "$here/analyse.py" "$work" nve pe_jump pe_jump_lobatto3
