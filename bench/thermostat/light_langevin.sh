#!/usr/bin/env bash
# The thermostat target of pe_jump/async: in.lj-light-langevin (4000-atom
# LJ liquid, one atom in ten light and on the fine clock, K = 5, fix
# langevin) for 10^5 coarse steps, and fix nve at the fine step for 5 10^5
# steps, then the summary and checks of light_langevin.py. About 15 + 35
# minutes on one core.
#   bash bench/thermostat/light_langevin.sh [NSTEPS]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
lmp=${LMP:-$here/../../build/lmp}
nsteps=${1:-100000}
work=$here/../work/thermostat-light
mkdir -p "$work"
cd "$work"
for integ in async nve; do
  "$lmp" -in "$here/in.lj-light-langevin" -var integ "$integ" -var nsteps "$nsteps" \
    -log "log.$integ" -screen none -nocite
done
${PYTHON:-/usr/bin/python3} "$here/light_langevin.py" "$work" nve async
