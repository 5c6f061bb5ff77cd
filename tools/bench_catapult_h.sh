#!/bin/bash
# The catapult's throw against the time step (docs/dynamics.md, "Choosing
# h"): configs/dynamics/catapult.yaml at h = 2e-4 ... 2.5e-5 s (event
# substeps with SUBSTEPS), one thread each, runs one after another. Prints a
# markdown table: the cube's apex, the time it first touches the table
# after the launch, its centre of mass mid-flight (t = 0.1 s) and at that
# touch-down, Newton steps and time per step. Needs python3 with h5py
# (PYTHON=... to name another).
#
#   tools/bench_catapult_h.sh build/bin out/bench/catapult_h
#   STEPS="1e-4 5e-5" SUBSTEPS="0 3" tools/bench_catapult_h.sh ...   # with event substeps too
set -euo pipefail
source "$(dirname "$0")/dac_bench_lib.sh"
bench_folders "${1:-build/bin}" "${2:-out/bench/catapult_h}"
STEPS=${STEPS:-"2e-4 1e-4 5e-5 2.5e-5"}
SUBSTEPS=${SUBSTEPS:-0}

echo "| h (s) | event substeps | cube apex (m) | first touch-down (s) | cube centre at 0.1 s (mm) | cube centre at touch-down (mm) | elastic steps | ms per step | wall (s) |"
echo "|---|---|---|---|---|---|---|---|---|"
for levels in $SUBSTEPS; do
  for h in $STEPS; do
    log=catapult_h${h}_L$levels.txt
    start=$(date +%s.%N)
    "$BIN/msfab-dynamics" --config "$SRC/configs/dynamics/catapult.yaml" --threads 1 --quiet \
      --set simulation.time_step=$h --set simulation.event_substeps=$levels \
      --out catapult_h${h}_L$levels.h5 > "$log"
    wall=$(echo "$(date +%s.%N) - $start" | bc)
    apex=$(sed -n 's/.*body cube.*highest z \([0-9.e+-]*\) m.*/\1/p' "$log")
    # Touch-down: the first force-carrying contact after 20 ms of flight
    # (the cube rests in the basket at the start and may graze it as it
    # leaves), from the samples, which count touches inside event substeps.
    read -r touch centres < <("${PYTHON:-python3}" - catapult_h${h}_L$levels.h5 <<'PY'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    t = f["/samples/time"][:]
    active = f["/samples/active_contacts"][:]
    cube = f["/samples/body_center_of_mass"][:, 3:6] * 1e3
down = int(np.argmax((t > 0.02) & (active > 0)))
def at(i):
    return ", ".join(f"{cube[i, k]:.2f}" for k in range(3))
print(f"{t[down]:.5f} ({at(int(np.argmin(abs(t - 0.1))))}) | ({at(down)})")
PY
)
    steps=$(sed -n 's/^ *\([0-9][0-9]*\) elastic steps.*/\1/p' "$log")
    per=$(sed -n 's/.*(\([0-9.]*\) Newton iterations, \([0-9.]*\) ms each).*/\2/p' "$log")
    printf '| %s | %s | %s | %s | %s | %s | %s | %.0f |\n' "$h" "$levels" "$apex" "$touch" "$centres" "$steps" "$per" "$wall"
  done
done
