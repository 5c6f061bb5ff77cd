#!/bin/bash
# A user's own object: an L-shaped bracket given as a binary STL, as an OBJ
# and as a numpy array gives the same scene, and so bit for bit the same
# displacements, as the same bracket built of layout boxes; a cell from a
# numpy array homogenizes like its layout; bad files exit 2 naming the file.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
PY=/usr/bin/python3
SIM="$BIN/msfab-simulate"

# The bracket: a 6 x 12 x 2 mm plate with a 6 x 4 x 4 mm upright at its far
# end, written in millimetres (the scenes scale it by 1e-3).
"$PY" - "$WORK" <<'PY'
import struct, sys
import numpy as np
work = sys.argv[1]
profile = [(0, 0), (12, 0), (12, 6), (8, 6), (8, 2), (0, 2)]  # (y, z), counter-clockwise
n = len(profile)
verts = [(x, y, z) for x in (0.0, 6.0) for (y, z) in profile]
tris = []
for i in range(n):  # the sides, outward
    j = (i + 1) % n
    tris += [(i, j, n + j), (i, n + j, n + i)]
fan = [(4, 5, 0), (4, 0, 1), (4, 1, 2), (4, 2, 3)]  # from the reflex corner (8, 2), counter-clockwise
tris += [(n + a, n + b, n + c) for a, b, c in fan]  # the x = 6 cap faces +x
tris += [(a, c, b) for a, b, c in fan]              # the x = 0 cap faces -x
with open(f"{work}/bracket.stl", "wb") as f:
    f.write(b"bracket".ljust(80, b" "))
    f.write(struct.pack("<I", len(tris)))
    for t in tris:
        f.write(struct.pack("<3f", 0, 0, 0))
        for v in t:
            f.write(struct.pack("<3f", *verts[v]))
        f.write(b"\0\0")
with open(f"{work}/bracket.obj", "w") as f:
    f.write("# the bracket\n")
    for v in verts:
        f.write("v %g %g %g\n" % v)
    for t in tris:
        f.write("f %d %d %d\n" % tuple(v + 1 for v in t))
# The same object as voxel ids, a[i, j, k] = voxel (i, j, k) at 1 mm.
c = np.arange(16) + 0.5
X, Y, Z = np.meshgrid(c[:6], c[:12], c[:6], indexing="ij")
ids = (((Z < 2) | ((Y > 8) & (Z < 6))) & (X < 6)).astype(np.uint8)
np.save(f"{work}/bracket.npy", ids)
np.save(f"{work}/wrong_shape.npy", ids[:, :, :5])
# A cell: two crossing stiff bars in a soft matrix, 8^3 voxels.
cell = np.full((8, 8, 8), 2, dtype=np.int32)
cell[:, 3:5, 3:5] = 1
cell[3:5, :, 3:5] = 1
np.save(f"{work}/cell.npy", cell)
PY

scene() {  # scene NAME LAYOUT...
  cat > "$WORK/$1.yaml" <<Y
name: bracket
grid: {size: [6, 12, 6], voxel_size: 0.001}
materials:
  - {id: 1, name: resin, model: neo-hookean, E: 1.0e6, nu: 0.4, density: 1100}
layout:
$2
boundary:
  - {region: {face: ymin}, fix: [x, y, z]}
loads:
  - {region: {face: zmax}, force: [0.0, -0.01, -0.02]}
Y
}
scene boxes "  - {box: {min: [0, 0, 0], max: [0.006, 0.012, 0.002]}, id: 1}
  - {box: {min: [0, 0.008, 0], max: [0.006, 0.012, 0.006]}, id: 1}"
scene stl "  - {mesh: {file: bracket.stl, scale: 0.001}, id: 1}"
scene obj "  - {mesh: {file: bracket.obj, scale: 0.001}, id: 1}"
scene npy "  - {voxels: {file: bracket.npy}}"
for s in boxes stl obj npy; do
  expect_exit 0 "converged in" -- "$SIM" --config "$WORK/$s.yaml" --out "$WORK/$s.h5" --threads 1
done
for s in stl obj npy; do
  check "$s scene gives the box scene's displacements bit for bit" -- \
    h5diff "$WORK/boxes.h5" "$WORK/$s.h5" /displacement /displacement
