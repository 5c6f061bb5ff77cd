#!/bin/bash
# msfab-ddfem-build on the tiny palette, level 1 and level 2: the database is
# identical for 1 and 3 MPI ranks and after a stop and --resume; bad
# palettes and bases exit 2.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
BUILD="$BIN/msfab-ddfem-build"
TINY="$SRC/configs/ddfem/tiny.yaml"
# Compared datasets: everything but the timings.
DATASETS="/palette/E /palette/nu /palette/density /combinations/ids /combinations/orbit /combinations/entry /fit/ids /fit/fitted /fit/mu
          /fit/lambda /fit/C /fit/v /fit/residual /fit/heldout_error /fit/heldout_energy_error /fit/samples_train"
same_db() {  # same_db A B
  local d
  for d in $DATASETS; do h5diff -q "$1" "$2" "$d" "$d" || { echo "differs: $d"; return 1; }; done
}

check "one-rank build" -- "$BUILD" --config "$TINY" --out "$WORK/one.h5" --quiet
check "artifact schema" -- bash -c "h5dump -a /schema '$WORK/one.h5' | grep -q msfab.coarse_db"
check "no checkpoint left" -- test ! -e "$WORK/one.h5.checkpoint.h5"
check "three-rank build" -- mpirun -np 3 --oversubscribe -x OMP_NUM_THREADS=1 "$BUILD" --config "$TINY" --out "$WORK/three.h5" --quiet
check "1 and 3 ranks give the same database" -- same_db "$WORK/one.h5" "$WORK/three.h5"

# In-situ (periodic) sampling: not the isolated database (its independence
# of the rank count is checked with the centre point below, which samples
# the same way).
check "periodic sampling, one rank" -- "$BUILD" --config "$TINY" --set sampling.mode=periodic --out "$WORK/p1.h5" --quiet
check "periodic and isolated databases differ" -- bash -c "! h5diff -q '$WORK/one.h5' '$WORK/p1.h5' /fit/mu /fit/mu"

# The centre point (docs/ddfem.md): stored, carried through the MPI records
# unchanged, and used by the simulator.
check "centre point, one rank" -- "$BUILD" --config "$TINY" --set sampling.mode=periodic --set fit.centre_point=true \
  --out "$WORK/c1.h5" --quiet
check "centre point, three ranks" -- mpirun -np 3 --oversubscribe -x OMP_NUM_THREADS=1 "$BUILD" --config "$TINY" \
  --set sampling.mode=periodic --set fit.centre_point=true --out "$WORK/c3.h5" --quiet
check "1 and 3 ranks give the same centre-point database" -- bash -c \
  "h5diff -q '$WORK/c1.h5' '$WORK/c3.h5' /fit/centre /fit/centre && $(declare -f same_db); DATASETS='$DATASETS' same_db '$WORK/c1.h5' '$WORK/c3.h5'"
check "centre-point database stores /fit/centre" -- bash -c "h5dump -H -d /fit/centre '$WORK/c1.h5' | grep -q '( 256, 2 )'"
check "databases without the centre point store none" -- bash -c "! h5dump -H -d /fit/centre '$WORK/p1.h5' >/dev/null 2>&1"
check "the simulator runs on a centre-point database" -- "$BIN/msfab-simulate" --config "$SRC/configs/scenes/demo_bar.yaml" \
  --coarsen 1 --database "$WORK/c1.h5" --out "$WORK/c1run.h5" --quiet

# Stop after two rounds (a batch job's time limit), then resume.
# A symlink planted under the checkpoint's old fixed temporary name is not followed.
echo "victim" > "$WORK/victim.txt"
ln -s "$WORK/victim.txt" "$WORK/part.h5.checkpoint.h5.tmp"
expect_exit 0 "stopped after 2 rounds" -- "$BUILD" --config "$TINY" --out "$WORK/part.h5" --max-rounds 2
check "checkpoint kept" -- test -e "$WORK/part.h5.checkpoint.h5"
check "checkpoint is a regular file, the planted symlink not followed" -- \
  bash -c "[ ! -L '$WORK/part.h5.checkpoint.h5' ] && [ \"\$(cat '$WORK/victim.txt')\" = victim ]"
