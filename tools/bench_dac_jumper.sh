#!/bin/bash
# DAC versus the accurate mesh on the flipper jumper (thesis §4.3,
# Fig. 4-11/4-17/4-21). The flipper (configs/dynamics/flipper_jumper.yaml)
# is meshed at 2 mm and LEVELS halvings of it; the converged frequencies of
# its first four modes are extrapolated from the three finest (Richardson),
# and the accurate mesh is the coarsest within 5% of them (the thesis's
# definition). The reference simulated is REFERENCE (a voxel size; default
# the accurate mesh); where the accurate mesh is finer than the reference
# (too large to run to the landing here), TIMING_STEPS of its take-off are
# timed (TIMING_STEPS=0 skips it). The 1 mm flipper runs as one halving, the 2 mm flipper once with
# the material's own modulus and once with the DAC modulus and damping
# fitted to the reference's first frequency and its Rayleigh decay
# (Eq. 4.16-4.18). Prints the convergence table, the first-10-mode
# frequency errors, time per step, peak memory and the centre-of-mass and
# rotation differences over take-off and flight (every 10 ms).
#
#   tools/bench_dac_jumper.sh build/bin out/bench/dac_jumper
#   REFERENCE=0.0005 tools/bench_dac_jumper.sh ...
set -euo pipefail
source "$(dirname "$0")/dac_bench_lib.sh"
bench_folders "${1:-build/bin}" "${2:-out/bench/dac_jumper}"
SCENE=$SRC/configs/dynamics/flipper_jumper.yaml

reference_meshes "$SCENE" rigur flipper

modes "$OUT/flipper_ref.yaml" rigur modes_ref.h5 > f_ref.txt
modes "$OUT/flipper_1mm.yaml" rigur modes_1mm.h5 > f_1mm.txt
modes "$SCENE" rigur modes_coarse.h5 > f_coarse.txt
echo "frequencies (Hz): reference | 1 mm | 2 mm"
paste f_ref.txt f_1mm.txt f_coarse.txt
f1=$(head -1 f_ref.txt)
scale=$(dac_fit "$SCENE" rigur "$f1" flipper.dac_model.h5)
echo "DAC: E_n = $scale E_m, target f1 $f1 Hz"
frequency_errors "1 mm against the reference:" f_ref.txt f_1mm.txt 1
frequency_errors "2 mm, E_m:" f_ref.txt f_coarse.txt 1
frequency_errors "2 mm, DAC:" f_ref.txt f_coarse.txt "$scale"
sed -e "s|{name: rigur, E: 0.65e9, nu: 0.45, density: 1200, damping_a: 0, damping_b: 1.64e-4}|{name: rigur, dac_model: $OUT/flipper.dac_model.h5, nu: 0.45, density: 1200}|" \
  "$SCENE" > flipper_dac.yaml
grep -q dac_model flipper_dac.yaml || { echo "flipper_dac.yaml: material line not replaced" >&2; exit 1; }

# Take-off and flight up to just after landing; 0.8 N keeps the fine
# flipper's press clear of self-contact. h = 1e-4 s for all three: the
# comparison is between discretizations in space at one time step (the
# scene's 2.5e-5 s would quadruple the elastic steps; docs/dynamics.md).
run=(--threads 1 --quiet --set simulation.duration=0.16 --set simulation.time_step=1e-4 --set 'press.force=[0,0,-0.8]')
for m in fine:flipper_ref.yaml one_halving:flipper_1mm.yaml coarse:$SCENE dac:flipper_dac.yaml; do
  timed_run "${m%%:*}" "${m#*:}" "${run[@]}"
done
if [ -n "$ACCURATE" ] && [ "$ACCURATE" != "$REF" ] && [ "${TIMING_STEPS:-10}" -gt 0 ]; then
  # The accurate mesh's take-off, timed only: the first TIMING_STEPS steps.
  sed "s/voxel_size: 0.002/voxel_size: $ACCURATE/" "$SCENE" > flipper_accurate.yaml
  timed_run accurate flipper_accurate.yaml "${run[@]}" --set "simulation.duration=$(awk -v n="${TIMING_STEPS:-10}" 'BEGIN { print n * 1e-4 }')"
fi

# Samples every 10 ms: centre of mass and rotation about y.
column() {  # file dataset columns
  local n rows
  n=$(h5dump -H -d /samples/time "$1" | grep -o "( [0-9]* )" | head -1 | tr -d '() ')
  rows=$(((n + 99) / 100))
  if [ "$3" = 1 ]; then sel=(-s 0 -c "$rows" -S 100); else sel=(-s 0,0 -c "$rows,$3" -S 100,1); fi
  h5dump -d "/samples/$2" "${sel[@]}" -y -w 0 "$1" | sed -n '/DATA {/,/}/p' | grep -v "DATA\|}" | tr -d ' ' |
    tr ',' '\n' | grep . | paste $(for _ in $(seq "$3"); do printf -- '- '; done)
}
for r in fine one_halving coarse dac; do column $r.h5 center_of_mass 3 > $r.com; column $r.h5 rotation 3 > $r.rot; done
column fine.h5 time 1 > t.txt
paste t.txt fine.com fine.rot dac.com dac.rot coarse.com coarse.rot one_halving.com one_halving.rot | awk 'NF == 25 { d = 57.29578;
  printf "t %.2f s  reference z %5.2f mm turn %6.1f deg | DAC dCOM %5.2f mm dturn %5.1f | E_m dCOM %5.2f mm dturn %5.1f | 1 mm dCOM %5.2f mm dturn %5.1f\n",
  $1, 1e3 * $4, d * $6, 1e3 * sqrt(($2 - $8)^2 + ($4 - $10)^2), d * ($12 - $6),
  1e3 * sqrt(($2 - $14)^2 + ($4 - $16)^2), d * ($18 - $6), 1e3 * sqrt(($2 - $20)^2 + ($4 - $22)^2), d * ($24 - $6) }'
