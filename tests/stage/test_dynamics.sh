#!/bin/bash
# msfab-dynamics and msfab-dac-calibrate: the block drop with the three
# impact models, DAC calibration of a coarse cantilever against a finer
# one (closed loop), and bad input.
BIN=$1 SRC=$(cd "$2" && pwd)
source "$SRC/tests/stage/lib.sh"
cd "$SRC"
S=configs/dynamics

# Drop test: BBI leaves no visible rebound, complementarity bounces.
for model in bbi complementarity; do
  "$BIN/msfab-dynamics" --quiet --out "$WORK/drop_$model.h5" --set simulation.impact=$model > "$WORK/drop_$model.txt"
  check "drop with $model writes the trajectory" -- test -s "$WORK/drop_$model.h5" -a -s "$WORK/drop_$model.xmf"
done
rebound() { awk '/rebound after the first contact/ {print $6}' "$1"; }
bbi=$(rebound "$WORK/drop_bbi.txt") comp=$(rebound "$WORK/drop_complementarity.txt")
echo "rebound from 3 cm: BBI $bbi m, complementarity $comp m"
check "BBI rebound below 0.5 mm" -- awk -v r="$bbi" 'BEGIN { exit !(r < 5e-4) }'
check "complementarity rebounds visibly, BBI does not" -- awk -v r="$comp" -v b="$bbi" 'BEGIN { exit !(r > 5e-4 && r > 100 * b) }'
check "no penetration beyond 1e-3 voxel" -- awk '/deepest penetration/ { exit !($NF + 0 <= 5e-6 || $(NF-1) + 0 <= 5e-6) }' "$WORK/drop_bbi.txt"

# A corner that touches and leaves again inside the event substeps of one
# step is still a touch-down: the oblique cube's first bounce at h = 4e-4 s
# is logged at the same step with event substeps as without.
first_touch() {
  "$BIN/msfab-dynamics" --config "$S/block_drop_oblique.yaml" --quiet --set simulation.impact=complementarity \
    --set simulation.time_step=4e-4 --set simulation.duration=0.08 --set simulation.event_substeps=$1 \
    --out "$WORK/oblique_L$1.h5" | awk '/event contact/ { print $5; exit }'
}
t0=$(first_touch 0) t3=$(first_touch 3)
echo "oblique drop, first touch-down: $t0 s without event substeps, $t3 s with 3 levels"
check "a touch inside event substeps is logged ($t0 s, $t3 s)" -- test -n "$t0" -a "$t0" = "$t3"

# DAC closed loop: a finer rig is the reference; the coarse rig calibrated
# on its tip marker reproduces its first frequency.
"$BIN/msfab-dynamics" --quiet --config $S/cantilever_pluck.yaml --set geometry.voxel_size=0.0015 \
  --set simulation.duration=0.015 --marker 0.06 0 0.006 --marker-csv "$WORK/fine_tip.csv" --out "$WORK/fine.h5" > /dev/null
check "fine rig writes its tip track" -- test -s "$WORK/fine_tip.csv"
cat > "$WORK/cal.yaml" <<YAML
scene: $SRC/$S/cantilever_pluck.yaml
material: rigur
marker_csv: $WORK/fine_tip.csv
column: z
YAML
"$BIN/msfab-dac-calibrate" --config "$WORK/cal.yaml" --out "$WORK/dac.h5" > "$WORK/cal.txt"
cat "$WORK/cal.txt"
# The modes and the fitted modulus do not depend on the thread count (Eigen's
# own threads once made them differ in the 12th digit).
for threads in 1 2; do
  check "calibration on $threads thread(s)" -- "$BIN/msfab-dac-calibrate" --config "$WORK/cal.yaml" --threads $threads \
    --out "$WORK/dac_t$threads.h5" --quiet
done
check "calibration independent of the thread count" -- h5diff -q "$WORK/dac_t1.h5" "$WORK/dac_t2.h5" /coarse_eigenvalues
check "fitted modulus independent of the thread count" -- test \
  "$(h5dump -m %.17g -a youngs_modulus "$WORK/dac_t1.h5" | grep -o '(0):.*')" = "$(h5dump -m %.17g -a youngs_modulus "$WORK/dac_t2.h5" | grep -o '(0):.*')"
# The report's DAC page (python/msfab/report.py) draws the artifact's modes.
check "the report draws the calibration's frequencies" -- env PYTHONPATH="$SRC/python:$SRC/tests/stage" \
  PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 - "$WORK" <<'PY'
