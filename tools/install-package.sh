#!/usr/bin/env bash
# Add the PE-JUMP sources to a LAMMPS source tree as the package PE-JUMP,
# the way LAMMPS packages are laid out: src/PE-JUMP/ with the styles, and
# the package name in the list of standard packages of LAMMPS' CMake build.
# Then build LAMMPS as usual with -D PKG_PE-JUMP=on.
#   bash tools/install-package.sh /path/to/lammps
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
lammps=${1:?usage: install-package.sh /path/to/lammps}
[ -f "$lammps/src/lammps.h" ] && [ -f "$lammps/cmake/CMakeLists.txt" ] ||
  { echo "install-package: $lammps is not a LAMMPS source tree with a CMake build" >&2; exit 1; }
# the same oldest LAMMPS as cmake/lammps-version.cmake (PEJUMP_SKIP_VERSION_CHECK=1 skips it)
version=$(sed -n 's/^#define LAMMPS_VERSION "\(.*\)"/\1/p' "$lammps/src/version.h")
number=$(date -d "$version" +%Y%m%d 2>/dev/null || echo 0)
if [ "$number" -lt 20250204 ] && [ -z "${PEJUMP_SKIP_VERSION_CHECK:-}" ]; then
  echo "install-package: PE-JUMP needs LAMMPS 4 Feb 2025 or newer (tested with 4 Feb 2025 and" \
    "4 Jul 2026); $lammps is LAMMPS ${version:-of unknown version}, which lacks interfaces the" \
    "styles use (PEJUMP_SKIP_VERSION_CHECK=1 tries anyway)" >&2
  exit 1
fi
mkdir -p "$lammps/src/PE-JUMP"
cp "$here"/src/*.cpp "$here"/src/*.h "$lammps/src/PE-JUMP/"
cat > "$lammps/src/PE-JUMP/README" <<TXT
PE-JUMP: explicit pseudo-energy conserving integrators with momentum jumps
(fix pe_jump, fix pe_jump/async). Documentation, examples and tests are in
the PE-JUMP project, from which these files were copied.
TXT
# register the package name once, next to the other standard packages
if ! grep -q "^  PE-JUMP$" "$lammps/cmake/CMakeLists.txt"; then
  sed -i 's/^set(STANDARD_PACKAGES$/set(STANDARD_PACKAGES\n  PE-JUMP/' "$lammps/cmake/CMakeLists.txt"
  grep -q "^  PE-JUMP$" "$lammps/cmake/CMakeLists.txt" ||
    { echo "install-package: could not find the package list in cmake/CMakeLists.txt" >&2; exit 1; }
fi
echo "install-package: PE-JUMP added to $lammps; build with -D PKG_PE-JUMP=on"
