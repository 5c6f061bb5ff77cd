#!/bin/bash
# The Python bindings (python/bindings, msfab.homogenize / msfab.simulate /
# msfab.open_database)
# run the stages' own code: their results equal the executables' artifacts
# bit for bit at one thread, and bad input raises msfab.InputError naming
# the key. Skipped (exit 77) when the build has no bindings (no pybind11).
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
PY=/usr/bin/python3
if ! ls "$BIN/../python"/msfab_bindings*.so > /dev/null 2>&1; then
  echo "no msfab_bindings module in $BIN/../python (pybind11-dev not installed when configured): skipped"
  exit 77
fi
export PYTHONPATH="$SRC/python:$BIN/../python" PYTHONDONTWRITEBYTECODE=1

# The executables' answers.
"$PY" - "$WORK" <<'PY'
import sys
import numpy as np
work = sys.argv[1]
cell = np.full((8, 8, 8), 2, dtype=np.int16)
cell[:, 3:5, 3:5] = 1
cell[3:5, :, 3:5] = 1
cell[5:7, 5:7, :] = 0  # a void channel along z
np.save(f"{work}/cell.npy", cell)
np.save(f"{work}/plate.npy", cell[:, :, 3])  # a 2D cell
PY
for c in cell:8 plate:1; do
  name=${c%%:*}
  cat > "$WORK/$name.yaml" <<Y
materials:
  - {id: 1, name: stiff, model: linear, E: 1.0e6, nu: 0.3}
  - {id: 2, name: soft, model: neo-hookean, E: 2.0e4, nu: 0.4}
cell: {size: [8, 8, ${c#*:}]}
void_stiffness: 1.0e-5
layout:
  - {voxels: {file: $name.npy}}
Y
  expect_exit 0 "msfab-homogenize" -- "$BIN/msfab-homogenize" --config "$WORK/$name.yaml" --out "$WORK/$name.h5" --threads 1
done
expect_exit 0 "converged in" -- "$BIN/msfab-simulate" --config "$SRC/configs/scenes/user/bracket.yaml" \
  --set "loads[0].force=[0.0, -0.02, -0.04]" --out "$WORK/bracket.h5" --threads 1

check "bindings equal the executables bit for bit" -- "$PY" - "$WORK" "$SRC" <<'PY'
import sys
import h5py
import numpy as np
import msfab
work, src = sys.argv[1], sys.argv[2]
palette = [{"id": 1, "name": "stiff", "model": "linear", "E": 1.0e6, "nu": 0.3},
           {"id": 2, "name": "soft", "model": "neo-hookean", "E": 2.0e4, "nu": 0.4}]
ok = True
for name in ("cell", "plate"):
    got = msfab.homogenize(np.load(f"{work}/{name}.npy"), palette, void_stiffness=1e-5)
    with h5py.File(f"{work}/{name}.h5", "r") as f:
        want = f["/C"][()]
    same = np.array_equal(got["C"], want)
    print(f"{name}: C equal bit for bit: {same} (C11 {got['C'][0, 0]:.9g}, solver {got['solver']})")
    ok &= same
run = msfab.simulate(f"{src}/configs/scenes/user/bracket.yaml", set=["loads[0].force=[0.0, -0.02, -0.04]"])
with h5py.File(f"{work}/bracket.h5", "r") as f:
    same = np.array_equal(run["displacement"], f["/displacement"][()]) and np.array_equal(run["nodes"], f["/mesh/nodes"][()])
print(f"bracket: displacement equal bit for bit: {same} ({run['newton_iterations']} Newton iterations)")
sys.exit(0 if ok and same else 1)
PY

# A DDFEM database looked up as msfab-simulate looks it up: every
# combination's coarse material equals the row the file assigns it.
expect_exit 0 "" -- "$BIN/msfab-ddfem-build" --quiet --config "$SRC/configs/ddfem/tiny.yaml" --out "$WORK/tiny.coarse_db.h5"
check "database lookup equals the file's rows" -- "$PY" - "$WORK" <<'PY'
import sys
import h5py
import numpy as np
import msfab
work = sys.argv[1]
db = msfab.open_database(f"{work}/tiny.coarse_db.h5")
ok = db.level == 1 and [m["E"] for m in db.materials] == [1.0e5, 1.0e7]
with h5py.File(f"{work}/tiny.coarse_db.h5") as f:
    ids, entry, fitted = f["/combinations/ids"][()], f["/combinations/entry"][()], f["/fit/fitted"][()]
    mu, C, v = f["/fit/mu"][()], f["/fit/C"][()], f["/fit/v"][()]
    for code in range(len(ids)):
        got = db.lookup([int(i) for i in ids[code]])
        row = entry[code]
        if row < 0 or not fitted[row]:
            ok &= got is None
            continue
        ok &= got is not None and np.array_equal(got["mu"], mu[row]) and np.array_equal(got["C"], C[row]) \
            and np.array_equal(got["v"].reshape(-1), v[row])
print(f"{len(ids)} combinations looked up, all equal: {ok}")
sys.exit(0 if ok else 1)
PY

check "bad input raises InputError naming the key" -- "$PY" - "$SRC" <<'PY'
import sys
import numpy as np
import msfab
src = sys.argv[1]
ids = np.ones((4, 4, 4), dtype=int)
stiff = [{"id": 1, "model": "linear", "E": 1.0e6, "nu": 0.3}]
cases = [
    (lambda: msfab.homogenize(ids, [{"id": 1, "model": "linear", "E": -1.0, "nu": 0.3}]), "materials[0].E"),
    (lambda: msfab.homogenize(ids, stiff, linear_solver="bogus"), "linear_solver = bogus"),
    (lambda: msfab.homogenize(ids, stiff, solver="bogus"), "solver = bogus"),
    (lambda: msfab.homogenize(2 * ids, stiff), "has id 2, which is not a material"),
    (lambda: msfab.homogenize(ids.astype(float), stiff), "expected an integer array"),
    (lambda: msfab.simulate(f"{src}/configs/scenes/user/bracket.yaml", set=["solver.tolerance=2"]), "solver.tolerance"),
    (lambda: msfab.simulate(f"{src}/configs/scenes/user/nowhere.yaml"), "no such file"),
    (lambda: msfab.open_database(f"{src}/configs/scenes/user/bracket.npy"), "bracket.npy"),
]
ok = True
for call, expected in cases:
    try:
        call()
        print(f"accepted: {expected}")
        ok = False
    except msfab.InputError as e:
        if expected not in str(e):
            print(f"message lacks '{expected}': {e}")
            ok = False
sys.exit(0 if ok and issubclass(msfab.InputError, ValueError) else 1)
PY
finish
