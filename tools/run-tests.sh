#!/usr/bin/env bash
# set up everything (tools/setup.sh) and run the whole test suite
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
# the configurations LAMMPS asks of a package (serial MPI stubs, 64-bit IDs)
bash tools/check-configs.sh
cd build
ctest --output-on-failure -j 2
