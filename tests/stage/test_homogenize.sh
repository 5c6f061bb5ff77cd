#!/bin/bash
# msfab-homogenize: the default cubic frame, a voxel file, thread-count
# independence, the multigrid solver, batch mode over a microstructures
# artifact, the finite-strain check, and bad input (exit 2 naming the problem).
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
H="$BIN/msfab-homogenize"

expect_exit 0 "cubic: E .* G' 0\.1" -- "$H" --out "$WORK/frame.h5"
check "artifact schema" -- bash -c "h5dump -a /schema '$WORK/frame.h5' | grep -q msfab.homogenized"
check "same tensor on 1 and 2 threads" -- bash -c \
  "'$H' --threads 1 --out '$WORK/t1.h5' --quiet && '$H' --threads 2 --out '$WORK/t2.h5' --quiet &&
   h5diff -q '$WORK/t1.h5' '$WORK/t2.h5' /C /C"

# A voxel file of one material: C^H is that material (E 1e6, nu 0.3).
{ echo "2 2 2"; echo "1 1 1 1 1 1 1 1"; } > "$WORK/solid.txt"
cat > "$WORK/file.yaml" <<'Y'
materials:
  - {id: 1, model: linear, E: 1.0e6, nu: 0.3}
cell: {voxels: solid.txt}
Y
expect_exit 0 "cubic: E 1e\+06, nu 0\.300000" -- "$H" --config "$WORK/file.yaml" --out "$WORK/solid.h5"

# A 2D cell (one voxel along z): plane strain, Ex = E / (1 - nu^2).
{ echo "2 2 1"; echo "1 1 1 1"; } > "$WORK/flat.txt"
sed 's/solid.txt/flat.txt/' "$WORK/file.yaml" > "$WORK/flat.yaml"
expect_exit 0 "2D plane strain: Ex 1\.0989e\+06" -- "$H" --config "$WORK/flat.yaml" --out "$WORK/flat.h5"
check "2D tensor written" -- bash -c "h5dump -H -d /C2 '$WORK/flat.h5' | grep -q '( 3, 3 )'"

# The matrix-free multigrid solver on the default frame at 24^3 agrees with CHOLMOD.
expect_exit 0 "matrix-free multigrid: [0-9]+ CG iterations" -- "$H" --set cell.size='[24, 24, 24]' \
  --set linear_solver=matrix-free --out "$WORK/mg.h5"
check "cholmod at 24^3" -- "$H" --set cell.size='[24, 24, 24]' --set linear_solver=cholmod --out "$WORK/direct.h5" --quiet
check "matrix-free and cholmod tensors agree to 1e-2 Pa (C ~ 1e5 Pa)" -- h5diff -q --delta=1e-2 "$WORK/mg.h5" "$WORK/direct.h5" /C /C
check "the artifact names the solver" -- bash -c "h5dump -a /solver '$WORK/mg.h5' | grep -q '\"matrix-free\"'"
# The earlier names (solver: multigrid, multigrid_tolerance) still read, with a
# warning naming the key to write, and give the same bits.
expect_exit 0 "solver is an earlier name; write linear_solver" -- "$H" --set cell.size='[24, 24, 24]' \
  --set solver=multigrid --set multigrid_tolerance=1e-6 --out "$WORK/mg_old.h5"
check "earlier names, same tensor bit for bit" -- h5diff -q "$WORK/mg.h5" "$WORK/mg_old.h5" /C /C
expect_exit 2 "solver = multigrid: is the earlier name of linear_solver; give only one of them" -- "$H" --set solver=multigrid \
  --set linear_solver=cholmod --out "$WORK/bad.h5"
expect_exit 2 "linear_solver = pcg: linear solver 'pcg' is unknown here; choose one of auto, cholmod, matrix-free" -- \
  "$H" --set linear_solver=pcg --out "$WORK/bad.h5"
expect_exit 2 "linear_max_iterations = 0: must be at least 1" -- "$H" --set linear_max_iterations=0 --out "$WORK/bad.h5"
expect_exit 3 "periodic multigrid CG did not converge.* set by linear_max_iterations" -- "$H" --set cell.size='[24, 24, 24]' \
  --set linear_solver=matrix-free --set linear_max_iterations=2 --set use_symmetry=false --out "$WORK/bad.h5"
