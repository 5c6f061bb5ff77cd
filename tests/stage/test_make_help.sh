#!/bin/bash
# `make -f Makefile.pipeline help` lists every phony target of the pipeline
# with what it does (tools/make_help.sh): none is undocumented. A build
# folder configured for another source tree is refused with a hint.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
cd "$SRC"
make -s -f Makefile.pipeline help > "$WORK/help.txt" 2>&1 || echo "FAIL: make help exited non-zero"
check "no phony target is undocumented" -- bash -c "! grep 'undocumented' '$WORK/help.txt'"
# Every .PHONY name, continuation lines included.
phony=$(awk '/^\.PHONY:/ || c { l = $0; sub(/^\.PHONY:/, "", l); c = (l ~ /\\$/); sub(/\\$/, "", l); print l }' \
  Makefile.pipeline pipelines/*.mk | tr ' \t' '\n\n' | grep -v '^$' | sort -u)
for t in $phony; do
  grep -qE "^  $t( |$)" "$WORK/help.txt" || { echo "FAIL: $t missing from make help"; FAILURES=$((FAILURES + 1)); }
done
check "at least 60 targets listed" -- bash -c "test \$(grep -cE '^  [a-z]' '$WORK/help.txt') -ge 60"

mkdir -p "$WORK/moved"
echo "CMAKE_HOME_DIRECTORY:INTERNAL=/elsewhere/msfab" > "$WORK/moved/CMakeCache.txt"
touch "$WORK/moved/.deps-ok"  # newer than Makefile.pipeline: no package check
expect_exit 2 "moved/ was configured for the sources in /elsewhere/msfab.*rm -rf" -- \
  make -s -f Makefile.pipeline build BUILD="$WORK/moved"
finish
