#!/bin/bash
# Runs that cannot fit in memory are refused before any work, with the
# estimate and the limit (docs/cli.md, "Memory"); --memory-limit overrides
# the available memory both ways. Numbers that no config needs (1e308) are
# refused by the config reader, naming the key. Each case is bounded in
# time: a run that starts allocating instead of refusing fails here.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
H="$BIN/msfab-homogenize"
T="timeout 30"

expect_exit 2 "a 4096 x 4096 x 4096 cell with the auto solver needs about .* GiB, more than the .* available" -- \
  $T "$H" --set 'cell.size=[4096,4096,4096]' --out "$WORK/h.h5"
expect_exit 2 "64 x 64 x 64 cell with the cholmod solver .* or linear_solver: matrix-free" -- \
  $T "$H" --set 'cell.size=[64,64,64]' --set linear_solver=cholmod --out "$WORK/h.h5"
expect_exit 2 "grid of 100000 x 100000 cells \(grid.size\) needs about" -- \
  $T "$BIN/msfab-topopt" --set 'grid.size=[100000,100000]' --out "$WORK/t.h5"
expect_exit 2 "grid of 400 x 400 x 400 cells \(grid.size\) with elements_per_cell 4" -- \
  $T "$BIN/msfab-topopt" --config "$SRC/configs/topopt/cantilever3d_simp.yaml" --set 'grid.size=[400,400,400]' \
  --set elements_per_cell=4 --out "$WORK/t.h5"
expect_exit 2 "population of 1000000000 structures of 8\^2 voxels needs about" -- \
  $T "$BIN/msfab-gamut-sample" --config "$SRC/configs/gamut/tiny2d.yaml" --set population=1000000000 \
  --out "$WORK/g.gamut.h5"
expect_exit 2 "1000030 structures of 64\^3 voxels \(templates\) needs about" -- \
  $T "$BIN/msfab-family-generate" --config "$SRC/configs/families/two_templates.yaml" \
  --set 'templates[0].moves=1000' --set 'templates[0].count=1000' --set resolution=64 --out "$WORK/f.h5"
expect_exit 2 "2000000000 sampling directions x 3 magnitudes per block \(sampling.sphere_directions" -- \
  $T "$BIN/msfab-ddfem-build" --config "$SRC/configs/ddfem/tiny.yaml" --set sampling.sphere_directions=2000000000 \
  --out "$WORK/d.h5"
expect_exit 2 "grid of 3000 x 3000 x 3000 voxels \(grid.size\) needs about .* GiB" -- \
  $T "$BIN/msfab-simulate" --set 'grid.size=[3000,3000,3000]' --out "$WORK/s.h5"
expect_exit 2 "model of 8000000 elements \(pcg-mg solver\) needs about .* GiB.*coarsen it" -- \
  $T "$BIN/msfab-simulate" --set 'grid.size=[200,200,200]' --set 'layout=[{fill: 1}]' --out "$WORK/s.h5"
expect_exit 2 "model of 13824 elements \(cholmod solver\) needs about .* MiB, more than the 100 MiB" -- \
  $T "$BIN/msfab-simulate" --set 'grid.size=[24,24,24]' --set 'layout=[{fill: 1}]' --set solver.linear_solver=cholmod \
  --memory-limit 100M --out "$WORK/s.h5"
expect_exit 2 "run of 8 elements over 10 s with a frame every 1 steps needs about .* GiB" -- \
  $T "$BIN/msfab-dynamics" --set simulation.time_step=2e-7 --set simulation.duration=10 \
  --set simulation.output_every=1 --out "$WORK/d.h5"
expect_exit 2 "the modes of 2621440 elements \(4 modes, search_levels 5\) needs about .* GiB" -- \
  $T "$BIN/msfab-dac-calibrate" --set "scene=$SRC/configs/dynamics/cantilever_pluck.yaml" --set search_levels=5 \
  --out "$WORK/c.h5"
check "refused runs leave nothing" -- bash -c "! ls '$WORK' | grep -q '\.h5'"

# The stages that read a design and a set: a 2D set, a design assigned
# from it, each refused under a small limit.
check "a 2D set" -- "$BIN/msfab-gamut-sample" --config "$SRC/configs/gamut/tiny2d.yaml" --set cycles=1 \
  --out "$WORK/set.gamut.h5" --quiet
cat > "$WORK/assign.yaml" <<'EOF_ASSIGN'
grid: {size: [64, 32], cell_size: 1.0}
space: cubic2d
supports: [{box: {min: [0, 0], max: [0, 32]}}]
loads: [{name: tip, objective: compliance, forces: [{box: {min: [64, 0], max: [64, 0]}, force: [0, -1]}]}]
pattern: {kind: random, structures: [0, 1, 2]}
EOF_ASSIGN
S="$WORK/set.microstructures.h5"
check "a design assigned from it" -- "$BIN/msfab-assign" --config "$WORK/assign.yaml" --structures "$S" \
  --out "$WORK/design.h5" --quiet
expect_exit 2 "design of 100000 x 100000 cells \(grid.size\) needs about .* GiB" -- \
  $T "$BIN/msfab-assign" --config "$WORK/assign.yaml" --set 'grid.size=[100000,100000]' --structures "$S" \
  --out "$WORK/big.h5"
expect_exit 2 "mapping 2048 cells with 16 candidates each needs about .* MiB, more than the 1 MiB" -- \
  $T "$BIN/msfab-map" --design "$WORK/design.h5" --structures "$S" --memory-limit 1M --out "$WORK/m.h5"
expect_exit 2 "coverage of 2048 cells and one cell problem of 8\^2 voxels per thread needs about" -- \
  $T "$BIN/msfab-fill-targets" --design "$WORK/design.h5" --structures "$S" --memory-limit 1M --out "$WORK/f.h5"
check "refused runs leave nothing" -- bash -c "! ls '$WORK' | grep -Eq '^(big|m|f)\.h5'"

# The limit given by hand: a small run refused under 1 MiB, the refused
# 64^3 direct solve let through to its first step by a large limit.
expect_exit 2 "12 x 12 x 12 cell with the auto solver needs about .* MiB, more than the 1 MiB of --memory-limit" -- \
  $T "$H" --memory-limit 1M --out "$WORK/h.h5"
expect_exit 0 "" -- $T "$H" --memory-limit 64G --set 'cell.size=[8,8,8]' --set linear_solver=cholmod --out "$WORK/small.h5" --quiet
expect_exit 2 "memory-limit '12X': expected a size such as 64G" -- $T "$H" --memory-limit 12X --out "$WORK/h.h5"
expect_exit 2 "memory-limit '0': expected a size" -- $T "$H" --memory-limit 0 --out "$WORK/h.h5"

# Numbers beyond any physical need, and non-finite ones, named by key.
expect_exit 2 "materials\[0\].E = 1e308: beyond" -- $T "$H" --set 'materials[0].E=1e308' --out "$WORK/h.h5"
expect_exit 2 "void_stiffness = .nan: expected a finite number" -- $T "$H" --set void_stiffness=.nan --out "$WORK/h.h5"
expect_exit 2 "materials.stiff.E = -.inf: expected a finite number" -- \
  $T "$BIN/msfab-gamut-sample" --config "$SRC/configs/gamut/tiny2d.yaml" --set materials.stiff.E=-.inf \
  --out "$WORK/g.gamut.h5"
finish
