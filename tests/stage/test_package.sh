#!/bin/bash
# msfab as a CMake package: the build installed into a temporary prefix,
# then a project outside the tree (tests/package) found with
# find_package(msfab), built against it and run (a laminate homogenized,
# compared with the exact value).
BIN=$1 SRC=$(cd "$2" && pwd)
source "$SRC/tests/stage/lib.sh"
BUILD=$(cd "$BIN/.." && pwd)
check "cmake --install into a fresh prefix" -- cmake --install "$BUILD" --prefix "$WORK/prefix" > "$WORK/install.log"
check "... installs the package config" -- test -s "$WORK/prefix/lib/cmake/msfab/msfabConfig.cmake"
check "... the headers" -- test -s "$WORK/prefix/include/msfab/homog/periodic_homogenization.hpp"
check "... and the stages" -- test -x "$WORK/prefix/bin/msfab-simulate"
check "a project outside the tree configures with find_package(msfab)" -- \
  cmake -S "$SRC/tests/package" -B "$WORK/example" -DCMAKE_PREFIX_PATH="$WORK/prefix" -DCMAKE_BUILD_TYPE=Release \
  > "$WORK/configure.log" 2>&1
check "... builds against the installed libraries" -- cmake --build "$WORK/example" > "$WORK/example.log" 2>&1
check "... and its laminate matches the exact stiffness" -- "$WORK/example/laminate"
# The Python package from the prefix: artifacts read, and with the
# bindings built, a cell homogenized by the installed module.
PYPATH="$WORK/prefix/lib/msfab/python"
check "... the Python package" -- test -s "$PYPATH/msfab/__init__.py"
"$BIN/msfab-homogenize" --quiet --out "$WORK/cell.h5" > /dev/null
check "the installed package reads an artifact" -- env PYTHONPATH="$PYPATH" PYTHONDONTWRITEBYTECODE=1 \
  /usr/bin/python3 -m msfab info "$WORK/cell.h5" > /dev/null
if ls "$BUILD/python"/msfab_bindings*.so > /dev/null 2>&1; then
  check "the installed bindings homogenize a cell" -- env PYTHONPATH="$PYPATH" PYTHONDONTWRITEBYTECODE=1 \
    MSFAB_BUILD=/nonexistent /usr/bin/python3 -c "
import numpy as np, msfab, msfab_bindings, sys
assert msfab_bindings.__file__.startswith('$PYPATH'), msfab_bindings.__file__
ids = np.full((4, 4, 4), 1); ids[:, :, :2] = 2
C = msfab.homogenize(ids, [{'id': 1, 'model': 'linear', 'E': 1e6, 'nu': 0.3}, {'id': 2, 'model': 'linear', 'E': 1e5, 'nu': 0.3}])['C']
sys.exit(0 if C[0, 0] > C[2, 2] > 0 else 1)"
fi
[ -x "$WORK/example/laminate" ] || tail -20 "$WORK/configure.log" "$WORK/example.log"
finish
