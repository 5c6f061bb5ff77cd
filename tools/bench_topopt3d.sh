#!/bin/bash
# The standard 3D SIMP cantilever with MMA (docs/BENCHMARKS.md, "3D SIMP
# cantilever"): configs/topopt/cantilever3d_simp.yaml, ITER (40) design
# iterations on 64x32x32 and 128x64x64 (h = 1/64, same force per node,
# filter radius 0.08 = 5.12 cells). Prints one Markdown table row per grid:
# seconds per design iteration, CG iterations per solve, peak memory, the
# compliance after 20 and after ITER iterations.
# Usage: tools/bench_topopt3d.sh [build-dir]
#   GRIDS="64" tools/bench_topopt3d.sh build   # the coarse grid only
set -euo pipefail
BIN=${1:-build}/bin
SRC=$(cd "$(dirname "$0")/.." && pwd)
ITER=${ITER:-40}
GRIDS=${GRIDS:-"64 128"}
THREADS=${THREADS:-$(nproc)}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}

# objective after k updates: the log line of evaluation k (logged every 10).
at() { grep -oE "mma iteration +$1: objective [0-9.e+-]+" "$2" | awk '{print $5}'; }
seconds_at() { grep -E "mma iteration +$1: " "$2" | grep -oE "\(([0-9.]+) s\)" | tr -d '(s)' | tr -d ' '; }

echo "| grid | unknowns | solver | s per design iteration | CG iterations per solve | peak MB | compliance after 20 | compliance after $ITER | wall m:ss |"
echo "|---|---|---|---|---|---|---|---|---|"
for n in $GRIDS; do
  case $n in
    64) grid=(); label=64x32x32 ;;
    128) grid=(--set 'grid.size=[128,64,64]' --set grid.cell_size=0.015625 --set filter.radius=5.12); label=128x64x64 ;;
    *) echo "unknown grid $n (64 or 128)" >&2; exit 2 ;;
  esac
  log=$W/$n.log
  /usr/bin/time -v "$BIN/msfab-topopt" --config "$SRC/configs/topopt/cantilever3d_simp.yaml" "${grid[@]}" \
    --set optimizer.max_iterations="$ITER" --set optimizer.change_tolerance=0 --threads "$THREADS" \
    --out "$W/$n.design.h5" >"$log" 2>&1
  unknowns=$(grep -oE "design cells, [0-9]+ unknowns" "$log" | awk '{print $3}')
  solver=$(grep -oE "solves \([a-z-]+\)" "$log" | tr -d '()' | awk '{print $2}')
  t0=$(seconds_at 0 "$log") t1=$(seconds_at "$ITER" "$log")
  per=$(awk -v a="$t0" -v b="$t1" -v k="$ITER" 'BEGIN { printf "%.2f", (b - a) / k }')
  cg=$(grep -oE "CG iterations per solve: [0-9.]+" "$log" | awk '{print $5}')
  peak=$(grep -oE "Maximum resident set size \(kbytes\): [0-9]+" "$log" | awk '{print int($6 / 1024)}')
  wall=$(grep -oE "Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): [0-9:.]+" "$log" | awk '{print $8}')
  printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n" "$label" "$unknowns" "$solver" "$per" "${cg:--}" \
    "$peak" "$(at 20 "$log")" "$(at "$ITER" "$log")" "$wall"
  if [ -n "${KEEP_LOGS:-}" ]; then cp "$log" "$KEEP_LOGS/cantilever3d_$label.log"; fi
done
