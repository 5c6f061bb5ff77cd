#!/bin/bash
# msfab-families and msfab-family-generate (thesis §3.3, Appendix A):
#  (a) two hand-made families (a body-centred lattice and a cubic frame, 30
#      members each) are found again: two families, each exactly one
#      template's members, each template fitted with one beam;
#  (b) structures generated along a family's first reduced parameter are
#      cubic-symmetric (the generator refuses otherwise) and their
#      homogenized Young's modulus moves the way the artifact predicts;
#  (c) bad input exits 2 naming the file or key, and writes nothing.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
F="$BIN/msfab-families" G="$BIN/msfab-family-generate"

check "two hand-made families" -- "$G" --config "$SRC/configs/families/two_templates.yaml" \
  --out "$WORK/two.microstructures.h5" --quiet
S="$WORK/two.microstructures.h5"
A=(--structures "$S" --set 'selection.nu=[-1,0.5]' --set min_members=10)
out=$("$F" "${A[@]}" --out "$WORK/two.families.h5" 2>&1)
echo "$out" | grep -v refitting
check "(a) two families" -- grep -q "60 structures selected, 60 embedded .*, 2 clusters, 2 families of >= 10 members" <<<"$out"
labels=$(h5dump -d /clusters/label "$WORK/two.families.h5" | sed -n '/DATA {/,/}/p' | sed 's/([0-9]*)://g' |
  tr -cs '0-9' '\n' | grep -E '^[0-9]+$' | paste -sd' ')
echo "labels: $labels"
first=$(cut -d' ' -f1-30 <<<"$labels" | tr ' ' '\n' | sort -u | paste -sd' ')
second=$(cut -d' ' -f31-60 <<<"$labels" | tr ' ' '\n' | sort -u | paste -sd' ')
check "(a) the lattice's members form one cluster" -- test "$(wc -w <<<"$first")" = 1
check "(a) the frame's members form one cluster" -- test "$(wc -w <<<"$second")" = 1
check "(a) the two clusters differ" -- test "$first" != "$second"
check "(a) each family has 30 members and a one-beam template" -- \
  test "$(grep -cE '^  family [12]: 30 members, .*template 1 beams' <<<"$out")" = 2
check "(a) a picture per family" -- test -s "$WORK/two.plots/family1.png" -a -s "$WORK/two.plots/family2.png" -a \
  ! -e "$WORK/two.plots/family3.png"
# The report's families page (python/msfab/report.py) draws what the
# artifact holds, with the input set's properties found through provenance.
check "(a) the report draws the families and their properties" -- env PYTHONPATH="$SRC/python:$SRC/tests/stage" \
  PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 - "$WORK" <<'PY'
import json, subprocess, sys
import h5py
import matplotlib.image
work = sys.argv[1]
subprocess.run([sys.executable, "-m", "msfab", "report", f"{work}/families_report.html", f"{work}/two.families.h5"],
               check=True, stdout=subprocess.DEVNULL)
from expectations import expect, finish
data = json.load(open(f"{work}/families_report_files/data.json"))
name = next(n for n in data if "families_two" in n)
with h5py.File(f"{work}/two.families.h5") as f:
    expect("selected structures", data[name]["selected"] == len(f["/selection"]))
    expect("families", data[name]["families"] == int(f.attrs["families"]) == 2)
image = matplotlib.image.imread(f"{work}/families_report_files/{name}")
expect("three panels (the input set was found)", image.shape[1] > 2.5 * image.shape[0])
expect("the table names both families", open(f"{work}/families_report.html").read().count("<td>30</td>") >= 2)
finish()
PY

# Memory (docs/cli.md): the distance matrices refused up front under a small limit.
expect_exit 2 "distances between 60 selected structures needs about .*, more than the 1 MiB of --memory-limit" -- \
  "$F" "${A[@]}" --memory-limit 1M --out "$WORK/small.families.h5"
check "the refused run writes nothing" -- test ! -e "$WORK/small.families.h5"

