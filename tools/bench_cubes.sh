#!/bin/bash
# The cubes of thesis Table 3.1 and the tiling study of Fig. 3-23: how far
# a full-resolution object departs from its homogenized model when nothing
# was optimized, so that only the homogenization's own error remains.
#
#   bash tools/bench_cubes.sh BIN OUT SET [STRUCTURES...]
#
# BIN: the stage binaries; OUT: a scratch folder; SET: a cubic3d
# msfab.microstructures artifact; STRUCTURES: indices to tile (default:
# the structures nearest to densities 0.2, 0.35 and 0.5, picked with
# PYTHON, default /usr/bin/python3 with h5py and numpy).
#
# 1. Tiling: the unit cube (configs/assign/cube.yaml: bottom clamped, top
#    pressed and sheared) as n^3 copies of one structure, n = 1, 2, 4, 8,
#    against its homogenized model meshed with 16 hexahedra per cube edge
#    (homogenized_elements = 16 / n, the same converged reference for every
#    n) and with one hexahedron per cell (the thesis's comparison).
# 2. Patterns at n = 4: layers of the tiled structure and its nearest
#    neighbour in the set along z and along x, and a random assignment over
#    it and its three nearest neighbours, mapped back as assigned, with the
#    half-shifted exemplars chosen by the mismatch descent, and as targets
#    mapped with msfab-map's defaults (16 candidates per cell, half shifts,
#    several starts, the void-pair cost), so each cell gets a structure
#    near its target that fits its neighbours. The property gap column
#    says how far those structures are from the assigned ones.
# TILES (default "1 2 4 8", each dividing 16) and PATTERN_N (4) shorten a
# trial run; TILING_STUDY=0 runs the patterns only. Prints a Markdown table on stdout.
set -euo pipefail
BIN=${1:?BIN}; OUT=${2:?OUT}; SET=${3:?SET}
shift 3
PYTHON=${PYTHON:-/usr/bin/python3}
SRC=$(cd "$(dirname "$0")/.." && pwd)
CUBE="$SRC/configs/assign/cube.yaml"
mkdir -p "$OUT"

# nearest INDEX COUNT: the COUNT structures nearest to INDEX in unit properties (itself first).
nearest() {
  "$PYTHON" - "$SET" "$1" "$2" <<'PY'
import sys, h5py, numpy as np
u = h5py.File(sys.argv[1], "r")["unit_properties"][()]
d = np.linalg.norm(u - u[int(sys.argv[2])], axis=1)
print(" ".join(str(i) for i in np.lexsort((np.arange(len(d)), d))[: int(sys.argv[3])]))
PY
}
if [ $# -gt 0 ]; then STRUCTURES=("$@"); else
  read -r -a STRUCTURES <<<"$("$PYTHON" - "$SET" <<'PY'
import sys, h5py, numpy as np
p = h5py.File(sys.argv[1], "r")["properties"][()]
print(" ".join(str(int(np.argmin(abs(p[:, -1] - r)))) for r in (0.2, 0.35, 0.5)))
PY
)"
fi
density() { "$PYTHON" -c "import h5py; print('%.3f' % h5py.File('$SET','r')['properties'][$1, -1])"; }

