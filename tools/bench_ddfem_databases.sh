#!/bin/bash
# DDFEM databases side by side at one level: for every scene, the error
# against the fine run (§2.5.2) of trilinear naive coarsening and of each
# database, in brackets over naive (the baseline of issue bars: a third at
# level 1, a half at level 2), and each database's Newton seconds. Used to
# measure sampling and fit settings against each other on identical scenes
# and references (docs/ddfem.md, "The thesis's settings").
#
#   tools/bench_ddfem_databases.sh BIN OUTDIR BENCHMARKS.md LABEL=DATABASE [LABEL=DATABASE ...]
# A column may instead give msfab-simulate's coarsening arguments itself,
# LABEL="--coarse-material matched --coarse-element enhanced" (value starting
# with --; COARSE_ARGS is not added to it).
# Env: LEVEL (1), SCENES (the Table 2.2 and mixed-block scenes), BENCH_SECTION
# (ddfem-databases), COARSE_ARGS (extra msfab-simulate arguments for the
# coarse runs, e.g. "--coarse-fallback galerkin"), BENCH_TIMES (1; 0 leaves the
# seconds out, for runs measured beside other work).
set -euo pipefail
BIN=$1 OUTDIR=$2 DOC=$3
shift 3
[ $# -gt 0 ] || { echo "bench: give at least one LABEL=DATABASE" >&2; exit 2; }
LABELS=() DBS=()
for spec in "$@"; do
  label=${spec%%=*} db=${spec#*=}
  [ "$label" != "$spec" ] && [ -n "$label" ] || { echo "bench: '$spec' is not LABEL=DATABASE" >&2; exit 2; }
  [ "${db#--}" != "$db" ] || [ -f "$db" ] || { echo "bench: no database $db (for $label)" >&2; exit 2; }
  LABELS+=("$label") DBS+=("$db")
done
LEVEL=${LEVEL:-1}
read -r -a SCENE_LIST <<< "${SCENES:-layers1 checker random3 sole fibers skeleton holes3 pushing bending bending_uniform twisting buckling bridge bridge_arch}"
read -r -a EXTRA <<< "${COARSE_ARGS:-}"
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUTDIR"
source "$SRC/tools/simulate_bench_lib.sh"

header="| scene | naive |" rule="|---|---|" theader="| scene | fine | naive |" trule="|---|---|---|"
for l in "${LABELS[@]}"; do header+=" $l |" rule+="---|" theader+=" $l |" trule+="---|"; done
rows="" times=""
for scene in "${SCENE_LIST[@]}"; do
  cfg="$SRC/configs/scenes/$scene.yaml"
  fine="$OUTDIR/$scene-L0.h5"
  echo "bench: $scene fine ..." >&2
  [ -f "$fine" ] || run "$fine" --config "$cfg" || continue
  fine_seconds=$(attr "$fine" /timings newton_total)
  naive_out="$OUTDIR/$scene-L$LEVEL-naive.h5"
  naive=failed naive_t=""
  run "$naive_out" --config "$cfg" --coarsen "$LEVEL" --reference "$fine" --coarse-material naive &&
    naive=$(attr "$naive_out" /coarsening error_vs_fine) && naive_t=$(attr "$naive_out" /timings newton_total)
  row="| $scene | $(awk -v n="$naive" 'BEGIN { if (n == "failed") print n; else printf "%.2e", n }') |"
  time_row="| $scene | $(printf %.3f "$fine_seconds") | ${naive_t:-—} |"
  for i in "${!LABELS[@]}"; do
    out="$OUTDIR/$scene-L$LEVEL-${LABELS[$i]}.h5"
    echo "bench: $scene level $LEVEL ${LABELS[$i]} ..." >&2
    e=failed t=""
    if [ "${DBS[$i]#--}" != "${DBS[$i]}" ]; then read -r -a column_args <<< "${DBS[$i]}"
    else column_args=(--database "${DBS[$i]}" "${EXTRA[@]}"); fi
    run "$out" --config "$cfg" --coarsen "$LEVEL" --reference "$fine" "${column_args[@]}" &&
      e=$(attr "$out" /coarsening error_vs_fine) && t=$(attr "$out" /timings newton_total)
    row+=$(awk -v e="$e" -v n="$naive" 'BEGIN { if (e == "failed") printf " failed |"; else if (n == "failed") printf " %.2e |", e;
                                                 else printf " %.2e (%.2f) |", e, e / n }')
    time_row+=$(awk -v t="$t" -v f="$fine_seconds" 'BEGIN { if (t == "") printf " — |"; else printf " %.3f (%.1f×) |", t, f / t }')
  done
  rows+="$row"$'\n' times+="$time_row"$'\n'
done

machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores"
legend=""
for i in "${!LABELS[@]}"; do
  if [ "${DBS[$i]#--}" != "${DBS[$i]}" ]; then legend+="${LABELS[$i]}: ${DBS[$i]}; "
  else legend+="${LABELS[$i]}: $(basename "${DBS[$i]}"); "; fi
done
table="Measured $(date -u +%Y-%m-%d) on $machine, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown), level $LEVEL${COARSE_ARGS:+, coarse runs with $COARSE_ARGS}. Databases: ${legend%; }. Error against the fine run; in brackets, over trilinear naive coarsening's.

$header
$rule
${rows}"
[ "${BENCH_TIMES:-1}" = 0 ] || table+="
Newton seconds of the same runs (in brackets the speedup over the fine solve):

$theader
$trule
${times}"
python3 "$SRC/tools/replace_bench_section.py" "$DOC" "${BENCH_SECTION:-ddfem-databases}" "$table"
echo "bench: table written to $DOC" >&2
