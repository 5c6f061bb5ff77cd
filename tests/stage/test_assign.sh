#!/bin/bash
# msfab-assign (designs written by hand, thesis Table 3.1 cubes): a tiny 3D
# set, a 2x2x2 cube of one structure mapped back with one candidate and
# checked at full resolution, which must give exactly what msfab-verify-map's
# own periodic tiling (fill: tile) gives on the same design; a cell tiled
# 2x2x2 by the mapping against eight cells of half the size; layers and
# random patterns; bad input exits 2 naming the file or key, writing nothing.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
A="$BIN/msfab-assign"

tiny_cubic3d_set 1
S="$WORK/set.microstructures.h5"
C="$SRC/configs/assign/cube.yaml"
check "a uniform cube" -- "$A" --config "$C" --structures "$S" --set 'pattern.structures=[3]' \
  --out "$WORK/cube.design.h5" --quiet
check "mapped with one candidate" -- "$BIN/msfab-map" --design "$WORK/cube.design.h5" --structures "$S" \
  --set candidates=1 --set half_shift=false --out "$WORK/cube.mapped.h5" --quiet
map_out=$("$BIN/msfab-map" --design "$WORK/cube.design.h5" --structures "$S" --set candidates=1 \
  --set half_shift=false --out "$WORK/cube2.mapped.h5" 2>&1)
check "every cell at its target (distance and property gap 0)" -- \
  grep -q "distance to target: max 0 .*property gap .*max 0, mean 0" <<<"$(tr '\n' ' ' <<<"$map_out")"
V=(--design "$WORK/cube.design.h5" --mapped "$WORK/cube.mapped.h5" --structures "$S")
mapped=$("$BIN/msfab-verify-map" "${V[@]}" --out "$WORK/cube.verify.h5" 2>&1 | grep '^msfab-verify-map:')
tiled=$("$BIN/msfab-verify-map" "${V[@]}" --set fill=tile --set tile_structure=3 --out "$WORK/tile.verify.h5" 2>&1 |
  grep '^msfab-verify-map:')
numbers() { sed -e 's/fill [a-z]*//' -e 's/homogenized [0-9.]* s/homogenized/' -e 's/full [0-9.]* s/full/' -e 's/;[^;]*h5$//' <<<"$1"; }
check "assigned cube = verify-map's tiling of structure 3" -- test -n "$mapped" -a "$(numbers "$mapped")" = "$(numbers "$tiled")"

# Tiled cells (msfab-map tiling: 2) are the same voxel object as twice as
# many cells of half the size. A column of two cells pressed by a
# prescribed displacement of its top face (forces would be spread from each
# design's own nodes; two cells, so that no cell has all its corners held)
# with 2^3 hexahedra per cell in the homogenized model, against 2 x 2 x 4
# cells: both runs are the same two models, so the energies must match
# (the displacements are compared at each design's own nodes).
cat > "$WORK/press.yaml" <<'Y'
grid: {size: [1, 1, 2], cell_size: 1.0}
space: cubic3d
supports:
  - {box: {min: [0, 0, 0], max: [1, 1, 0]}, fix: [x, y, z]}
  - {box: {min: [0, 0, 2], max: [1, 1, 2]}, fix: [z], displacement: [0, 0, -0.01]}
loads:
  - {name: press, objective: target, targets: [{node: [0, 0, 2], displacement: [0, 0, -0.01]}]}
pattern: {kind: uniform, structures: [3]}
Y
check "two cells" -- "$A" --config "$WORK/press.yaml" --structures "$S" --out "$WORK/one.design.h5" --quiet
check "two cells, tiled 2x2x2" -- "$BIN/msfab-map" --design "$WORK/one.design.h5" --structures "$S" --set candidates=1 \
  --set half_shift=false --set tiling=2 --out "$WORK/one.mapped.h5" --quiet
check "sixteen cells" -- "$A" --config "$WORK/press.yaml" --structures "$S" --set 'grid.size=[2,2,4]' \
  --set grid.cell_size=0.5 --out "$WORK/eight.design.h5" --quiet
