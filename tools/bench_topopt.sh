#!/bin/bash
# Topology-optimization benchmarks (docs/BENCHMARKS.md, "Topology optimization"):
#  1. the 2D cantilever of Fig. 3-16 (left side clamped, load on the right
#     half of the bottom) in every material space that needs no sampled gamut,
#     plus cubic2d / orthotropic2d / isotropic2d when gamut artifacts are given:
#       CUBIC2D=out/gamut/cubic2d.gamut.h5 ORTHO2D=out/gamut/orthotropic2d.gamut.h5 tools/bench_topopt.sh
#     (CANTILEVER_ONLY=1 stops after this table)
#  2. time per FEM solve on 3D grids (bench_grid_solver: cholmod, pcg-mg and
#     matrix-free side by side; LARGEST="nx ny nz" adds a matrix-free row for
#     a bigger grid) and per optimizer step (STEP_LARGE=1 adds 320x160x80).
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
  st=$(grep -E "^msfab-topopt: .* after [0-9]+ iterations" <<<"$out" | sed -E 's/^msfab-topopt: (.*) after [0-9]+ iterations.*/\1/')
  printf "| %s | %s | %s | %s | %s | %s |\n" "$name" "$c" "$it" "$st" "$t" "$v"
}
# A 2D gamut's structures are homogenized in plane strain: its rows compare
# with SIMP on the same solid (docs/topopt.md, material.plane).
strain=(--set material.plane=strain)
long=(--set optimizer.max_iterations=${GAMUT_MAX_ITERATIONS:-2000})
echo "### Cantilever ${NX}x${NY}, volume fraction 0.5, E0 1e6, filter 1.5 ($(date -u +%F), $(nproc) cores)"
echo
echo "| space | final compliance | iterations | status | seconds | max constraint |"
echo "|---|---|---|---|---|---|"
row simp-p3 --set space=simp2d --set material.penalty=3
row simp-p1 --set space=simp2d --set material.penalty=1
row simp-p3-ipopt --set space=simp2d --set material.penalty=3 --set optimizer.name=ipopt
row analytic --set space=analytic2d
if [ -n "${CUBIC2D:-}${ORTHO2D:-}" ]; then
  row simp-p3-plane-strain --set space=simp2d --set material.penalty=3 "${strain[@]}"
  row simp-p1-plane-strain --set space=simp2d --set material.penalty=1 "${strain[@]}"
fi
[ -n "${CUBIC2D:-}" ] && row cubic --set space=cubic2d --set gamut="$CUBIC2D" "${long[@]}"
[ -n "${CUBIC2D:-}" ] && row cubic-no-bound --set space=cubic2d --set gamut="$CUBIC2D" --set gamut_bound=none "${long[@]}"
[ -n "${CUBIC2D:-}" ] && row isotropic --set space=isotropic2d --set gamut="$CUBIC2D" "${long[@]}"
[ -n "${ORTHO2D:-}" ] && row orthotropic --set space=orthotropic2d --set gamut="$ORTHO2D" "${long[@]}"
# Fig. 3-16's order with Ipopt on one orthotropic gamut (see the cell MMA
# rows below for the cubic2d_slice space), against SIMP with Ipopt.
if [ -n "${ORTHO2D:-}" ]; then
  ip=(--set optimizer.name=ipopt "${long[@]}" "${strain[@]}")
  row simp-p3-ipopt-plane-strain --set space=simp2d --set material.penalty=3 "${ip[@]}"
  row simp-p1-ipopt-plane-strain --set space=simp2d --set material.penalty=1 "${ip[@]}"
  row cubic-slice --set space=cubic2d_slice --set gamut="$ORTHO2D" "${ip[@]}"
  row orthotropic-from-slice --set space=orthotropic2d --set gamut="$ORTHO2D" \
    --set initial.design="$W/cubic-slice.design.h5" "${ip[@]}"
