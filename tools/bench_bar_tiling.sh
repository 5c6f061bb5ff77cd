#!/bin/bash
# The Table 3.1 bar against tiling: the same design mapped with t^3 copies
# of each cell's structure (msfab-map --set tiling=t, t = 1, 2, 3) and
# checked under configs/topopt/bar_check_loads.yaml (the bar's stretch,
# bend and line-load twist, and the twist as end-face tractions) against
# its homogenized model with one and with 4^3 hexahedra per cell. A
# difference that falls with t is the boundary layer of cells cut open at
# the bar's surface; one that stays is the homogenized model's own.
#
#   bash tools/bench_bar_tiling.sh BIN OUT DESIGN STRUCTURES [SEED]
#
# DESIGN, STRUCTURES: the bar's design and microstructures artifacts (e.g.
# out/topopt/bar.design.h5, out/topopt/bar.structures.h5); the mapping
# takes msfab-map's defaults and SEED (default 1). TILES (default "1 2 3")
# shortens a trial run. Prints a Markdown table on stdout.
set -euo pipefail
BIN=${1:?BIN}; OUT=${2:?OUT}; DESIGN=${3:?DESIGN}; SET=${4:?STRUCTURES}; SEED=${5:-1}
SRC=$(cd "$(dirname "$0")/.." && pwd)
SCENE="$SRC/configs/topopt/bar_check_loads.yaml"
mkdir -p "$OUT"
cases() {  # the "case: displacement x%, energy y%" pairs of a verify line as "x / y" cells
  grep -oE "(stretch|bend|twist|twist_face): displacement [0-9.]+%, energy [0-9.]+%" <<<"$1" |
    sed -E 's/.*displacement ([0-9.]+)%, energy ([0-9.]+)%/\1 \/ \2/' | paste -sd'|' - | sed 's/|/ | /g'
}
echo "| tiling t | voxels | homogenized model | stretch | bend | twist (edge line loads) | twist (face tractions) | check s |"
echo "|---|---|---|---|---|---|---|---|"
for t in ${TILES:-1 2 3}; do
  mapped="$OUT/bar.t$t.mapped.h5"
  "$BIN/msfab-map" --design "$DESIGN" --structures "$SET" --seed "$SEED" --set tiling="$t" --out "$mapped" \
    > "$OUT/bar.t$t.map.log" 2>&1
  for m in 1 4; do
    start=$(date +%s.%N)
    line=$("$BIN/msfab-verify-map" --design "$DESIGN" --mapped "$mapped" --structures "$SET" --scene "$SCENE" \
      --set homogenized_elements=$m --out "$OUT/bar.t$t.m$m.verify.h5" 2> "$OUT/bar.t$t.m$m.verify.log" |
      grep '^msfab-verify-map:')
    end=$(date +%s.%N)
    voxels=$(grep -oE "[0-9]+ voxels" <<<"$line" | head -1 | grep -oE "[0-9]+")
    label="one hexahedron per cell"
    [ "$m" = 4 ] && label="4³ hexahedra per cell"
    printf '| %d | %s | %s | %s | %.1f |\n' "$t" "$voxels" "$label" "$(cases "$line")" "$(echo "$end - $start" | bc)"
  done
done
