#!/usr/bin/env bash
# The thermostat target of pe_jump/async: in.lj-light-langevin (4000-atom
# LJ liquid, one atom in ten light and on the fine clock, K = 5, fix
# langevin) for 10^5 coarse steps with the midpoint rule (the default) and
# with lobatto 3, and fix nve at the fine step for 5 10^5 steps, then the
# summary and checks of light_langevin.py. About 15 + 18 + 20-30 minutes
# on one core.
#   bash bench/thermostat/light_langevin.sh [NSTEPS]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
lmp=${LMP:-$here/../../build/lmp}
nsteps=${1:-100000}
work=$here/../work/thermostat-light
mkdir -p "$work"
cd "$work"
run() {    # tag, then -var pairs
  local tag=$1
  shift
  "$lmp" -in "$here/in.lj-light-langevin" -var nsteps "$nsteps" -var tag "$tag" "$@" \
    -log "log.$tag" -screen none -nocite
}
run async -var integ async
run async_l3 -var integ async -var quad "lobatto 3"
run nve -var integ nve
${PYTHON:-/usr/bin/python3} "$here/light_langevin.py" "$work" nve async async_l3
