#!/bin/bash
# The demo pipeline end to end through Makefile.pipeline: builds the
# artifact, skips it when nothing changed, rebuilds it when its config did;
# the coarsened run and the page of pictures that ends the demo.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
BUILD=$(dirname "$BIN")
cp -r "$SRC/configs" "$SRC/pipelines" "$SRC/Makefile.pipeline" "$WORK/"
ln -s "$SRC/python" "$WORK/python"; ln -s "$SRC/common" "$WORK/common"; ln -s "$SRC/stages" "$WORK/stages"; ln -s "$SRC/CMakeLists.txt" "$WORK/CMakeLists.txt"
ln -s "$SRC/tools" "$WORK/tools"; ln -s "$SRC/cmake" "$WORK/cmake"
mkdir -p "$BUILD" && touch "$BUILD/.deps-ok"
# The binaries are newer than the sources after a build; make must not rebuild them.
touch "$BIN"/msfab-*
cd "$WORK"
run_make() { make -f Makefile.pipeline BUILD="$BUILD" OUT="$WORK/out" THREADS=2 "$@"; }
expect_exit 0 "converged in" -- run_make "$WORK/out/demo/bar.result.h5"
check "artifact written" -- test -s out/demo/bar.result.h5
check "sidecar written" -- test -s out/demo/bar.result.xmf
expect_exit 0 "up to date|Nothing to be done" -- run_make "$WORK/out/demo/bar.result.h5"
sleep 1; touch configs/scenes/demo_bar.yaml
expect_exit 0 "converged in" -- run_make "$WORK/out/demo/bar.result.h5"
expect_exit 0 "schema +msfab.result" -- "$BIN/msfab-inspect" out/demo/bar.result.h5
# The coarsened demo: tiny database, then the DDFEM run against the fine one.
expect_exit 0 "vs fine: error" -- run_make "$WORK/out/demo/bar.ddfem.result.h5"
check "database built" -- test -s out/ddfem/tiny.coarse_db.h5
expect_exit 0 "up to date|Nothing to be done" -- run_make "$WORK/out/demo/bar.ddfem.result.h5"
# The demo ends with a picture: speed against error of the coarsened run.
expect_exit 0 "report.html: 2 pictures" -- run_make "$WORK/out/demo/report.html"
check "speed against error drawn" -- test -s out/demo/report_files/01_speed_error_demo-bar.png
expect_exit 0 "up to date|Nothing to be done" -- run_make "$WORK/out/demo/report.html"
finish
