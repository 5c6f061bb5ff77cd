#!/bin/bash
# The quasistatic press against dynamic loading (thesis App. B.3): each
# scene's press solved by the quasistatic contact solver, and the same load
# applied in a dynamic run (press.mode: dynamic, ramped on over RAMP s and
# held until the Rayleigh damping has taken the motion out). Prints, per
# scene, the Hausdorff distance and elastic-energy difference between the
# two pressed states and the wall-time ratio (tools/compare_press.py), at
# the end of the run and at half of it.
#
#   tools/bench_press.sh build/bin out/bench/press
#   DURATION=0.01 tools/bench_press.sh ...   # a quick check of the script
#   ONLY=jumper_touching tools/bench_press.sh ...   # one scene of the list
set -euo pipefail
source "$(dirname "$0")/dac_bench_lib.sh"
bench_folders "${1:-build/bin}" "${2:-out/bench/press}"
H=${TIME_STEP:-1e-4} RAMP=${RAMP:-0.05} DURATION=${DURATION:-0.2}
PY=/usr/bin/python3
common=(--threads 1 --quiet --set "simulation.time_step=$H" --set simulation.rigid_flight.enabled=false)
# name | config | extra --set arguments (separated by ';') | for the
# quasistatic press only | for the dynamic run only
SCENES=(
  "flipper_jumper|flipper_jumper.yaml|"
  "flipper_short_low|flipper_param.yaml|parameters.length=0.034;parameters.hinge_height=0.006;press.force=[0, 0, -2]"
  "jumper_touching|jumper_over.yaml|parameters.length=0.050;parameters.hinge_height=0.004|press.stop_at_touch=false;press.self_contact=true|simulation.body_contact=true"
  "soft_block|block_drop_face.yaml|materials[0].E=2e6;geometry.voxel_size=0.0025;placement.translation=[0, 0, 0];press={region: {min: [0, 0, 0.01], max: [0.005, 0.01, 0.01]}, force: [0.3, 0, -3]}"
)
as_args() {  # as_args 'k=v;k=v': prints --set k=v, one per line
  local pairs kv
  IFS=';' read -r -a pairs <<<"$1"
  for kv in "${pairs[@]}"; do [ -n "$kv" ] && printf '%s\n' --set "$kv"; done
  return 0
}
for entry in "${SCENES[@]}"; do
  IFS='|' read -r scene file sets qs_sets dynamic_sets <<<"$entry"
  [ -z "${ONLY:-}" ] || [ "$ONLY" = "$scene" ] || continue
  cfg=$SRC/configs/dynamics/$file
  mapfile -t extra < <(as_args "$sets")
  mapfile -t qs_extra < <(as_args "${qs_sets:-}")
  mapfile -t dynamic_extra < <(as_args "${dynamic_sets:-}")
  qs=$("$BIN/msfab-dynamics" --config "$cfg" "${common[@]}" "${extra[@]}" "${qs_extra[@]}" --set "simulation.duration=$H" \
    --out "${scene}_qs.h5")
  # A press that stops at touch (press.stop_at_touch) ends at a fraction of
  # its load; the dynamic run gets that fraction.
  load=()
  percent=$(sed -n 's/.*stopped at touch: \([0-9.e+-]*\)% of the load.*/\1/p' <<<"$qs")
  if [ -n "$percent" ]; then
    force=$(sed -n 's/.*press\.force=\[\([^]]*\)\].*/\1/p' <<<"$sets")
    [ -n "$force" ] || { echo "$scene: a press that stops at touch needs its press.force in the scene list" >&2; exit 1; }
    scaled=$(awk -v p="$percent" -v f="$force" 'BEGIN { n = split(f, c, ","); s = "";
      for (i = 1; i <= n; ++i) s = s (i > 1 ? ", " : "") c[i] * p / 100; print "[" s "]" }')
    load=(--set "press.force=$scaled")
    echo "== $scene: the quasistatic press stopped at touch at $percent% of its load; dynamic load $scaled N"
  fi
  "$BIN/msfab-dynamics" --config "$cfg" "${common[@]}" "${extra[@]}" "${dynamic_extra[@]}" "${load[@]}" --set press.stop_at_touch=false \
    --set press.mode=dynamic --set "press.ramp_time=$RAMP" --set "simulation.duration=$DURATION" \
    --out "${scene}_dynamic.h5" > /dev/null
  echo "== $scene (h = $H s, ramp $RAMP s)"
  $PY "$SRC/tools/compare_press.py" "${scene}_qs.h5" "${scene}_dynamic.h5"
  $PY "$SRC/tools/compare_press.py" "${scene}_qs.h5" "${scene}_dynamic.h5" --at "$(awk -v d="$DURATION" 'BEGIN { print d / 2 }')"
done
