#!/bin/bash
# Static-solver benchmark: runs scenes with msfab-simulate and writes a table
# (DOFs, Newton iterations, time per iteration split into assembly / solve /
# line search, peak memory) between markers in docs/BENCHMARKS.md.
#
#   tools/bench_static.sh BIN OUTDIR BENCHMARKS.md [scene:solver ...]
# Default runs: fibers with pcg-mg, bending and pushing with cholmod and pcg-mg.
set -euo pipefail
BIN=$1 OUTDIR=$2 DOC=$3
shift 3
RUNS=("$@")
[ ${#RUNS[@]} -gt 0 ] || RUNS=(pushing:cholmod pushing:pcg-mg bending:cholmod bending:pcg-mg fibers:pcg-mg)
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUTDIR"

attr() {  # attr FILE OBJECT NAME -> value
  h5dump -a "$2/$3" "$1" | sed -n 's/^ *(0): *//p' | head -n1
}

rows=""
for run in "${RUNS[@]}"; do
  scene=${run%%:*} solver=${run#*:}
  out="$OUTDIR/$scene-$solver.h5"
  echo "bench: $scene with $solver ..." >&2
  /usr/bin/time -v "$BIN/msfab-simulate" --config "$SRC/configs/scenes/$scene.yaml" --out "$out" \
      --set solver.linear_solver="$solver" --log-level warn > "$OUTDIR/$scene-$solver.log" 2> "$OUTDIR/$scene-$solver.time"
  rss_kb=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$OUTDIR/$scene-$solver.time")
  its=$(attr "$out" /newton iterations)
  dofs=$(attr "$out" / dofs)
  asm=$(attr "$out" /timings assembly) sol=$(attr "$out" /timings solve) ls=$(attr "$out" /timings line_search)
  tot=$(attr "$out" /timings newton_total)
  rows+=$(awk -v s="$scene" -v v="$solver" -v d="$dofs" -v i="$its" -v a="$asm" -v b="$sol" -v l="$ls" -v t="$tot" -v m="$rss_kb" \
    'BEGIN { printf "| %s | %s | %d | %d | %.3f | %.3f | %.3f | %.3f | %.1f | %.0f |\n", s, v, d, i, a/i, b/i, l/i, t/i, t, m/1024 }')
  rows+=$'\n'
done

machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB"
table="Measured $(date -u +%Y-%m-%d) on $machine, OMP_NUM_THREADS=${OMP_NUM_THREADS:-all}, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown).

| scene | linear solver | DOFs | Newton its | assembly s/it | solve s/it | line search s/it | total s/it | total s | peak MiB |
|---|---|---|---|---|---|---|---|---|---|
$rows"
begin='<!-- bench:static:begin -->' end='<!-- bench:static:end -->'
if ! grep -q "$begin" "$DOC" 2>/dev/null; then printf '\n%s\n%s\n' "$begin" "$end" >> "$DOC"; fi
awk -v b="$begin" -v e="$end" -v t="$table" '
  $0 == b { print; print t; skip = 1; next }
  $0 == e { skip = 0 }
  !skip { print }' "$DOC" > "$DOC.tmp" && mv "$DOC.tmp" "$DOC"
echo "$table"
