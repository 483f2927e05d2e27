#!/usr/bin/env bash
# PE-JUMP benchmarks: every study that doc/benchmarks.md reports, with one
# binary, then the report (doc/benchmarks.md and doc/bench_*.png).
#
#   bash bench/run_all.sh            full run (about 2 hours on 2 cores)
#   bash bench/run_all.sh --quick    bench.py's stages only, small systems (a few minutes)
#   bash bench/run_all.sh --stages lj_cost,mpi     only these stages of bench.py (then the report)
#   bash bench/run_all.sh --no-wait  do not wait for a quiet machine before timing
#
# The full run, in this order (each study writes its own results, the report
# reads them all and checks that they name the same binary):
#   bench/bench.py (chain, wave, lattice)  work-precision of pe_jump/async's scenes (results/full/)
#   bench/cost/cost.py              overhead of pe_jump/async, 1, 2 and 4 ranks (results/cost/)
#   bench/composite/composite.py    composite lattices against fix nve, and the
#                                   lattices split for run_style respa (results/composite/)
#   bench/moving_region/run.sh      crack, impact, cascade (results/moving_region/)
#   bench/bench.py (the other stages)  the other scenes, per-step cost, MPI, profiles
# --stages or --quick run bench.py alone.
#
# Environment: LMP=/path/to/lmp (default build/lmp; its liblammps.so.0 is
# copied with it), PYTHON (default /usr/bin/python3, which needs numpy, scipy
# and matplotlib).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-/usr/bin/python3}
quick=""
only_bench=""
for a in "$@"; do
  case "$a" in
    --quick) quick="--quick"; only_bench=1 ;;
    --stages*) only_bench=1 ;;
  esac
done

# one copy of the binary for every study: a rebuild during the run cannot mix binaries
src=${LMP:-build/lmp}
bin=$PWD/bench/work/binary
mkdir -p "$bin"
cp -p "$src" "$bin/lmp"
cp -p "$(dirname "$src")/liblammps.so.0" "$bin/liblammps.so.0"
export LMP=$bin/lmp
export LD_LIBRARY_PATH=$bin${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}

if [ -n "$only_bench" ]; then
  "$PY" bench/bench.py "$@"
else
  # the scenes of pe_jump/async first, then the rest of bench.py's stages
  "$PY" bench/bench.py --stages chain,wave,lattice "$@"
  "$PY" bench/cost/cost.py --label current --lmp "$LMP" --libdir "$bin" --reps 7 --ranks 1,2,4 \
    --scenes bonded,lj,springs,chain
  "$PY" bench/cost/cost.py --report --labels current --out bench/results/cost/report.md
  "$PY" bench/composite/composite.py --lmp "$LMP" --label full --reps 3 --variants inc10,inc01
  "$PY" bench/composite/composite.py --lmp "$LMP" --label split --reps 1 --variants inc10split,inc01split
  "$PY" bench/moving_region/moving_region.py --lmp "$LMP"
  "$PY" bench/bench.py --stages lj_cost,mpi,fpu,string,lj_wp,dtreset,skip,profile,retime "$@"
fi
"$PY" bench/report.py $quick