done
# The files a layout reads are inputs of the result, with their hashes.
lists_input() {  # lists_input ARTIFACT FILE
  h5dump -a /inputs "$1" | grep -q "$(sha256sum "$2" | cut -d' ' -f1)  .*$(basename "$2")"
}
check "the STL scene's result lists bracket.stl with its hash" -- lists_input "$WORK/stl.h5" "$WORK/bracket.stl"
check "the .npy scene's result lists bracket.npy with its hash" -- lists_input "$WORK/npy.h5" "$WORK/bracket.npy"

# The shipped example (configs/scenes/user, docs/walkthrough.md): the same
# bracket as an ASCII STL and as a .npy, then read back in Python.
for s in bracket bracket_voxels; do
  expect_exit 0 "ParaView: .*$s.xmf" -- "$SIM" --config "$SRC/configs/scenes/user/$s.yaml" --out "$WORK/$s.h5" --threads 1
  check "shipped $s.yaml gives the box scene's displacements" -- h5diff "$WORK/boxes.h5" "$WORK/$s.h5" /displacement /displacement
done
expect_exit 0 "bracket.vtu: 413 nodes, 240 hexahedra" -- env PYTHONPATH="$SRC/python" PYTHONDONTWRITEBYTECODE=1 \
  "$PY" -m msfab export "$WORK/bracket.h5" "$WORK/bracket.vtu"
check "exported mesh has the bracket's 240 voxels" -- env PYTHONPATH="$SRC/python" PYTHONDONTWRITEBYTECODE=1 \
  "$PY" -c "import meshio, sys; m = meshio.read(sys.argv[1]); sys.exit(0 if len(m.cells[0].data) == 240 else 1)" "$WORK/bracket.vtu"

# The bracket as an image stack: one PNG per z layer (white = material),
# turned into a .npy by python3 -m msfab stack; a second stack with three
# gray levels mapped to void and two materials.
"$PY" - "$WORK" <<'PY'
import sys
import matplotlib.image
import numpy as np
work = sys.argv[1]
ids = np.load(f"{work}/bracket.npy")
for z in range(ids.shape[2]):  # rows run downwards in an image: y upwards
    matplotlib.image.imsave(f"{work}/slice{z:02d}.png", 255 * ids[:, ::-1, z].T, cmap="gray", vmin=0, vmax=255)
    level = np.where(ids[:, :, z] == 1, np.where(np.arange(12)[None, :] < 6, 255, 128), 0)
    matplotlib.image.imsave(f"{work}/gray{z:02d}.png", level[:, ::-1].T, cmap="gray", vmin=0, vmax=255)
PY
expect_exit 0 "stack.npy: 6 x 12 x 6 voxels" -- env PYTHONPATH="$SRC/python" "$PY" -m msfab stack "$WORK/stack.npy" "$WORK"/slice*.png
check "the image stack is the bracket's array" -- "$PY" -c \
  "import numpy as np, sys; sys.exit(0 if np.array_equal(np.load('$WORK/stack.npy'), np.load('$WORK/bracket.npy')) else 1)"
scene stack "  - {voxels: {file: stack.npy}}"
expect_exit 0 "converged in" -- "$SIM" --config "$WORK/stack.yaml" --out "$WORK/stack.h5" --threads 1
check "image stack scene gives the box scene's displacements" -- h5diff "$WORK/boxes.h5" "$WORK/stack.h5" /displacement /displacement
expect_exit 0 "voxels per id \{0: 192, 1: 72, 2: 168\}" -- env PYTHONPATH="$SRC/python" "$PY" -m msfab stack \
  "$WORK/two.npy" "$WORK"/gray*.png --map 0:0 255:1 128:2
expect_exit 2 "gray00.png: pixel .* has gray level 128, which --map does not name" -- env PYTHONPATH="$SRC/python" \
  "$PY" -m msfab stack "$WORK/bad.npy" "$WORK"/gray*.png --map 0:0 255:1
check "nothing written for the refused stack" -- test ! -e "$WORK/bad.npy"

# A cell from a numpy array against the same cell painted from boxes.
cell() {  # cell NAME LAYOUT...
  cat > "$WORK/$1.yaml" <<Y
materials:
  - {id: 1, name: stiff, model: linear, E: 1.0e6, nu: 0.3}
  - {id: 2, name: soft, model: linear, E: 1.0e4, nu: 0.3}
cell: {size: [8, 8, 8]}
layout:
$2
Y
}
cell cell_boxes "  - {fill: 2}
  - {box: {min: [0, 0.375, 0.375], max: [1, 0.625, 0.625]}, id: 1}
  - {box: {min: [0.375, 0, 0.375], max: [0.625, 1, 0.625]}, id: 1}"
