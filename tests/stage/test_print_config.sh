#!/bin/bash
# --print-config on every stage that runs on built-in defaults: exit 0, the
# effective config on stdout (the file, --set overrides, and the defaults
# the stage read written in), nothing at --out; the printed config read back
# prints the same config; an unknown key is still refused.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

for stage in simulate dynamics topopt gamut-sample homogenize ddfem-build family-generate dac-calibrate; do
  exe="$BIN/msfab-$stage"
  check "$stage --print-config exits 0" -- "$exe" --print-config --out "$WORK/$stage.h5"
  "$exe" --print-config --out "$WORK/$stage.h5" > "$WORK/$stage.yaml"
  check "$stage --print-config writes nothing at --out" -- test ! -e "$WORK/$stage.h5"
  check "$stage --print-config starts with its header" -- grep -q "^# effective config: <built-in defaults of msfab-$stage>" "$WORK/$stage.yaml"
  # Read back: nothing left to fill in, and the same values.
  "$exe" --print-config --config "$WORK/$stage.yaml" > "$WORK/$stage.again.yaml"
  check "$stage: the printed config prints back unchanged" -- \
    diff <(grep -v '^#' "$WORK/$stage.yaml") <(grep -v '^#' "$WORK/$stage.again.yaml")
  check "$stage: read back, no default is left to fill in" -- bash -c "! grep -q 'defaults filled in' '$WORK/$stage.again.yaml'"
done

# Defaults and overrides appear where the stage reads them.
"$BIN/msfab-dynamics" --print-config --set simulation.edge_contact=false > "$WORK/dyn.yaml"
check "dynamics: an override is printed" -- grep -q "edge_contact: false" "$WORK/dyn.yaml"
check "dynamics: a default is listed" -- grep -q "^#   simulation.newton_tolerance = 1e-09$" "$WORK/dyn.yaml"
expect_exit 2 "unknown key 'edge_contacts'" -- "$BIN/msfab-dynamics" --print-config --set simulation.edge_contacts=false
finish
