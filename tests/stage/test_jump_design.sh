#!/bin/bash
# msfab-jump-design on a tiny problem (a two-voxel block thrown at a target;
# its length and launch speed are the parameters): the artifact, a final
# design no worse than the initial one, the same result on 1 and 2 MPI
# ranks, a parameterized scene run directly by msfab-dynamics, and bad
# input (exit 2, nothing written).
BIN=$1 SRC=$(cd "$2" && pwd)
source "$SRC/tests/stage/lib.sh"
DESIGN=$BIN/msfab-jump-design

cat > "$WORK/throw.yaml" <<'YAML'
name: tiny-throw
parameters: {length: 0.010, vz: 0.5}
materials: [{name: m, E: 1.0e7, nu: 0.3, density: 1000, damping_a: 0, damping_b: 1.0e-3}]
geometry:
  voxel_size: 0.005
  boxes: [{material: m, min: [0, 0, 0], max: [length, 0.005, 0.005]}]
placement: {translation: [0, 0, 0.001]}
initial_velocity: [0.3, 0, vz]
obstacles: [{type: ground, z: 0}]
simulation: {time_step: 1.0e-3, duration: 0.4, impact: bbi, rigid_flight: {enabled: true}}
YAML
cat > "$WORK/design.yaml" <<YAML
scene: $WORK/throw.yaml
parameters:
  - {name: length, lower: 0.008, upper: 0.014, step: 0.002}
  - {name: vz, lower: 0.3, upper: 0.9, step: 0.1}
task: target
target_x: 0.05
measure: {settle: 0.002}
optimizer: {max_evaluations: 8, starts: 2}
YAML

check "one rank, two threads" -- "$DESIGN" --config "$WORK/design.yaml" --threads 2 --out "$WORK/one.h5" --quiet
check "artifact schema" -- bash -c "h5dump -a /schema '$WORK/one.h5' | grep -q msfab.jump_design"
check "every evaluation recorded" -- bash -c "h5dump -H -d /evaluations/parameters '$WORK/one.h5' | grep -Eq '\\( (9|1[0-6]), 2 \\)'"
check "initial design is the scene's" -- bash -c "h5dump -d /initial/parameters '$WORK/one.h5' | grep -q '0.01, 0.5'"
objective() { h5dump -a "/$2/objective" "$1" | awk '/\(0\)/ { print $2 }'; }
initial=$(objective "$WORK/one.h5" initial) final=$(objective "$WORK/one.h5" final)
echo "distance to target: initial $initial m, final $final m"
check "final design no worse than the initial one" -- awk -v a="$initial" -v b="$final" 'BEGIN { exit !(b <= a) }'
check "final design within 2 mm of the target" -- awk -v b="$final" 'BEGIN { exit !(b < 2e-3) }'
check "it landed" -- bash -c "h5dump -d /final/outcome '$WORK/one.h5' | grep -q '(0): 1, 1,'"

# The final design's whole run: a trajectory with the scene's ground, which
# passes through the centre of mass the search measured at the landing.
check "the final design's run is written beside the artifact" -- test -s "$WORK/one.final.trajectory.h5"
check "... and reproduces the landing the search measured" -- env PYTHONPATH="$SRC/python" PYTHONDONTWRITEBYTECODE=1 \
  /usr/bin/python3 -c "
import sys, h5py, numpy as np
d = h5py.File('$WORK/one.h5')
cols = d.attrs['outcome_columns']
cols = (cols.decode() if isinstance(cols, bytes) else cols).split(',')
o = dict(zip([c.strip() for c in cols], d['/final/outcome'][()]))
t = h5py.File('$WORK/one.final.trajectory.h5')
time, com = t['/samples/time'][()], t['/samples/center_of_mass'][()]
k = int(np.argmin(np.abs(time - o['landing_time'])))
ok = abs(time[k] - o['landing_time']) < 1e-12 and np.abs(com[k] - [o['com_landing_x'], o['com_landing_y'], o['com_landing_z']]).max() < 1e-12
ok = ok and time[-1] >= o['landing_time'] and len(t['/frames/time']) > 2
sys.exit(0 if ok else 1)"
check "python3 -m msfab strip draws it with the ground" -- bash -c "cd '$WORK' && env PYTHONPATH='$SRC/python' \
  PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 -m msfab strip one.final.trajectory.h5 strip.png --frames 5 | grep -q \"obstacles \\['ground'\\]\""
