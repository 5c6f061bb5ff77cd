#!/usr/bin/env bash
# The finite-strain check of a family's members (thesis §3.3: linear
# elasticity against Neo-Hookean at up to 7% strain, Poisson's ratio 16% off
# on average): every member of family F of a families artifact, as a cell
# of its microstructures set with the set's material as Neo-Hookean, under
# uniaxial stress at -7 ... +7% (docs/homogenization.md, "Finite-strain
# check").
#
#   bash tools/bench_finite_strain.sh BIN STRUCTURES FAMILIES [FAMILY] [OUT]
#
# Prints a Markdown table: per member the linear nu (C^H), the secant nu at
# -7% and +7%, their relative differences, and whether Newton had to shift
# the Hessian (a hinge, or buckling); then the mean relative difference.
set -euo pipefail
BIN=$1 STRUCTURES=$2 FAMILIES=$3 FAMILY=${4:-0} OUT=${5:-out/bench/finite_strain}
mkdir -p "$OUT"
export OMP_WAIT_POLICY=PASSIVE
members=$(h5dump -d "/families/$FAMILY/members" "$FAMILIES" | sed -n '/DATA {/,/}/p' | tr -d '(){}DATA' |
  sed 's/[0-9]*://g' | tr ',' ' ')
echo "| member | linear nu | nu at -7% | nu at +7% | diff at -7% | diff at +7% | Hessian shifted | s |"
echo "|---|---|---|---|---|---|---|---|"
sum=0 count=0
for m in $members; do
  cat > "$OUT/member$m.yaml" <<Y
cell: {structures: $(realpath "$STRUCTURES"), index: $m}
finite_strain: {strains: [-0.07, 0.07]}
Y
  t0=$(date +%s.%N)
  if ! log=$("$BIN/msfab-homogenize" --config "$OUT/member$m.yaml" --out "$OUT/member$m.h5" --quiet 2>&1); then
    echo "| $m | | | | | | failed: $(echo "$log" | grep -o 'error: .*' | head -1) | |"
    continue
  fi
  seconds=$(echo "$(date +%s.%N) - $t0" | bc -l)
  row=$(echo "$log" | awk -v m="$m" -v s="$seconds" '
    /linear C\^H/ { for (i = 1; i <= NF; ++i) if ($i ~ /^nu_/) { lin = $(i + 1); sub(",", "", lin); break } }
    /^ +-0\.0700/ { nm = $2; dm = $4; if (index($0, "shifted")) sh = sh "-7% " }
    /^ +\+0\.0700/ { np = $2; dp = $4; if (index($0, "shifted")) sh = sh "+7% " }
    END { printf "| %d | %s | %s | %s | %s | %s | %s | %.1f |\n", m, lin, nm, np, dm, dp, (sh == "" ? "no" : sh), s }')
  echo "$row"
  for d in $(echo "$row" | awk -F'|' '{ gsub("%", "", $6); gsub("%", "", $7); print $6, $7 }'); do
    sum=$(echo "$sum + $d" | bc -l) count=$((count + 1))
  done
done
[ "$count" -gt 0 ] && printf "\nmean relative difference of nu at +-7%%: %.1f%% over %d values\n" "$(echo "$sum / $count" | bc -l)" "$count"
