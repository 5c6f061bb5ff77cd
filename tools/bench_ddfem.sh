#!/bin/bash
# DDFEM speed-versus-error benchmark, the analogue of thesis Table 2.2 (with
# the assembly / solve split of Table 2.3 and the CG-iteration comparison of
# Figure 2-13). Every scene is solved fine once; each coarse run is compared
# with that fine result (msfab-simulate --reference), so all numbers of one
# row come from the same run of this script.
#
#   tools/bench_ddfem.sh BIN OUTDIR BENCHMARKS.md DATABASE [scene ...]
# DATABASE: a level-1 coarse_db of the scenes' palette (E = 1e5, 1e6, 1e7,
# nu = 0.45), e.g. from `make -f Makefile.pipeline ddfem-db-level1`;
# DATABASE2 (environment, optional): a level-2 coarse_db of the same palette
# (`ddfem-db-level2`), without it level 2 has only the baselines. DDFEM_ARGS
# (environment, optional): more msfab-simulate arguments of the DDFEM runs
# (e.g. "--coarse-fallback galerkin --coarse-check 0.1"). BENCH_SECTION
# (environment, default ddfem) names the section of BENCHMARKS.md written. A run that
# does not converge within BENCH_RUN_LIMIT seconds (default 900) is "failed".
set -euo pipefail
BIN=$1 OUTDIR=$2 DOC=$3 DB=$4
shift 4
SCENES=("$@")
DB2=${DATABASE2:-}
read -r -a DDFEM_ARG_LIST <<< "${DDFEM_ARGS:-}"
[ ${#SCENES[@]} -gt 0 ] || SCENES=(pushing bending bending_uniform twisting buckling fibers bridge bridge_arch layers1 checker random3 skeleton sole holes3)
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUTDIR"

source "$SRC/tools/simulate_bench_lib.sh"
grid_of() {  # the grid size as NxMxK from a result
  h5dump -a /grid/size "$1" | sed -n 's/^ *(0): *//p' | head -n1 | tr -d ' ' | tr ',' 'x'
}
mean_linear_its() {  # mean CG iterations per Newton iteration
  h5dump -d /newton/linear_iterations "$1" | sed -n 's/^ *([0-9]*): *//p' | tr ',' '\n' |
    awk 'NF { s += $1; n++ } END { printf "%.0f", n ? s / n : 0 }'
}

rows="" cg_rows="" direct_rows=""
for scene in "${SCENES[@]}"; do
  cfg="$SRC/configs/scenes/$scene.yaml"
  echo "bench: $scene fine ..." >&2
  fine="$OUTDIR/$scene-L0.h5"
  run "$fine" --config "$cfg"
  f_tot=$(attr "$fine" /timings newton_total) f_its=$(attr "$fine" /newton iterations)
  f_asm=$(attr "$fine" /timings assembly) f_sol=$(attr "$fine" /timings solve)
  rows+=$(awk -v s="$scene" -v g="$(grid_of "$fine")" -v d="$(attr "$fine" / dofs)" -v t="$f_tot" -v i="$f_its" \
    -v a="$f_asm" -v b="$f_sol" \
    'BEGIN { printf "| %s | 0 | %s | %d | 1.0 | %.3f | %d | %.3f | %.3f | — | — | — | — |\n", s, g, d, t/i, i, a/i, b/i }')
  rows+=$'\n'
  for level in 1 2; do
    declare -A err=() tot=() its=() asm=() sol=() crs=()
    db=$DB
    [ "$level" = 2 ] && db=$DB2
    for m in ddfem naive averaged; do
      if [ "$m" = ddfem ] && [ -z "$db" ]; then continue; fi
      out="$OUTDIR/$scene-L$level-$m.h5"
      echo "bench: $scene level $level $m ..." >&2
      extra=()
      [ "$m" = ddfem ] && extra=("${DDFEM_ARG_LIST[@]}")
      if ! run "$out" --config "$cfg" --coarsen "$level" --coarse-material "$m" ${db:+--database "$db"} "${extra[@]}" \
        --reference "$fine"; then
        # A baseline that does not converge is a result too (the naive
        # model is pathologically stiff); the row says so.
        err[$m]=nan tot[$m]=nan its[$m]=0 asm[$m]=nan sol[$m]=nan crs[$m]=nan dofs[$level]=0
        continue
      fi
      err[$m]=$(attr "$out" /coarsening error_vs_fine)
      tot[$m]=$(attr "$out" /timings newton_total) its[$m]=$(attr "$out" /newton iterations)
      asm[$m]=$(attr "$out" /timings assembly) sol[$m]=$(attr "$out" /timings solve)
      crs[$m]=$(attr "$out" /coarsening seconds)
      dofs[$level]=$(attr "$out" / dofs)
    done
    # The speed columns are DDFEM's; naive coarsening's where there is no
    # database of that level (marked).
    k=ddfem mark=""
    [ -z "$db" ] && k=naive mark="*"
    rows+=$(awk -v s="$scene" -v L="$level$mark" -v d="${dofs[$level]}" -v ft="$f_tot" -v t="${tot[$k]}" -v i="${its[$k]}" \
      -v a="${asm[$k]}" -v b="${sol[$k]}" -v ed="${err[ddfem]:-}" -v en="${err[naive]}" -v ea="${err[averaged]}" \
      -v c="${crs[$k]}" -v g="$(awk -v l=$level -v s="$(grid_of "$fine")" 'BEGIN { split(s, n, "x"); f = 2^l;
          printf "%dx%dx%d", int((n[1]+f-1)/f), int((n[2]+f-1)/f), int((n[3]+f-1)/f) }')" \
      'function e(x) { return x == "" ? "—" : (x == "nan" ? "failed" : sprintf("%.2e", x)) }
       BEGIN { if (i == 0) { printf "| %s | %s | %s | — | failed | — | — | — | — | %s | %s | %s | — |\n", s, L, g, e(ed), e(en), e(ea); exit }
               printf "| %s | %s | %s | %d | %.1f | %.3f | %d | %.3f | %.3f | %s | %s | %s | %.2f |\n",
               s, L, g, d, ft/t, t/i, i, a/i, b/i, e(ed), e(en), e(ea), 1e3*c }')
    rows+=$'\n'
    unset err tot its asm sol crs
  done
  # The thesis's set-up: a direct solver at both levels (fine meshes small
  # enough for CHOLMOD only).
  if [ "$scene" != fibers ] && [ "$scene" != buckling ]; then
    echo "bench: $scene with CHOLMOD at both levels ..." >&2
    run "$OUTDIR/$scene-direct-L0.h5" --config "$cfg" --set solver.linear_solver=cholmod
    run "$OUTDIR/$scene-direct-L1.h5" --config "$cfg" --set solver.linear_solver=cholmod --coarsen 1 --database "$DB" \
      "${DDFEM_ARG_LIST[@]}"
    d0=$(attr "$OUTDIR/$scene-direct-L0.h5" /timings newton_total) d1=$(attr "$OUTDIR/$scene-direct-L1.h5" /timings newton_total)
    i0=$(attr "$OUTDIR/$scene-direct-L0.h5" /newton iterations) i1=$(attr "$OUTDIR/$scene-direct-L1.h5" /newton iterations)
    direct_rows+=$(awk -v s="$scene" -v a="$d0" -v b="$d1" -v i="$i0" -v j="$i1" \
      'BEGIN { printf "| %s | %.3f | %d | %.3f | %d | %.1f |\n", s, a/i, i, b/j, j, a/b }')
    direct_rows+=$'\n'
  fi
  # Figure 2-13: Jacobi-preconditioned CG, fine against DDFEM level 1.
  if [ "$scene" != fibers ] && [ "$scene" != buckling ]; then
    echo "bench: $scene CG iterations ..." >&2
    run "$OUTDIR/$scene-cg-L0.h5" --config "$cfg" --set solver.linear_solver=pcg
    run "$OUTDIR/$scene-cg-L1.h5" --config "$cfg" --set solver.linear_solver=pcg --coarsen 1 --database "$DB" \
      "${DDFEM_ARG_LIST[@]}"
    cg_rows+="| $scene | $(mean_linear_its "$OUTDIR/$scene-cg-L0.h5") | $(mean_linear_its "$OUTDIR/$scene-cg-L1.h5") |"$'\n'
  fi
done

star_note=""
[ -n "$DB2" ] || star_note="\* level 2 without a level-2 database: speed columns are naive coarsening's."
machine="$(lscpu | sed -n 's/^Model name: *//p' | head -n1), $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB"
table="Measured $(date -u +%Y-%m-%d) on $machine, OMP_NUM_THREADS=${OMP_NUM_THREADS:-all}, revision $(git -C "$SRC" rev-parse --short HEAD 2>/dev/null || echo unknown), databases $(basename "$DB")${DB2:+ (level 1) and $(basename "$DB2") (level 2)}${DDFEM_ARGS:+, DDFEM runs with $DDFEM_ARGS}.

| scene | level | grid | DOFs | speedup | s/it | its | assembly s/it | solve s/it | DDFEM error | naive error | averaged error | coarsening ms |
|---|---|---|---|---|---|---|---|---|---|---|---|---|
${rows}
${star_note}
Speed columns use the default linear solver (\`auto\`: CHOLMOD below 4 000 DOFs, pcg-mg above).

The thesis's set-up, a direct solver (CHOLMOD) at both levels:

| scene | fine s/it | fine its | DDFEM level 1 s/it | its | speedup |
|---|---|---|---|---|---|
${direct_rows}

Jacobi-preconditioned CG iterations per Newton iteration (Figure 2-13):

| scene | fine | DDFEM level 1 |
|---|---|---|
${cg_rows}"
python3 "$SRC/tools/replace_bench_section.py" "$DOC" "${BENCH_SECTION:-ddfem}" "$table"
echo "bench: table written to $DOC" >&2
