#!/bin/bash
# msfab-homogenize: the default cubic frame, a voxel file, thread-count
# independence, and bad input (exit 2 naming the problem).
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
