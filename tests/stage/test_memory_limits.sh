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
expect_exit 2 "64 x 64 x 64 cell with the direct solver .* or solver: multigrid" -- \
  $T "$H" --set 'cell.size=[64,64,64]' --set solver=direct --out "$WORK/h.h5"
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
check "refused runs leave nothing" -- bash -c "! ls '$WORK' | grep -q '\.h5'"

# The limit given by hand: a small run refused under 1 MiB, the refused
# 64^3 direct solve let through to its first step by a large limit.
expect_exit 2 "12 x 12 x 12 cell with the auto solver needs about .* MiB, more than the 1 MiB of --memory-limit" -- \
  $T "$H" --memory-limit 1M --out "$WORK/h.h5"
expect_exit 0 "" -- $T "$H" --memory-limit 64G --set 'cell.size=[8,8,8]' --set solver=direct --out "$WORK/small.h5" --quiet
expect_exit 2 "memory-limit '12X': expected a size such as 64G" -- $T "$H" --memory-limit 12X --out "$WORK/h.h5"
expect_exit 2 "memory-limit '0': expected a size" -- $T "$H" --memory-limit 0 --out "$WORK/h.h5"

# Numbers beyond any physical need, and non-finite ones, named by key.
expect_exit 2 "materials\[0\].E = 1e308: beyond" -- $T "$H" --set 'materials[0].E=1e308' --out "$WORK/h.h5"
expect_exit 2 "void_stiffness = .nan: expected a finite number" -- $T "$H" --set void_stiffness=.nan --out "$WORK/h.h5"
expect_exit 2 "materials.stiff.E = -.inf: expected a finite number" -- \
  $T "$BIN/msfab-gamut-sample" --config "$SRC/configs/gamut/tiny2d.yaml" --set materials.stiff.E=-.inf \
  --out "$WORK/g.gamut.h5"
finish
