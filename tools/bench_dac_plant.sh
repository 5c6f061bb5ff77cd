#!/bin/bash
# DAC versus the accurate mesh on the plant-like scene (thesis §4.3,
# Fig. 4-9/4-11). The plant (configs/dynamics/plant.yaml) is meshed at
# 2 mm and LEVELS halvings of it; the converged frequencies of its first
# four modes are extrapolated from the three finest (Richardson), and the
# accurate mesh is the coarsest within 5% of them (the thesis's definition).
# The accurate mesh (or REFERENCE, a voxel size) is simulated as the
# reference, the 1 mm plant as one halving, and the 2 mm plant once with
# the material's own modulus and once with the DAC modulus and damping
# fitted to the reference's first frequency and its Rayleigh decay
# (Eq. 4.16-4.18). Prints the convergence table, the first-10-mode
# frequency errors, time per step, peak memory and the flower marker's
# difference to the reference over the swaying.
#
#   tools/bench_dac_plant.sh build/bin out/bench/dac_plant
#   LEVELS=2 REFERENCE=0.001 DURATION=0.005 tools/bench_dac_plant.sh ...   # a quick check of the script
set -euo pipefail
source "$(dirname "$0")/dac_bench_lib.sh"
bench_folders "${1:-build/bin}" "${2:-out/bench/dac_plant}"
SCENE=$SRC/configs/dynamics/plant.yaml

reference_meshes "$SCENE" dm4825 plant

modes "$OUT/plant_ref.yaml" dm4825 modes_ref.h5 > f_ref.txt
modes "$OUT/plant_1mm.yaml" dm4825 modes_1mm.h5 > f_1mm.txt
modes "$SCENE" dm4825 modes_2mm.h5 > f_2mm.txt
echo "frequencies (Hz): reference | 1 mm | 2 mm"
paste f_ref.txt f_1mm.txt f_2mm.txt

f1=$(head -1 f_ref.txt)
scale=$(dac_fit "$SCENE" dm4825 "$f1" plant.dac_model.h5)
echo "DAC: E_n = $scale E_m, target f1 $f1 Hz"
frequency_errors "1 mm against the reference:" f_ref.txt f_1mm.txt 1
frequency_errors "2 mm, E_m:" f_ref.txt f_2mm.txt 1
frequency_errors "2 mm, DAC:" f_ref.txt f_2mm.txt "$scale"
sed -e "s|{name: dm4825, E: 1.57e9, nu: 0.45, density: 1170, damping_a: 0, damping_b: 2.55e-4}|{name: dm4825, dac_model: $OUT/plant.dac_model.h5, nu: 0.45, density: 1170}|" \
  "$SCENE" > plant_dac.yaml
grep -q dac_model plant_dac.yaml || { echo "plant_dac.yaml: material line not replaced" >&2; exit 1; }

# Pluck, release, DURATION of swaying (0.03 s: three periods of the first
# mode); the flower's top centre is tracked.
run=(--threads 1 --quiet --marker 0.024 0.014 0.070 --set "simulation.duration=${DURATION:-0.03}")
for m in fine:plant_ref.yaml one_halving:plant_1mm.yaml coarse:$SCENE dac:plant_dac.yaml; do
  timed_run "${m%%:*}" "${m#*:}" "${run[@]}" --marker-csv "${m%%:*}.csv"
done

# Flower marker: displacement from its rest position (a node at every
# resolution), difference to the reference (RMS over the run relative to
# the reference's RMS displacement, and the largest difference); every
# 2.5 ms over the first three periods.
paste -d, fine.csv dac.csv coarse.csv one_halving.csv | awk -F, -v x0=0.024 -v y0=0.014 -v z0=0.070 'NR == 1 { next }
  { ux = $2 - x0; uy = $3 - y0; uz = $4 - z0; u2 = ux^2 + uy^2 + uz^2
    dd = ($6 - $2)^2 + ($7 - $3)^2 + ($8 - $4)^2; dc = ($10 - $2)^2 + ($11 - $3)^2 + ($12 - $4)^2
    dh = ($14 - $2)^2 + ($15 - $3)^2 + ($16 - $4)^2
    su += u2; sd += dd; sc += dc; sh += dh; n++; if (dd > md) md = dd; if (dc > mc) mc = dc; if (dh > mh) mh = dh
    if ((NR - 2) % 25 == 0 && $1 < 0.0301) printf "t %.4f s  reference |u| %.3f mm | DAC diff %.3f mm | E_m diff %.3f mm | 1 mm diff %.3f mm\n", $1, 1e3 * sqrt(u2), 1e3 * sqrt(dd), 1e3 * sqrt(dc), 1e3 * sqrt(dh) }
  END { printf "flower marker, RMS difference / RMS displacement: DAC %.1f%%, E_m %.1f%%, 1 mm %.1f%%; largest difference DAC %.3f mm, E_m %.3f mm, 1 mm %.3f mm\n",
        100 * sqrt(sd / su), 100 * sqrt(sc / su), 100 * sqrt(sh / su), 1e3 * sqrt(md), 1e3 * sqrt(mc), 1e3 * sqrt(mh) }'
