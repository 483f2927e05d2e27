#!/usr/bin/env bash
# Long thermostatted runs (10^6 steps each; fix langevin, temp/csvr,
# temp/berendsen, temp/rescale) of fix nve, fix pe_jump (midpoint) and fix
# pe_jump quadrature lobatto 3 on a 256-atom LJ liquid, then the summary of
# analyse.py for each thermostat. About 22 minutes on one core.
#   bash bench/thermostat/run.sh [NSTEPS]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
lmp=${LMP:-$here/../../build/lmp}
nsteps=${1:-1000000}
work=$here/../work/thermostat
mkdir -p "$work"
cd "$work"
for thermostat in "langevin 1.0 1.0 0.5 48279" "temp/csvr 1.0 1.0 0.5 48279" \
  "temp/berendsen 1.0 1.0 0.5" "temp/rescale 10 1.0 1.0 0.02 1.0"; do
  name=$(echo "$thermostat" | cut -d' ' -f1 | tr '/' '_')
  for fix in nve pe_jump "pe_jump quadrature lobatto 3"; do
    tag=${name}_$(echo "$fix" | tr -d ' ' | sed 's/quadrature/_/')
    jumpsrc='f_1[2]'
    [ "$fix" = nve ] && jumpsrc=0.0
    "$lmp" -in "$here/in.lj-langevin-long" -var fix "$fix" -var tag "$tag" -var nsteps "$nsteps" \
      -var thermostat "$thermostat" -var jumpsrc "$jumpsrc" -log "log.$tag" -screen none -nocite
  done
  echo "fix $thermostat"
  ${PYTHON:-/usr/bin/python3} "$here/analyse.py" "$work" "${name}_nve" "${name}_pe_jump" \
    "${name}_pe_jump_lobatto3"
done
