#!/bin/bash
# How far each coarse model is from the best its coarse mesh allows.
# For every scene and level: the error of naive, homogenized and DDFEM
# coarsening against the fine run (§2.5.2), and the floor, the smallest
# error any displacement field on the coarse mesh has (the best trilinear
# fit of the fine displacements, with its dual certificate; docs/ddfem.md,
# "Error floor"). "Room used" is (naive - DDFEM) / (naive - floor): 1 means
# DDFEM reached what the mesh allows, 0 that it did no better than naive.
# The last two columns repeat naive and homogenized coarsening with the
# enhanced coarse element (--coarse-element enhanced: condensed bubble
# modes, no bending locking). DDFEM uses the element its database was
# fitted for (fit.element).
#
#   tools/bench_ddfem_floor.sh BIN OUTDIR BENCHMARKS.md DATABASE1 DATABASE2 [scene ...]
# DATABASE1/2: level-1 and level-2 coarse_db of the scenes' palette
# (DATABASE2 may be "-" with LEVELS=1). The section `ddfem-floor` of
# BENCHMARKS.md is written (BENCH_SECTION overrides); LEVELS="1" runs level 1
# only (default "1 2").
set -euo pipefail
BIN=$1 OUTDIR=$2 DOC=$3 DB1=$4 DB2=$5
shift 5
SCENES=("$@")
[ ${#SCENES[@]} -gt 0 ] || SCENES=(layers1 checker random3 sole fibers skeleton holes3 pushing bending bending_uniform twisting buckling bridge bridge_arch)
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUTDIR"
LEVELS=${LEVELS:-1 2}
for level in $LEVELS; do
  f=$DB1
  [ "$level" = 2 ] && f=$DB2
  [ -f "$f" ] || { echo "bench: no database $f" >&2; exit 2; }
done
source "$SRC/tools/simulate_bench_lib.sh"

rows=""
for scene in "${SCENES[@]}"; do
  cfg="$SRC/configs/scenes/$scene.yaml"
  fine="$OUTDIR/$scene-L0.h5"
  echo "bench: $scene fine ..." >&2
  run "$fine" --config "$cfg" || continue
  for level in $LEVELS; do
    db=$DB1
    [ "$level" = 2 ] && db=$DB2
    declare -A err=()
    floor="" lower=""
    for m in naive homogenized ddfem naive-enhanced homogenized-enhanced; do
      out="$OUTDIR/$scene-L$level-$m.h5"
      echo "bench: $scene level $level $m ..." >&2
      # DDFEM uses the element its database was fitted for.
      element=(--coarse-element "$([ "$m" = "${m%-enhanced}" ] && echo trilinear || echo enhanced)")
      [ "$m" = ddfem ] && element=()
      if run "$out" --config "$cfg" --coarsen "$level" --coarse-material "${m%-enhanced}" ${db:+--database "$db"} \
        "${element[@]}" --reference "$fine"; then
        err[$m]=$(attr "$out" /coarsening error_vs_fine)
        floor=$(attr "$out" /coarsening error_floor) lower=$(attr "$out" /coarsening error_floor_lower_bound)
      else
        err[$m]=nan
      fi
    done
    rows+=$(awk -v s="$scene" -v L="$level" -v f="$floor" -v lo="$lower" -v n="${err[naive]}" -v h="${err[homogenized]}" \
      -v d="${err[ddfem]}" -v ne="${err[naive-enhanced]}" -v he="${err[homogenized-enhanced]}" \
      'function e(x) { return x == "nan" || x == "" ? "failed" : sprintf("%.2e", x) }
      BEGIN { used = (n != "nan" && d != "nan" && f != "") ? sprintf("%.2f", (n - d) / (n - f)) : "—"
              printf "| %s | %s | %s (≥ %s) | %.2f | %s | %s | %s | %s | %s | %s | %s |\n", s, L, e(f), e(lo), f / n, e(n), e(h), e(d),
                     d == "nan" ? "—" : sprintf("%.2f", d / n), used, e(ne), e(he) }')
    rows+=$'\n'
    unset err
  done
done

machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores"
table="Measured $(date -u +%Y-%m-%d) on $machine, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown), databases $(basename "$DB1") (level 1)$([ "$LEVELS" = 1 ] || echo " and $(basename "$DB2") (level 2)").

| scene | level | floor (certified ≥) | floor / naive | naive | homogenized | DDFEM | DDFEM / naive | room used | naive, enhanced element | homogenized, enhanced element |
|---|---|---|---|---|---|---|---|---|---|---|
${rows}"
python3 "$SRC/tools/replace_bench_section.py" "$DOC" "${BENCH_SECTION:-ddfem-floor}" "$table"
echo "bench: table written to $DOC" >&2