cell cell_npy "  - {voxels: {file: cell.npy}}"
for c in cell_boxes cell_npy; do
  "$BIN/msfab-homogenize" --config "$WORK/$c.yaml" --out "$WORK/$c.h5" > "$WORK/$c.txt" 2>&1 || echo "FAIL: homogenize $c"
done
check "numpy cell homogenizes like its layout" -- h5diff "$WORK/cell_boxes.h5" "$WORK/cell_npy.h5" /C /C
check "the numpy cell's result lists cell.npy with its hash" -- lists_input "$WORK/cell_npy.h5" "$WORK/cell.npy"

# Bad files: exit 2, naming the file.
"$PY" - "$WORK" <<'PY'
import sys
work = sys.argv[1]
data = open(f"{work}/bracket.stl", "rb").read()
n = int.from_bytes(data[80:84], "little")
open(f"{work}/open.stl", "wb").write(data[:80] + (n - 1).to_bytes(4, "little") + data[84:84 + 50 * (n - 1)])
PY
scene open "  - {mesh: {file: open.stl, scale: 0.001}, id: 1}"
expect_exit 2 "open.stl: the surface does not enclose a volume" -- "$SIM" --config "$WORK/open.yaml" --out "$WORK/x.h5"
scene shape "  - {voxels: {file: wrong_shape.npy}}"
expect_exit 2 "wrong_shape.npy: array of shape \(6, 12, 5\) for a grid of 6 x 12 x 6" -- \
  "$SIM" --config "$WORK/shape.yaml" --out "$WORK/x.h5"
scene far "  - {mesh: {file: bracket.stl, scale: 0.001, offset: [1, 0, 0]}, id: 1}"
expect_exit 2 "bracket.stl contains no voxel centre" -- "$SIM" --config "$WORK/far.yaml" --out "$WORK/x.h5"
scene missing "  - {mesh: {file: nowhere.stl}, id: 1}"
expect_exit 2 "nowhere.stl: no such file" -- "$SIM" --config "$WORK/missing.yaml" --out "$WORK/x.h5"
# The grid sized from the part: the bracket's 6 x 12 x 6 mm box at 1 mm voxels
# is the box scene's grid, so the displacements are the same bit for bit.
sed 's/grid: {size: \[6, 12, 6\], voxel_size: 0.001}/grid: {voxel_size: 0.001, size_from_parts: true}/' "$WORK/stl.yaml" > "$WORK/parts.yaml"
expect_exit 0 "grid from the parts: 6 x 12 x 6 voxels from \(0, 0, 0\)" -- "$SIM" --config "$WORK/parts.yaml" \
  --out "$WORK/parts.h5" --threads 1
check "grid sized from the STL gives the box scene's displacements bit for bit" -- \
  h5diff "$WORK/boxes.h5" "$WORK/parts.h5" /displacement /displacement
sed 's/size_from_parts: true}/size_from_parts: true, margin: 1}/' "$WORK/parts.yaml" > "$WORK/margin.yaml"
# With a margin the grid's faces lie in void, so the face clamp selects nothing (refused).
expect_exit 2 "grid from the parts: 8 x 14 x 8 voxels from \(-0.001, -0.001, -0.001\)" -- "$SIM" \
  --config "$WORK/margin.yaml" --out "$WORK/x.h5" --threads 1
sed 's/grid: {size: \[6, 12, 6\], voxel_size: 0.001}/grid: {voxel_size: 0.001, size_from_parts: true}/' "$WORK/npy.yaml" > "$WORK/noparts.yaml"
expect_exit 2 "grid.size_from_parts.*needs at least one .mesh. or .vdb. item" -- "$SIM" --config "$WORK/noparts.yaml" --out "$WORK/x.h5"
sed 's/size_from_parts: true}/size_from_parts: true, size: [6, 12, 6]}/' "$WORK/parts.yaml" > "$WORK/both.yaml"
expect_exit 2 "grid.size.*comes from the parts" -- "$SIM" --config "$WORK/both.yaml" --out "$WORK/x.h5"
check "nothing written for refused scenes" -- test ! -e "$WORK/x.h5"

# OpenVDB grids (python3-openvdb writes them): the bracket's ids as a float
# grid and as a bool grid in one file (and again at another index origin),
# its density ("fog") at 1 mm voxels that sizes the grid, a cell's ids, and
# a level-set ball whose voxels are counted against the exact ball.
scene vdb_probe "  - {voxels: {file: bracket.npy}}
  - {vdb: {file: nowhere.vdb}, id: 1}"
