#!/bin/bash
# msfab-verify-map (thesis Table 3.1): a tiny 3D gamut (8^3 voxels per cell),
# a 4x2x2 bar optimized in it, mapped, then checked at full resolution:
#  (a) every cell solid, the bar on rollers under a uniform traction: the
#      design grid and the voxel grid carry the same uniform stress, so they
#      agree (up to the CG tolerance); a prescribed stretch likewise; with
#      8^3 hexahedra per cell in the homogenized model both are the same
#      model, so the design's own clamp and loads give identical answers;
#  (b) the mapped bar under its own loads: finite differences below bounds;
#  (c) bad input exits 2 naming the file or key, and writes nothing.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
V="$BIN/msfab-verify-map"

tiny_cubic3d_set 2
S="$WORK/set.microstructures.h5"
cat > "$WORK/bar.yaml" <<Y
grid: {size: [4, 2, 2], cell_size: 1.0}
space: cubic3d
gamut: $WORK/set.gamut.h5
supports: [{box: {min: [0, 0, 0], max: [0, 2, 2]}}]
loads:
  - {name: bend, objective: compliance, forces: [{box: {min: [4, 0, 0], max: [4, 2, 2]}, force: [0, 0, -10], distribute: total}]}
  - {name: stretch, objective: compliance, forces: [{box: {min: [4, 0, 0], max: [4, 2, 2]}, force: [10, 0, 0], distribute: total}]}
mass: {volume_fraction: 0.5}
optimizer: {max_iterations: 200}
# (b) checks that nodes without material are fixed, so it needs a mapping
# that has some: this tiny gamut's optimum without the Voigt bound does;
# with it, the mapped bar leaves no node without material.
gamut_bound: none
Y
check "a 3D bar design" -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" --out "$WORK/bar.design.h5" --quiet
check "mapped" -- "$BIN/msfab-map" --design "$WORK/bar.design.h5" --structures "$S" --out "$WORK/bar.mapped.h5" --seed 1 --quiet
A=(--design "$WORK/bar.design.h5" --mapped "$WORK/bar.mapped.h5" --structures "$S")

# percent NAME OUTPUT KIND: the percentage of load case NAME in the summary line (KIND displacement | energy).
percent() { grep -oE "$1: displacement [0-9.]+%, energy [0-9.]+%" <<<"$2" | grep -oE "$3 [0-9.]+" | awk '{print $2}'; }
below() { awk -v x="$1" -v b="$2" 'BEGIN { exit !(x != "" && x + 0 < b + 0) }'; }

# (a) Solid bar on rollers (x on the face x = 0, y and z on its middle lines),
# the end face loaded by the consistent nodal loads of a uniform traction
# (interior 1/4, edges 1/8, corners 1/16 of the total); and the same bar
# stretched by a prescribed end displacement.
cat > "$WORK/rollers.yaml" <<'Y'
grid: {size: [4, 2, 2], cell_size: 1.0}
space: cubic3d
supports:
  - {box: {min: [0, 0, 0], max: [0, 2, 2]}, fix: [x]}
  - {box: {min: [0, 1, 0], max: [0, 1, 2]}, fix: [y]}
  - {box: {min: [0, 0, 1], max: [0, 2, 1]}, fix: [z]}
loads:
  - name: traction
    objective: compliance
    forces:
      - {box: {min: [4, 0, 0], max: [4, 2, 2]}, force: [2.5, 0, 0]}
      - {box: {min: [4, 0, 0], max: [4, 2, 0]}, force: [-1.25, 0, 0]}
      - {box: {min: [4, 0, 2], max: [4, 2, 2]}, force: [-1.25, 0, 0]}
      - {box: {min: [4, 0, 0], max: [4, 0, 2]}, force: [-1.25, 0, 0]}
      - {box: {min: [4, 2, 0], max: [4, 2, 2]}, force: [-1.25, 0, 0]}
      - {node: [4, 0, 0], force: [0.625, 0, 0]}
      - {node: [4, 2, 0], force: [0.625, 0, 0]}
      - {node: [4, 0, 2], force: [0.625, 0, 0]}
      - {node: [4, 2, 2], force: [0.625, 0, 0]}
Y
out=$("$V" "${A[@]}" --scene "$WORK/rollers.yaml" --set fill=solid --out "$WORK/solid.verify.h5" --quiet 2>&1)
echo "$out"
check "(a) solid bar, uniform traction: displacement within 0.1%" -- below "$(percent traction "$out" displacement)" 0.1
check "(a) solid bar, uniform traction: energy within 0.1%" -- below "$(percent traction "$out" energy)" 0.1
check "(a) a solid bar has no edge joints" -- grep -q "edge joints: 0 (largest stiffness ratio across an edge 1)" <<<"$out"
check "(a) and records none" -- bash -c "h5dump -a /edge_joints '$WORK/solid.verify.h5' | grep -q '(0): 0'"
cat "$WORK/rollers.yaml" > "$WORK/pull.yaml"
sed -i '/^loads:/,$d' "$WORK/pull.yaml"
cat >> "$WORK/pull.yaml" <<'Y'
  - {box: {min: [4, 0, 0], max: [4, 2, 2]}, fix: [x], displacement: [0.01, 0, 0]}
