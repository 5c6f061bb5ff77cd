#!/bin/bash
# DDFEM in dynamics (thesis §2.5.2; docs/ddfem.md, "Coarsening in
# dynamics"): configs/dynamics/fiber_bar.yaml run fine once, then coarsened
# at levels 1 and 2 with naive materials and with each database given,
# every coarse run compared with that fine run frame by frame (msfab-dynamics
# --reference). Prints a markdown table. Runs one after another, THREADS
# threads each (default 2).
#
#   tools/bench_ddfem_dynamics.sh build/bin out/bench/ddfem_dynamics \
#     L1:isolated=out/ddfem/palette3.coarse_db.h5 L2:isolated=out/ddfem/palette3.level2.k400.coarse_db.h5 ...
#   REUSE_FINE=1 tools/bench_ddfem_dynamics.sh ...   # keep fine.h5 of an earlier run (same binary and scene)
#   SCENE=path.yaml SCENE_SET="key=value;key=value" tools/bench_ddfem_dynamics.sh ...   # another scene or layout
set -euo pipefail
START=$PWD
BIN=$(cd "${1:-build/bin}" && pwd)
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "${2:-out/bench/ddfem_dynamics}"
cd "${2:-out/bench/ddfem_dynamics}"
shift 2 || true
export OMP_NUM_THREADS=${THREADS:-2} OPENBLAS_NUM_THREADS=1
SCENE=${SCENE:-$SRC/configs/dynamics/fiber_bar.yaml}
SETS=()
if [ -n "${SCENE_SET:-}" ]; then
  IFS=';' read -ra assignments <<< "$SCENE_SET"
  for kv in "${assignments[@]}"; do SETS+=(--set "$kv"); done
fi

per_step() { sed -n 's/.*(\([0-9.]*\) Newton iterations, \([0-9.]*\) ms each).*/\2/p' "$1"; }
its() { sed -n 's/.*(\([0-9.]*\) Newton iterations, \([0-9.]*\) ms each).*/\1/p' "$1"; }
dofs() { sed -n "s/.*elements, \([0-9]*\) DOFs.*/\1/p" "$1"; }
field() {  # field LOG WORD: the number after WORD on the "vs fine" line
  awk -v w="$2" '/vs fine/ { for (i = 1; i <= NF; ++i) if ($i == w) { v = $(i + 1); gsub(/,/, "", v); print v } }' "$1"
}

if [ "${REUSE_FINE:-0}" != 1 ] || [ ! -s fine.h5 ] || [ ! -s fine.txt ]; then
  "$BIN/msfab-dynamics" --config "$SCENE" "${SETS[@]}" --quiet --out fine.h5 > fine.txt
fi
echo "Scene ${SCENE#$SRC/}${SCENE_SET:+ with $SCENE_SET}, $OMP_NUM_THREADS threads, revision $(git -C "$SRC" rev-parse --short HEAD)."
echo
echo "| model | level | DOFs | error at release | max error | error at the end | centre of mass apart (mm) | ms per step | Newton its per step | speedup |"
echo "|---|---|---|---|---|---|---|---|---|---|"
echo "| fine | 0 | $(dofs fine.txt) | — | — | — | — | $(per_step fine.txt) | $(its fine.txt) | 1.0 |"
run() {  # run LABEL LEVEL ARGS...
  local label=$1 level=$2 file=run_${1// /_}_$2
  local log=$file.txt
  shift 2
  if ! "$BIN/msfab-dynamics" --config "$SCENE" "${SETS[@]}" --quiet --coarsen "$level" "$@" --reference fine.h5 \
    --out "$file.h5" > "$log" 2> "$file.err"; then
    echo "| $label | $level | $(dofs "$log") | failed: $(sed -n 's/^msfab-dynamics: error: //p' "$file.err" | head -1) |||||||"
    return
  fi
  local com speed
  com=$(awk '/centre of mass apart by up to/ { for (i = 1; i <= NF; ++i) if ($i == "to") printf "%.2f", 1e3 * $(i + 1) }' "$log")
  speed=$(sed -n 's/.*: \([0-9.]*\)x faster.*/\1/p' "$log")
  echo "| $label | $level | $(dofs "$log") | $(field "$log" release) | $(field "$log" max) | $(field "$log" end) | $com | $(per_step "$log") | $(its "$log") | $speed |"
}
for level in 1 2; do
  run naive $level --coarse-material naive
  for spec in "$@"; do
    case $spec in
      L$level:*)
        name=${spec#L$level:} db=${spec#*=}
        case $db in /*) ;; *) db=$START/$db ;; esac
        run "DDFEM ${name%%=*}" $level --database "$db" ;;
    esac
  done
done