import json, subprocess, sys
import h5py
import numpy as np
work = sys.argv[1]
subprocess.run([sys.executable, "-m", "msfab", "report", f"{work}/dac_report.html", f"{work}/dac.h5"], check=True,
               stdout=subprocess.DEVNULL)
from expectations import expect, finish
data = json.load(open(f"{work}/dac_report_files/data.json"))
drawn = data[next(n for n in data if "dac_dac" in n)]
with h5py.File(f"{work}/dac.h5") as f:
    eig = np.atleast_1d(f["/coarse_eigenvalues"][()])
    expect("frequencies are the coarse eigenvalues'", np.allclose(drawn["frequencies"], np.sqrt(eig) / (2 * np.pi)))
    scale = np.sqrt(f.attrs["youngs_modulus"] / f.attrs["reference_modulus"])
    expect("scaled by the calibrated modulus", abs(drawn["scale"] - scale) < 1e-12 * scale)
finish()
PY
sed -e "s|E: 1.9e9, nu: 0.45, density: 1200, damping_a: 0, damping_b: 2.0e-5|dac_model: $WORK/dac.h5, nu: 0.45, density: 1200|" \
  $S/cantilever_pluck.yaml > "$WORK/coarse_dac.yaml"
"$BIN/msfab-dynamics" --quiet --config "$WORK/coarse_dac.yaml" --set simulation.duration=0.015 \
  --marker 0.06 0 0.006 --marker-csv "$WORK/coarse_tip.csv" --out "$WORK/coarse.h5" > /dev/null
sed -e "s|$WORK/fine_tip.csv|$WORK/coarse_tip.csv|" -e "s|scene: .*|scene: $WORK/coarse_dac.yaml|" "$WORK/cal.yaml" > "$WORK/recal.yaml"
"$BIN/msfab-dac-calibrate" --config "$WORK/recal.yaml" --out "$WORK/dac2.h5" > "$WORK/recal.txt"
cat "$WORK/recal.txt"
f_fine=$(awk '/target f_t =/ { print $4 }' "$WORK/cal.txt")
f_coarse=$(awk '/target f_t =/ { print $4 }' "$WORK/recal.txt")
echo "tip frequency: fine rig $f_fine Hz, calibrated coarse rig $f_coarse Hz"
check "calibrated coarse rig reproduces the fine f1 within 1%" -- \
  awk -v a="$f_fine" -v b="$f_coarse" 'BEGIN { d = (b - a) / a; if (d < 0) d = -d; exit !(a > 0 && d < 0.01) }'

# The accurate mesh (Fig. 4-11): the rig at 3, 1.5 and 0.75 mm; every
# mode's converged frequency extrapolated (the meshes soften towards it, so
# it lies below the finest mesh's), and the coarsest mesh within 5% named.
printf 'scene: %s\nmaterial: rigur\ntarget: {frequency: 340.0, decay: 0.0}\nmodes: 4\nsearch_levels: 2\n' \
  "$SRC/$S/cantilever_pluck.yaml" > "$WORK/search.yaml"
check "mesh search with converged frequencies" -- bash -c "'$BIN/msfab-dac-calibrate' --config '$WORK/search.yaml' \
  --out '$WORK/search.h5' > '$WORK/search.txt' 2> '$WORK/search.log'"
grep -E "converged frequencies|accurate mesh|level [0-9]:" "$WORK/search.txt" "$WORK/search.log"
check "every mode extrapolated" -- bash -c "grep 'converged frequencies' '$WORK/search.txt' | grep -o '(p ' | wc -l | grep -qx 4"
f_limit=$(awk '/converged frequencies/ { for (i = 1; i <= NF; ++i) if ($i == "(p") { print $(i - 1); exit } }' "$WORK/search.txt")
f_finest=$(grep -o "level 2: .* f1 [0-9.]*" "$WORK/search.log" | awk '{ print $NF }')
echo "f1: finest mesh $f_finest Hz, extrapolated $f_limit Hz"
check "the limit lies below the finest mesh, within 5%" -- \
  awk -v l="$f_limit" -v f="$f_finest" 'BEGIN { exit !(l > 0 && l < f && f < 1.05 * l) }'
check "the accurate mesh is named" -- grep -q "accurate mesh: level [0-2], voxel" "$WORK/search.txt"
expect_exit 2 "accuracy_tolerance.*must be in \(0, 1\)" -- "$BIN/msfab-dac-calibrate" --config "$WORK/search.yaml" \
  --set accuracy_tolerance=0 --out "$WORK/x.h5"

