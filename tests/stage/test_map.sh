#!/bin/bash
# msfab-map: bad input exits with code 2 and a message naming the file and
# the problem, and writes nothing. (A design mapped end to end, and a set
# that is not the design's, are in test_topopt.sh; the mapping itself is
# covered by tests/unit/test_mapping.cpp.)
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
M="$BIN/msfab-map"

# A tiny 2D set of 8 x 8 cells, one short cycle (well under a second).
cat > "$WORK/set.yaml" <<'Y'
space: cubic2d
resolution: 8
materials:
  stiff: {E: 1.0e6, nu: 0.3}
population: 4
cycles: 1
initial_beams: 2
beams: {max: 1, min_radius: 0.5, max_radius: 1.2}
continuous: {per_cycle: 0}
level_set: {cells: 6}
Y
check "a tiny 2D set" -- "$BIN/msfab-gamut-sample" --config "$WORK/set.yaml" --seed 3 --out "$WORK/set.gamut.h5" --quiet
S="$WORK/set.microstructures.h5"
OUT="$WORK/part.mapped.h5"

expect_exit 2 "--design is required" -- "$M" --structures "$S" --out "$OUT"
expect_exit 2 "--structures is required" -- "$M" --design "$S" --out "$OUT"
expect_exit 2 "missing --out" -- "$M" --design "$S" --structures "$S"
expect_exit 2 "missing.design.h5: no such file" -- "$M" --design "$WORK/missing.design.h5" --structures "$S" --out "$OUT"
expect_exit 2 "set.microstructures.h5: expected schema 'msfab.design' version 1, found schema 'msfab.microstructures'" -- \
  "$M" --design "$S" --structures "$S" --out "$OUT"
expect_exit 2 "set.gamut.h5: expected schema 'msfab.microstructures' version 1, found schema 'msfab.gamut'" -- \
  "$M" --design "$S" --structures "$WORK/set.gamut.h5" --out "$OUT"
expect_exit 2 "set.yaml: not a valid HDF5 file" -- "$M" --design "$WORK/set.yaml" --structures "$S" --out "$OUT"
expect_exit 2 "candidates = 0: must be 1..4096" -- "$M" --design "$S" --structures "$S" --out "$OUT" --set candidates=0
expect_exit 2 "void_pair_cost = 1.5: must lie in \\[0, 1\\]" -- "$M" --design "$S" --structures "$S" --out "$OUT" \
  --set void_pair_cost=1.5
expect_exit 2 "starts = 0: must be 1..1000" -- "$M" --design "$S" --structures "$S" --out "$OUT" --set starts=0
expect_exit 2 "radius = -0.1: candidate radius must be positive" -- \
  "$M" --design "$S" --structures "$S" --out "$OUT" --set radius=-0.1
expect_exit 2 "unknown key 'candidate'.*did you mean 'candidates'" -- "$M" --design "$S" --structures "$S" --out "$OUT" --set candidate=4
expect_exit 2 "unknown key 'stl_max' .*under 'export'" -- "$M" --design "$S" --structures "$S" --out "$OUT" --set export.stl_max=10
expect_exit 2 "output folder does not exist" -- "$M" --design "$S" --structures "$S" --out "$WORK/nowhere/part.mapped.h5"
check "nothing written on bad input" -- bash -c "! ls '$WORK'/part.* 2>/dev/null | grep -q ."
finish
