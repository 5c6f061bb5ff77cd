#!/bin/bash
# The flipper jumper's take-off against the time step, uniform and with
# event substeps (simulation.event_substeps: steps with a contact event
# retaken as halves down to h / 2^L): turn about y at 20 ms and at
# touch-down, touch-down time and place, the centre-of-mass velocity after
# the push-off (2.5 ms) and after the edge strike (5 ms), Newmark steps
# and run time. One thread per run, runs one after another.
#
#   tools/bench_takeoff.sh build/bin out/bench/takeoff
#   RUNS="1e-4:0 1e-4:3" tools/bench_takeoff.sh ...   # h:levels pairs
# Needs python3 with h5py and numpy (PYTHON=... to name another).
set -euo pipefail
source "$(dirname "$0")/dac_bench_lib.sh"
bench_folders "${1:-build/bin}" "${2:-out/bench/takeoff}"
RUNS=${RUNS:-"1e-4:0 5e-5:0 2.5e-5:0 1.25e-5:0 1e-4:1 1e-4:2 1e-4:3 1e-4:4 1e-4:5 1e-4:6"}

echo "| h | event substeps | turn at 20 ms | turn at touch-down | touch-down time | COM x at touch-down | COM velocity at 2.5 ms | at 5 ms | Newmark steps | run time |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for run in $RUNS; do
  h=${run%:*} levels=${run#*:}
  name=flipper_${h}_$levels
  start=$(date +%s.%N)
  "$BIN/msfab-dynamics" --config "$SRC/configs/dynamics/flipper_jumper.yaml" --threads 1 --quiet \
    --set simulation.time_step=$h --set simulation.event_substeps=$levels --out $name.h5 > $name.txt
  seconds=$(echo "$(date +%s.%N) - $start" | bc)
  "${PYTHON:-python3}" - "$name.h5" "$h" "$levels" "$seconds" <<'EOF'
import sys
import h5py
import numpy as np
path, h, levels, seconds = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
with h5py.File(path, "r") as f:
    t = f["/samples/time"][:]
    com = f["/samples/center_of_mass"][:]
    vel = f["/samples/com_velocity"][:]
    turn = np.degrees(np.unwrap(f["/samples/rotation"][:, 1]))
    kinds = f["/events"].attrs["kind"]
    kinds = (kinds.decode() if isinstance(kinds, bytes) else kinds).split("\n")
    times = f["/events/time"][:]
    steps = int(f.attrs["elastic_steps"]) if "elastic_steps" in f.attrs else -1
# Touch-down: the first contact after the body has left the ground.
lifted = [tt for k, tt in zip(kinds, times) if k == "lift-off"]
landing = [tt for k, tt in zip(kinds, times) if k == "contact" and lifted and tt > lifted[0] + 0.01]
at = lambda when: int(np.argmin(np.abs(t - when)))
down = landing[0] if landing else float("nan")
i_down = at(down) if landing else None
v25, v5 = vel[at(0.0025)], vel[at(0.005)]
print(f"| {h} s | {levels} | {turn[at(0.020)]:.2f}° | "
      + (f"{turn[i_down]:.2f}° | {down:.4f} s | {1e3 * com[i_down, 0]:.2f} mm" if landing else "– | – | –")
      + f" | ({v25[0]:.4f}, {v25[2]:.4f}) m/s | ({v5[0]:.4f}, {v5[2]:.4f}) | {steps} | {seconds:.1f} s |")
EOF
done
