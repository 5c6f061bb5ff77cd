#!/bin/bash
# msfab-fill-targets: on a tiny 2D gamut and a design optimized in it, the
# structures it generates lower the gap the mapper sees, the given
# structures keep their indices, the result is the same on 1 and 2 MPI
# ranks, and bad input exits 2 naming the problem with nothing written.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
F="$BIN/msfab-fill-targets"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

cat > "$WORK/set.yaml" <<'Y'
space: cubic2d
resolution: 8
materials:
  stiff: {E: 1.0e6, nu: 0.3}
population: 8
cycles: 1
initial_beams: 3
beams: {max: 2, min_radius: 0.5, max_radius: 1.5}
continuous: {per_cycle: 0}
level_set: {cells: 8}
Y
check "a tiny 2D gamut" -- "$BIN/msfab-gamut-sample" --config "$WORK/set.yaml" --seed 3 --out "$WORK/set.gamut.h5" --quiet
S="$WORK/set.microstructures.h5"
cat > "$WORK/cubic.yaml" <<Y
grid: {size: [12, 6]}
space: cubic2d
gamut: $WORK/set.gamut.h5
supports: [{box: {min: [0, 0], max: [0, 6]}}]
loads: [{objective: compliance, forces: [{node: [12, 0], force: [0, -1]}]}]
mass: {volume_fraction: 0.5}
optimizer: {max_iterations: 300}
Y
check "a design in it" -- "$BIN/msfab-topopt" --config "$WORK/cubic.yaml" --out "$WORK/cubic.design.h5" --quiet
D="$WORK/cubic.design.h5"

out=$("$F" --design "$D" --structures "$S" --set gap=0.05 --set max_targets=6 --set rounds=1 \
  --out "$WORK/filled.h5" --threads 2 2>&1)
echo "$out" | sed -n '/msfab-fill-targets:/,$p'
given=$(grep -oE "given set: property gap of the best candidate max [0-9.e+-]+, mean [0-9.e+-]+" <<<"$out" | awk '{print $NF}')
after=$(grep -oE "with the new structures: property gap of the best candidate max [0-9.e+-]+, mean [0-9.e+-]+" <<<"$out" | awk '{print $NF}')
added=$(grep -oE "[0-9]+ generated" <<<"$out" | awk '{print $1}')
check "structures generated ($added)" -- test "${added:-0}" -gt 0
check "mean gap lowered ($given -> $after)" -- awk -v a="$given" -v b="$after" 'BEGIN { exit !(b < a) }'
check "the filled set is a microstructures artifact" -- "$BIN/msfab-inspect" --schema msfab.microstructures "$WORK/filled.h5"
# The first N rows of the filled set's voxels are the given set's.
read -r n row < <(h5ls "$S/voxels" | grep -oE "\{[0-9]+, [0-9]+\}" | tr -d '{},')
slab() { h5dump -d /voxels -s 0,0 -c "$n,$row" "$1" | sed -n '/DATA {/,/^   }/p'; }
check "the given structures come first, unchanged ($n)" -- test -n "$n" -a -n "$(slab "$S")" -a "$(slab "$S")" = "$(slab "$WORK/filled.h5")"
check "the mapper takes the filled set" -- "$BIN/msfab-map" --design "$D" --structures "$WORK/filled.h5" \
  --out "$WORK/filled.mapped.h5" --quiet
if command -v mpirun >/dev/null; then
  check "two ranks" -- mpirun --oversubscribe -np 2 "$F" --design "$D" --structures "$S" --set gap=0.05 \
    --set max_targets=6 --set rounds=1 --out "$WORK/filled2.h5" --threads 1 --quiet
  check "same structures on 1 and 2 ranks" -- bash -c \
    "h5diff '$WORK/filled.h5' '$WORK/filled2.h5' /voxels && h5diff '$WORK/filled.h5' '$WORK/filled2.h5' /C"
fi

O=(--out "$WORK/bad.h5")
expect_exit 2 "--design is required" -- "$F" --structures "$S" "${O[@]}"
expect_exit 2 "expected schema 'msfab.design'" -- "$F" --design "$S" --structures "$S" "${O[@]}"
expect_exit 2 "gap = 0: must be in" -- "$F" --design "$D" --structures "$S" --set gap=0 "${O[@]}"
expect_exit 2 "starts = 40: must be 1..candidates" -- "$F" --design "$D" --structures "$S" --set starts=40 "${O[@]}"
expect_exit 2 "match = mass: must be 'all' or 'stiffness'" -- "$F" --design "$D" --structures "$S" --set match=mass "${O[@]}"
expect_exit 2 "refine.threshold_levels.*every level must lie in" -- "$F" --design "$D" --structures "$S" \
  --set 'refine.threshold_levels=[0.5, 1.2]' "${O[@]}"
expect_exit 2 "name the same file" -- "$F" --design "$D" --structures "$S" --out "$S"
expect_exit 2 "output folder does not exist" -- "$F" --design "$D" --structures "$S" --out "$WORK/nowhere/x.h5"
check "nothing written on bad input" -- test ! -e "$WORK/bad.h5"
finish