check "... as a PNG" -- bash -c "head -c 8 '$WORK/strip.png' | od -An -c | grep -q 'P   N   G'"
expect_exit 2 "--trajectory .*nowhere" -- "$DESIGN" --config "$WORK/design.yaml" --trajectory "$WORK/nowhere/x.h5" \
  --out "$WORK/bad.h5"

check "two ranks" -- mpirun -np 2 --oversubscribe -x OMP_NUM_THREADS=1 "$DESIGN" --config "$WORK/design.yaml" \
  --out "$WORK/two.h5" --quiet
same() {
  for d in /evaluations/start /evaluations/index /evaluations/parameters /evaluations/objective \
           /evaluations/outcome /final/parameters /final/outcome /initial/outcome; do
    [ "$(h5dump -d $d "$1" | tail -n +3)" = "$(h5dump -d $d "$2" | tail -n +3)" ] || { echo "differs: $d"; return 1; }
  done
}
check "1 and 2 ranks give identical evaluations and designs" -- same "$WORK/one.h5" "$WORK/two.h5"

# Stopped after three evaluations per start (a batch job's time limit) and
# resumed on two ranks: the recorded evaluations are replayed, not
# simulated, and the run ends where the uninterrupted one did.
expect_exit 0 "stopped after 3 new evaluations per start" -- "$DESIGN" --config "$WORK/design.yaml" --threads 2 \
  --max-new-evaluations 3 --out "$WORK/part.h5"
check "each start's checkpoint kept, no artifact yet" -- bash -c "[ -s '$WORK/part.h5.start0.checkpoint.h5' ] && \
  [ -s '$WORK/part.h5.start1.checkpoint.h5' ] && [ ! -e '$WORK/part.h5' ]"
expect_exit 2 "different configuration or seed" -- "$DESIGN" --config "$WORK/design.yaml" --seed 9 --resume \
  --out "$WORK/part.h5"
expect_exit 0 "start 0: resuming with 3 recorded evaluations" -- mpirun -np 2 --oversubscribe -x OMP_NUM_THREADS=1 \
  "$DESIGN" --config "$WORK/design.yaml" --resume --out "$WORK/part.h5"
check "the resumed run is the uninterrupted one" -- same "$WORK/one.h5" "$WORK/part.h5"
check "no checkpoint left" -- bash -c "! ls '$WORK'/part.h5.start*.checkpoint.h5 2> /dev/null"
expect_exit 2 "--max-new-evaluations = -1: must be >= 0" -- "$DESIGN" --config "$WORK/design.yaml" \
  --max-new-evaluations -1 --out "$WORK/bad.h5"

# Space-filling starts (the global stage): start k > 0 begins at the k-th
# Halton point of the box, bases 2 and 3: (1/2, 1/3), then (1/4, 2/3).
check "space-filling starts" -- "$DESIGN" --config "$WORK/design.yaml" --set optimizer.start_points=space_filling \
  --set optimizer.starts=3 --set optimizer.max_evaluations=1 --threads 2 --out "$WORK/halton.h5" --quiet
