#!/bin/bash
# msfab-gamut-sample on a tiny 2D gamut: the artifacts are written;
# the result (directed pushes included) is identical for 1 and 3 MPI ranks, for 1 and 2 threads, and
# after a stop and --resume; a run to convergence stops where the coverage
# stops growing; bad settings exit 2 naming the key.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
SAMPLE="$BIN/msfab-gamut-sample"
TINY="$SRC/configs/gamut/tiny2d.yaml"
same_run() {  # same_run STEM_A STEM_B
  local d
  for d in /voxels /properties /unit_properties /C /cycle /step /parent; do
    h5diff -q "$1.microstructures.h5" "$2.microstructures.h5" "$d" "$d" || { echo "differs: $d"; return 1; }
  done
  for d in /level_set/phi /history/coverage /history/samples; do
    h5diff -q "$1.gamut.h5" "$2.gamut.h5" "$d" "$d" || { echo "differs: $d"; return 1; }
  done
}

expect_exit 0 "after 3 cycles" -- "$SAMPLE" --config "$TINY" --seed 7 --out "$WORK/one.gamut.h5"
check "gamut schema" -- bash -c "h5dump -a /schema '$WORK/one.gamut.h5' | grep -q msfab.gamut"
check "microstructures schema" -- bash -c "h5dump -a /schema '$WORK/one.microstructures.h5' | grep -q msfab.microstructures"
check "level set is 4-D, 12 cells per axis" -- bash -c "h5dump -H -d /level_set/phi '$WORK/one.gamut.h5' | grep -q '( 12, 12, 12, 12 )'"
check "voxels packed at two bits per voxel (3 ids): 16 bytes per 8 x 8 cell" -- bash -c "h5dump -H -d /voxels '$WORK/one.microstructures.h5' | grep -q ', 16 )'"
check "history has cycles 0..3" -- bash -c "h5dump -d /history/cycle '$WORK/one.gamut.h5' | grep -q '0, 1, 2, 3'"
check "no plots folder" -- test ! -e "$WORK/one.plots"
check "no checkpoint left" -- test ! -e "$WORK/one.gamut.h5.checkpoint.h5"
# The two artifacts are one commit (io/commit_group.hpp): no journal left,
# and the gamut records the hash of the very set beside it.
check "no commit journal left" -- bash -c "! ls '$WORK' | grep -q '\.pending$'"
check "the gamut records the set's hash" -- bash -c \
  "h5dump -a /inputs '$WORK/one.gamut.h5' | grep -q \$(sha256sum '$WORK/one.microstructures.h5' | cut -c1-64)"

check "three ranks" -- mpirun -np 3 --oversubscribe -x OMP_NUM_THREADS=1 "$SAMPLE" --config "$TINY" --seed 7 \
  --out "$WORK/three.gamut.h5" --quiet
check "1 and 3 ranks give the same gamut and structures" -- same_run "$WORK/one" "$WORK/three"
check "one thread" -- "$SAMPLE" --config "$TINY" --seed 7 --threads 1 --out "$WORK/t1.gamut.h5" --quiet
check "1 and 2 threads give the same gamut and structures" -- same_run "$WORK/one" "$WORK/t1"
check "another seed" -- "$SAMPLE" --config "$TINY" --seed 8 --out "$WORK/s8.gamut.h5" --quiet
check "another seed gives other structures" -- bash -c "[ \"\$(h5dump -d /voxels '$WORK/one.microstructures.h5' | md5sum)\" != \"\$(h5dump -d /voxels '$WORK/s8.microstructures.h5' | md5sum)\" ]"

# Stop after one cycle (a batch job's time limit), then resume.
# A symlink planted under the checkpoint's old fixed temporary name is not followed.
echo "victim" > "$WORK/victim.txt"
ln -s "$WORK/victim.txt" "$WORK/part.gamut.h5.checkpoint.h5.tmp"
expect_exit 0 "stopped after cycle 1 of 3" -- "$SAMPLE" --config "$TINY" --seed 7 --out "$WORK/part.gamut.h5" --max-cycles 1
check "checkpoint is a regular file, the planted symlink not followed" -- \
  bash -c "[ ! -L '$WORK/part.gamut.h5.checkpoint.h5' ] && [ \"\$(cat '$WORK/victim.txt')\" = victim ]"
