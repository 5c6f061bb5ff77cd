#!/bin/bash
# msfab-simulate on the demo scene: a complete artifact, a ParaView sidecar,
# and the same answer for any thread count.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
SIM="$BIN/msfab-simulate"
CFG="$SRC/configs/scenes/demo_bar.yaml"

expect_exit 0 "converged in" -- "$SIM" --config "$CFG" --out "$WORK/t1.h5" --threads 1
expect_exit 0 "ParaView: .*t2.xmf" -- "$SIM" --config "$CFG" --out "$WORK/t2.h5" --threads 2
expect_exit 0 "schema +msfab.result v1" -- "$BIN/msfab-inspect" "$WORK/t1.h5" --schema msfab.result
check "sidecar points at the artifact" -- grep -q 't2.h5:/displacement' "$WORK/t2.xmf"
check "sidecar has hexahedra" -- grep -q 'Hexahedron' "$WORK/t2.xmf"
# Assembly is bitwise independent of the thread count; the factorization's
# BLAS may round differently, so compare to far below the solver tolerance.
check "1 and 2 threads agree" -- h5diff --delta=1e-13 "$WORK/t1.h5" "$WORK/t2.h5" /displacement /displacement
check "resolved config stored" -- bash -c "h5dump -a /config '$WORK/t1.h5' | grep -q 'demo-bar'"
check "no NaN in the displacement" -- bash -c "! h5dump -d /displacement '$WORK/t1.h5' | grep -qi nan"
# The linear solver is a choice, not a result: PCG reaches the same answer.
expect_exit 0 "converged in" -- "$SIM" --config "$CFG" --out "$WORK/pcg.h5" --set solver.linear_solver=pcg \
  --set solver.pcg_preconditioner=block-jacobi3 --set solver.linear_tolerance=1e-10
check "pcg and cholmod agree" -- h5diff --relative=1e-5 "$WORK/t1.h5" "$WORK/pcg.h5" /displacement /displacement
expect_exit 0 "converged in" -- "$SIM" --config "$CFG" --out "$WORK/mg.h5" --set solver.linear_solver=pcg-mg \
  --set solver.linear_tolerance=1e-10
check "pcg-mg and cholmod agree" -- h5diff --relative=1e-5 "$WORK/t1.h5" "$WORK/mg.h5" /displacement /displacement
# The earlier key names still read, with a warning, to the same bits.
expect_exit 0 "solver.pcg_tolerance is an earlier name; write solver.linear_tolerance" -- "$SIM" --config "$CFG" \
  --out "$WORK/mg_old.h5" --set solver.linear_solver=pcg-mg --set solver.pcg_tolerance=1e-10
check "earlier key names, same displacements bit for bit" -- h5diff "$WORK/mg.h5" "$WORK/mg_old.h5" /displacement /displacement
expect_exit 3 "did not converge.*iteration limit 3 set by solver.linear_max_iterations" -- "$SIM" --config "$CFG" \
  --out "$WORK/bad.h5" --set solver.linear_solver=pcg --set solver.linear_max_iterations=3 --set solver.max_step_halvings=0
finish