# (b) Three structures along r1 of family 1: E must follow the predicted slope.
gen=$("$G" --families "$WORK/two.families.h5" --family 1 --reduced=-1,0 --reduced=0,0 --reduced=1,0 \
  --out "$WORK/gen.microstructures.h5" 2>&1)
echo "$gen"
slope=$(grep -oE 'r1: dlog10E [-+][0-9.]+' <<<"$gen" | awk '{print $3}')
E=($(grep -oE 'E/E_stiff [0-9.e+-]+' <<<"$gen" | awk '{print $2}'))
check "(b) three homogenized structures" -- test "${#E[@]}" = 3
check "(b) r1 moves E as predicted (slope $slope; E ${E[*]})" -- awk -v s="$slope" -v a="${E[0]}" -v b="${E[1]}" \
  -v c="${E[2]}" 'BEGIN { exit !((s > 0 && a < b && b < c) || (s < 0 && a > b && b > c)) }'
check "(b) a sweep at 24^3" -- "$G" --families "$WORK/two.families.h5" --family 2 --sweep 3 --set resolution=24 \
  --set homogenize=false --out "$WORK/sweep.microstructures.h5" --quiet
check "(b) sweep written" -- bash -c "h5dump -a /schema '$WORK/sweep.microstructures.h5' | grep -q msfab.microstructures"

# (c) Bad input.
B="$WORK/bad.families.h5"
expect_exit 2 "no structure lies in the selection" -- "$F" --structures "$S" --set 'selection.nu=[-1,-0.9]' --out "$B"
expect_exit 2 "the selection holds 60 structures; family discovery needs at least min_members = 100" -- \
  "$F" "${A[@]}" --set min_members=100 --out "$B"
cat > "$WORK/flat.yaml" <<'Y'
space: cubic2d
resolution: 8
materials: {stiff: {E: 1.0e6, nu: 0.3}}
population: 6
cycles: 1
continuous: {per_cycle: 0}
level_set: {cells: 6}
Y
check "a 2D gamut" -- "$BIN/msfab-gamut-sample" --config "$WORK/flat.yaml" --out "$WORK/flat.gamut.h5" --quiet
expect_exit 2 "flat.microstructures.h5: attribute 'space' is 'cubic2d'; family discovery needs a 3D cubic set" -- \
  "$F" --structures "$WORK/flat.microstructures.h5" --out "$B"
expect_exit 2 "selection.nu = .*must be \[low, high\]" -- "$F" --structures "$S" --set 'selection.nu=[0.5,-1]' --out "$B"
expect_exit 2 "selection.boundary_margin = .*needs --gamut" -- "$F" "${A[@]}" --set selection.boundary_margin=0.1 --out "$B"
expect_exit 2 "expected schema 'msfab.microstructures'" -- "$F" --structures "$WORK/two.families.h5" --out "$B"
expect_exit 2 "unknown key 'neighbors'.*did you mean 'neighbours'" -- "$F" "${A[@]}" --set isomap.neighbors=4 --out "$B"
check "nothing written on bad input" -- test ! -e "$B"
BG="$WORK/bad.microstructures.h5"
expect_exit 2 "--family 3: .*holds 2 families" -- "$G" --families "$WORK/two.families.h5" --family 3 --out "$BG"
expect_exit 2 "reduced parameter 1 is 2.*must lie in \[-1, 1\]" -- "$G" --families "$WORK/two.families.h5" --family 1 \
  --reduced 2,0 --out "$BG"
expect_exit 2 "--reduced 0,x: 'x' is not a number" -- "$G" --families "$WORK/two.families.h5" --family 1 --reduced 0,x --out "$BG"
expect_exit 2 "nothing to generate" -- "$G" --out "$BG"
expect_exit 2 "templates\[0\].beams\[0\].r0 .*" -- "$G" --set 'templates=[{beams: [{a: [0,0,0], b: [0.5,0,0], r0: -1, r1: 0.1}]}]' --out "$BG"
check "nothing written on bad input" -- test ! -e "$BG"
finish
