#!/bin/sh
# The moving-region study in one command: every run it needs (one MPI rank
# each, one at a time, nice -n 5, median of 3 interleaved rounds) with one
# binary, then bench/results/moving_region/report.json and report.md.
#
#   bash bench/moving_region/run.sh [--lmp PATH] [--reps N] [--quick] ...
#
# LMP (default build/lmp) names the binary; the liblammps.so.0 beside it is
# copied with it. The options are those of moving_region.py (--help).
# Needs /usr/bin/python3 with numpy.
set -e
here=$(cd "$(dirname "$0")" && pwd)
exec /usr/bin/python3 "$here/moving_region.py" "$@"
