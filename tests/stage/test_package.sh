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
[ -x "$WORK/example/laminate" ] || tail -20 "$WORK/configure.log" "$WORK/example.log"
finish