check "no artifact before the end" -- test ! -e "$WORK/part.h5"
expect_exit 2 "different configuration" -- "$BUILD" --config "$TINY" --set fit.regularization=0.5 --out "$WORK/part.h5" --resume
expect_exit 0 "resuming: 8 of 22" -- "$BUILD" --config "$TINY" --out "$WORK/part.h5" --resume
check "resumed build gives the same database" -- same_db "$WORK/one.h5" "$WORK/part.h5"

# Compression to k representatives (thesis 2.3.4).
COMPRESS="$BIN/msfab-ddfem-compress"
expect_exit 0 "256 -> 16 coarse materials" -- "$COMPRESS" --database "$WORK/one.h5" --set representatives=16 --out "$WORK/k16.h5"
check "compressed database holds 16 materials" -- bash -c "h5dump -H -d /fit/mu '$WORK/k16.h5' | grep -q '( 16, 8 )'"
expect_exit 0 "256 -> 16 coarse materials" -- "$COMPRESS" --database "$WORK/one.h5" --set representatives=16 \
  --set corner_moves=true --out "$WORK/k16c.h5"
expect_exit 2 "exceeds the 256 coarse materials" -- "$COMPRESS" --database "$WORK/one.h5" --set representatives=300 --out "$WORK/bad.h5"
expect_exit 2 "already compressed" -- "$COMPRESS" --database "$WORK/k16.h5" --set representatives=4 --out "$WORK/bad.h5"
expect_exit 2 "tiny.yaml: not a valid HDF5" -- "$COMPRESS" --database "$SRC/configs/ddfem/tiny.yaml" --out "$WORK/bad.h5"

# Level 2 over the tiny database (thesis 2.3.5): same for 1 and 3 ranks and after a resume.
L2="$SRC/configs/ddfem/tiny_level2.yaml"
L2SETS="/fit/ids /fit/mu /fit/lambda /fit/C /fit/v /fit/heldout_error /hierarchy/stage0/table /hierarchy/stage1/pairs
        /hierarchy/stage2/table /level1/fit/mu /level1/combinations/entry"
same_db2() {
  local d
  for d in $L2SETS; do h5diff -q "$1" "$2" "$d" "$d" || { echo "differs: $d"; return 1; }; done
}
expect_exit 0 "16 level-2 coarse materials over 256 level-1 materials" -- \
  "$BUILD" --config "$L2" --set base_database="$WORK/one.h5" --out "$WORK/l2one.h5"
check "level-2 fits have 64 points" -- bash -c "h5dump -H -d /fit/mu '$WORK/l2one.h5' | grep -q '( 16, 64 )'"
check "three-rank level-2 build" -- mpirun -np 3 --oversubscribe -x OMP_NUM_THREADS=1 "$BUILD" --config "$L2" \
  --set base_database="$WORK/one.h5" --out "$WORK/l2three.h5" --quiet
check "level 2: 1 and 3 ranks give the same database" -- same_db2 "$WORK/l2one.h5" "$WORK/l2three.h5"
expect_exit 0 "stopped after 1 rounds" -- "$BUILD" --config "$L2" --set base_database="$WORK/one.h5" --out "$WORK/l2part.h5" --max-rounds 1
expect_exit 2 "different configuration" -- "$BUILD" --config "$L2" --set base_database="$WORK/k16.h5" --out "$WORK/l2part.h5" --resume
expect_exit 0 "resuming: 4 of 16" -- "$BUILD" --config "$L2" --set base_database="$WORK/one.h5" --out "$WORK/l2part.h5" --resume
check "level 2: resumed build gives the same database" -- same_db2 "$WORK/l2one.h5" "$WORK/l2part.h5"
expect_exit 2 "must be a level-1 database" -- "$BUILD" --config "$L2" --set base_database="$WORK/l2one.h5" --out "$WORK/bad.h5"
expect_exit 2 "takes its palette from base_database" -- "$BUILD" --config "$L2" --set base_database="$WORK/one.h5" \
  --set 'palette=[{E: 1, nu: 0.3}]' --out "$WORK/bad.h5"
