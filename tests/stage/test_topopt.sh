#!/bin/bash
# msfab-topopt: the SIMP cantilever on built-in defaults, a cubic2d design
# inside a sampled gamut mapped to microstructures by msfab-map, the
# coarse-to-fine continuation, and bad input (exit 2, clear message).
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
T="$BIN/msfab-topopt"

# 1. Built-in defaults on a smaller grid.
out=$("$T" --set 'grid.size=[24,12]' --set 'supports=[{box: {min: [0, 0], max: [0, 12]}}]' \
  --set 'loads=[{objective: compliance, forces: [{box: {min: [12, 0], max: [24, 0]}, force: [0, -1], distribute: total}]}]' \
  --out "$WORK/simp.design.h5" --quiet 2>&1)
check "simp cantilever converges" -- grep -q "converged" <<<"$out"
check "design artifact and sidecar" -- test -s "$WORK/simp.design.h5" -a -s "$WORK/simp.design.xmf"
check "mass fraction at the budget" -- grep -Eq "mass fraction 0\.(49[89]|500)" <<<"$out"
out=$("$T" --set 'grid.size=[24,12]' --set 'supports=[{box: {min: [0, 0], max: [0, 12]}}]' \
  --set 'loads=[{objective: compliance, forces: [{box: {min: [12, 0], max: [24, 0]}, force: [0, -1], distribute: total}]}]' \
  --set optimizer.name=mma --set optimizer.max_iterations=30 --set optimizer.change_tolerance=0 --out "$WORK/mma.design.h5" --quiet 2>&1)
check "simp cantilever with mma" -- grep -q "after 30 iterations (31 objective evaluations)" <<<"$out"
check "mma: mass fraction within the budget" -- grep -Eq "mass fraction 0\.(4[89][0-9]|500)" <<<"$out"

# 2. A tiny cubic2d gamut, a design inside it, and its mapping.
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
cat > "$WORK/cubic.yaml" <<Y
grid: {size: [12, 6]}
space: cubic2d
gamut: $WORK/set.gamut.h5
supports: [{box: {min: [0, 0], max: [0, 6]}}]
loads: [{objective: compliance, forces: [{node: [12, 0], force: [0, -1]}]}]
mass: {volume_fraction: 0.5}
optimizer: {max_iterations: 300}
Y
out=$("$T" --config "$WORK/cubic.yaml" --out "$WORK/cubic.design.h5" --quiet 2>&1)
check "cubic2d design written" -- test -s "$WORK/cubic.design.h5"
check "cubic2d design inside its gamut" -- grep -Eq "max constraint (-|[0-9.]+e-0[4-9]|0\.000)" <<<"$out"
check "the gamut stores its base materials for the Voigt bound" -- h5ls "$WORK/set.gamut.h5/bound/stiff"
check "the design maps to microstructures" -- "$BIN/msfab-map" --design "$WORK/cubic.design.h5" \
  --structures "$WORK/set.microstructures.h5" --out "$WORK/cubic.mapped.h5" --quiet
# Several descents keep the lowest mismatch: start 0 is the single start's.
one=$("$BIN/msfab-map" --design "$WORK/cubic.design.h5" --structures "$WORK/set.microstructures.h5" --seed 5 \
  --set starts=1 --set void_pair_cost=0 --out "$WORK/one.mapped.h5" --quiet | grep -oE "final [0-9]+" | grep -oE "[0-9]+")
many=$("$BIN/msfab-map" --design "$WORK/cubic.design.h5" --structures "$WORK/set.microstructures.h5" --seed 5 \
  --set starts=6 --set void_pair_cost=0 --out "$WORK/many.mapped.h5" --quiet)
many_final=$(grep -oE "final [0-9]+" <<<"$many" | grep -oE "[0-9]+")
check "starts: six descents reported, the first the single start's" -- \
  grep -Eq "starts: 6 \(final mismatch $one, [0-9]+, [0-9]+, [0-9]+, [0-9]+, [0-9]+\)" <<<"$many"
check "starts: the kept mismatch is at most the single start's" -- test -n "$one" -a "$many_final" -le "$one"
check "the face pairs are reported" -- grep -Eq "voxel pairs across cell faces: [0-9.]+% solid on both sides" <<<"$many"
costed=$("$BIN/msfab-map" --design "$WORK/cubic.design.h5" --structures "$WORK/set.microstructures.h5" --seed 5 \
  --set void_pair_cost=0.5 --out "$WORK/costed.mapped.h5" --quiet)