# case NAME N M PATTERN MAP_ARGS...: assign, map, verify; prints one table row.
case_row() {
  local name=$1 n=$2 m=$3 pattern=$4
  shift 4
  local stem="$OUT/$name.n$n.m$m" h
  h=$("$PYTHON" -c "print(1 / $n)")
  "$BIN/msfab-assign" --config "$CUBE" --structures "$SET" --set "grid.size=[$n,$n,$n]" --set "grid.cell_size=$h" \
    --set "pattern=$pattern" --seed 1 --out "$stem.design.h5" > /dev/null
  "$BIN/msfab-map" --design "$stem.design.h5" --structures "$SET" --set candidates=1 "$@" --seed 1 \
    --out "$stem.mapped.h5" > "$stem.map.log" 2>&1
  local start end line
  start=$(date +%s.%N)
  if ! "$BIN/msfab-verify-map" --design "$stem.design.h5" --mapped "$stem.mapped.h5" --structures "$SET" \
    --set homogenized_elements="$m" --out "$stem.verify.h5" > "$stem.verify.out" 2> "$stem.verify.log"; then
    # A refused check (e.g. a load left on a piece the supports do not hold) is a result too.
    printf '| %s | %d | %d | %s | | refused: %s | | | |\n' "$name" "$n" "$m" \
      "$(grep -oE "final [0-9]+" "$stem.map.log" | awk '{print $2}')" "$(tail -1 "$stem.verify.log" | sed 's/^msfab-verify-map: error: //')"
    return 0
  fi
  line=$(grep '^msfab-verify-map:' "$stem.verify.out")
  end=$(date +%s.%N)
  local mismatch pct unknowns gap
  mismatch=$(grep -oE "final [0-9]+" "$stem.map.log" | awk '{print $2}')
  gap=$(grep -oE "property gap .*mean [0-9.e+-]+" "$stem.map.log" | grep -oE "mean [0-9.e+-]+" | awk '{print $2}')
  pct=$(grep -oE "(compress|shear): displacement [0-9.]+%, energy [0-9.]+%" <<<"$line" |
    sed -E 's/.*displacement ([0-9.]+)%, energy ([0-9.]+)%/\1 \/ \2/' | paste -sd'|' -)
  unknowns=$(grep -oE "[0-9]+ unknowns\)" <<<"$line" | tail -1 | grep -oE "[0-9]+")
  printf '| %s | %d | %d | %s | %s | %s | %s | %s | %.1f |\n' "$name" "$n" "$m" "$mismatch" "${gap:-}" "${pct%%|*}" \
    "${pct##*|}" "$unknowns" "$(echo "$end - $start" | bc)"
}

echo "| case | cells per edge n | homogenized hexahedra per cell edge | mismatch | property gap mean | compress: displacement / energy % | shear: displacement / energy % | full unknowns | check s |"
echo "|---|---|---|---|---|---|---|---|---|"
for s in "${STRUCTURES[@]}"; do
  [ "${TILING_STUDY:-1}" = 1 ] || break
  for n in ${TILES:-1 2 4 8}; do case_row "tile-$s-rho$(density "$s")" "$n" $((16 / n)) "{kind: uniform, structures: [$s]}" --set half_shift=false; done
  for n in 1 $(echo ${TILES:-8} | awk '{print $NF}'); do case_row "tile-$s-rho$(density "$s")" "$n" 1 "{kind: uniform, structures: [$s]}" --set half_shift=false; done
done
s=${STRUCTURES[1]:-${STRUCTURES[0]}}
read -r -a near <<<"$(nearest "$s" 4)"
pair="[${near[0]}, ${near[1]}]"; four="[${near[0]}, ${near[1]}, ${near[2]}, ${near[3]}]"
# The assigned rows with the thesis's descent: one start, the plain mismatch.
plain=(--set starts=1 --set void_pair_cost=0)
for shift in false true; do
  case_row "layers-z-${near[0]}-${near[1]}-shift-$shift" "${PATTERN_N:-4}" $((16 / ${PATTERN_N:-4})) "{kind: layers, structures: $pair, axis: z}" --set half_shift=$shift "${plain[@]}"
  case_row "layers-x-${near[0]}-${near[1]}-shift-$shift" "${PATTERN_N:-4}" $((16 / ${PATTERN_N:-4})) "{kind: layers, structures: $pair, axis: x}" --set half_shift=$shift "${plain[@]}"
  case_row "random-${near[0]}-${near[1]}-${near[2]}-${near[3]}-shift-$shift" "${PATTERN_N:-4}" $((16 / ${PATTERN_N:-4})) "{kind: random, structures: $four}" --set half_shift=$shift "${plain[@]}"
done
mapped=(--set candidates=16 --set half_shift=true)
case_row "layers-z-${near[0]}-${near[1]}-mapped" "${PATTERN_N:-4}" $((16 / ${PATTERN_N:-4})) "{kind: layers, structures: $pair, axis: z}" "${mapped[@]}"
case_row "layers-x-${near[0]}-${near[1]}-mapped" "${PATTERN_N:-4}" $((16 / ${PATTERN_N:-4})) "{kind: layers, structures: $pair, axis: x}" "${mapped[@]}"
case_row "random-${near[0]}-${near[1]}-${near[2]}-${near[3]}-mapped" "${PATTERN_N:-4}" $((16 / ${PATTERN_N:-4})) "{kind: random, structures: $four}" "${mapped[@]}"