check "checkpoint kept" -- test -e "$WORK/part.gamut.h5.checkpoint.h5"
check "no artifact before the end" -- test ! -e "$WORK/part.gamut.h5"
expect_exit 2 "different configuration or seed" -- "$SAMPLE" --config "$TINY" --seed 9 --out "$WORK/part.gamut.h5" --resume
expect_exit 0 "resuming after cycle 1" -- "$SAMPLE" --config "$TINY" --seed 7 --out "$WORK/part.gamut.h5" --resume
check "resumed run gives the same gamut and structures" -- same_run "$WORK/one" "$WORK/part"

# Void variants (thesis 3.6.1): the soft material removed, on 1 and 3 ranks.
expect_exit 0 "void variants: [0-9]+ of [0-9]+ structures" -- "$SAMPLE" --config "$TINY" --seed 7 --set void_variants=true \
  --out "$WORK/v.gamut.h5"
check "void variants are marked step 3 and one material" -- bash -c "h5dump -d /step '$WORK/v.void.microstructures.h5' | grep -A1 'DATA {' | grep -vq '[0-24-9],' && \
  h5dump -a /soft_is_void '$WORK/v.void.microstructures.h5' | grep -q '(0): 1'"
check "void variants keep no soft voxels (one bit per voxel)" -- bash -c "h5dump -H -d /voxels '$WORK/v.void.microstructures.h5' | grep -q ', 8 )'"
check "three ranks with void variants" -- mpirun -np 3 --oversubscribe -x OMP_NUM_THREADS=1 "$SAMPLE" --config "$TINY" --seed 7 \
  --set void_variants=true --out "$WORK/v3.gamut.h5" --quiet
check "void variants: 1 and 3 ranks agree" -- bash -c "h5diff -q '$WORK/v.void.microstructures.h5' '$WORK/v3.void.microstructures.h5' /properties /properties && \
  h5diff -q '$WORK/v.void.gamut.h5' '$WORK/v3.void.gamut.h5' /level_set/phi /level_set/phi"
expect_exit 2 "void_variants.*needs a soft material" -- "$SAMPLE" --config "$TINY" --set void_variants=true \
  --set materials='{stiff: {E: 1.0e6, nu: 0.3}}' --out "$WORK/bad.gamut.h5"

# Two materials and void (thesis Fig. 3-15): beams add the stiff or the soft
# material or cut to void, so structures mix all three; 1 and 3 ranks agree.
THREE_MATERIALS='{stiff: {E: 1.0e6, nu: 0.3}, soft: {E: 1.0e3, nu: 0.45}, void: true}'
expect_exit 0 "phases: [1-9][0-9]* structures with void, [1-9][0-9]* with the soft material, [1-9][0-9]* with both" -- \
  "$SAMPLE" --config "$TINY" --seed 7 --set materials="$THREE_MATERIALS" --set continuous.per_cycle=0 \
  --set directed.per_cycle=0 --out "$WORK/tri.gamut.h5"
check "two materials and void: 1 and 3 ranks agree" -- bash -c "mpirun -np 3 --oversubscribe -x OMP_NUM_THREADS=1 \
  '$SAMPLE' --config '$TINY' --seed 7 --set materials='$THREE_MATERIALS' --set continuous.per_cycle=0 \
  --set directed.per_cycle=0 --out '$WORK/tri3.gamut.h5' --quiet && \
  h5diff -q '$WORK/tri.microstructures.h5' '$WORK/tri3.microstructures.h5' /voxels /voxels && \
  h5diff -q '$WORK/tri.gamut.h5' '$WORK/tri3.gamut.h5' /level_set/phi /level_set/phi"