# Catapult: the cube lying in the basket is carried into the loaded basket,
# then thrown upward by the released arm through body contact.
OMP_NUM_THREADS=1 "$BIN/msfab-dynamics" --quiet --config $S/catapult.yaml --set simulation.duration=0.02 \
  --out "$WORK/catapult.h5" > "$WORK/catapult.txt"
check "catapult places the cube in the loaded basket" -- grep -q "cube carried with its support" "$WORK/catapult.txt"
check "catapult records each body's centre of mass" -- h5ls "$WORK/catapult.h5/samples/body_center_of_mass"
cube=$(awk '$1 == "body" && $2 == "cube" { gsub(/[(),]/, " "); print $9, $14 }' "$WORK/catapult.txt")
echo "cube centre of mass height: start and after 20 ms: $cube"
check "the cube is thrown upward (> 1 cm in 20 ms)" -- awk -v s="${cube% *}" -v e="${cube#* }" 'BEGIN { exit !(e - s > 0.01) }'
check "no body penetrates beyond 1e-3 voxel" -- awk '/deepest penetration/ { exit !($NF + 0 <= 2e-6 || $(NF-1) + 0 <= 2e-6) }' "$WORK/catapult.txt"

# Bad input.
expect_exit 2 "press: the preload folds the body through itself.*set press.self_contact" -- "$BIN/msfab-dynamics" \
  --config $S/flipper_jumper.yaml --out "$WORK/x.h5" --set 'press.force=[0,0,-3]'
# The same press with stop_at_touch stops where the top plate meets the
# base, short of the full load, and the run goes on from there.
"$BIN/msfab-dynamics" --quiet --config $S/flipper_jumper.yaml --out "$WORK/touch.h5" --set 'press.force=[0,0,-3]' \
  --set press.stop_at_touch=true --set simulation.duration=0.0005 > "$WORK/touch.txt"
share=$(awk '/stopped at touch/ { for (i = 1; i <= NF; ++i) if ($i ~ /%$/) print $i + 0 }' "$WORK/touch.txt")
echo "press with stop_at_touch: stopped at ${share}% of 3 N"
check "press.stop_at_touch stops short of a load that folds" -- awk -v s="$share" 'BEGIN { exit !(s > 10 && s < 100) }'
check "press.stop_at_touch: the run continues" -- test -s "$WORK/touch.h5"
# With press.self_contact the top plate rests on the base and the full 3 N
# is carried through the contact: the press ties nodes and the run goes on.
"$BIN/msfab-dynamics" --quiet --config $S/flipper_jumper.yaml --out "$WORK/tied.h5" --set 'press.force=[0,0,-3]' \
  --set press.self_contact=true --set simulation.duration=0.0005 > "$WORK/tied.txt"
ties=$(awk '/self-contact ties/ { for (i = 1; i <= NF; ++i) if ($i == "self-contact") print $(i - 1) + 0 }' "$WORK/tied.txt")
echo "press with self-contact: ${ties} ties at the full 3 N"
check "press.self_contact carries the full load through tied nodes" -- awk -v t="$ties" 'BEGIN { exit !(t > 0) }'
check "press.self_contact: the run continues" -- test -s "$WORK/tied.h5"
expect_exit 2 "press.self_contact = true: and stop_at_touch exclude each other" -- "$BIN/msfab-dynamics" \
  --config $S/flipper_jumper.yaml --out "$WORK/x.h5" --set press.self_contact=true --set press.stop_at_touch=true
# The press applied dynamically (B.3; tools/bench_press.sh compares it with
# the quasistatic press): ramped on over 2 ms, the plate is pushed down and
# the body stays on the ground; its keys are checked.
"$BIN/msfab-dynamics" --quiet --config $S/flipper_jumper.yaml --out "$WORK/dynamic_press.h5" \
  --set press.mode=dynamic --set press.ramp_time=0.002 --set simulation.duration=0.003 \
  --set simulation.time_step=1e-4 --set simulation.rigid_flight.enabled=false > "$WORK/dynamic_press.txt"
check "press.mode dynamic: the press event" -- grep -q "event press .* dynamic press: 1.2 N ramped on over 0.002 s" \
  "$WORK/dynamic_press.txt"