check "starts at the Halton points" -- bash -c "h5dump -d /evaluations/parameters '$WORK/halton.h5' | awk '
  /\\(0,0\\)/ { ok += (\$2 + 0 == 0.01 && \$3 + 0 == 0.5) }
  /\\(1,0\\)/ { ok += (\$2 - 0.011 < 1e-12 && 0.011 - \$2 < 1e-12 && \$3 - 0.5 < 1e-12 && 0.5 - \$3 < 1e-12) }
  /\\(2,0\\)/ { ok += (\$2 - 0.0095 < 1e-12 && 0.0095 - \$2 < 1e-12 && \$3 - 0.7 < 1e-12 && 0.7 - \$3 < 1e-12) }
  END { exit ok != 3 }'"
expect_exit 2 "start_points" -- "$DESIGN" --config "$WORK/design.yaml" --set optimizer.start_points=random --out "$WORK/bad.h5"

# A confirmation step: every evaluation runs again at another time step
# and scores the worse of the two, exactly the runs at each step alone.
# Aimed at x = 2 cm, the throw at 2.5e-3 s lands 0.3 mm further from it
# than at the scene's 1e-3 s, so the confirmation decides the score.
one_evaluation=(--set target_x=0.02 --set optimizer.max_evaluations=1 --set optimizer.starts=1 --quiet)
check "run at the scene's step" -- "$DESIGN" --config "$WORK/design.yaml" "${one_evaluation[@]}" --out "$WORK/at_h.h5"
check "run at 2.5e-3 s" -- "$DESIGN" --config "$WORK/design.yaml" \
  --set 'scene_set=["simulation.time_step=2.5e-3"]' "${one_evaluation[@]}" --out "$WORK/coarse.h5"
check "run at the scene's step, confirmed at 2.5e-3 s" -- "$DESIGN" --config "$WORK/design.yaml" \
  --set measure.confirm_time_step=2.5e-3 "${one_evaluation[@]}" --out "$WORK/confirm.h5"
full_objective() { h5dump -m %.17g -a "/$2/objective" "$1" | awk '/\(0\)/ { print $2 }'; }
at_h=$(full_objective "$WORK/at_h.h5" initial) at_coarse=$(full_objective "$WORK/coarse.h5" initial)
confirmed=$(full_objective "$WORK/confirm.h5" initial)
echo "distance to x = 2 cm: $at_h m at 1e-3 s, $at_coarse m at 2.5e-3 s, confirmed $confirmed m"
check "the confirmed objective is the worse of the two steps" -- \
  awk -v a="$at_h" -v b="$at_coarse" -v c="$confirmed" 'BEGIN { exit !(c == (a > b ? a : b) && b - a > 1e-4) }'
same_data() { [ "$(h5dump -d "$2" -A 0 "$1" | tail -n +3)" = "$(h5dump -d "$4" -A 0 "$3" | tail -n +3)" ]; }
check "the artifact keeps both runs" -- bash -c "$(declare -f same_data); \
  same_data '$WORK/coarse.h5' /evaluations/outcome '$WORK/confirm.h5' /evaluations/confirm_outcome && \
  same_data '$WORK/at_h.h5' /evaluations/outcome '$WORK/confirm.h5' /evaluations/outcome"
expect_exit 2 "measure.confirm_time_step = 0.001 s is the scene's own time step" -- \
  "$DESIGN" --config "$WORK/design.yaml" --set measure.confirm_time_step=1e-3 --out "$WORK/bad.h5"
expect_exit 2 "measure.confirm_time_step.*positive" -- \
  "$DESIGN" --config "$WORK/design.yaml" --set measure.confirm_time_step=-1e-3 --out "$WORK/bad.h5"

# Modulus factors: every evaluation also runs with the modulus times each
# factor and scores the worst of its runs, exactly the runs at each modulus
# alone. A tiny jumper (two plates and a flexure, pressed and released),
# whose turn in the air grows with its modulus: 18, 31 and 101 degrees at
# E x 0.8, 1 and 1.2.
cat > "$WORK/jumper.yaml" <<'YAML'
name: tiny-jumper
parameters: {length: 0.020, hinge_height: 0.010}
materials: [{name: m, E: 2.0e5, nu: 0.3, density: 1000, damping_a: 0, damping_b: 1.0e-3}]
geometry:
  voxel_size: 0.005
  boxes:
    - {material: m, min: [0, 0, 0], max: [length, 0.005, 0.005]}
    - {material: m, min: ["length - 0.005", 0, 0.005], max: [length, 0.005, "0.005 + hinge_height"]}
    - {material: m, min: [0, 0, "0.005 + hinge_height"], max: [length, 0.005, "0.010 + hinge_height"]}
