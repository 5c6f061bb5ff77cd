#!/bin/bash
# Contact between and within bodies, what the additions of 2026-11-28 cost
# and change:
#  1. edge-edge contact on the catapult (simulation.edge_contact on / off):
#     the cube's apex, first touch-down, end position and time per step;
#  2. the quasistatic press with self-contact against press.stop_at_touch on
#     jump-over jumpers whose top plate meets the base before the full
#     1.2 N: share of the load carried, elastic energy at release, ties and
#     preload time.
# Prints markdown tables. Times are one thread each, runs one after another.
#
#   tools/bench_contact.sh build/bin out/bench/contact
#   PRESS_SETS="0.050:0.004" tools/bench_contact.sh ...   # length:hinge_height pairs
set -euo pipefail
source "$(dirname "$0")/dac_bench_lib.sh"
bench_folders "${1:-build/bin}" "${2:-out/bench/contact}"
PRESS_SETS=${PRESS_SETS:-"0.050:0.004 0.050:0.002 0.054:0.002"}

first_sample() {  # first_sample FILE DATASET: its first value
  h5dump -d "$2" -s 0 -c 1 "$1" | awk '/\(0\):/ { print $2; exit }'
}

echo "### Edge-edge contact on the catapult"
echo
echo "| edge contact | cube apex (m) | first touch-down (s) | cube at the end (m) | rotation at the end | ms per step | Newton iterations per step |"
echo "|---|---|---|---|---|---|---|"
for edges in true false; do
  log=catapult_edges_$edges.txt
  "$BIN/msfab-dynamics" --config "$SRC/configs/dynamics/catapult.yaml" --threads 1 --quiet \
    --set simulation.edge_contact=$edges --out catapult_edges_$edges.h5 > "$log"
  apex=$(sed -n 's/.*body cube.*highest z \([0-9.e+-]*\) m.*/\1/p' "$log")
  touch=$(awk '/event contact/ { n++; if (n == 2) { print $5; exit } }' "$log")
  end=$(sed -n 's/.*body cube.*end (\([^)]*\)).*/\1/p' "$log")
  rot=$(sed -n 's/.*rotation at the end: \([0-9.e+-]*\) deg.*/\1/p' "$log")
  per=$(sed -n 's/.*(\([0-9.]*\) Newton iterations, \([0-9.]*\) ms each).*/\2/p' "$log")
  its=$(sed -n 's/.*(\([0-9.]*\) Newton iterations, \([0-9.]*\) ms each).*/\1/p' "$log")
  echo "| $edges | $apex | $touch | ($end) | $rot° | $per | $its |"
done
echo
echo "### The press with self-contact against stop_at_touch (jumper_over.yaml, 1.2 N)"
echo
echo "| length, hinge height (m) | press | load carried | elastic energy at release (J) | ties | preload (s) |"
echo "|---|---|---|---|---|---|"
for pair in $PRESS_SETS; do
  length=${pair%:*} hinge=${pair#*:}
  for mode in stop_at_touch self_contact; do
    if [ $mode = self_contact ]; then extra=(--set press.stop_at_touch=false --set press.self_contact=true); else extra=(); fi
    log=press_${length}_${hinge}_$mode.txt
    "$BIN/msfab-dynamics" --config "$SRC/configs/dynamics/jumper_over.yaml" --threads 1 --quiet "${extra[@]}" \
      --set parameters.length=$length --set parameters.hinge_height=$hinge --set simulation.duration=0.0005 \
      --out press_${length}_${hinge}_$mode.h5 > "$log"
    share=$(sed -n 's/.*stopped at touch: \([0-9.e+-]*\)% of the load.*/\1/p' "$log")
    ties=$(awk '/self-contact ties/ { for (i = 1; i <= NF; ++i) if ($i == "self-contact") print $(i - 1) }' "$log")
    seconds=$(sed -n 's/.*time: preload \([0-9.]*\) s.*/\1/p' "$log")
    energy=$(first_sample press_${length}_${hinge}_$mode.h5 /samples/elastic)
    echo "| $length, $hinge | $mode | ${share:-100}% | $energy | ${ties:-–} | $seconds |"
  done
done
