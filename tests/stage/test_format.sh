#!/bin/bash
# Every C++ file of the project is laid out as .clang-format says
# (`make -f Makefile.pipeline format` applies it), and the formatter is
# really applied: a file with a layout error is caught.
BIN=$1 SRC=$(cd "$2" && pwd)
source "$SRC/tests/stage/lib.sh"
: "$BIN"
if ! command -v clang-format >/dev/null; then
  echo "FAIL: clang-format is not installed (make -f Makefile.pipeline deps installs it)"
  exit 1
fi
check "the style file is there" -- test -s "$SRC/.clang-format"

# The files: git's list in a checkout, every C++ file under the source
# folders otherwise (an unpacked source tree).
cd "$SRC"
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h')
else
  mapfile -t files < <(find common stages tests tools python -name '*.cpp' -o -name '*.hpp' -o -name '*.h')
fi
check "there are C++ files to check (${#files[@]})" -- test "${#files[@]}" -gt 100
bad=$(clang-format --dry-run "${files[@]}" 2>&1 | sed -n 's|^\([^:]*\):[0-9]*:[0-9]*: warning: code should be clang-formatted.*|\1|p' | sort -u)
if [ -n "$bad" ]; then
  echo "FAIL: not formatted (run make -f Makefile.pipeline format):"; echo "$bad" | head -20
  FAILURES=$((FAILURES + 1))
else
  PASSES=$((PASSES + 1))
fi

# The check can fail: a misformatted copy of a file is reported.
printf 'int  main( ) {return 0 ;}\n' > "$WORK/bad.cpp"
cp .clang-format "$WORK/"
check "a misformatted file is reported" -- bash -c \
  "cd '$WORK' && clang-format --dry-run bad.cpp 2>&1 | grep -q 'code should be clang-formatted'"
finish