loads:
  - {name: pull, objective: target, targets: [{node: [4, 0, 0], displacement: [0.01, 0, 0]}]}
Y
out=$("$V" "${A[@]}" --scene "$WORK/pull.yaml" --set fill=solid --out "$WORK/pull.verify.h5" --quiet 2>&1)
echo "$out"
check "(a) solid bar, prescribed stretch: displacement within 0.1%" -- below "$(percent pull "$out" displacement)" 0.1
check "(a) solid bar, prescribed stretch: energy within 0.1%" -- below "$(percent pull "$out" energy)" 0.1

# With as many hexahedra per cell in the homogenized model as voxels, the
# solid bar is the same model twice: the design's own loads and clamped face
# carried over by the same rules must give the same answer.
out=$("$V" "${A[@]}" --set fill=solid --set homogenized_elements=8 --out "$WORK/same.verify.h5" --quiet 2>&1)
echo "$out"
for c in bend stretch; do
  check "(a) solid, 8^3 elements per cell: $c displacement identical" -- below "$(percent $c "$out" displacement)" 0.01
  check "(a) solid, 8^3 elements per cell: $c energy identical" -- below "$(percent $c "$out" energy)" 0.01
done

# (b) The mapped bar under the loads it was optimized for (read back from the design).
out=$("$V" "${A[@]}" --out "$WORK/bar.verify.h5" 2>&1)
echo "$out" | grep msfab-verify-map
check "(b) report written" -- bash -c "h5dump -a /schema '$WORK/bar.verify.h5' | grep -q msfab.verify_map"
check "(b) 32 x 16 x 16 voxels" -- grep -q "4 x 2 x 2 cells, 8192 voxels (8^3 per cell, fill mapped)" <<<"$out"
check "(b) per-case datasets" -- bash -c "h5dump -H -d /nodes/displacement_full '$WORK/bar.verify.h5' | grep -q '( 2, 45, 3 )'"
for c in bend stretch; do
  check "(b) $c: displacement difference below 30%" -- below "$(percent $c "$out" displacement)" 30
  check "(b) $c: energy difference below 40%" -- below "$(percent $c "$out" energy)" 40
done
# Void removed (the default) against ersatz void at 1e-6: the same answers
# to well below the differences measured, and the pieces are reported.
attr() { h5dump -a "/$2" "$1" | grep -oE '\(0\): [-0-9.e+]+' | head -1 | cut -d' ' -f2; }
check "(b) pieces reported" -- test "$(attr "$WORK/bar.verify.h5" pieces_full)" -ge 1
removed=$(attr "$WORK/bar.verify.h5" removed_voxels_full)
check "(b) removed voxels counted" -- test "$removed" -ge 0
check "(b) void fixed at nodes without material" -- test "$(attr "$WORK/bar.verify.h5" inactive_nodes_full)" -gt 0
ersatz=$("$V" "${A[@]}" --set void=ersatz --out "$WORK/ersatz.verify.h5" --quiet 2>&1)
echo "$ersatz"
close() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a != "" && b != "" && d <= t) }'; }
# The matrix-free multigrid (the voxel model as a field of one weight per
# voxel, energies from the field) against CHOLMOD on the assembled model.
free=$("$V" "${A[@]}" --solver matrix-free --out "$WORK/free.verify.h5" --quiet 2>&1)
echo "$free"
for c in bend stretch; do
  for k in displacement energy; do
    check "(b) $c: matrix-free and cholmod agree ($k)" -- close "$(percent $c "$out" $k)" "$(percent $c "$free" $k)" 0.01
  done
done
# The trilinear coarse space gives the same model's answer.
sattr() { h5dump -a "/$2" "$1" | grep -oE '\(0\): "[^"]*"' | head -1 | cut -d'"' -f2; }
lattice=$("$V" "${A[@]}" --solver matrix-free --set coarse_space=lattice --out "$WORK/lattice.verify.h5" --quiet 2>&1)
check "(b) coarse space recorded" -- test "$(sattr "$WORK/free.verify.h5" coarse_space_full)" = material
check "(b) lattice coarse space recorded" -- test "$(sattr "$WORK/lattice.verify.h5" coarse_space_full)" = lattice
for c in bend stretch; do
  check "(b) $c: material and lattice coarse spaces agree" -- \
    close "$(percent $c "$free" displacement)" "$(percent $c "$lattice" displacement)" 0.01
done
if [ "$removed" = 0 ]; then
  for c in bend stretch; do
    check "(b) $c: void removed and ersatz void agree (displacement)" -- \
      close "$(percent $c "$out" displacement)" "$(percent $c "$ersatz" displacement)" 0.05
    check "(b) $c: void removed and ersatz void agree (energy)" -- \
      close "$(percent $c "$out" energy)" "$(percent $c "$ersatz" energy)" 0.05
  done
fi

