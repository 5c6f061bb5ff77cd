#!/bin/bash
# msfab-simulate refuses bad input with exit 2 and a message naming the
# file, field and problem, and never destroys an existing output.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
SIM="$BIN/msfab-simulate"
BASE="$SRC/configs/scenes/demo_bar.yaml"

# A variant of the demo scene with one edit (python-free: sed on a copy).
variant() {  # variant NAME SED-EXPRESSION
  sed -e "$2" "$BASE" > "$WORK/$1.yaml"
  echo "$WORK/$1.yaml"
}

expect_exit 2 "no such file" -- "$SIM" --config "$WORK/missing.yaml" --out "$WORK/o.h5"
printf 'grid: {size: [4, 4\nmaterials: [\n' > "$WORK/malformed.yaml"
expect_exit 2 "malformed.yaml.*line" -- "$SIM" --config "$WORK/malformed.yaml" --out "$WORK/o.h5"
expect_exit 2 "unknown key 'nmae'" -- "$SIM" --config "$(variant typo 's/^name:/nmae:/')" --out "$WORK/o.h5"
expect_exit 2 "missing required list 'materials'" -- "$SIM" --config "$(variant typo2 's/^materials:/materails:/')" --out "$WORK/o.h5"
expect_exit 2 "materials\[0\]\.E.*(positive|> 0)" -- "$SIM" --config "$(variant negE 's/E: 1.0e5/E: -1.0e5/')" --out "$WORK/o.h5"
expect_exit 2 "materials\[1\]\.nu.*Poisson" -- "$SIM" --config "$(variant nu05 's/nu: 0.45, density: 1200/nu: 0.5, density: 1200/')" --out "$WORK/o.h5"
expect_exit 2 "empty grid" -- "$SIM" --config "$(variant empty 's/- {fill: 1}/- {fill: 0}/; /layers/d')" --out "$WORK/o.h5"
expect_exit 2 "no boundary condition.*singular" -- "$SIM" --config "$(variant nobc '/^boundary:/,/fix:/d')" --out "$WORK/o.h5"
expect_exit 2 "rigid motion" -- "$SIM" --config "$(variant rigid 's/fix: \[x, y, z\]/fix: [z]/')" --out "$WORK/o.h5"
# A load on a box of void: carve the tip out and load it.
cat "$BASE" > "$WORK/void.yaml"
sed -i 's/^  - {layers: .*/&\n  - {box: {min: [0, 0.012, 0], max: [0.004, 0.016, 0.004]}, id: 0}/' "$WORK/void.yaml"
expect_exit 2 "selects no solid node" -- "$SIM" --config "$WORK/void.yaml" --out "$WORK/o.h5"
expect_exit 2 "unknown|grid\.size" -- "$SIM" --set grid.size=[4,4] --out "$WORK/o.h5"
expect_exit 2 "out" -- "$SIM"
expect_exit 2 "linear_solver" -- "$SIM" --set solver.linear_solver=superlu --out "$WORK/o.h5"

# A failed run leaves an existing output byte for byte as it was.
echo "precious" > "$WORK/keep.h5"
cp "$WORK/keep.h5" "$WORK/keep.ref"
expect_exit 2 "Poisson" -- "$SIM" --config "$WORK/nu05.yaml" --out "$WORK/keep.h5"
check "existing output untouched" -- cmp -s "$WORK/keep.h5" "$WORK/keep.ref"
check "no temporary left behind" -- bash -c "! ls '$WORK' | grep -q '^keep\.h5\..*tmp$'"

# Numerical failure: exit 3 with the residual history, output untouched.
expect_exit 3 "residual history" -- "$SIM" --out "$WORK/keep.h5" \
  --set solver.max_iterations=1 --set solver.tolerance=1e-12 --set solver.max_step_halvings=0
check "existing output untouched after exit 3" -- cmp -s "$WORK/keep.h5" "$WORK/keep.ref"

# Artifacts of the wrong kind or damaged are refused by readers.
"$SIM" --out "$WORK/good.h5" --quiet >/dev/null
expect_exit 2 "expected schema 'msfab.coarse_db'.*found schema 'msfab.result'" -- "$BIN/msfab-inspect" "$WORK/good.h5" --schema msfab.coarse_db
head -c 2000 "$WORK/good.h5" > "$WORK/truncated.h5"
expect_exit 2 "truncated or corrupt" -- "$BIN/msfab-inspect" "$WORK/truncated.h5"
echo "not hdf5" > "$WORK/text.h5"
expect_exit 2 "not a valid HDF5" -- "$BIN/msfab-inspect" "$WORK/text.h5"
finish