if "$SIM" --config "$WORK/vdb_probe.yaml" --out "$WORK/x.h5" 2>&1 | grep -q "this build of msfab reads no .vdb files"; then
  echo "note: this build has no OpenVDB (libopenvdb-dev, libboost-iostreams-dev); .vdb inputs refused with exit 2"
  expect_exit 2 "nowhere.vdb: this build of msfab reads no .vdb files" -- "$SIM" --config "$WORK/vdb_probe.yaml" --out "$WORK/x.h5"
  finish
fi
"$PY" - "$WORK" <<'PY'
import sys
import numpy as np
import pyopenvdb as vdb
work = sys.argv[1]
ids = np.load(f"{work}/bracket.npy")
def grid(kind, array, name, ijk=(0, 0, 0), voxel=1.0, background=0):
    g = kind(background)
    g.copyFromArray(array, ijk=ijk)
    g.name = name
    g.transform = vdb.createLinearTransform(voxelSize=voxel)
    return g
vdb.write(f"{work}/bracket_ids.vdb", grids=[grid(vdb.FloatGrid, ids.astype(np.float32), "ids"),
                                           grid(vdb.BoolGrid, ids.astype(bool), "mask", background=False)])
vdb.write(f"{work}/shifted.vdb", grids=[grid(vdb.FloatGrid, ids.astype(np.float32), "ids", ijk=(-3, 5, 70))])
# Density 1 inside, 0 outside, at the scene's voxels: index (i, j, k) is the
# voxel centre, so the scene places the file at 0.001 p + 0.0005 (metres).
vdb.write(f"{work}/bracket_fog.vdb", grids=[grid(vdb.FloatGrid, ids.astype(np.float32), "density")])
bad = ids.astype(np.float32)
bad[2, 3, 1] = 0.5
vdb.write(f"{work}/half.vdb", grids=[grid(vdb.FloatGrid, bad, "ids")])
three = ids.astype(np.float32)
three[0, 0, 0] = 3
vdb.write(f"{work}/three.vdb", grids=[grid(vdb.FloatGrid, three, "ids")])
v = vdb.Vec3SGrid()
v.name = "velocity"
vdb.write(f"{work}/vector.vdb", grids=[v])
cell = np.load(f"{work}/cell.npy")
vdb.write(f"{work}/cell.vdb", grids=[grid(vdb.FloatGrid, cell.astype(np.float32), "ids")])
# The ball: a narrow-band level set at a quarter of the cell's voxel, its
# radius chosen so that no voxel centre of the 10^3 cell lies within 0.05
# voxels of the sphere (trilinear sampling is far more accurate than that).
c = (np.arange(10) + 0.5) / 10
X, Y, Z = np.meshgrid(c, c, c, indexing="ij")
d = np.sqrt((X - 0.5) ** 2 + (Y - 0.5) ** 2 + (Z - 0.45) ** 2)
for r in np.arange(0.30, 0.40, 0.001):
    if np.abs(d - r).min() > 0.005:
        break
