#!/bin/bash
# Topology-optimization benchmarks (docs/BENCHMARKS.md, "Topology optimization"):
#  1. the 2D cantilever of Fig. 3-16 (left side clamped, load on the right
#     half of the bottom) in every material space that needs no sampled gamut,
#     plus cubic2d / orthotropic2d / isotropic2d when gamut artifacts are given:
#       CUBIC2D=out/gamut/cubic2d.gamut.h5 ORTHO2D=out/gamut/orthotropic2d.gamut.h5 tools/bench_topopt.sh
#  2. time per FEM solve (assembly + factorization + solve) on 3D grids.
# Usage: tools/bench_topopt.sh [build-dir]
set -euo pipefail
BIN=${1:-build}/bin
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
NX=${NX:-64} NY=${NY:-32}
scene=(--set "grid.size=[$NX,$NY]" --set "supports=[{box: {min: [0, 0], max: [0, $NY]}}]"
       --set "loads=[{name: bottom, objective: compliance, forces: [{box: {min: [$((NX / 2)), 0], max: [$NX, 0]}, force: [0, -1], distribute: total}]}]"
       --set mass.volume_fraction=0.5 --set filter.radius=1.5 --set material.E=1.0e6 --set material.nu=0.3)
row() {  # name, extra args...
  local name=$1; shift
  local out; out=$("$BIN/msfab-topopt" "${scene[@]}" "$@" --out "$W/$name.design.h5" --quiet 2>&1)
  local c it t v
  c=$(grep -oE "load case bottom: compliance [0-9.e+-]+" <<<"$out" | awk '{print $5}')
  it=$(grep -oE "after [0-9]+ iterations" <<<"$out" | awk '{print $2}')
  t=$(grep -oE "evaluations\), [0-9.]+ s" <<<"$out" | awk '{print $2}')
  v=$(grep -oE "max constraint [0-9.e+-]+" <<<"$out" | awk '{print $3}')
  printf "| %s | %s | %s | %s | %s |\n" "$name" "$c" "$it" "$t" "$v"
}
echo "### Cantilever ${NX}x${NY}, volume fraction 0.5, E0 1e6, filter 1.5 ($(date -u +%F), $(nproc) cores)"
echo
echo "| space | final compliance | iterations | seconds | max constraint |"
echo "|---|---|---|---|---|"
row simp-p3 --set space=simp2d --set material.penalty=3
row simp-p1 --set space=simp2d --set material.penalty=1
row simp-p3-ipopt --set space=simp2d --set material.penalty=3 --set optimizer.name=ipopt
row analytic --set space=analytic2d
[ -n "${CUBIC2D:-}" ] && row cubic --set space=cubic2d --set gamut="$CUBIC2D"
[ -n "${CUBIC2D:-}" ] && row isotropic --set space=isotropic2d --set gamut="$CUBIC2D"
[ -n "${ORTHO2D:-}" ] && row orthotropic --set space=orthotropic2d --set gamut="$ORTHO2D"
echo
echo "### Time per FEM solve on 3D grids (SIMP, one OC step)"
echo
echo "| cells | unknowns | solver | seconds per assembly+factorization+solve |"
echo "|---|---|---|---|"
for g in "96 24 4" "64 32 8" "128 64 32"; do
  set -- $g
  for solver in cholmod pcg-mg; do
    [ "$1" = 128 ] && [ "$solver" = cholmod ] && continue
    out=$("$BIN/msfab-topopt" --set "grid.size=[$1,$2,$3]" --set space=simp3d \
      --set "supports=[{box: {min: [0, 0, 0], max: [0, $2, $3]}}]" \
      --set "loads=[{objective: compliance, forces: [{box: {min: [$1, 0, 0], max: [$1, $2, 0]}, force: [0, 0, -1], distribute: total}]}]" \
      --set solver=$solver --set optimizer.max_iterations=1 --out "$W/g.design.h5" --quiet 2>&1)
    s=$(grep -oE "[0-9.]+ s per factorization\+solve" <<<"$out" | awk '{print $1}')
    printf "| %sx%sx%s | %s | %s | %s |\n" "$1" "$2" "$3" $((3 * ($1 + 1) * ($2 + 1) * ($3 + 1))) "$solver" "$s"
  done
done
