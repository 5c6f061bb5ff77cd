#!/bin/bash
# Void in the palette (docs/ddfem.md, "Blocks with void"): a database whose
# blocks with void children are fitted is the same for 1 and 3 MPI ranks;
# on a holed cantilever of odd size (partly-void blocks along the hole and
# on the padded faces) its level-1 error is below a third of naive
# coarsening's and below half of a database without void children (whose
# partly-void blocks are closer with the Galerkin fallback than naive); it
# compresses, and its level 2 (with the all-void child as a hierarchy input)
# beats naive level 2; bad requests exit 2.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
BUILD="$BIN/msfab-ddfem-build"
SIM="$BIN/msfab-simulate"
CFG="$SRC/configs/ddfem/one_void.yaml"
BAR="$SRC/configs/scenes/holed_bar.yaml"
DATASETS="/combinations/ids /combinations/orbit /combinations/entry /fit/ids /fit/fitted /fit/mu /fit/lambda /fit/C /fit/v
          /fit/residual /fit/heldout_error /fit/samples_train"

check "one-rank build" -- "$BUILD" --config "$CFG" --out "$WORK/v1.h5" --quiet
check "three-rank build" -- mpirun -np 3 --oversubscribe -x OMP_NUM_THREADS=1 "$BUILD" --config "$CFG" --out "$WORK/v3.h5" --quiet
same=1
for d in $DATASETS; do h5diff -q "$WORK/v1.h5" "$WORK/v3.h5" "$d" "$d" || { echo "differs: $d"; same=0; }; done
check "1 and 3 ranks give the same database" -- test "$same" = 1
check "256 combinations, the all-void one without an entry" -- bash -c \
  "h5dump -H -d /combinations/entry '$WORK/v1.h5' | grep -q '( 256 )' && h5dump -d /combinations/entry -s 0 -c 1 '$WORK/v1.h5' | grep -q '(0): -1'"
check "database without void children" -- "$BUILD" --config "$CFG" --set void_children=false --out "$WORK/nv.h5" --quiet

"$SIM" --config "$BAR" --out "$WORK/fine.h5" --quiet >/dev/null
error_of() {  # error_of DATABASE MATERIAL LEVEL [OPTION ...]
  "$SIM" --config "$BAR" --coarsen "$3" --coarse-material "$2" --database "$1" "${@:4}" --reference "$WORK/fine.h5" \
    --out "$WORK/run.h5" --quiet >/dev/null || return 1
  h5dump -a /coarsening/error_vs_fine "$WORK/run.h5" | sed -n 's/.*(0): *//p'
}
void=$(error_of "$WORK/v1.h5" ddfem 1)
novoid=$(error_of "$WORK/nv.h5" ddfem 1)
naive=$(error_of "$WORK/v1.h5" naive 1)
echo "level-1 errors: void children fitted $void, not fitted $novoid, naive $naive"
check "void fitted: below a third of naive" -- awk -v d="$void" -v n="$naive" 'BEGIN { exit !(d > 0 && d < n / 3) }'
check "void fitted: below half of the database without void" -- awk -v d="$void" -v n="$novoid" 'BEGIN { exit !(d > 0 && d < n / 2) }'
# Without void children in the database, the partly-void blocks coarsened
# by the Galerkin element (their solid voxels integrated exactly over the
# coarse field, void empty) instead of naively (void filled with the
# nearest material): closer to the fine solution, and the run says so.
novoid_galerkin=$(error_of "$WORK/nv.h5" ddfem 1 --coarse-fallback galerkin)
galerkin=$(error_of "$WORK/v1.h5" galerkin 1)
echo "level-1 errors: not fitted with the Galerkin fallback $novoid_galerkin, Galerkin everywhere $galerkin"
check "Galerkin fallback below the naive fallback" -- \
  awk -v g="$novoid_galerkin" -v n="$novoid" 'BEGIN { exit !(g > 0 && g < n) }'
check "Galerkin coarsening below naive" -- awk -v g="$galerkin" -v n="$naive" 'BEGIN { exit !(g > 0 && g < n) }'
check "Galerkin fallback run" -- bash -c "'$SIM' --config '$BAR' --coarsen 1 --database '$WORK/nv.h5' \
  --coarse-fallback galerkin --out '$WORK/run.h5' > '$WORK/fallback.log' 2>&1"
check "the run names the fallback" -- grep -q 'without a database fit coarsened galerkin' "$WORK/fallback.log"
check "the result records the fallback" -- bash -c "h5dump -a /coarsening/fallback '$WORK/run.h5' | grep -q galerkin"

# Level 2 over the compressed database (compression keeps the fitted blocks).
expect_exit 2 "not fitted.*compress it first" -- "$BUILD" --config "$SRC/configs/ddfem/tiny_level2.yaml" \
  --set base_database="$WORK/v1.h5" --out "$WORK/l2.h5"
check "compressed to 32" -- "$BIN/msfab-ddfem-compress" --database "$WORK/v1.h5" --set representatives=32 --out "$WORK/k32.h5" --quiet
check "level-2 database" -- "$BUILD" --config "$SRC/configs/ddfem/tiny_level2.yaml" --set base_database="$WORK/k32.h5" \
  --set sampling.mode=periodic --out "$WORK/l2.h5" --quiet
level2=$(error_of "$WORK/l2.h5" ddfem 2)
naive2=$(error_of "$WORK/l2.h5" naive 2)
echo "level-2 errors: ddfem $level2, naive $naive2"
check "level 2: below naive level 2" -- awk -v d="$level2" -v n="$naive2" 'BEGIN { exit !(d > 0 && d < n) }'
check "level 2: the all-void child is an input of the hierarchy" -- bash -c \
  "h5dump -a /hierarchy/void_input '$WORK/l2.h5' | grep -q '(0): 1'"
expect_exit 2 "has void children.*need sampling.mode: periodic" -- "$BUILD" --config "$SRC/configs/ddfem/tiny_level2.yaml" \
  --set base_database="$WORK/k32.h5" --out "$WORK/bad.h5"

# Bad requests.
expect_exit 2 "coarse-fallback" -- "$SIM" --config "$BAR" --coarsen 1 --database "$WORK/nv.h5" --coarse-fallback average \
  --out "$WORK/bad.h5"
expect_exit 2 "void_children.*needs sampling.mode: periodic" -- "$BUILD" --config "$CFG" --set sampling.mode=isolated \
  --out "$WORK/bad.h5"
expect_exit 2 "void_children.*level-1 builds only" -- "$BUILD" --config "$SRC/configs/ddfem/tiny_level2.yaml" \
  --set base_database="$WORK/k32.h5" --set void_children=true --out "$WORK/bad.h5"
finish