# (c) Bad input: exit 2, the file or key named, nothing written.
B="$WORK/bad.verify.h5"
cat > "$WORK/flat.yaml" <<'Y'
grid: {size: [6, 3]}
space: simp2d
supports: [{box: {min: [0, 0], max: [0, 3]}}]
loads: [{objective: compliance, forces: [{node: [6, 0], force: [0, -1]}]}]
optimizer: {max_iterations: 5}
mass: {volume_fraction: 0.5}
Y
check "a 2D design" -- "$BIN/msfab-topopt" --config "$WORK/flat.yaml" --out "$WORK/flat.design.h5" --quiet
expect_exit 2 "flat.design.h5: a 2D design .*needs a 3D design" -- "$V" --design "$WORK/flat.design.h5" \
  --mapped "$WORK/bar.mapped.h5" --structures "$S" --out "$B"
check "a 2x2x2 design" -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" --set 'grid.size=[2,2,2]' \
  --set 'loads=[{objective: compliance, forces: [{box: {min: [2, 0, 0], max: [2, 2, 2]}, force: [0, 0, -1]}]}]' \
  --out "$WORK/short.design.h5" --quiet
check "its mapping" -- "$BIN/msfab-map" --design "$WORK/short.design.h5" --structures "$S" --out "$WORK/short.mapped.h5" --quiet
expect_exit 2 "short.mapped.h5: attribute 'grid' is 2 x 2 x 2 cells, the design .*bar.design.h5 has 4 x 2 x 2" -- \
  "$V" --design "$WORK/bar.design.h5" --mapped "$WORK/short.mapped.h5" --structures "$S" --out "$B"
expect_exit 2 "none.mapped.h5: no such file" -- "$V" --design "$WORK/bar.design.h5" --mapped "$WORK/none.mapped.h5" \
  --structures "$S" --out "$B"
expect_exit 2 "expected schema 'msfab.mapped' version 1, found schema 'msfab.microstructures'" -- \
  "$V" --design "$WORK/bar.design.h5" --mapped "$S" --structures "$S" --out "$B"
check "another set" -- "$BIN/msfab-gamut-sample" --config "$WORK/set.yaml" --seed 4 --out "$WORK/other.gamut.h5" --quiet
expect_exit 2 "bar.mapped.h5: was not mapped with .*other.microstructures.h5" -- "$V" --design "$WORK/bar.design.h5" \
  --mapped "$WORK/bar.mapped.h5" --structures "$WORK/other.microstructures.h5" --out "$B"
sed 's/size: \[4, 2, 2\]/size: [8, 2, 2]/' "$WORK/pull.yaml" > "$WORK/long.yaml"
expect_exit 2 "long.yaml: grid.size = .*: is 8 x 2 x 2 cells, the design .*has 4 x 2 x 2" -- "$V" "${A[@]}" \
  --scene "$WORK/long.yaml" --out "$B"
expect_exit 2 "none.yaml: no such file" -- "$V" "${A[@]}" --scene "$WORK/none.yaml" --out "$B"
expect_exit 2 "fill = bogus" -- "$V" "${A[@]}" --set fill=bogus --out "$B"
expect_exit 2 "void_ratio = 0: must be in \(0, 1\]" -- "$V" "${A[@]}" --set void_ratio=0 --out "$B"
expect_exit 2 "homogenized_elements = 0: must be 1..64" -- "$V" "${A[@]}" --set homogenized_elements=0 --out "$B"
expect_exit 2 "tile_structure = 99: is 99, the set .* holds" -- "$V" "${A[@]}" --set fill=tile --set tile_structure=99 --out "$B"
expect_exit 2 "void = 0.1: must be one of" -- "$V" "${A[@]}" --set void=0.1 --out "$B"
expect_exit 2 "coarse_space = trilinear: must be one of" -- "$V" "${A[@]}" --set coarse_space=trilinear --out "$B"
expect_exit 2 "unknown key 'voids'" -- "$V" "${A[@]}" --set voids=remove --out "$B"
# Hinged on one line of nodes, the bar can turn about it: no piece is held.
sed 's/supports: .*/supports: [{box: {min: [0, 0, 0], max: [0, 0, 2]}}]/' "$WORK/bar.yaml" > "$WORK/hinge.yaml"
expect_exit 2 "supports hold none of the design's non-empty cells" -- "$V" "${A[@]}" --scene "$WORK/hinge.yaml" --out "$B"
expect_exit 2 "--solver bogus: linear solver 'bogus' is unknown here; choose one of auto, cholmod, pcg-mg, matrix-free" -- "$V" "${A[@]}" --solver bogus --out "$B"
expect_exit 2 "homogenized_linear_solver = pcg: linear solver 'pcg' is unknown here" -- "$V" "${A[@]}" \
  --set homogenized_linear_solver=pcg --out "$B"
expect_exit 2 "linear_tolerance = 1: must be in \(0, 1\)" -- "$V" "${A[@]}" --set linear_tolerance=1 --out "$B"
expect_exit 2 "--mapped is required" -- "$V" --design "$WORK/bar.design.h5" --structures "$S" --out "$B"
expect_exit 2 "output folder does not exist" -- "$V" "${A[@]}" --out "$WORK/nowhere/x.verify.h5"
check "nothing written on bad input" -- test ! -e "$B"
finish