fi
# Fig. 3-16's order with one optimizer and one regularization for every
# space: cell MMA, which smooths the gradient (docs/topopt.md).
if [ -n "${CUBIC2D:-}${ORTHO2D:-}" ]; then
  # A constraint tolerance well below the rows' differences (the default
  # 1e-3 of the unit cube is about 1% in a modulus).
  cm=(--set optimizer.name=cell-mma "${long[@]}" "${strain[@]}" --set optimizer.constraint_tolerance=1e-5)
  row simp-p3-cell-mma --set space=simp2d --set material.penalty=3 "${cm[@]}"
  row simp-p1-cell-mma --set space=simp2d --set material.penalty=1 "${cm[@]}"
  [ -n "${CUBIC2D:-}" ] && row cubic-cell-mma --set space=cubic2d --set gamut="$CUBIC2D" "${cm[@]}"
  [ -n "${CUBIC2D:-}" ] && row isotropic-cell-mma --set space=isotropic2d --set gamut="$CUBIC2D" "${cm[@]}"
  [ -n "${ORTHO2D:-}" ] && row orthotropic-cell-mma --set space=orthotropic2d --set gamut="$ORTHO2D" "${cm[@]}"
  # Both spaces on the one orthotropic gamut: the cubic cells are its slice
  # Ex = Ey (space cubic2d_slice), a subset of the orthotropic feasible set
  # by construction; the orthotropic run then starts from the slice optimum.
  if [ -n "${ORTHO2D:-}" ]; then
    row cubic-slice-cell-mma --set space=cubic2d_slice --set gamut="$ORTHO2D" "${cm[@]}"
    row orthotropic-from-slice-cell-mma --set space=orthotropic2d --set gamut="$ORTHO2D" \
      --set initial.design="$W/cubic-slice-cell-mma.design.h5" "${cm[@]}"
  fi
fi
[ -n "${CANTILEVER_ONLY:-}" ] && exit 0
echo
echo "### Time per FEM solve on 3D grids (SIMP cantilever)"
echo
echo "bench_grid_solver: set-up (assembly + factorization, or the multigrid hierarchy) and one solve,"
echo "CG tolerance 1e-8; f.u is the compliance (equal across solvers to the CG tolerance)."
echo
echo "| cells | unknowns | solver | density | set-up s | solve s | CG iterations | peak MB | f.u |"
echo "|---|---|---|---|---|---|---|---|---|"
for g in "96 24 4" "64 32 8" "128 64 32" "320 160 80" ${LARGEST:+"$LARGEST"}; do
  set -- $g
  for solver in cholmod pcg-mg matrix-free; do
    [ "$1" -ge 128 ] && [ "$solver" = cholmod ] && continue
    [ "$1" -ge 320 ] && [ "$solver" = pcg-mg ] && continue
    for field in uniform random; do
      [ "$1" -gt 320 ] && [ "$field" = random ] && continue
      "$BIN/bench_grid_solver" "$1" "$2" "$3" "$solver" "$field"
    done
  done
done
echo
echo "### Time per optimizer step (msfab-topopt, SIMP/OC, solver auto, 3 iterations)"
echo
echo "| cells | solver | seconds per OC iteration | FEM seconds per solve | CG iterations per solve | peak MB |"
echo "|---|---|---|---|---|---|"
for g in "96 24 4" "64 32 8" "128 64 32" ${STEP_LARGE:+"320 160 80"}; do
  set -- $g
  log=$(/usr/bin/time -f "peak %M" "$BIN/msfab-topopt" --set "grid.size=[$1,$2,$3]" --set space=simp3d \
    --set "supports=[{box: {min: [0, 0, 0], max: [0, $2, $3]}}]" \
    --set "loads=[{objective: compliance, forces: [{box: {min: [$1, 0, 0], max: [$1, $2, 0]}, force: [0, 0, -1], distribute: total}]}]" \
    --set optimizer.max_iterations=3 --out "$W/g.design.h5" --quiet 2>&1)
  total=$(grep -oE "evaluations\), [0-9.]+ s" <<<"$log" | awk '{print $2}')
  solver=$(grep -oE "solves \([a-z-]+\)" <<<"$log" | tr -d '()' | awk '{print $2}')
  fem=$(grep -oE "[0-9.]+ s per factorization\+solve" <<<"$log" | awk '{print $1}')
  cg=$(grep -oE "CG iterations per solve: [0-9.]+" <<<"$log" | awk '{print $5}')
  peak=$(grep -oE "peak [0-9]+" <<<"$log" | awk '{print int($2 / 1024)}')
  printf "| %sx%sx%s | %s | %.2f | %s | %s | %s |\n" "$1" "$2" "$3" "$solver" "$(awk -v t="$total" 'BEGIN { print t / 3 }')" "$fem" "${cg:--}" "$peak"
done
