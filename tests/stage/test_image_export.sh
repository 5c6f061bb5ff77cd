#!/bin/bash
# ParaView files of the voxel and cell-grid results (python/msfab/image.py):
# a microstructure set, a mapped design's voxel model, the mapping and its
# full-resolution check, each written as VTK image data and read back. The
# checks use what the artifacts say independently of the voxels' layout:
# each structure's stiff fraction is its rho, and every cell of the voxel
# model is its mapped structure (shifted where the mapping shifted it).
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
PY=/usr/bin/python3
export PYTHONPATH="$SRC/python:$SRC/tests/stage" PYTHONDONTWRITEBYTECODE=1
tiny_cubic3d_set 1
cat > "$WORK/bar.yaml" <<Y
grid: {size: [4, 2, 2], cell_size: 0.002}
space: cubic3d
gamut: $WORK/set.gamut.h5
supports: [{box: {min: [0, 0, 0], max: [0, 0.004, 0.004]}}]
loads:
  - {name: bend, objective: compliance, forces: [{box: {min: [0.008, 0, 0], max: [0.008, 0.004, 0.004]}, force: [0, 0, -1], distribute: total}]}
mass: {volume_fraction: 0.5}
optimizer: {max_iterations: 40}
Y
check "a bar design" -- "$BIN/msfab-topopt" --config "$WORK/bar.yaml" --out "$WORK/bar.design.h5" --quiet
check "mapped with its voxel model" -- "$BIN/msfab-map" --design "$WORK/bar.design.h5" \
  --structures "$WORK/set.microstructures.h5" --set export.voxels=true --out "$WORK/bar.mapped.h5" --seed 1 --quiet
check "checked at full resolution" -- "$BIN/msfab-verify-map" --design "$WORK/bar.design.h5" --mapped "$WORK/bar.mapped.h5" \
  --structures "$WORK/set.microstructures.h5" --out "$WORK/bar.verify.h5" --quiet
cd "$WORK"
for pair in set.microstructures.h5:set.vti bar.voxels.h5:voxels.vti bar.mapped.h5:cells.vti bar.verify.h5:check.vti; do
  expect_exit 0 "${pair#*:}: " -- "$PY" -m msfab export "${pair%%:*}" "${pair#*:}"
done
expect_exit 0 "s3.vti: 1 structures" -- "$PY" -m msfab export set.microstructures.h5 s3.vti --structure 3

check "images hold what the artifacts say" -- "$PY" - <<'PY'
import sys
import h5py
import numpy as np
import msfab
from msfab.image import unpack_voxels
from expectations import expect, finish
with h5py.File("set.microstructures.h5") as f:
    size = tuple(int(v) for v in f["/size"])
    names = f.attrs["property_names"]
    names = (names.decode() if isinstance(names, bytes) else str(names)).split(",")
    rho = f["/properties"][()][:, names.index("rho")]
    bits = int(f["/voxels"].attrs["bits_per_voxel"])
    structures = [unpack_voxels(row, bits, int(np.prod(size))).reshape(size[::-1]) for row in f["/voxels"][()]]
for s, ids in enumerate(structures):
    expect(f"structure {s}: stiff fraction {np.mean(ids == 1)} is its rho {rho[s]}", abs(np.mean(ids == 1) - rho[s]) < 1e-12)
cells, _, _, a = msfab.read_vti("set.vti")
expect("every structure in the set image", sorted(set(a["structure"][a["structure"] >= 0])) == list(range(len(structures))))
for s, ids in enumerate(structures):
    expect(f"structure {s}: its voxels in the set image", np.sum(a["material"][a["structure"] == s] == 1) == np.sum(ids == 1))
_, _, _, one = msfab.read_vti("s3.vti")
expect("--structure 3", np.array_equal(one["material"].reshape(size[::-1]), structures[3]))

with h5py.File("bar.mapped.h5") as f:
    grid = tuple(int(v) for v in f.attrs["grid"])
    chosen, shift, role = f["/cells/structure"][()], f["/cells/shift"][()], f["/cells/role"][()]
(nx, ny, nz), spacing, _, v = msfab.read_vti("voxels.vti")
expect("voxel model size", (nx, ny, nz) == tuple(g * s for g, s in zip(grid, size)))
model = v["material"].reshape(nz, ny, nx)
n, checked = size[0], 0
for k in range(grid[2]):
    for j in range(grid[1]):
        for i in range(grid[0]):
            c = i + grid[0] * (j + grid[1] * k)
            block = model[k * n:(k + 1) * n, j * n:(j + 1) * n, i * n:(i + 1) * n]
            if role[c] != 0:
                continue
            want = structures[chosen[c]]
            if shift[c]:
                want = np.roll(want, (-(n // 2), -(n // 2), -(n // 2)), axis=(0, 1, 2))
            expect(f"cell {c} is structure {chosen[c]}", np.array_equal(block, want))
            checked += 1
expect("design cells compared", checked > 0)
_, _, _, m = msfab.read_vti("cells.vti")
expect("mapped structure per cell", np.array_equal(m["structure"], chosen))
_, _, _, chk = msfab.read_vti("check.vti")
with h5py.File("bar.verify.h5") as f:
    full = f["/nodes/displacement_full"][()]
    found = [name for name in chk if name.startswith("displacement_full_")]
    expect("one field per load case", len(found) == full.shape[0])
    expect("full-resolution displacement", np.array_equal(chk[found[0]], full[0]))
finish()
PY
# The report draws the mapping's property gaps and tables the check.
check "the report draws the mapping and the check" -- "$PY" -c "
import sys, h5py, numpy as np
from msfab.report import build_report
data = build_report(['bar.mapped.h5', 'bar.verify.h5'], 'report.html')
f = h5py.File('bar.verify.h5')
rows = data['verify_map']
ok = [r['displacement'] for r in rows] == list(f['/cases/relative_displacement_difference'][()])
mapped = [v for k, v in data.items() if 'mapped_bar' in k]
g = h5py.File('bar.mapped.h5')
gap = g['/cells/property_gap'][()][g['/cells/role'][()] == 0]
ok = ok and len(mapped) == 1 and mapped[0]['cells'] == len(gap) and mapped[0]['max'] == gap.max()
sys.exit(0 if ok else 1)"
expect_exit 2 "exported as VTK image data \(.vti\)" -- "$PY" -m msfab export set.microstructures.h5 set.vtu
expect_exit 2 "structure 99 asked for" -- "$PY" -m msfab export set.microstructures.h5 x.vti --structure 99
finish