check "void_pair_cost: the descent reports a cost" -- grep -q "cost (16 mismatch + 16 c void pairs): initial" <<<"$costed"
check "void_pair_cost: stored" -- bash -c "h5dump -a /void_pair_cost '$WORK/costed.mapped.h5' | grep -q '0.5'"
# Another gamut of the same material and space: its structures are not the
# design's (refused, naming both files); a set derived from the design's
# structures (re-homogenized) is accepted.
check "another gamut" -- "$BIN/msfab-gamut-sample" --config "$WORK/set.yaml" --seed 4 --out "$WORK/other.gamut.h5" --quiet
expect_exit 2 "other.microstructures.h5: not the structures of the gamut .*set.gamut.h5 that .*cubic.design.h5 was optimized in" -- \
  "$BIN/msfab-map" --design "$WORK/cubic.design.h5" --structures "$WORK/other.microstructures.h5" --out "$WORK/other.mapped.h5"
check "nothing written for the refused set" -- test ! -e "$WORK/other.mapped.h5"
check "a set derived from the gamut's structures" -- "$BIN/msfab-homogenize" --structures "$WORK/set.microstructures.h5" \
  --out "$WORK/derived.microstructures.h5" --quiet
check "maps the design too" -- "$BIN/msfab-map" --design "$WORK/cubic.design.h5" \
  --structures "$WORK/derived.microstructures.h5" --out "$WORK/derived.mapped.h5" --quiet
out=$("$T" --config "$WORK/cubic.yaml" --set optimizer.name=cell-mma --set filter.radius=1.5 \
  --out "$WORK/cellmma.design.h5" --quiet 2>&1)
check "cell-mma: cubic2d design inside its gamut" -- grep -Eq "max constraint (-|[0-9.]+e-0[4-9]|0\.000)" <<<"$out"
check "cell-mma: mass fraction within the budget" -- grep -Eq "mass fraction 0\.(4[89][0-9]|500)" <<<"$out"
check "coarse-to-fine continuation" -- "$T" --config "$WORK/cubic.yaml" --set 'grid.size=[24,12]' \
  --set "initial.design=$WORK/cubic.design.h5" --set 'loads=[{objective: compliance, forces: [{node: [24, 0], force: [0, -1]}]}]' \
  --set 'supports=[{box: {min: [0, 0], max: [0, 12]}}]' --set optimizer.max_iterations=20 --out "$WORK/fine.design.h5" --quiet

# Fig. 3-16 on one gamut: the cubic slice of a tiny orthotropic gamut, its
# design mapped with that gamut's structures and starting an orthotropic
# run (the default initial.rho gives way to initial.design).
sed -e 's/space: cubic2d/space: orthotropic2d/' "$WORK/set.yaml" > "$WORK/ortho_set.yaml"
check "a tiny orthotropic gamut" -- "$BIN/msfab-gamut-sample" --config "$WORK/ortho_set.yaml" --seed 3 \
  --out "$WORK/ortho.gamut.h5" --quiet
cantilever=(--set 'grid.size=[12,6]' --set 'supports=[{box: {min: [0, 0], max: [0, 6]}}]'
  --set 'loads=[{objective: compliance, forces: [{node: [12, 0], force: [0, -1]}]}]' --set optimizer.name=cell-mma
  --set optimizer.max_iterations=40 --set gamut="$WORK/ortho.gamut.h5" --quiet)
check "cubic2d_slice: a design in the orthotropic gamut" -- "$T" "${cantilever[@]}" --set space=cubic2d_slice \
  --out "$WORK/slice.design.h5"
check "cubic2d_slice: recorded as an orthotropic design with Ex = Ey" -- /usr/bin/python3 -c "
import h5py, numpy as np, sys
f = h5py.File('$WORK/slice.design.h5', 'r')
u = f['cells/unit'][...]
sys.exit(0 if f.attrs['space'] in (b'orthotropic2d', 'orthotropic2d') and u.shape[1] == 5 and np.array_equal(u[:, 0], u[:, 1]) else 1)"
check "cubic2d_slice: the design maps with the orthotropic structures" -- "$BIN/msfab-map" \
  --design "$WORK/slice.design.h5" --structures "$WORK/ortho.microstructures.h5" --out "$WORK/slice.mapped.h5" --quiet
check "orthotropic2d starts from the slice design" -- "$T" "${cantilever[@]}" --set space=orthotropic2d \
  --set "initial.design=$WORK/slice.design.h5" --out "$WORK/ortho.design.h5"
check "cubic2d_slice starts from an orthotropic design" -- "$T" "${cantilever[@]}" --set space=cubic2d_slice \
  --set "initial.design=$WORK/ortho.design.h5" --out "$WORK/slice2.design.h5"