check "press.mode dynamic: the load puts energy into the body (> 1 mJ)" -- \
  awk '/energy start/ { gsub(/,/, ""); for (i = 1; i <= NF; ++i) if ($i == "end") e = $(i + 1) } END { exit !(e > 1e-3) }' \
  "$WORK/dynamic_press.txt"
expect_exit 2 "missing required key 'press.ramp_time'" -- "$BIN/msfab-dynamics" --config $S/flipper_jumper.yaml --out "$WORK/x.h5" \
  --set press.mode=dynamic
expect_exit 2 "press.ramp_time = 0.01: belongs to mode: dynamic" -- "$BIN/msfab-dynamics" --config $S/flipper_jumper.yaml \
  --out "$WORK/x.h5" --set press.ramp_time=0.01
expect_exit 2 "stop_at_touch = true: belongs to the quasistatic press" -- "$BIN/msfab-dynamics" \
  --config $S/flipper_jumper.yaml --out "$WORK/x.h5" --set press.mode=dynamic --set press.ramp_time=0.01 \
  --set press.stop_at_touch=true --set simulation.rigid_flight.enabled=false
expect_exit 2 "rigid_flight.enabled = true: a body under a dynamic press is not in free flight" -- "$BIN/msfab-dynamics" --config $S/flipper_jumper.yaml \
  --out "$WORK/x.h5" --set press.mode=dynamic --set press.ramp_time=0.01
expect_exit 2 "press.mode = sudden: .*quasistatic, dynamic" -- "$BIN/msfab-dynamics" --config $S/flipper_jumper.yaml \
  --out "$WORK/x.h5" --set press.mode=sudden
expect_exit 2 "boxes\[5\].*overlaps a box of body 'catapult'" -- "$BIN/msfab-dynamics" --config $S/catapult.yaml \
  --out "$WORK/x.h5" --set 'geometry.boxes[5].min=[0.030,0.002,0.010]'
expect_exit 2 "time_step.*must be positive" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" --set simulation.time_step=0
expect_exit 2 "time_step.*must be positive" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" --set simulation.time_step=-1e-4
expect_exit 2 "time_step.*longer than duration" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" --set simulation.time_step=1e50
expect_exit 2 "time_step = 1e308: beyond" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" --set simulation.time_step=1e308
expect_exit 2 "time_step.*steps over duration.*at most" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" \
  --set simulation.time_step=1e-300
expect_exit 2 "friction coefficient must be >= 0" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" --set friction.default=-0.2
expect_exit 2 "starts inside obstacle 'ground'" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" --set 'placement.translation=[0,0,-0.002]'
expect_exit 2 "unknown impact model" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" --set simulation.impact=bouncy
printf 't,z\n0,1\n0.001,nan\n' > "$WORK/nan.csv"
for i in $(seq 2 40); do printf '0.%03d,1\n' $i >> "$WORK/nan.csv"; done
expect_exit 2 "nan.csv.*line 3.*finite" -- "$BIN/msfab-dac-calibrate" --config "$WORK/cal.yaml" --set marker_csv="$WORK/nan.csv" --out "$WORK/x.h5"
printf 't,z\n0,1\n0.001,2\n0.002,1\n' > "$WORK/short.csv"
expect_exit 2 "short.csv.*samples" -- "$BIN/msfab-dac-calibrate" --config "$WORK/cal.yaml" --set marker_csv="$WORK/short.csv" --out "$WORK/x.h5"
# A track that grows is no free decay; one from a rig without damping is
# calibrated as undamped (its fitted decay scatters about zero).
awk 'BEGIN { print "t,z"; for (k = 0; k < 400; ++k) { t = k / 24000; printf "%.8f,%.9f\n", t, exp(60 * t) * sin(2 * 3.14159265 * 340 * t) } }' \
  > "$WORK/growing.csv"
expect_exit 2 "growing.csv: the tracked oscillation grows" -- "$BIN/msfab-dac-calibrate" --config "$WORK/cal.yaml" \
  --set marker_csv="$WORK/growing.csv" --out "$WORK/x.h5"
# DDFEM in dynamics: the fibre bar at 4 mm voxels, fine and coarsened by the
# tiny database (its stiff material as the fibre), compared frame by frame.
"$BIN/msfab-ddfem-build" --config configs/ddfem/tiny.yaml --out "$WORK/tiny.coarse_db.h5" --quiet > /dev/null
FIBER=(--config $S/fiber_bar.yaml --set geometry.voxel_size=0.004 --set simulation.duration=0.02
       --set 'geometry.layout[0].id=2' --set 'materials[1].E=1.0e7')
