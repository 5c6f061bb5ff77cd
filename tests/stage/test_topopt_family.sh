#!/bin/bash
# Two-scale design in a family's own parameters (topopt space family3d):
# msfab-family-generate draws a structure grid, msfab-topopt designs on it,
# the design records the family's parameters and maps to the grid's
# members; bad input exits 2 naming the file and key.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"

cat > "$WORK/grid.yaml" <<'Y'
resolution: 8
material: {E: 1.0e6, nu: 0.3}
grid:
  parameters:
    - {name: axis, values: [0.1, 0.25, 0.5]}
    - {name: diagonal, values: [0, 0.12]}
  beams:
    - {a: [0.5, 0.5, 0.5], b: [1.0, 0.5, 0.5], parameter: axis}
    - {a: [0.5, 0.5, 0.5], b: [1.0, 1.0, 1.0], parameter: diagonal}
Y
out=$("$BIN/msfab-family-generate" --config "$WORK/grid.yaml" --out "$WORK/grid.microstructures.h5" 2>&1)
check "a 3 x 2 grid of members" -- grep -q "6 structures of 8^3 voxels" <<<"$out"
check "the last axis value is the solid cell" -- grep -q "axis 0.500, diagonal 0.120: solid 1.000" <<<"$out"
check "the set records its grid" -- h5ls "$WORK/grid.microstructures.h5/grid/axis1"

cat > "$WORK/bar.yaml" <<Y
grid: {size: [6, 2, 2], cell_size: 1.0}
space: family3d
family: $WORK/grid.microstructures.h5
supports: [{box: {min: [0, 0, 0], max: [0, 2, 2]}, fix: [x, y, z]}]
loads: [{objective: compliance, forces: [{box: {min: [6, 0, 0], max: [6, 2, 2]}, force: [0, 0, -1], distribute: total}]}]
mass: {volume_fraction: 0.4}
optimizer: {max_iterations: 150}
Y
out=$("$BIN/msfab-topopt" --config "$WORK/bar.yaml" --out "$WORK/bar.design.h5" --quiet 2>&1)
check "family3d design written" -- test -s "$WORK/bar.design.h5"
check "family3d: within the budget" -- grep -Eq "mass fraction 0\.(3[89][0-9]|400)" <<<"$out"
check "family3d: every cell pays for its member" -- grep -Eq "max constraint (-|[0-9.]+e-0[4-9]|0\.000)" <<<"$out"
check "the design records the family's parameters" -- h5ls "$WORK/bar.design.h5/family/raw"
check "and the cubic3d material they interpolate" -- test "$(h5dump -a /space "$WORK/bar.design.h5" | grep -c cubic3d)" = 1
out=$("$BIN/msfab-map" --design "$WORK/bar.design.h5" --structures "$WORK/grid.microstructures.h5" \
  --set half_shift=false --set candidates=1 --out "$WORK/bar.mapped.h5" 2>&1)
check "the design maps to the grid's members" -- test -s "$WORK/bar.mapped.h5"
check "coarse-to-fine continuation in the family" -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" \
  --set 'grid.size=[12, 4, 4]' --set "initial.design=$WORK/bar.design.h5" --set optimizer.max_iterations=5 \
  --set loads[0].forces[0].box.min=[12,0,0] --set loads[0].forces[0].box.max=[12,4,4] \
  --set supports[0].box.max=[0,4,4] --out "$WORK/bar_fine.design.h5" --quiet

out=$("$BIN/msfab-topopt" --config "$WORK/bar.yaml" --set elements_per_cell=2 --set optimizer.max_iterations=20 \
  --out "$WORK/bar_m2.design.h5" 2>&1)
check "the elasticity on 2^3 hexahedra per cell" -- grep -q "2^3 elements per cell, 975 unknowns" <<<"$out"
check "its design keeps the design grid's nodes" -- test "$(h5dump -H -d /nodes/displacement "$WORK/bar_m2.design.h5" | grep -c '( 63, 3 )')" = 1