# The frame is mirror-symmetric: solved on one octant, the same tensor as the whole cell.
check "the frame is solved on one octant" -- bash -c "h5dump -a /domain '$WORK/frame.h5' | grep -q octant"
check "use_symmetry: false solves the whole cell" -- bash -c \
  "'$H' --set use_symmetry=false --out '$WORK/whole.h5' --quiet && h5dump -a /domain '$WORK/whole.h5' | grep -q '\"cell\"'"
check "octant and whole cell agree to 1e-3 Pa" -- h5diff -q --delta=1e-3 "$WORK/frame.h5" "$WORK/whole.h5" /C /C
expect_exit 2 "solver matrix-free needs every cell dimension even" -- "$H" --set cell.size='[12, 12, 9]' \
  --set linear_solver=matrix-free --out "$WORK/bad.h5"

# Batch mode: a small 3D set from the sampler, homogenized again.
cat > "$WORK/set.yaml" <<'Y'
space: cubic3d
resolution: 8
materials:
  stiff: {E: 1.0e6, nu: 0.3}
population: 6
cycles: 1
initial_beams: 2
beams: {max: 1, min_radius: 0.5, max_radius: 1.2}
continuous: {per_cycle: 0}
level_set: {cells: 6}
Y
check "a small 3D set" -- "$BIN/msfab-gamut-sample" --config "$WORK/set.yaml" --seed 3 --out "$WORK/set.gamut.h5" --quiet
expect_exit 0 "change of C\^H against the input: median 0\.000e\+00, max 0\.000e\+00" -- \
  "$H" --structures "$WORK/set.microstructures.h5" --out "$WORK/same.microstructures.h5"
check "same solver, same tensors and properties" -- bash -c "h5diff -q '$WORK/set.microstructures.h5' '$WORK/same.microstructures.h5' /C /C &&
  h5diff -q '$WORK/set.microstructures.h5' '$WORK/same.microstructures.h5' /properties /properties"
expect_exit 0 "structures of 16 x 16 x 16 voxels \(matrix-free\)" -- "$H" --structures "$WORK/set.microstructures.h5" \
  --set refine=2 --set linear_solver=matrix-free --threads 1 --out "$WORK/fine1.microstructures.h5"
check "refined cells are stored (16^3 voxels, one bit each)" -- bash -c "h5dump -H -d /voxels '$WORK/fine1.microstructures.h5' | grep -q ', 512 )'"
check "refined set, threads inside each solve" -- "$H" --structures "$WORK/set.microstructures.h5" \
  --set refine=2 --set linear_solver=matrix-free --threads 8 --out "$WORK/fine8.microstructures.h5" --quiet
check "1 and 8 threads give the same refined set" -- h5diff -q "$WORK/fine1.microstructures.h5" "$WORK/fine8.microstructures.h5" /C /C
expect_exit 2 "batch mode .* drop it" -- "$H" --structures "$WORK/set.microstructures.h5" --set 'materials=[]' --out "$WORK/bad.h5"
expect_exit 2 "refine.*must be 1..16" -- "$H" --structures "$WORK/set.microstructures.h5" --set refine=0 --out "$WORK/bad.h5"
expect_exit 2 "missing.h5" -- "$H" --structures "$WORK/missing.h5" --out "$WORK/bad.h5"
expect_exit 2 "msfab.microstructures" -- "$H" --structures "$WORK/frame.h5" --out "$WORK/bad.h5"

# The finite-strain check: a Neo-Hookean frame of bars (void between) under
# uniaxial stress; at 1e-4 strain its Poisson ratio is C^H's.
cat > "$WORK/nh.yaml" <<'Y'
materials:
  - {id: 1, model: neo-hookean, E: 1.0e6, nu: 0.3}
cell: {size: [12, 12, 12]}
layout:
  - {box: {min: [0, 0.333, 0.333], max: [1, 0.667, 0.667]}, id: 1}
  - {box: {min: [0.333, 0, 0.333], max: [0.667, 1, 0.667]}, id: 1}
  - {box: {min: [0.333, 0.333, 0], max: [0.667, 0.667, 1]}, id: 1}
