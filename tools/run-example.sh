#!/usr/bin/env bash
# set up everything (tools/setup.sh) and run the main example: the
# Fermi-Pasta-Ulam chain with fix pe_jump
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cd examples/fpu
../../build/lmp -in in.fpu