out=$("$BIN/msfab-topopt" --config "$WORK/bar.yaml" --set optimizer.name=cell-mma --set filter.kind=density \
  --set filter.radius=1.5 --set optimizer.max_iterations=40 --out "$WORK/bar_density.design.h5" 2>&1)
check "cell MMA with a density filter on the family's parameters" -- test -s "$WORK/bar_density.design.h5"
check "density filter: within the budget" -- grep -Eq "mass fraction 0\.(3[89][0-9]|400)" <<<"$out"
check "density filter: rho derived, so no cell constraint" -- grep -Eq "max constraint (-|0\.000)" <<<"$out"

# Bad input.
expect_exit 2 "filter.kind = density: is read by the cell-mma optimizer only" -- "$BIN/msfab-topopt" \
  --config "$WORK/bar.yaml" --set filter.kind=density --out "$WORK/x.design.h5"
expect_exit 2 "filter.kind = blur: " -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" --set optimizer.name=cell-mma \
  --set filter.kind=blur --out "$WORK/x.design.h5"
expect_exit 2 "filter.kind = density: density needs a space without per-cell constraints" -- "$BIN/msfab-topopt" \
  --config "$WORK/bar.yaml" --set family=null --set space=analytic3d --set optimizer.name=cell-mma \
  --set filter.kind=density --out "$WORK/x.design.h5"
expect_exit 2 "family = \\(nothing\\): is missing: space family3d needs" -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" \
  --set family=null --out "$WORK/x.design.h5"
check "re-homogenizing keeps the grid" -- "$BIN/msfab-homogenize" --structures "$WORK/grid.microstructures.h5" \
  --out "$WORK/same.microstructures.h5" --quiet
check "(its /grid)" -- h5ls "$WORK/same.microstructures.h5/grid/axis0"
cat > "$WORK/templates.yaml" <<'Y'
resolution: 8
templates: [{beams: [{a: [0.5, 0.5, 0.5], b: [1.0, 0.5, 0.5], r0: 0.2, r1: 0.2}]}]
Y
check "a set of templates (no grid)" -- "$BIN/msfab-family-generate" --config "$WORK/templates.yaml" \
  --out "$WORK/templates.microstructures.h5" --quiet
expect_exit 2 "templates.microstructures.h5: the structures are not a parameter grid" -- "$BIN/msfab-topopt" \
  --config "$WORK/bar.yaml" --set "family=$WORK/templates.microstructures.h5" --out "$WORK/x.design.h5"
expect_exit 2 "family = .*grid.microstructures.h5: is read by the family3d space only" -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" \
  --set space=simp3d --out "$WORK/x.design.h5"
expect_exit 2 "material.nu = 0.25: is 0.25.* the family's base material has 0.3" -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" \
  --set material.nu=0.25 --out "$WORK/x.design.h5"
expect_exit 2 "grid.parameters\[1\].values = .*: half-sizes must lie in \[0, 1\] and increase strictly" -- \
  "$BIN/msfab-family-generate" --config "$WORK/grid.yaml" --set 'grid.parameters[1].values=[0.1, 0.05]' --out "$WORK/x.h5"
expect_exit 2 "grid.beams\[0\].parameter = width: 'width' is not one of grid.parameters" -- \
  "$BIN/msfab-family-generate" --config "$WORK/grid.yaml" --set 'grid.beams[0].parameter=width' --out "$WORK/x.h5"
expect_exit 2 "elements_per_cell = 9: must be 1..8" -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" \
  --set elements_per_cell=9 --out "$WORK/x.design.h5"
expect_exit 2 "elements_per_cell = 2: above 1 needs a 3D grid" -- "$BIN/msfab-topopt" --set elements_per_cell=2 \
  --out "$WORK/x.design.h5"
check "nothing written for refused runs" -- test ! -e "$WORK/x.design.h5" -a ! -e "$WORK/x.h5"
finish
