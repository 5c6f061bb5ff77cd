#!/bin/bash
# Adaptive coarsening (msfab-simulate --target-error; docs/ddfem.md,
# "Adaptive coarsening"): speed against error per scene. Every scene is solved
# fine once; the uniform level-2 model and the adaptive model at each target
# are compared with that fine result (--reference), so one row's numbers come
# from one run of this script.
#
#   tools/bench_adaptive.sh BIN OUTDIR BENCHMARKS.md DATABASE2 [scene ...]
# DATABASE2: a level-2 coarse_db of the scenes' palette (E = 1e5, 1e6, 1e7,
# nu = 0.45); DATABASE1 (environment, optional) a level-1 one for the uniform
# level-1 rows. Naive coarsening at both levels is measured too. TARGETS (environment) lists the target errors (default
# "0.02 0.01 0.005 0.002"); COARSE_ARGS, extra msfab-simulate arguments of
# the database runs (e.g. "--coarse-fallback galerkin"); ADAPTIVE_ARGS, extra
# arguments of the adaptive runs only (e.g. "--level1-database DB"); PYTHON, a python3
# with matplotlib (Debian python3-matplotlib). Writes the section
# bench:$BENCH_SECTION (default ddfem-adaptive) of BENCHMARKS.md,
# OUTDIR/adaptive.csv and docs/images/$BENCH_SECTION.png.
set -euo pipefail
BIN=$1 OUTDIR=$2 DOC=$3 DB2=$4
shift 4
SCENES=("$@")
[ ${#SCENES[@]} -gt 0 ] || SCENES=(bending twisting pushing layers1 checker random3 sole bridge_arch skeleton holes3)
read -r -a TARGET_LIST <<< "${TARGETS:-0.02 0.01 0.005 0.002}"
read -r -a COARSE_ARG_LIST <<< "${COARSE_ARGS:-}"
read -r -a ADAPTIVE_ARG_LIST <<< "${ADAPTIVE_ARGS:-}"
SECTION=${BENCH_SECTION:-ddfem-adaptive}
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUTDIR"

source "$SRC/tools/simulate_bench_lib.sh"
levels() {  # "fine/L1/L2" element counts of an adaptive result
  h5dump -a /coarsening/elements_per_level "$1" | sed -n 's/^ *(0): *//p' | head -n1 | tr -d ' ' | tr ',' '/'
}
# Seconds after the fine mesh: coarsening, the uniform solves the estimate
# comes from, mixed solves the a-posteriori check rejected, and the Newton
# solve of the model itself.
coarse_seconds() {
  local f=$1 extra=0
  [ "$(h5dump -a /coarsening/adaptive "$f" 2>/dev/null | sed -n 's/^ *(0): *//p')" = 1 ] &&
    extra=$(awk -v u="$(attr "$f" /coarsening uniform_solve_seconds)" \
      -v r="$(attr "$f" /coarsening rejected_solve_seconds)" 'BEGIN { print u + r }')
  awk -v a="$(attr "$f" /timings newton_total)" -v b="$(attr "$f" /coarsening seconds)" -v c="$extra" \
    'BEGIN { printf "%.4f", a + b + c }'
}

# One uniform coarse model of the current scene: a table row and a CSV line.
uniform() {  # uniform NAME LABEL ARGS...
  local name=$1 label=$2 f="$OUTDIR/$scene-$1.h5"
  shift 2
  echo "bench: $scene $label ..." >&2
  run "$f" --config "$cfg" --reference "$fine" "$@" || return 0
  local e t levels
  e=$(attr "$f" /coarsening error_vs_fine) t=$(coarse_seconds "$f")
  levels="0/0/$(attr "$f" / elements)"
  [ "$(attr "$f" /coarsening level)" = 1 ] && levels="0/$(attr "$f" / elements)/0"
  rows+=$(awk -v s="$scene" -v m="$label" -v e="$e" -v t="$t" -v tf="$tf" -v l="$levels" -v nf="$nf" \
    'BEGIN { printf "| %s | %s | — | — | — | %.2e | — | %s of %d | %.3f | %.3f | %.1f |", s, m, e, l, nf, t, tf, tf / t }')$'\n'
  csv+="$scene,$name,,,$e,$t,$tf"$'\n'
}
rows="" csv="scene,model,target,predicted,error,seconds,fine_seconds"$'\n'
for scene in "${SCENES[@]}"; do
  cfg="$SRC/configs/scenes/$scene.yaml"
  fine="$OUTDIR/$scene-L0.h5"
  echo "bench: $scene fine ..." >&2
  [ -f "$fine" ] || run "$fine" --config "$cfg" || continue
  tf=$(attr "$fine" /timings newton_total)
  nf=$(attr "$fine" / elements)
  uniform naive2 "naive level 2" --coarsen 2 --coarse-material naive
  uniform level2 "level 2" --coarsen 2 --database "$DB2" "${COARSE_ARG_LIST[@]}"
  if [ -n "${DATABASE1:-}" ]; then
    uniform naive1 "naive level 1" --coarsen 1 --coarse-material naive
    uniform level1 "level 1" --coarsen 1 --database "$DATABASE1" "${COARSE_ARG_LIST[@]}"
  fi
  for target in "${TARGET_LIST[@]}"; do
    echo "bench: $scene adaptive $target ..." >&2
    f="$OUTDIR/$scene-A$target.h5"
    run "$f" --config "$cfg" --target-error "$target" --database "$DB2" "${COARSE_ARG_LIST[@]}" "${ADAPTIVE_ARG_LIST[@]}" --reference "$fine" ||
      continue
    e=$(attr "$f" /coarsening error_vs_fine) p=$(attr "$f" /coarsening predicted_error) t=$(coarse_seconds "$f")
    a=$(attr "$f" /coarsening a_posteriori_error) n=$(attr "$f" /coarsening adaptive_solves)
    rows+=$(awk -v s="$scene" -v g="$target" -v p="$p" -v a="$a" -v n="$n" -v e="$e" -v t="$t" -v tf="$tf" \
      -v l="$(levels "$f")" -v nf="$nf" 'BEGIN { printf "| %s | adaptive | %g | %.2e | %.2e (%d) | %.2e | %s | %s of %d | %.3f | %.3f | %.1f |",
        s, g, p, a, n, e, (e <= g ? "yes" : "**no**"), l, nf, t, tf, tf / t }')$'\n'
    csv+="$scene,adaptive,$target,$p,$e,$t,$tf"$'\n'
  done
done
printf "%s" "$csv" > "$OUTDIR/adaptive.csv"
"${PYTHON:-python3}" "$SRC/tools/plot_adaptive.py" "$OUTDIR/adaptive.csv" "$SRC/docs/images/$SECTION.png" ||
  echo "bench: no plot (python3 with matplotlib needed)" >&2

machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB"
table="Measured $(date -u +%Y-%m-%d) on $machine, OMP_NUM_THREADS=${OMP_NUM_THREADS:-all}, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown), databases $(basename "$DB2")${DATABASE1:+ (level 2) and $(basename "$DATABASE1") (level 1)}${COARSE_ARGS:+, database runs with $COARSE_ARGS}${ADAPTIVE_ARGS:+, adaptive runs with $(echo "$ADAPTIVE_ARGS" | sed 's|[^ ]*/||g')}.

| scene | model | target | predicted | a-posteriori (solves) | error | met | elements fine/L1/L2 | s | fine s | speedup |
|---|---|---|---|---|---|---|---|---|---|---|
${rows}
\"predicted\": the a-priori estimate of the levels kept; \"a-posteriori\": the kept solution's a-posteriori estimate
(its distance from the extrapolated fine one, or with --posterior-estimate newton the size of one fine Newton step
from it), with the number of mixed solves (with --posterior-check a miss solves again, finer, at most 3).
Seconds after the fine mesh is built: coarsening, for adaptive runs the uniform level-2 and level-1 solves the
estimate comes from, the Newton estimate and rejected mixed solves, and Newton on the model; \"fine s\" is the fine model's Newton time in the same run.

![adaptive speed against error](images/$SECTION.png)"
python3 "$SRC/tools/replace_bench_section.py" "$DOC" "$SECTION" "$table"
echo "bench: table written to $DOC" >&2