obstacles: [{type: ground, z: 0}]
press:
  region: {min: [0, 0, "0.010 + hinge_height"], max: [0.005, 0.005, "0.010 + hinge_height"]}
  force: [0, 0, -0.05]
  steps: 4
  stop_at_touch: true
simulation: {time_step: 5.0e-4, duration: 0.4, impact: bbi, rigid_flight: {enabled: true}}
YAML
cat > "$WORK/flip.yaml" <<YAML
scene: $WORK/jumper.yaml
parameters:
  - {name: length, lower: 0.015, upper: 0.025, step: 0.005}
  - {name: hinge_height, lower: 0.005, upper: 0.015, step: 0.005}
task: flip
target_flip_deg: 0
measure: {settle: 0.002}
optimizer: {max_evaluations: 1, starts: 1}
YAML
for m in 0.8 1 1.2; do
  check "the tiny jumper at E x $m" -- "$DESIGN" --config "$WORK/flip.yaml" --set "scene_set=[\"modulus_scale=$m\"]" \
    --quiet --out "$WORK/modulus$m.h5"
done
check "the tiny jumper scored over E x 0.8 and 1.2, with print variation" -- "$DESIGN" --config "$WORK/flip.yaml" \
  --set 'measure.modulus_scales=[0.8, 1.2]' --set robustness.samples=3 --quiet --out "$WORK/scaled.h5"
check "... and without the factors" -- "$DESIGN" --config "$WORK/flip.yaml" --set robustness.samples=3 --quiet \
  --out "$WORK/unscaled.h5"
check "the objective is the worst of the three moduli, each run kept as it ran alone" -- env \
  PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 -c "
import sys, h5py, numpy as np
run = {m: h5py.File('$WORK/modulus%s.h5' % m) for m in ('0.8', '1', '1.2')}
s = h5py.File('$WORK/scaled.h5')
objective = {m: f['/evaluations/objective'][0] for m, f in run.items()}
print('turn at landing (deg):', {m: round(float(np.degrees(np.sqrt(o))), 1) for m, o in objective.items()})
ok = s['/evaluations/objective'][0] == max(objective.values()) and len(set(objective.values())) == 3
ok = ok and list(s['/evaluations'].attrs['modulus_scales']) == [0.8, 1.2]
for k, m in enumerate(('0.8', '1.2')):
    ok = ok and s['/evaluations/modulus_scale_objective'][0, k] == objective[m]
    ok = ok and np.array_equal(s['/evaluations/modulus_scale_outcome'][0, k], run[m]['/evaluations/outcome'][0])
ok = ok and np.array_equal(s['/evaluations/outcome'][0], run['1']['/evaluations/outcome'][0])
# Print-variation samples vary the modulus themselves: scored alone.
u = h5py.File('$WORK/unscaled.h5')
ok = ok and np.array_equal(s['/robustness/objective'][()], u['/robustness/objective'][()])
sys.exit(0 if ok else 1)"
expect_exit 2 "measure.modulus_scales.*factor 1 is the scene's own modulus" -- "$DESIGN" --config "$WORK/flip.yaml" \
  --set 'measure.modulus_scales=[0.8, 1]' --out "$WORK/bad.h5"
expect_exit 2 "measure.modulus_scales.*not in \(0, 10\]" -- "$DESIGN" --config "$WORK/flip.yaml" \
  --set 'measure.modulus_scales=[-0.5]' --out "$WORK/bad.h5"
