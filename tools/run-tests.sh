#!/usr/bin/env bash
# set up everything (tools/setup.sh) and run the whole test suite
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cd build
ctest --output-on-failure -j 2