expect_exit 2 "continuous.per_cycle = 2: must be 0 with two materials and void" -- "$SAMPLE" --config "$TINY" \
  --set materials="$THREE_MATERIALS" --out "$WORK/bad.gamut.h5"
expect_exit 2 "directed.per_cycle = 1: must be 0 with two materials and void" -- "$SAMPLE" --config "$TINY" \
  --set materials="$THREE_MATERIALS" --set continuous.per_cycle=0 --out "$WORK/bad.gamut.h5"
expect_exit 2 "initial_set.path .*tri.microstructures.h5: structure [0-9]+ holds void" -- "$SAMPLE" --config "$TINY" \
  --set initial_set="{path: $WORK/tri.microstructures.h5}" --set materials='{stiff: {E: 1.0e6, nu: 0.3}, soft: {E: 1.0e3, nu: 0.45}}' \
  --out "$WORK/bad.gamut.h5"
expect_exit 2 "materials.void.*false needs materials.soft" -- "$SAMPLE" --config "$TINY" \
  --set materials='{stiff: {E: 1.0e6, nu: 0.3}, void: false}' --out "$WORK/bad.gamut.h5"

# An earlier set as part of the initial population: every structure of
# `one` (8 x 8) is added again, as is, or with each voxel split into 2 x 2
# for a 16 x 16 gamut.
count_of() { h5dump -H -d /voxels "$1" | sed -n 's/.*DATASPACE *SIMPLE { ( \([0-9]*\),.*/\1/p'; }
initial_of() { sed -n 's/.* structures (\([0-9]*\) initial.*/\1/p' <<<"$1"; }
n_one=$(count_of "$WORK/one.microstructures.h5")
out=$("$SAMPLE" --config "$TINY" --seed 7 --set initial_set="{path: $WORK/one.microstructures.h5}" --set cycles=1 \
  --out "$WORK/seeded.gamut.h5" 2>&1)
echo "seeded: $(initial_of "$out") initial structures from a set of $n_one"
check "seeded run adds every structure of the set" -- test "$(initial_of "$out")" -ge "$n_one"
out=$("$SAMPLE" --config "$TINY" --seed 7 --set resolution=16 --set initial_set="{path: $WORK/one.microstructures.h5, refine: 2}" \
  --set cycles=1 --set continuous.per_cycle=0 --set directed.per_cycle=0 --out "$WORK/seeded16.gamut.h5" 2>&1)
check "refined seeds start a 16 x 16 gamut" -- test "$(initial_of "$out")" -ge "$n_one"
check "its cells are 16 x 16" -- bash -c "h5dump -H -d /voxels '$WORK/seeded16.microstructures.h5' | grep -q ', 64 )'"
expect_exit 2 "initial_set.path .*one.microstructures.h5: cells of 8 voxels per side, refined 1 times, are not the sampler's resolution 16" -- \
  "$SAMPLE" --config "$TINY" --set resolution=16 --set initial_set="{path: $WORK/one.microstructures.h5}" --out "$WORK/bad.gamut.h5"
expect_exit 2 "initial_set.path .*base materials" -- "$SAMPLE" --config "$TINY" --set materials.stiff.E=2e6 \
  --set initial_set="{path: $WORK/one.microstructures.h5}" --out "$WORK/bad.gamut.h5"
expect_exit 2 "initial_set.refine.*must be in 1..8" -- "$SAMPLE" --config "$TINY" \
  --set initial_set="{path: $WORK/one.microstructures.h5, refine: 0}" --out "$WORK/bad.gamut.h5"
expect_exit 2 "initial_set.*missing.h5" -- "$SAMPLE" --config "$TINY" --set initial_set="{path: $WORK/missing.h5}" \
  --out "$WORK/bad.gamut.h5"

# `mode: set`: the gamut of a given set (and the solid cell) alone, nothing
# sampled: the set's structures come back unchanged, in order, after the solid cell.
out=$("$SAMPLE" --config "$TINY" --seed 7 --set mode=set --set cycles=0 \
  --set initial_set="{path: $WORK/one.microstructures.h5}" --out "$WORK/setonly.gamut.h5" 2>&1)