expect_exit 2 "level2.representatives" -- "$BUILD" --config "$L2" --set base_database="$WORK/one.h5" \
  --set 'level2.representatives=[4, 4]' --out "$WORK/bad.h5"
expect_exit 2 "needs base_database" -- "$BUILD" --config "$TINY" --set 'level2.deformations=4' --out "$WORK/bad.h5"
# Corner moves in the level-2 lookup, over the base compressed with them.
expect_exit 0 "16 level-2 coarse materials over 16 level-1 materials" -- "$BUILD" --config "$L2" \
  --set base_database="$WORK/k16c.h5" --set level2.corner_moves=true --out "$WORK/l2c.h5"
# Level 2 sampled on the blocks' fine voxels (periodic only), same for 1 and 2 ranks.
expect_exit 0 "16 level-2 coarse materials over 256 level-1 materials" -- "$BUILD" --config "$L2" \
  --set base_database="$WORK/one.h5" --set sampling.mode=periodic --set level2.samples=voxels --out "$WORK/l2vox.h5"
check "two-rank voxel-sampled level-2 build" -- mpirun -np 2 --oversubscribe -x OMP_NUM_THREADS=1 "$BUILD" --config "$L2" \
  --set base_database="$WORK/one.h5" --set sampling.mode=periodic --set level2.samples=voxels --out "$WORK/l2vox2.h5" --quiet
check "level 2 on voxels: 1 and 2 ranks give the same database" -- same_db2 "$WORK/l2vox.h5" "$WORK/l2vox2.h5"
check "level 2 on voxels differs from level 2 on level-1 elements" -- bash -c "! h5diff -q '$WORK/l2vox.h5' '$WORK/l2one.h5' /fit/mu"
expect_exit 2 "level2.samples.*needs sampling.mode: periodic" -- "$BUILD" --config "$L2" --set base_database="$WORK/one.h5" \
  --set level2.samples=voxels --out "$WORK/bad.h5"
expect_exit 2 "level2.samples.*level1 .* or voxels" -- "$BUILD" --config "$L2" --set base_database="$WORK/one.h5" \
  --set sampling.mode=periodic --set level2.samples=fine --out "$WORK/bad.h5"
# The pairing's memory is checked before the hierarchy is built (the thesis
# paired all 6561 level-1 materials of its palette; a machine decides).
expect_exit 2 "pairing 256 level-1 materials \(65536 candidates x [0-9]+ level2.deformations\) needs about .* MiB, more than the 4 MiB" -- \
  "$BUILD" --config "$L2" --set base_database="$WORK/one.h5" --memory-limit 4M --out "$WORK/l2mem.h5"
check "a refused level-2 build writes nothing" -- test ! -e "$WORK/l2mem.h5"

# Bad palettes.
sed 's/nu: 0.45, density: 1200/nu: 0.5, density: 1200/' "$TINY" > "$WORK/nu05.yaml"
expect_exit 2 "palette\[1\]\.nu.*Poisson" -- "$BUILD" --config "$WORK/nu05.yaml" --out "$WORK/bad.h5"
sed 's/E: 1.0e5/E: -3/' "$TINY" > "$WORK/negE.yaml"
expect_exit 2 "palette\[0\]\.E" -- "$BUILD" --config "$WORK/negE.yaml" --out "$WORK/bad.h5"
expect_exit 2 "unknown key 'magnitude'" -- "$BUILD" --config "$TINY" --set sampling.magnitude=2 --out "$WORK/bad.h5"
expect_exit 2 "folder does not exist" -- "$BUILD" --config "$TINY" --out "$WORK/nowhere/db.h5"
expect_exit 2 "element.*trilinear or enhanced" -- "$BUILD" --config "$TINY" --set fit.element=quadratic --out "$WORK/bad.h5"
expect_exit 2 "sampling.mode.*isolated, patch or periodic" -- "$BUILD" --config "$TINY" --set sampling.mode=situ --out "$WORK/bad.h5"
expect_exit 2 "sampling.context.*1 to 4" -- "$BUILD" --config "$TINY" --set sampling.mode=patch --set sampling.context=9 \
  --out "$WORK/bad.h5"
check "nothing written on bad input" -- test ! -e "$WORK/bad.h5"
finish