check "sixteen cells mapped" -- "$BIN/msfab-map" --design "$WORK/eight.design.h5" --structures "$S" --set candidates=1 \
  --set half_shift=false --out "$WORK/eight.mapped.h5" --quiet
tiled=$("$BIN/msfab-verify-map" --design "$WORK/one.design.h5" --mapped "$WORK/one.mapped.h5" --structures "$S" \
  --set homogenized_elements=2 --out "$WORK/one.verify.h5" 2>&1 | grep '^msfab-verify-map:')
split=$("$BIN/msfab-verify-map" --design "$WORK/eight.design.h5" --mapped "$WORK/eight.mapped.h5" --structures "$S" \
  --out "$WORK/eight.verify.h5" 2>&1 | grep '^msfab-verify-map:')
energies() { grep -oE "energy [0-9.]+%" <<<"$1" | paste -sd' ' -; }
check "tiled cell reports 16^3 voxels per cell" -- grep -q "16\^3 per cell, 2\^3 copies per cell" <<<"$tiled"
check "tiled cells = sixteen cells (energies: $(energies "$tiled") / $(energies "$split"))" -- \
  test -n "$(energies "$tiled")" -a "$(energies "$tiled")" = "$(energies "$split")"
expect_exit 2 "tiling = 17: must be 1..16" -- "$BIN/msfab-map" --design "$WORK/one.design.h5" --structures "$S" \
  --set tiling=17 --out "$WORK/bad.mapped.h5"

check "layers along x" -- "$A" --config "$C" --structures "$S" --set 'pattern={kind: layers, structures: [1, 4], axis: x}' \
  --out "$WORK/layers.design.h5" --quiet
check "random over three" -- "$A" --config "$C" --structures "$S" --set 'pattern={kind: random, structures: [0, 2, 5]}' \
  --seed 4 --out "$WORK/random.design.h5" --quiet
check "the random design checks at full resolution" -- bash -c "'$BIN/msfab-map' --design '$WORK/random.design.h5' \
  --structures '$S' --set candidates=1 --out '$WORK/random.mapped.h5' --quiet && '$BIN/msfab-verify-map' \
  --design '$WORK/random.design.h5' --mapped '$WORK/random.mapped.h5' --structures '$S' --out '$WORK/random.verify.h5' --quiet"

OUT="$WORK/bad.design.h5"
expect_exit 2 "--structures is required" -- "$A" --config "$C" --out "$OUT"
expect_exit 2 "pattern.structures = .*index 999 is outside the set .*set.microstructures.h5" -- \
  "$A" --config "$C" --structures "$S" --set 'pattern.structures=[999]' --out "$OUT"
expect_exit 2 "pattern.structures = .*a uniform pattern takes exactly one structure" -- \
  "$A" --config "$C" --structures "$S" --set 'pattern.structures=[1, 2]' --out "$OUT"
expect_exit 2 "pattern.kind = .*stripes" -- "$A" --config "$C" --structures "$S" --set pattern.kind=stripes --out "$OUT"
expect_exit 2 "pattern.axis = w" -- "$A" --config "$C" --structures "$S" --set pattern.kind=layers --set pattern.axis=w --out "$OUT"
expect_exit 2 "pattern.thickness = 0: must be >= 1" -- "$A" --config "$C" --structures "$S" --set pattern.thickness=0 --out "$OUT"
expect_exit 2 "space = cubic2d: is cubic2d, the set .*holds cubic3d structures" -- \
  "$A" --config "$C" --structures "$S" --set space=cubic2d --set 'grid.size=[2, 2]' --out "$OUT"
expect_exit 2 "unknown key 'patern'" -- "$A" --config "$C" --structures "$S" --set 'patern.kind=uniform' --out "$OUT"
expect_exit 2 "expected schema 'msfab.microstructures'" -- "$A" --config "$C" --structures "$WORK/set.gamut.h5" --out "$OUT"
check "nothing written on bad input" -- bash -c "! ls '$WORK'/bad.* 2>/dev/null | grep -q ."
finish