echo "mode set: $(initial_of "$out") structures from a set of $n_one"
check "mode set keeps the set and the solid cell, nothing else" -- \
  test "$(count_of "$WORK/setonly.microstructures.h5")" -le "$((n_one + 1))"
check "mode set: no cycle ran" -- bash -c "h5dump -d /history/cycle '$WORK/setonly.gamut.h5' | grep -q '(0): 0\$'"
check "mode set: the set's last structure is the artifact's last" -- bash -c \
  "h5dump -d /properties '$WORK/one.microstructures.h5' | grep -o '([0-9]*,0):.*' | tail -1 | cut -d: -f2 > '$WORK/a' && \
   h5dump -d /properties '$WORK/setonly.microstructures.h5' | grep -o '([0-9]*,0):.*' | tail -1 | cut -d: -f2 > '$WORK/b' && \
   cmp -s '$WORK/a' '$WORK/b'"
expect_exit 2 "mode.*set needs initial_set.path" -- "$SAMPLE" --config "$TINY" --set mode=set --set cycles=0 \
  --out "$WORK/bad.gamut.h5"
# The axis backbone: refused with two materials (every cell is solid) and
# wider than the cell; with void the run completes (the unit test
# ConnectedFamily checks the cells themselves).
expect_exit 2 "backbone.*needs a void phase" -- "$SAMPLE" --config "$TINY" --set backbone=1 --out "$WORK/bad.gamut.h5"
expect_exit 2 "backbone = 5: must be in 0..resolution/2 .4" -- "$SAMPLE" --config "$TINY" --set materials='{stiff: {E: 1.0e6, nu: 0.3}}' \
  --set backbone=5 --out "$WORK/bad.gamut.h5"
expect_exit 0 "after 3 cycles" -- "$SAMPLE" --config "$TINY" --seed 7 --set materials='{stiff: {E: 1.0e6, nu: 0.3}}' \
  --set backbone=1 --out "$WORK/backbone.gamut.h5"
expect_exit 2 "cycles.*must be 0 with mode: set" -- "$SAMPLE" --config "$TINY" --set mode=set \
  --set initial_set="{path: $WORK/one.microstructures.h5}" --out "$WORK/bad.gamut.h5"

# Runs to convergence: `stop` ends the run once the coverage grew by less
# than coverage_growth over `window` cycles; `cycles` is then the most. On
# this seed the coverage per cycle is 0.0059, 0.0080, 0.0141, 0.0140 (best
# so far: 0.0059, 0.0080, 0.0141, 0.0141): +36% in cycle 1 is below a 50%
# threshold, so that run stops after cycle 1; over two cycles +139% and
# then +76%, so a 90% threshold stops after cycle 3, also when the run is
# stopped after cycle 2 and resumed.
expect_exit 0 "converged: best coverage grew 35.59% over the last 1 cycle" -- "$SAMPLE" --config "$TINY" --seed 7 \
  --set cycles=3 --set stop='{coverage_growth: 0.5, window: 1}' --out "$WORK/conv1.gamut.h5"
check "converged run stopped after cycle 1" -- bash -c "h5dump -d /history/cycle '$WORK/conv1.gamut.h5' | grep -q '(0): 0, 1\$'"
expect_exit 0 "after 1 cycles" -- "$SAMPLE" --config "$TINY" --seed 7 --set cycles=1 --out "$WORK/cyc1.gamut.h5"
check "the converged run is the one-cycle run" -- same_run "$WORK/conv1" "$WORK/cyc1"
STOP2='{coverage_growth: 0.9, window: 2}'
expect_exit 0 "stopped after cycle 2 of 4" -- "$SAMPLE" --config "$TINY" --seed 7 --set cycles=4 --set stop="$STOP2" \
  --out "$WORK/convpart.gamut.h5" --max-cycles 2
