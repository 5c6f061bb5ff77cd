#!/bin/bash
# Homogenization speed: seconds per cell and cells per second for random
# two-phase cells (E 1e6 / 1e3, nu 0.45, the gamut issue's contrast) at 2D
# and 3D resolutions, one msfab-homogenize run per size (the stage's own
# /seconds, i.e. without process start-up and file output).
#
#   tools/bench_homogenize.sh BIN OUTDIR BENCHMARKS.md
set -euo pipefail
BIN=$1 OUTDIR=$2 DOC=$3
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUTDIR"
cat > "$OUTDIR/cell.yaml" <<'Y'
materials:
  - {id: 1, name: stiff, model: linear, E: 1.0e6, nu: 0.45}
  - {id: 2, name: soft,  model: linear, E: 1.0e3, nu: 0.45}
cell: {voxels: cell.txt}
Y
rows=""
for dims in "16 16 1" "32 32 1" "64 64 1" "8 8 8" "16 16 16" "32 32 32"; do
  read -r nx ny nz <<<"$dims"
  awk -v nx=$nx -v ny=$ny -v nz=$nz 'BEGIN { srand(7); print nx, ny, nz;
    for (v = 0; v < nx * ny * nz; v++) printf "%d%s", 1 + int(rand() * 2), (v % 32 == 31 ? "\n" : " "); print "" }' \
    > "$OUTDIR/cell.txt"
  echo "bench: homogenize ${nx}x${ny}x${nz} ..." >&2
  "$BIN/msfab-homogenize" --config "$OUTDIR/cell.yaml" --out "$OUTDIR/cell.h5" --quiet > /dev/null
  s=$(h5dump -a /seconds "$OUTDIR/cell.h5" | sed -n 's/^ *(0): *//p')
  u=$(h5dump -a /unknowns "$OUTDIR/cell.h5" | sed -n 's/^ *(0): *//p')
  rows+=$(awk -v d="${nx}x${ny}x${nz}" -v u="$u" -v s="$s" 'BEGIN { printf "| %s | %d | %.4f | %.3g |\n", d, u, s, 1 / s }')
  rows+=$'\n'
done
machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores"
table="Measured $(date -u +%Y-%m-%d) on $machine, OMP_NUM_THREADS=${OMP_NUM_THREADS:-all}, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown).

| cell | unknowns | seconds per cell | cells per second |
|---|---|---|---|
${rows}"
python3 "$SRC/tools/replace_bench_section.py" "$DOC" homogenize "$table"
echo "bench: table written to $DOC" >&2
