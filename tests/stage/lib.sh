# Helpers for stage tests: source from a test_*.sh script.
# Usage in a test: BIN=$1 SRC=$2; source "$SRC/tests/stage/lib.sh"
set -u
# MSFAB_TEST_WORK=DIR keeps a test's files in DIR (made if missing) instead
# of a temporary folder removed at the end, e.g. to compare the artifacts
# of two runs.
if [ -n "${MSFAB_TEST_WORK:-}" ]; then
  WORK=$MSFAB_TEST_WORK
  mkdir -p "$WORK"
else
  WORK=$(mktemp -d)
  trap 'rm -rf "$WORK"' EXIT
fi
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

# tiny_cubic3d_set CYCLES: a tiny 3D cubic gamut of one material and void
# (8^3 voxels per cell, 16 particles, seed 3) as $WORK/set.gamut.h5 and
# $WORK/set.microstructures.h5, in about a second per cycle.
tiny_cubic3d_set() {
  cat > "$WORK/set.yaml" <<Y
space: cubic3d
resolution: 8
materials:
  stiff: {E: 1.0e6, nu: 0.3}
population: 16
cycles: $1
initial_beams: 2
beams: {max: 2, min_radius: 0.5, max_radius: 1.5}
continuous: {per_cycle: 0}
level_set: {cells: 8}
Y
  check "a tiny 3D gamut" -- "$BIN/msfab-gamut-sample" --config "$WORK/set.yaml" --seed 3 --out "$WORK/set.gamut.h5" --quiet
}