ball = vdb.createLevelSetSphere(radius=float(r), center=(0.5, 0.5, 0.45), voxelSize=0.025, halfWidth=3.0)
ball.name = "ball"
vdb.write(f"{work}/ball.vdb", grids=[ball])
np.save(f"{work}/ball_expected.npy", (d < r).astype(np.int32))
open(f"{work}/not.vdb", "w").write("solid bracket\nendsolid\n")
whole = open(f"{work}/bracket_ids.vdb", "rb").read()
open(f"{work}/truncated.vdb", "wb").write(whole[:len(whole) // 2])
PY
scene vdb_ids "  - {voxels: {file: bracket_ids.vdb, grid: ids}}"
scene vdb_mask "  - {voxels: {file: bracket_ids.vdb, grid: mask}}"
scene vdb_shifted "  - {voxels: {file: shifted.vdb, origin: [-3, 5, 70]}}"
scene vdb_fog "  - {vdb: {file: bracket_fog.vdb, scale: 0.001, offset: [0.0005, 0.0005, 0.0005]}, id: 1}"
sed -i 's/grid: {size: \[6, 12, 6\], voxel_size: 0.001}/grid: {voxel_size: 0.001, size_from_parts: true}/' "$WORK/vdb_fog.yaml"
expect_exit 0 "converged in" -- "$SIM" --config "$WORK/vdb_ids.yaml" --out "$WORK/vdb_ids.h5" --threads 1
expect_exit 0 "converged in" -- "$SIM" --config "$WORK/vdb_mask.yaml" --out "$WORK/vdb_mask.h5" --threads 1
expect_exit 0 "converged in" -- "$SIM" --config "$WORK/vdb_shifted.yaml" --out "$WORK/vdb_shifted.h5" --threads 1
expect_exit 0 "grid from the parts: 6 x 12 x 6 voxels from \(0, 0, 0\)" -- "$SIM" --config "$WORK/vdb_fog.yaml" \
  --out "$WORK/vdb_fog.h5" --threads 1
for s in vdb_ids vdb_mask vdb_shifted vdb_fog; do
  check "$s scene gives the box scene's displacements bit for bit" -- \
    h5diff "$WORK/boxes.h5" "$WORK/$s.h5" /displacement /displacement
done
check "the .vdb scene's result lists bracket_ids.vdb with its hash" -- lists_input "$WORK/vdb_ids.h5" "$WORK/bracket_ids.vdb"
cell cell_vdb "  - {voxels: {file: cell.vdb}}"
cell ball "  - {fill: 2}
  - {vdb: {file: ball.vdb}, id: 1}"
sed -i 's/cell: {size: \[8, 8, 8\]}/cell: {size: [10, 10, 10]}/' "$WORK/ball.yaml"
for c in cell_vdb ball; do
  "$BIN/msfab-homogenize" --config "$WORK/$c.yaml" --out "$WORK/$c.h5" > "$WORK/$c.txt" 2>&1 || echo "FAIL: homogenize $c"
done
check "a cell from a .vdb homogenizes like its layout" -- h5diff "$WORK/cell_boxes.h5" "$WORK/cell_vdb.h5" /C /C
check "the level-set ball paints exactly the voxels whose centre is in the ball" -- "$PY" -c "
import h5py, numpy as np, sys
with h5py.File('$WORK/ball.h5') as f: ids = f['/cell/ids'][:]
want = np.load('$WORK/ball_expected.npy')
got = (ids.reshape(10, 10, 10).transpose(2, 1, 0) == 1).astype(np.int32)  # stored x fastest
print('ball voxels', got.sum(), 'expected', want.sum())
sys.exit(0 if np.array_equal(got, want) and 100 < want.sum() < 400 else 1)"

refused() {  # refused NAME LAYOUT PATTERN: the scene exits 2 with PATTERN in its message
  scene "$1" "$2"
  expect_exit 2 "$3" -- "$SIM" --config "$WORK/$1.yaml" --out "$WORK/x.h5"
}
refused vdb_two "  - {voxels: {file: bracket_ids.vdb}}" \
  "bracket_ids.vdb: the file holds 2 grids \('ids', 'mask'\); name one with .grid."
refused vdb_name "  - {voxels: {file: bracket_ids.vdb, grid: stress}}" "no grid named 'stress'; the file holds 'ids', 'mask'"
refused vdb_half "  - {voxels: {file: half.vdb}}" \
  "half.vdb: grid 'ids' holds 0.5 at index \(2, 3, 1\), which is not a material id"
refused vdb_three "  - {voxels: {file: three.vdb}}" "three.vdb uses material id 3 \(1 voxels\), which is not in the palette"
refused vdb_vector "  - {vdb: {file: vector.vdb}, id: 1}" \
  "vector.vdb: grid 'velocity' holds values of type vec3s; a shape needs a float, double or bool grid"
refused vdb_not "  - {vdb: {file: not.vdb}, id: 1}" "not.vdb: not a readable OpenVDB file"
refused vdb_truncated "  - {voxels: {file: truncated.vdb, grid: ids}}" "truncated.vdb: not a readable OpenVDB file"
refused vdb_far "  - {vdb: {file: bracket_fog.vdb, scale: 0.001, offset: [1, 0, 0]}, id: 1}" \
  "bracket_fog.vdb: grid 'density' \(float, density, voxel 1\) contains no voxel centre"
refused vdb_dtype "  - {voxels: {file: bracket_ids.vdb, grid: ids, dtype: uint8}}" "dtype.*a .vdb file says its own value type"
refused vdb_threshold "  - {vdb: {file: bracket_fog.vdb, threshold: 1.5}, id: 1}" \
  "grid 'density' \(float, density, voxel 1\) has no stored value above the threshold 1.5, so nothing is inside"
refused npy_origin "  - {voxels: {file: bracket.npy, origin: [0, 0, 0]}}" "origin.*is for .vdb files only"
check "nothing written for refused .vdb scenes" -- test ! -e "$WORK/x.h5"
finish
