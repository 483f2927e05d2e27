#!/usr/bin/env bash
# PE-JUMP benchmarks: run every stage and write doc/benchmarks.md + doc/bench_*.png
#
#   bash bench/run_all.sh            full run (about 20-30 minutes on 2 cores)
#   bash bench/run_all.sh --quick    small systems, few repetitions (a few minutes)
#   bash bench/run_all.sh --stages lj_cost,mpi     only some stages (then the report)
#   bash bench/run_all.sh --no-wait  do not wait for a quiet machine before timing
#
# Environment: LMP=/path/to/lmp (default build/lmp), PYTHON (default /usr/bin/python3,
# which needs numpy, scipy and matplotlib).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-/usr/bin/python3}
quick=""
for a in "$@"; do [ "$a" = "--quick" ] && quick="--quick"; done
"$PY" bench/bench.py "$@"
"$PY" bench/report.py $quick