expect_exit 2 "measure.modulus_scales.*listed twice" -- "$DESIGN" --config "$WORK/flip.yaml" \
  --set 'measure.modulus_scales=[0.8, 0.8]' --out "$WORK/bad.h5"

# The print variation in batches: stopped after two new samples (the search,
# one evaluation, finishes first), resumed on two ranks with the recorded
# samples read back, not simulated: the artifact of the uninterrupted run.
expect_exit 0 "print variation stopped after 2 new samples" -- "$DESIGN" --config "$WORK/flip.yaml" \
  --set robustness.samples=3 --max-new-evaluations 2 --out "$WORK/batch.h5"
check "samples 0 and 1 recorded, sample 2 not, no artifact yet" -- bash -c "[ -s '$WORK/batch.h5.sample0.checkpoint.h5' ] \
  && [ -s '$WORK/batch.h5.sample1.checkpoint.h5' ] && [ ! -e '$WORK/batch.h5.sample2.checkpoint.h5' ] && \
  [ ! -e '$WORK/batch.h5' ]"
expect_exit 0 "print variation: 2 of 3 samples recorded" -- mpirun -np 2 --oversubscribe -x OMP_NUM_THREADS=1 \
  "$DESIGN" --config "$WORK/flip.yaml" --set robustness.samples=3 --resume --out "$WORK/batch.h5"
check "the resumed samples are the uninterrupted run's" -- bash -c "$(declare -f same_data); for d in \
  /robustness/modulus_scale /robustness/parameters /robustness/objective /robustness/outcome /robustness/success \
  /evaluations/outcome; do same_data '$WORK/unscaled.h5' \$d '$WORK/batch.h5' \$d || exit 1; done"
check "no sample checkpoint left" -- bash -c "! ls '$WORK'/batch.h5.*checkpoint.h5 2> /dev/null"

# Print variation of the final design: the samples are recorded, do not
# depend on the rank count, and a throw that hits within 2 mm still hits
# within 1 cm with E +-20% and the length +-0.2 mm.
check "robustness, one rank" -- "$DESIGN" --config "$WORK/design.yaml" --set robustness.samples=4 --threads 2 \
  --out "$WORK/robust1.h5" --quiet
check "robustness, two ranks" -- mpirun -np 2 --oversubscribe -x OMP_NUM_THREADS=1 "$DESIGN" --config "$WORK/design.yaml" \
  --set robustness.samples=4 --out "$WORK/robust2.h5" --quiet
check "four samples recorded" -- bash -c "h5dump -H -d /robustness/parameters '$WORK/robust1.h5' | grep -q '( 4, 2 )'"
check "moduli varied within 20%" -- bash -c "h5dump -d /robustness/modulus_scale '$WORK/robust1.h5' | \
  awk '/\(0\)/ { for (i = 2; i <= NF; ++i) { x = \$i + 0; if (x < 0.8 || x > 1.2 || x == 1) bad = 1 } } END { exit bad }'"
check "every sample hits the target" -- bash -c "h5dump -a /robustness/success_fraction '$WORK/robust1.h5' | grep -q '(0): 1$'"
samples_same() {
  for d in /robustness/modulus_scale /robustness/parameters /robustness/success /robustness/outcome; do
    [ "$(h5dump -d $d "$1" | tail -n +3)" = "$(h5dump -d $d "$2" | tail -n +3)" ] || { echo "differs: $d"; return 1; }
  done
}
check "1 and 2 ranks give the same samples" -- samples_same "$WORK/robust1.h5" "$WORK/robust2.h5"
# The report draws the loop: every evaluation's objective, and the print
# variation's success fraction as the artifact stores it.
mkdir -p "$WORK/rep" && cp "$WORK/robust1.h5" "$WORK/rep/"
check "the report draws the design loop" -- env PYTHONPATH="$SRC/python" PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 -c "
import json, sys, h5py, numpy as np
from msfab.report import build_report
data = build_report(['$WORK/rep'], '$WORK/rep/report.html')
jump = [v for k, v in data.items() if k.endswith('jump_robust1.png')]
f = h5py.File('$WORK/robust1.h5')
ok = len(jump) == 1 and np.array_equal(jump[0]['objective'], f['/evaluations/objective'][()]) \
    and jump[0]['success_fraction'] == f['/robustness'].attrs['success_fraction']