expect_exit 2 "is a cubic2d gamut; space cubic2d_slice needs a orthotropic2d gamut" -- "$T" "${cantilever[@]}" \
  --set space=cubic2d_slice --set gamut="$WORK/set.gamut.h5" --out "$WORK/bad_slice.design.h5"

# The thesis's 2D scenes (configs/topopt/) read and run in a cubic2d gamut.
for scene in s_beam gripper gripper_pull gripper_push gripper_stretch; do
  check "configs/topopt/$scene.yaml runs" -- "$T" --config "$SRC/configs/topopt/$scene.yaml" \
    --set gamut="$WORK/set.gamut.h5" --set optimizer.max_iterations=3 --out "$WORK/$scene.design.h5" --quiet
done
# The same design on one thread and on two, to the last bit (the pull
# gripper is the scene whose KKT systems MUMPS once ordered with SCOTCH).
for threads in 1 2; do
  check "gripper_pull runs on $threads thread(s)" -- "$T" --config "$SRC/configs/topopt/gripper_pull.yaml" \
    --set gamut="$WORK/set.gamut.h5" --set optimizer.max_iterations=3 --threads $threads \
    --out "$WORK/pull_t$threads.design.h5" --quiet
done
check "a design does not depend on the thread count" -- h5diff -q "$WORK/pull_t1.design.h5" "$WORK/pull_t2.design.h5" /cells/raw

# Plane strain: the same as the plane-stress plate of E / (1 - nu^2), nu / (1 - nu).
simp=(--set 'grid.size=[24,12]' --set 'supports=[{box: {min: [0, 0], max: [0, 12]}}]'
  --set 'loads=[{objective: compliance, forces: [{box: {min: [12, 0], max: [24, 0]}, force: [0, -1], distribute: total}]}]'
  --set optimizer.max_iterations=5 --quiet)
a=$("$T" "${simp[@]}" --set material.plane=strain --out "$WORK/strain.design.h5" 2>&1 | grep -oE "compliance [0-9.e+-]+")
b=$("$T" "${simp[@]}" --set material.E=1.0989010989010989 --set material.nu=0.42857142857142855 \
  --out "$WORK/strain2.design.h5" 2>&1 | grep -oE "compliance [0-9.e+-]+")
check "plane strain is the equivalent plane-stress plate ($a)" -- test -n "$a" -a "$a" = "$b"

# 3. Bad input.
D=(--out "$WORK/bad.design.h5")
expect_exit 2 "supports.*fixes no unknown" -- "$T" --set 'supports=[]' "${D[@]}"
expect_exit 2 "load on void" -- "$T" --set 'domain=[{box: {min: [40, 0], max: [48, 24]}, role: empty}]' "${D[@]}"
expect_exit 2 "no such node" -- "$T" --set 'loads=[{objective: target, forces: [{node: [48, 0], force: [0, -1]}], targets: [{node: [60, 0], displacement: [0, -1]}]}]' "${D[@]}"
expect_exit 2 "is a cubic2d gamut; space cubic3d needs a cubic3d gamut" -- "$T" --config "$WORK/cubic.yaml" \
  --set space=cubic3d --set 'grid.size=[4,2,2]' "${D[@]}"
expect_exit 2 "space simp2d takes no gamut" -- "$T" --config "$WORK/cubic.yaml" --set space=simp2d "${D[@]}"
expect_exit 2 "none.h5: no such file" -- "$T" --config "$WORK/cubic.yaml" --set gamut=$WORK/none.h5 "${D[@]}"
expect_exit 2 "gamut_bound.*space simp2d takes no gamut" -- "$T" --set gamut_bound=voigt "${D[@]}"
expect_exit 2 "gamut_bound.*one of" -- "$T" --config "$WORK/cubic.yaml" --set gamut_bound=reuss "${D[@]}"
expect_exit 2 "material.plane.*applies to 2D grids only" -- "$T" --set space=simp3d --set 'grid.size=[4,2,2]' \
  --set material.plane=strain "${D[@]}"
expect_exit 2 "mma is for the simp spaces" -- "$T" --set space=analytic2d --set optimizer.name=mma "${D[@]}"
expect_exit 2 "optimizer.move.*read by the cell-mma optimizer only" -- "$T" --set optimizer.move=0.1 "${D[@]}"
expect_exit 2 "optimizer.move.*must be in" -- "$T" --set optimizer.name=cell-mma --set optimizer.move=2 "${D[@]}"
expect_exit 2 "optimizer.change_tolerance.*must be in" -- "$T" --set optimizer.change_tolerance=-1 "${D[@]}"
expect_exit 2 "unknown key 'fitler'" -- "$T" --set fitler.radius=2 "${D[@]}"
check "nothing written on bad input" -- test ! -e "$WORK/bad.design.h5"
finish
