#!/bin/bash
# PE-JUMP stability stress tests: CFL sweep, long FPU run, nonlinear
# string with adapt, slow/fast resonance over K, hard cases.
#
#   bash bench/stability/run_stress.sh            # full: about 10 minutes on one core
#   bash bench/stability/run_stress.sh --quick    # small versions: about 1-2 minutes
#   bash bench/stability/run_stress.sh --studies cfl,hard
#
# Copies build/lmp and build/liblammps.so.0 to bench/work/stability-bin/ (so a
# rebuild during the run cannot mix binaries; set LMP to use another binary)
# and runs one LAMMPS process at a time. Results: bench/stability/results/*.json
# (the quick run writes *_quick.json), plots doc/stability_*.png (quick run:
# bench/work/stability/), report doc/stability.md (written by hand from them).
set -e
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
PYTHON="${PYTHON:-/usr/bin/python3}"
if [ -z "$LMP" ]; then
  BIN="$ROOT/bench/work/stability-bin"
  mkdir -p "$BIN"
  cp "$ROOT/build/lmp" "$ROOT/build/liblammps.so.0" "$BIN/"
  export LMP="$BIN/lmp"
fi
exec "$PYTHON" "$ROOT/bench/stability/stress.py" "$@"