sys.exit(0 if ok else 1)"
# A given design checked without a search: meshed at voxel-aligned
# reference values, morphed to the design.
check "a given design on its reference mesh" -- "$DESIGN" --config "$WORK/design.yaml" \
  --set 'scene_set=["parameters.length=0.0137", "reference_parameters.length=0.010"]' \
  --set optimizer.max_evaluations=1 --set optimizer.starts=1 --set robustness.samples=2 --out "$WORK/given.h5" --quiet
check "the given design is the one evaluated" -- bash -c "h5dump -d /final/parameters '$WORK/given.h5' | grep -q '0.0137, 0.5'"
expect_exit 2 "one simulation of 2 elements per thread \(2 threads\) needs about .*, more than the 64 kiB of --memory-limit" -- \
  "$DESIGN" --config "$WORK/design.yaml" --threads 2 --memory-limit 64K --out "$WORK/big.h5"
check "the refused design loop writes nothing" -- test ! -e "$WORK/big.h5"
expect_exit 2 "robustness.modulus.*must be in \[0, 1\)" -- \
  "$DESIGN" --config "$WORK/design.yaml" --set robustness.modulus=1.5 --out "$WORK/bad.h5"
expect_exit 2 "modulus_scale.*must be positive" -- "$BIN/msfab-dynamics" --config "$WORK/throw.yaml" \
  --set modulus_scale=0 --out "$WORK/bad.h5"

# The parameterized scene runs directly, with overrides of its parameters.
check "msfab-dynamics runs a parameterized scene" -- "$BIN/msfab-dynamics" --config "$WORK/throw.yaml" \
  --set parameters.length=0.015 --set simulation.duration=0.01 --out "$WORK/direct.h5" --quiet

# Bad input: exit 2, nothing written.
sed -e 's/max: \[length,/max: ["lenght + 0.001",/' "$WORK/throw.yaml" > "$WORK/typo.yaml"
sed -e "s|$WORK/throw.yaml|$WORK/typo.yaml|" "$WORK/design.yaml" > "$WORK/typo_design.yaml"
expect_exit 2 "typo.yaml: geometry.boxes\[0\].max\[0\] = \"lenght \+ 0.001\": unknown parameter 'lenght'" -- \
  "$DESIGN" --config "$WORK/typo_design.yaml" --out "$WORK/bad.h5"
expect_exit 2 "parameters\[1\].upper.*must exceed lower" -- \
  "$DESIGN" --config "$WORK/design.yaml" --set 'parameters[1].upper=0.2' --out "$WORK/bad.h5"
expect_exit 2 "'width' is not a parameter" -- \
  "$DESIGN" --config "$WORK/design.yaml" --set 'parameters[0].name=width' --out "$WORK/bad.h5"
expect_exit 2 "corner of the bounds.*change order" -- \
  "$DESIGN" --config "$WORK/design.yaml" --set 'parameters[0].lower=-0.001' --out "$WORK/bad.h5"
expect_exit 2 "measure.body = cube: the scene .* has no body of that name" -- \
  "$DESIGN" --config "$WORK/design.yaml" --set 'measure.body=cube' --out "$WORK/bad.h5"
expect_exit 2 "unknown parameter 'lenght'" -- "$BIN/msfab-dynamics" --config "$WORK/typo.yaml" --out "$WORK/bad.h5"
check "failed runs leave nothing" -- bash -c "! ls '$WORK'/bad.h5* 2> /dev/null"
finish