"$BIN/msfab-dynamics" --quiet "${FIBER[@]}" --out "$WORK/fiber_fine.h5" > /dev/null
"$BIN/msfab-dynamics" --quiet "${FIBER[@]}" --coarsen 1 --database "$WORK/tiny.coarse_db.h5" \
  --reference "$WORK/fiber_fine.h5" --out "$WORK/fiber_l1.h5" > "$WORK/fiber_l1.txt"
check "a coarsened run reports its difference from the fine run" -- grep -q "vs fine (interpolated): error at release" "$WORK/fiber_l1.txt"
err=$(awk '/vs fine/ { for (i = 1; i <= NF; ++i) if ($i == "max") print $(i + 1) }' "$WORK/fiber_l1.txt" | tr -d ,)
check "... which is small and not zero (0 < $err < 0.05)" -- awk -v e="$err" 'BEGIN { exit !(e > 0 && e < 0.05) }'
check "... and runs fewer DOFs" -- grep -q "msfab-dynamics: scene 'fiber-bar', 208 elements" "$WORK/fiber_l1.txt"
# Windowed matched materials: the trajectory records the margin and the
# cells left on their own C^H (those next to the void padding of the odd
# grid).
"$BIN/msfab-dynamics" --quiet "${FIBER[@]}" --coarsen 1 --coarse-material matched --coarse-window 2 \
  --out "$WORK/fiber_window.h5" > /dev/null
check "a windowed run records its margin in the trajectory" -- \
  bash -c "h5dump -a /coarsening/window '$WORK/fiber_window.h5' | grep -q '(0): 2' &&
           h5dump -a /coarsening/unresolved_windows '$WORK/fiber_window.h5' | grep -q '(0): [0-9]'"
"$BIN/msfab-dynamics" --quiet "${FIBER[@]}" --reference "$WORK/fiber_fine.h5" --out "$WORK/fiber_again.h5" > "$WORK/fiber_again.txt"
check "the fine run against itself: no difference" -- grep -q "vs fine (same mesh): error at release 0.000e+00, max 0.000e+00" "$WORK/fiber_again.txt"
expect_exit 2 "fiber_fine.h5: the reference has .* rest nodes" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" \
  --reference "$WORK/fiber_fine.h5"
expect_exit 2 "fiber_fine.h5: run with time step 0.001 s, this scene's is 0.002 s" -- "$BIN/msfab-dynamics" \
  "${FIBER[@]}" --set simulation.time_step=0.002 --coarsen 1 --coarse-material naive --reference "$WORK/fiber_fine.h5" \
  --out "$WORK/x.h5"
expect_exit 2 "tiny.coarse_db.h5.*palette" -- "$BIN/msfab-dynamics" --config $S/fiber_bar.yaml --set geometry.voxel_size=0.004 \
  --coarsen 1 --database "$WORK/tiny.coarse_db.h5" --out "$WORK/x.h5"
expect_exit 2 "--coarsen: the scene has 2 bodies" -- "$BIN/msfab-dynamics" --config $S/catapult.yaml --coarsen 1 \
  --coarse-material naive --out "$WORK/x.h5"
expect_exit 2 "--coarse-material and --database need --coarsen 1 or 2" -- "$BIN/msfab-dynamics" --out "$WORK/x.h5" \
  --database "$WORK/tiny.coarse_db.h5"
check "failed runs leave no artifact" -- test ! -e "$WORK/x.h5"
sed -e "s|damping_b: 2.0e-5|damping_b: 0|" $S/cantilever_pluck.yaml > "$WORK/undamped_rig.yaml"
"$BIN/msfab-dynamics" --quiet --config "$WORK/undamped_rig.yaml" --set simulation.duration=0.015 \
  --marker 0.06 0 0.006 --marker-csv "$WORK/undamped_tip.csv" --out "$WORK/undamped.h5" > /dev/null
sed -e "s|$WORK/fine_tip.csv|$WORK/undamped_tip.csv|" "$WORK/cal.yaml" > "$WORK/undamped_cal.yaml"
check "a track of an undamped rig calibrates" -- "$BIN/msfab-dac-calibrate" --config "$WORK/undamped_cal.yaml" \
  --out "$WORK/dac_undamped.h5" --log-level info
check "... as undamped" -- test "$(h5dump -a /target_decay "$WORK/dac_undamped.h5" 2>/dev/null | grep -oE '\(0\): [-0-9.e+]+' | awk '{print $2}')" = 0
finish
