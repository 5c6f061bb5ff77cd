#!/bin/bash
# Gamut sampling against random sampling (thesis §3.2): the same material
# space, seed and level-set settings; the sampler's discrete + continuous
# cycles against fresh random-beam structures with at least the same number
# of homogenizations per cycle. Reports structures, coverage of the unit
# cube (level-set volume), the property ranges reached and wall time, for
# several seeds.
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
    --set plot_every_cycle=false --seed "$seed" --out "$OUTDIR/$name.$mode.$seed.gamut.h5" "$@" > "$log" 2>&1
  local n cov nu E wall
  n=$(sed -n 's/.*: [a-z0-9]*, \([0-9]*\) structures.*/\1/p' "$log")
  cov=$(sed -n 's/^  coverage \([0-9.]*\).*/\1/p' "$log")
  nu=$(sed -n 's/^  range nu[_xy]*: \[\(.*\)\]/\1/p' "$log")
  E=$(sed -n 's/^  range Ex*: \[\([^,]*\),.*/\1/p' "$log")
  wall=$(cat "$OUTDIR/time")
  rows+="| $name | $mode | $seed | $n | $cov | [$nu] | $E | $wall |"$'\n'
}
for seed in $SEEDS; do
  for mode in sampler random; do run cubic2d "$SRC/configs/gamut/cubic2d.yaml" $mode $seed; done
done
# 3D, one material and void: a short run at 12^3 (the full 16^3 gamut is `make gamut-3d`).
for mode in sampler random; do
  run cubic3d_void_12 "$SRC/configs/gamut/cubic3d_void.yaml" $mode 1 --set resolution=12 --set population=24 \
    --set cycles=6 --set continuous.per_cycle=2 --set continuous.max_iterations=15
done
machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores"
table="Measured $(date -u +%Y-%m-%d) on $machine, OMP_NUM_THREADS=${OMP_NUM_THREADS:-all}, one MPI rank, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown).
Coverage: fraction of the level-set nodes in the unit cube with Phi <= 0 (the gamut's normalized volume). Smallest E: the softest structure kept (E normalized over 4 decades below the stiff material).

| space | mode | seed | structures | coverage | nu range | smallest E | wall s |
|---|---|---|---|---|---|---|---|
${rows}"
python3 "$SRC/tools/replace_bench_section.py" "$DOC" gamut "$table"
echo "bench: table written to $DOC" >&2
