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
source "$(dirname "$0")/dac_bench_lib.sh"
bench_folders "${1:-build/bin}" "${2:-out/bench/dac_jumper}"
SCENE=$SRC/configs/dynamics/flipper_jumper.yaml
sed "s/voxel_size: 0.002/voxel_size: 0.001/" "$SCENE" > flipper_fine.yaml

modes "$OUT/flipper_fine.yaml" rigur modes_fine.h5 > f_fine.txt
modes "$SCENE" rigur modes_coarse.h5 > f_coarse.txt
f1=$(head -1 f_fine.txt)
scale=$(dac_fit "$SCENE" rigur "$f1" flipper.dac_model.h5)
echo "DAC: E_n = $scale E_m, target f1 $f1 Hz"
frequency_errors "2 mm, E_m, against 1 mm:" f_fine.txt f_coarse.txt 1
frequency_errors "2 mm, DAC, against 1 mm:" f_fine.txt f_coarse.txt "$scale"
sed -e "s|{name: rigur, E: 0.65e9, nu: 0.45, density: 1200, damping_a: 0, damping_b: 1.64e-4}|{name: rigur, dac_model: $OUT/flipper.dac_model.h5, nu: 0.45, density: 1200}|" \
  "$SCENE" > flipper_dac.yaml

# Take-off and flight up to just after landing; 0.8 N keeps the fine
# flipper's press clear of self-contact. h = 1e-4 s for all three: the
# comparison is between discretizations in space at one time step (the
# scene's 2.5e-5 s would quadruple the elastic steps; docs/dynamics.md).
run=(--threads 1 --quiet --set simulation.duration=0.16 --set simulation.time_step=1e-4 --set 'press.force=[0,0,-0.8]')
for m in fine:flipper_fine.yaml coarse:$SCENE dac:flipper_dac.yaml; do
  timed_run "${m%%:*}" "${m#*:}" "${run[@]}"
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
