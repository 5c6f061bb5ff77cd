#!/bin/bash
# Coarse models on blocks where materials (and void) mix: for every scene
# and level, the error against the fine run (§2.5.2) of naive coarsening on
# the trilinear and the enhanced element, the Galerkin element (each fine
# voxel integrated over the coarse field, void empty) on both, and DDFEM
# with its database's element, its blocks without a fit coarsened naively
# (as the other tables) or by the Galerkin element (--coarse-fallback).
# Ratios are to trilinear naive coarsening, the baseline of the issue's bars
# (a third at level 1, a half at level 2). docs/ddfem.md, "Galerkin element".
#
#   tools/bench_ddfem_mixed.sh BIN OUTDIR BENCHMARKS.md DATABASE1 [DATABASE2|-] [scene ...]
# DATABASE2 "-" leaves DDFEM out at level 2 (LEVELS=1 leaves level 2 out). Writes the section
# `ddfem-mixed` of BENCHMARKS.md (BENCH_SECTION overrides): errors, then the
# Newton seconds of the same runs against the fine solve's.
set -euo pipefail
BIN=$1 OUTDIR=$2 DOC=$3 DB1=$4 DB2=${5:--}
shift $(( $# < 5 ? $# : 5 ))
SCENES=("$@")
[ ${#SCENES[@]} -gt 0 ] || SCENES=(layers1 checker random3 sole fibers skeleton holes3 pushing bending bending_uniform twisting buckling bridge bridge_arch)
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUTDIR"
LEVELS=${LEVELS:-1 2}
for f in "$DB1" "$DB2"; do
  [ "$f" = - ] || [ -f "$f" ] || { echo "bench: no database $f" >&2; exit 2; }
done
source "$SRC/tools/simulate_bench_lib.sh"

MODELS=(naive naive-enhanced galerkin galerkin-enhanced ddfem ddfem-galerkin)
rows="" times=""
for scene in "${SCENES[@]}"; do
  cfg="$SRC/configs/scenes/$scene.yaml"
  fine="$OUTDIR/$scene-L0.h5"
  echo "bench: $scene fine ..." >&2
  run "$fine" --config "$cfg" || continue
  fine_seconds=$(attr "$fine" /timings newton_total)
  for level in $LEVELS; do
    db=$DB1
    [ "$level" = 2 ] && db=$DB2
    row="| $scene | $level |"
    time_row="| $scene | $level | $(printf %.3f "$fine_seconds") |"
    naive=""
    for m in "${MODELS[@]}"; do
      out="$OUTDIR/$scene-L$level-$m.h5"
      echo "bench: $scene level $level $m ..." >&2
      args=(--coarsen "$level" --reference "$fine")
      case $m in
        naive) args+=(--coarse-material naive) ;;
        naive-enhanced) args+=(--coarse-material naive --coarse-element enhanced) ;;
        galerkin) args+=(--coarse-material galerkin) ;;
        galerkin-enhanced) args+=(--coarse-material galerkin --coarse-element enhanced) ;;
        ddfem) args+=(--database "$db") ;;
        ddfem-galerkin) args+=(--database "$db" --coarse-fallback galerkin) ;;
      esac
      e=failed
      if [ "$db" = - ] && [ "${m#ddfem}" != "$m" ]; then
        row+=" — |" time_row+=" — |"
        continue
      fi
      t=""
      run "$out" --config "$cfg" "${args[@]}" && e=$(attr "$out" /coarsening error_vs_fine) && t=$(attr "$out" /timings newton_total)
      time_row+=$(awk -v t="$t" -v f="$fine_seconds" 'BEGIN { if (t == "") printf " — |"; else printf " %.3f (%.1f×) |", t, f / t }')
      [ "$m" = naive ] && naive=$e
      row+=$(awk -v e="$e" -v n="$naive" 'BEGIN { if (e == "failed") printf " failed |"; else if (n == "failed" || n == "") printf " %.2e |", e;
                                                    else printf " %.2e (%.2f) |", e, e / n }')
    done
    rows+="$row"$'\n' times+="$time_row"$'\n'
  done
done

machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores"
table="Measured $(date -u +%Y-%m-%d) on $machine, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown), databases $(basename "$DB1") (level 1)$([ "$DB2" = - ] || echo " and $(basename "$DB2") (level 2)"). In brackets: the error over trilinear naive coarsening's.

| scene | level | naive | naive, enhanced | Galerkin | Galerkin, enhanced | DDFEM | DDFEM, Galerkin fallback |
|---|---|---|---|---|---|---|---|
${rows}
Newton seconds of the same runs (2 threads; in brackets the speedup over the fine solve):

| scene | level | fine | naive | naive, enhanced | Galerkin | Galerkin, enhanced | DDFEM | DDFEM, Galerkin fallback |
|---|---|---|---|---|---|---|---|---|
${times}"
python3 "$SRC/tools/replace_bench_section.py" "$DOC" "${BENCH_SECTION:-ddfem-mixed}" "$table"
echo "bench: table written to $DOC" >&2
