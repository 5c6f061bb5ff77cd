#!/bin/bash
# DAC versus an accurate fine mesh on the flipper jumper (thesis §4.3,
# Fig. 4-17/4-21): the 1 mm flipper (8x the elements) is the reference; the
# 2 mm flipper runs once with the material's own modulus and once with the
# DAC modulus and damping fitted to the fine mesh's first frequency and its
# Rayleigh decay (Eq. 4.16-4.18). Prints the first-10-mode frequency errors,
# time per step, peak memory and the centre-of-mass and rotation
# differences over take-off and flight (every 10 ms).
#
#   tools/bench_dac_jumper.sh build/bin out/bench/dac_jumper
set -euo pipefail
BIN=$(cd "${1:-build/bin}" && pwd)
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "${2:-out/bench/dac_jumper}"
OUT=$(cd "${2:-out/bench/dac_jumper}" && pwd)
cd "$OUT"
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
SCENE=$SRC/configs/dynamics/flipper_jumper.yaml
sed "s/voxel_size: 0.002/voxel_size: 0.001/" "$SCENE" > flipper_fine.yaml

# Modes of both meshes with the material's own modulus (the target given
# here only labels the printout).
modes() {
  printf 'scene: %s\nmaterial: rigur\ntarget: {frequency: 100.0, decay: 1.0}\nmodes: 10\n' "$1" > modes.yaml
  "$BIN/msfab-dac-calibrate" --config modes.yaml --out "$2" | awk '/^  mode/ { print $6 }'
}
modes "$OUT/flipper_fine.yaml" modes_fine.h5 > f_fine.txt
modes "$SCENE" modes_coarse.h5 > f_coarse.txt
f1=$(head -1 f_fine.txt)
b=$(awk '/name: rigur/ { for (i = 1; i <= NF; ++i) if ($i == "damping_b:") print $(i + 1) }' "$SCENE" | tr -d '}')
d1=$(awk -v f="$f1" -v b="$b" 'BEGIN { l = (2 * 3.141592653589793 * f)^2; print b * l / 2 }')
printf 'scene: %s\nmaterial: rigur\ntarget: {frequency: %s, decay: %s}\nmodes: 10\n' "$SCENE" "$f1" "$d1" > dac.yaml
"$BIN/msfab-dac-calibrate" --config dac.yaml --out flipper.dac_model.h5 > dac.txt
scale=$(awk '/E_n =/ { for (i = 1; i <= NF; ++i) if ($i ~ /^\(x/) { gsub(/[(x),]/, "", $i); print $i } }' dac.txt)
paste f_fine.txt f_coarse.txt | awk -v s="$scale" '{ b = ($2 - $1) / $1; a = ($2 * sqrt(s) - $1) / $1;
  b = b < 0 ? -b : b; a = a < 0 ? -a : a; sb += b; sa += a; if (b > mb) mb = b; if (a > ma) ma = a; n++ }
  END { printf "first %d modes, mean (max) error: E_m %.1f%% (%.1f%%), DAC %.1f%% (%.1f%%); E_n = %s E_m\n",
        n, 100 * sb / n, 100 * mb, 100 * sa / n, 100 * ma, s }'
sed -e "s|{name: rigur, E: 0.65e9, nu: 0.45, density: 1200, damping_a: 0, damping_b: 1.64e-4}|{name: rigur, dac_model: $OUT/flipper.dac_model.h5, nu: 0.45, density: 1200}|" \
  "$SCENE" > flipper_dac.yaml

# Take-off and flight up to just after landing; 0.8 N keeps the fine
# flipper's press clear of self-contact. h = 1e-4 s for all three: the
# comparison is between discretizations in space at one time step (the
# scene's 2.5e-5 s would quadruple the elastic steps; docs/dynamics.md).
run=(--threads 1 --quiet --set simulation.duration=0.16 --set simulation.time_step=1e-4 --set 'press.force=[0,0,-0.8]')
for m in fine:flipper_fine.yaml coarse:$SCENE dac:flipper_dac.yaml; do
  name=${m%%:*} scene=${m#*:}
  /usr/bin/time -f "%M" -o "$name.rss" "$BIN/msfab-dynamics" --config "$scene" --out "$name.h5" "${run[@]}" > "$name.txt"
  awk -v n="$name" -v r="$(cat "$name.rss")" '/elastic steps/ { ms = $7 } /highest z/ { z = $(NF - 1) }
    /^  time:/ { t = $(NF - 1) } END { printf "%-6s %s ms per elastic step, %s s in all, %.0f MB, apex %s\n", n, ms, t, r / 1024, z }' "$name.txt"
done

# Samples every 10 ms: centre of mass and rotation about y.
column() {  # file dataset columns
  local n rows
  n=$(h5dump -H -d /samples/time "$1" | grep -o "( [0-9]* )" | head -1 | tr -d '() ')
  rows=$(((n + 99) / 100))
  if [ "$3" = 1 ]; then sel=(-s 0 -c "$rows" -S 100); else sel=(-s 0,0 -c "$rows,$3" -S 100,1); fi
  h5dump -d "/samples/$2" "${sel[@]}" -y -w 0 "$1" | sed -n '/DATA {/,/}/p' | grep -v "DATA\|}" | tr -d ' ' |
    tr ',' '\n' | grep . | paste $(for _ in $(seq "$3"); do printf -- '- '; done)
}
for r in fine coarse dac; do column $r.h5 center_of_mass 3 > $r.com; column $r.h5 rotation 3 > $r.rot; done
column fine.h5 time 1 > t.txt
paste t.txt fine.com fine.rot dac.com dac.rot coarse.com coarse.rot | awk 'NF == 19 { d = 57.29578;
  printf "t %.2f s  fine z %5.2f mm turn %6.1f deg | DAC dCOM %5.2f mm dturn %5.1f | E_m dCOM %5.2f mm dturn %5.1f\n",
  $1, 1e3 * $4, d * $6, 1e3 * sqrt(($2 - $8)^2 + ($4 - $10)^2), d * ($12 - $6),
  1e3 * sqrt(($2 - $14)^2 + ($4 - $16)^2), d * ($18 - $6) }'
