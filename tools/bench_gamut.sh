#!/bin/bash
# Gamut sampling against random sampling (thesis §3.2): the same material
# space, seed and level-set settings; the sampler's discrete + continuous
# cycles against fresh random-beam structures with at least the same number
# of homogenizations per cycle. Reports structures, coverage of the unit
# cube (level-set volume), the property ranges reached, wall time and
# structures per hour: 2D cubic (three seeds), 2D orthotropic, and 3D cubic
# with two materials (E 1e6 and 1e3, nu 0.45, the gamut issue's setting)
# and with one material and void, all at 16 voxels per side.
#
#   tools/bench_gamut.sh BIN OUTDIR BENCHMARKS.md
set -euo pipefail
BIN=$1 OUTDIR=$2 DOC=$3
SRC=$(cd "$(dirname "$0")/.." && pwd)
SEEDS=${SEEDS:-"1 2 3"}
mkdir -p "$OUTDIR"
rows=""
run() {  # run NAME CONFIG MODE SEED EXTRA...
  local name=$1 config=$2 mode=$3 seed=$4
  shift 4
  echo "bench: gamut $name $mode seed $seed ..." >&2
  local log="$OUTDIR/$name.$mode.$seed.log"
  /usr/bin/time -f "%e" -o "$OUTDIR/time" "$BIN/msfab-gamut-sample" --config "$config" --set mode=$mode \
    --seed "$seed" --out "$OUTDIR/$name.$mode.$seed.gamut.h5" "$@" > "$log" 2>&1
  local n cov nu E wall
  n=$(sed -n 's/.*: [a-z0-9]*, \([0-9]*\) structures.*/\1/p' "$log")
  cov=$(sed -n 's/^  coverage \([0-9.]*\).*/\1/p' "$log")
  nu=$(sed -n 's/^  range nu[_xy]*: \[\(.*\)\]/\1/p' "$log")
  E=$(sed -n 's/^  range Ex*: \[\([^,]*\),.*/\1/p' "$log")
  wall=$(cat "$OUTDIR/time")
  rows+="| $name | $mode | $seed | $n | $cov | [$nu] | $E | $wall | $(awk -v n="$n" -v w="$wall" 'BEGIN { printf "%.0f", 3600 * n / w }') |"$'\n'
}
for seed in $SEEDS; do
  for mode in sampler random; do run cubic2d "$SRC/configs/gamut/cubic2d.yaml" $mode $seed; done
done
run orthotropic2d "$SRC/configs/gamut/orthotropic2d.yaml" sampler 1
run orthotropic2d "$SRC/configs/gamut/orthotropic2d.yaml" random 1
# 3D at 16^3: short runs (the full gamut is `make gamut-3d`).
SHORT3D=(--set population=32 --set cycles=8 --set continuous.per_cycle=2 --set continuous.max_iterations=20)
TWO=(--set 'materials={stiff: {E: 1.0e6, nu: 0.45}, soft: {E: 1.0e3, nu: 0.45}}')
for mode in sampler random; do
  run cubic3d_1000x "$SRC/configs/gamut/cubic3d_void.yaml" $mode 1 "${SHORT3D[@]}" "${TWO[@]}"
done
for mode in sampler random; do
  run cubic3d_void "$SRC/configs/gamut/cubic3d_void.yaml" $mode 1 "${SHORT3D[@]}"
done
machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores"
table="Measured $(date -u +%Y-%m-%d) on $machine, OMP_NUM_THREADS=${OMP_NUM_THREADS:-all}, one MPI rank, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown).
Coverage: fraction of the level-set nodes in the unit cube with Phi <= 0 (the gamut's normalized volume). Smallest E: the softest structure kept (E normalized over 4 decades below the stiff material).

| space | mode | seed | structures | coverage | nu range | smallest E | wall s | structures per hour |
|---|---|---|---|---|---|---|---|---|
${rows}"
python3 "$SRC/tools/replace_bench_section.py" "$DOC" gamut "$table"
echo "bench: table written to $DOC" >&2
