#!/bin/sh
# Baseline runs of the three moving-fast-region scenes (one rank each).
# Writes log.<date>.<scene>-<name>.g++.1, final.<...>.dump and
# loadavg.txt (the load of the machine at the start of each run), then
#   python3 analyze.py
# reads them. LMP (default: lmp on the PATH) and DATE (default 24Nov26)
# can be set in the environment; NICE="nice -n 10" on a shared machine.
LMP=${LMP:-lmp}
DATE=${DATE:-24Nov26}
NICE=${NICE:-}
run() {   # scene name args...
  scene=$1; name=$2; shift 2
  echo "$scene-$name $(cat /proc/loadavg)" >> loadavg.txt
  echo "running $scene $name"
  $NICE $LMP -in in.$scene -var name $name -log log.$DATE.$scene-$name.g++.1 -screen none "$@" \
    || echo "  $scene $name FAILED (see the log)"
}
: > loadavg.txt
# scene 1: crack (fine step 0.003, T = 12, 4000 steps)
run crack nve      -var integrator nve
run crack sync     -var integrator sync
run crack async    -var integrator async -var K 10 -var fast static -var R 10.0
run crack async-band -var integrator async -var K 10 -var fast band -var R 10.0
run crack nve-coarse -var integrator nve -var h 0.03
run crack sync-coarse -var integrator sync -var h 0.03
run crack ref      -var integrator sync -var h 0.00075
# the energy error without pair_modify shift (as examples/crack)
run crack nve-noshift   -var integrator nve -var shift no
run crack async-noshift -var integrator async -var K 10 -var fast static -var R 10.0 -var shift no
# scene 2: impact on the bonded lattice (fine step 0.01, T = 25, 2500 steps)
run impact nve     -var integrator nve
run impact sync    -var integrator sync
run impact async   -var integrator async -var K 10 -var fast static -var R 8.0
run impact nve-coarse -var integrator nve -var h 0.1
run impact sync-coarse -var integrator sync -var h 0.1 -var skin 0.5
run impact ref     -var integrator sync -var h 0.0025
# scene 3: cascade (fine step 2e-4, T = 1.0, 5000 steps)
run cascade nve    -var integrator nve -var sites yes
run cascade sync   -var integrator sync
run cascade async  -var integrator async -var K 10 -var fast static -var R 4.0
run cascade nve-coarse -var integrator nve -var h 2e-3
run cascade sync-coarse -var integrator sync -var h 2e-3
run cascade ref    -var integrator sync -var h 5e-5
# tracking runs: the dynamic fast groups of the inputs with fix nve (the
# group is computed, column v_nfast; the integration is plain nve)
run crack track-dyn    -var integrator nve -var fast dynamic
run impact track-dyn   -var integrator nve -var fast dynamic
run impact track-auto  -var integrator nve -var fast auto
run cascade track-dyn  -var integrator nve -var fast dynamic
run cascade track-auto -var integrator nve -var fast auto
# dynamic / automatic fast groups in fix pe_jump/async (atoms change clock
# at coarse nodes; since 8be7040 an atom that changes clock restarts its
# jump with the initial kick of the new step). Main rows at the static
# baselines' K 10, then the variants (see the README, "Dynamic fast groups").
# The fix follows the group at the first coarse node after each of its
# updates (every N steps): every 50 where the region moves slowly (crack
# tip, projectile), every K elsewhere
run crack async-dyn       -var integrator async -var K 10 -var fast dynamic -var R 10.0 -var every 50
# the crack with the energy tip finder (no neighbor list of its own)
run crack sync-pe         -var integrator sync -var tipfind pe
run crack async-pe        -var integrator async -var K 10 -var fast static -var R 10.0 -var tipfind pe
run crack async-dyn-pe    -var integrator async -var K 10 -var fast dynamic -var R 10.0 -var every 50 -var tipfind pe
run impact async-dyn      -var integrator async -var K 10 -var fast dynamic -var R 8.0  -var every 50
run impact async-dyn-r12  -var integrator async -var K 10 -var fast dynamic -var R 12.0 -var every 50
run impact async-auto     -var integrator async -var K 10 -var fast auto -var kthr 0.01 -var every 10 -var skin 0.5
run cascade async-dyn     -var integrator async -var K 10 -var fast dynamic -var R 4.0  -var every 10
run cascade async-dyn-r3  -var integrator async -var K 10 -var fast dynamic -var R 3.0  -var every 10
run cascade async-auto    -var integrator async -var K 10 -var fast auto -var kthr 2.0 -var every 10
run crack async-dyn-k5    -var integrator async -var K 5  -var fast dynamic -var R 10.0 -var every 50
run cascade async-auto-k2 -var integrator async -var K 2  -var fast auto -var kthr 2.0 -var every 2
# fast auto TOL (keyword of fix pe_jump/async): the fix chooses the fine-clock atoms
run impact async-fastauto -var integrator async -var K 10 -var fast keyword -var tol 0.02
run cascade async-fastauto -var integrator async -var K 10 -var fast keyword -var tol 0.02
run cascade async-fastauto-b1 -var integrator async -var K 10 -var fast keyword -var tol 0.02 -var buffer 1
# larger tolerances: fewer fine-clock atoms
run impact async-fastauto-tol0.1 -var integrator async -var K 10 -var fast keyword -var tol 0.1
run impact async-fastauto-tol0.2 -var integrator async -var K 10 -var fast keyword -var tol 0.2
run cascade async-fastauto-tol0.1 -var integrator async -var K 10 -var fast keyword -var tol 0.1
run cascade async-fastauto-tol0.2 -var integrator async -var K 10 -var fast keyword -var tol 0.2
run crack async-fastauto -var integrator async -var K 10 -var fast keyword -var tol 0.02
run crack async-fastauto-tol0.1 -var integrator async -var K 10 -var fast keyword -var tol 0.1
run crack async-fastauto-tol0.2 -var integrator async -var K 10 -var fast keyword -var tol 0.2
# fast auto with a thin buffer: the partners closer than 1.2 (the nearest
# neighbours; keyword buffer 1 within 1.2) of the chosen atoms, those
# about to be hit, join them
run crack async-fastauto-near -var integrator async -var K 10 -var fast keyword -var tol 0.2 -var buffer 1 -var reach 1.2
run impact async-fastauto-near -var integrator async -var K 10 -var fast keyword -var tol 0.2 -var buffer 1 -var reach 1.2
run cascade async-fastauto-near -var integrator async -var K 10 -var fast keyword -var tol 0.05 -var buffer 1 -var reach 1.2
run cascade async-fastauto-near-tol0.02 -var integrator async -var K 10 -var fast keyword -var tol 0.02 -var buffer 1 -var reach 1.2
