# Helpers for stage tests: source from a test_*.sh script.
# Usage in a test: BIN=$1 SRC=$2; source "$SRC/tests/stage/lib.sh"
set -u
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
FAILURES=0
PASSES=0

# expect_exit CODE PATTERN -- command...: runs the command, checks its exit
# code and that stderr+stdout contain PATTERN (grep -E).
expect_exit() {
  local code=$1 pattern=$2
  shift 3
  local out rc
  out=$("$@" 2>&1) && rc=0 || rc=$?
  if [ "$rc" != "$code" ]; then
    echo "FAIL: expected exit $code, got $rc: $*"; echo "$out" | tail -5; FAILURES=$((FAILURES + 1)); return
  fi
  if ! grep -Eq -- "$pattern" <<<"$out"; then
    echo "FAIL: output lacks /$pattern/: $*"; echo "$out" | tail -5; FAILURES=$((FAILURES + 1)); return
  fi
  PASSES=$((PASSES + 1))
}

check() {  # check DESCRIPTION -- command...: the command must succeed
  local what=$1
  shift 2
  if "$@"; then PASSES=$((PASSES + 1)); else echo "FAIL: $what"; FAILURES=$((FAILURES + 1)); fi
}

finish() {
  echo "$PASSES checks passed, $FAILURES failed"
  [ "$FAILURES" = 0 ]
}