finite_strain: {strains: [0.0001, -0.07, 0.07], axis: y}
Y
expect_exit 0 "finite strain, uniaxial stress along y" -- "$H" --config "$WORK/nh.yaml" --out "$WORK/nh.h5"
check "at strain 1e-4 nu is C^H's (0.0% off)" -- bash -c "'$H' --config '$WORK/nh.yaml' --out '$WORK/nh2.h5' | grep -E '^ +\+0\.0001 .* 0\.0%'"
check "finite-strain results stored" -- bash -c "h5dump -H -d /finite_strain/nu '$WORK/nh.h5' | grep -q '( 3, 2 )'"
expect_exit 2 "finite_strain.strains.*nonzero" -- "$H" --config "$WORK/nh.yaml" --set 'finite_strain.strains=[0]' --out "$WORK/bad.h5"
expect_exit 2 "finite_strain.*needs a 3D cell" -- "$H" --config "$WORK/flat.yaml" --set 'finite_strain={strains: [0.01]}' \
  --out "$WORK/bad.h5"
# One structure of a gamut's set as the cell, with the set's material as Neo-Hookean.
cat > "$WORK/member.yaml" <<Y
cell: {structures: $WORK/set.microstructures.h5, index: 0}
finite_strain: {strains: [-0.05]}
Y
expect_exit 0 "finite strain, uniaxial stress along x" -- "$H" --config "$WORK/member.yaml" --out "$WORK/member.h5"
check "the member's result names the set as its input" -- bash -c "h5dump -a /inputs '$WORK/member.h5' | grep -q set.microstructures.h5"
expect_exit 2 "cell.index.*must be in 0\.\." -- "$H" --config "$WORK/member.yaml" --set cell.index=100000 --out "$WORK/bad.h5"
expect_exit 2 "materials.*come from cell.structures" -- "$H" --config "$WORK/member.yaml" --set 'materials=[]' --out "$WORK/bad.h5"

# Bad input.
{ echo "2 2 2"; echo "1 1 1 1 1 1 1"; } > "$WORK/short.txt"
sed 's/solid.txt/short.txt/' "$WORK/file.yaml" > "$WORK/short.yaml"
expect_exit 2 "short.txt: 7 voxel ids for a 2 x 2 x 2 cell" -- "$H" --config "$WORK/short.yaml" --out "$WORK/bad.h5"
{ echo "2 2 2"; echo "0 0 0 0 0 0 0 0"; } > "$WORK/void.txt"
sed 's/solid.txt/void.txt/' "$WORK/file.yaml" > "$WORK/void.yaml"
expect_exit 2 "all void" -- "$H" --config "$WORK/void.yaml" --out "$WORK/bad.h5"
{ echo "2 2 2"; echo "1 1 1 1 1 1 1 x"; } > "$WORK/text.txt"
sed 's/solid.txt/text.txt/' "$WORK/file.yaml" > "$WORK/text.yaml"
expect_exit 2 "text.txt: line 2: 'x' is not an integer" -- "$H" --config "$WORK/text.yaml" --out "$WORK/bad.h5"
{ echo "2 2 2"; echo "1 1 1 1 1 1 1 3"; } > "$WORK/id3.txt"
sed 's/solid.txt/id3.txt/' "$WORK/file.yaml" > "$WORK/id3.yaml"
expect_exit 2 "material id 3, which is not defined" -- "$H" --config "$WORK/id3.yaml" --out "$WORK/bad.h5"
expect_exit 2 "either cell.voxels .* or a layout" -- "$H" --config "$WORK/file.yaml" --set 'layout=[{fill: 1}]' --out "$WORK/bad.h5"
expect_exit 2 "nu.*Poisson" -- "$H" --set 'materials[0].nu=0.5' --out "$WORK/bad.h5"
expect_exit 2 "unknown key 'void_stifness'" -- "$H" --set void_stifness=1e-3 --out "$WORK/bad.h5"
check "nothing written on bad input" -- test ! -e "$WORK/bad.h5"
finish