expect_exit 0 "after 3 cycles" -- "$SAMPLE" --config "$TINY" --seed 7 --set cycles=4 --set stop="$STOP2" \
  --out "$WORK/convpart.gamut.h5" --resume
check "resumed, it converges after cycle 3 like the uninterrupted run" -- same_run "$WORK/one" "$WORK/convpart"
expect_exit 0 "not converged, stopped at the cycle limit" -- "$SAMPLE" --config "$TINY" --seed 7 --set cycles=2 \
  --set stop="$STOP2" --out "$WORK/limit.gamut.h5"
# An adaptive push step: it changes with the pushes' progress, and is
# kept in the checkpoint (stopped and resumed, the same run).
expect_exit 0 "continuous: step 0\.0(67|44)" -- "$SAMPLE" --config "$TINY" --seed 7 \
  --set continuous.adaptive_step=true --out "$WORK/adapt.gamut.h5"
expect_exit 0 "stopped after cycle 1 of 3" -- "$SAMPLE" --config "$TINY" --seed 7 --set continuous.adaptive_step=true \
  --out "$WORK/adaptpart.gamut.h5" --max-cycles 1
expect_exit 0 "resuming after cycle 1" -- "$SAMPLE" --config "$TINY" --seed 7 --set continuous.adaptive_step=true \
  --out "$WORK/adaptpart.gamut.h5" --resume
check "an adaptive run stopped and resumed is the same run" -- same_run "$WORK/adapt" "$WORK/adaptpart"

# Bad settings.
expect_exit 2 "stop.coverage_growth.*must be in \[0, 1\)" -- "$SAMPLE" --config "$TINY" --set stop.coverage_growth=1.5 \
  --out "$WORK/bad.gamut.h5"
expect_exit 2 "stop.window.*must be in 1..1000" -- "$SAMPLE" --config "$TINY" --set stop.window=0 --out "$WORK/bad.gamut.h5"
expect_exit 2 "population.*must be >= 2" -- "$SAMPLE" --config "$TINY" --set population=1 --out "$WORK/bad.gamut.h5"
expect_exit 2 "space" -- "$SAMPLE" --config "$TINY" --set space=cubic4d --out "$WORK/bad.gamut.h5"
expect_exit 2 "materials.soft.*E must be below" -- "$SAMPLE" --config "$TINY" --set materials.soft.E=2e6 --out "$WORK/bad.gamut.h5"
expect_exit 2 "continuous.step" -- "$SAMPLE" --config "$TINY" --set continuous.step=0 --out "$WORK/bad.gamut.h5"
expect_exit 2 "directed.objectives.*'min_mu' is not one of" -- "$SAMPLE" --config "$TINY" --set 'directed.objectives=[min_mu]' \
  --out "$WORK/bad.gamut.h5"
expect_exit 2 "min_feature.*must be in 1..resolution/2 \(4\)" -- "$SAMPLE" --config "$TINY" --set min_feature=5 --out "$WORK/bad.gamut.h5"
# A one-material cell has void, so beams or gaps thinner than 2 voxels are refused.
expect_exit 0 " [1-9][0-9]* thinner than min_feature" -- "$SAMPLE" --config "$TINY" --set min_feature=2 \
  --set materials='{stiff: {E: 1.0e6, nu: 0.3}}' --out "$WORK/mf.gamut.h5"
expect_exit 2 "directed.modulus_drop" -- "$SAMPLE" --config "$TINY" --set directed.modulus_drop=0 --out "$WORK/bad.gamut.h5"
check "directed pushes ran and their structures are step 4" -- bash -c "h5dump -d /step '$WORK/one.microstructures.h5' | grep -q ' 4'"
expect_exit 2 "unknown|not a known" -- "$SAMPLE" --config "$TINY" --set cylces=3 --out "$WORK/bad.gamut.h5"
expect_exit 2 "output folder does not exist" -- "$SAMPLE" --config "$TINY" --out "$WORK/missing/x.gamut.h5"
finish
