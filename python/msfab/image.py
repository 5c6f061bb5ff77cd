"""Voxel and cell-grid artifacts as VTK image data (``.vti``), which
ParaView opens directly: microstructure sets (every structure, or one),
voxel models of mapped designs, mappings and full-resolution checks on
their design grid.

    python3 -m msfab export set.microstructures.h5 set.vti              # all structures side by side
    python3 -m msfab export set.microstructures.h5 s7.vti --structure 7
    python3 -m msfab export bar.voxels.h5 bar.vti                       # the mapped voxel model
    python3 -m msfab export bar.mapped.h5 bar_cells.vti                 # structure, gap per design cell
    python3 -m msfab export bar.verify.h5 bar_check.vti                 # both models' displacements

The file is VTK's XML ImageData with inline base64 data (a UInt64 byte
count, then the values, little-endian), cell data for voxel or cell
values and point data for node values, x fastest as in the artifacts.
"""

import base64
import math

import numpy as np

from .artifact import ArtifactError

# A larger model is refused: inline base64 of it would not fit in memory
# comfortably (and ParaView reads such models better from the raw voxels).
MAX_IMAGE_CELLS = 1 << 28

_VTK_TYPES = {np.dtype("uint8"): "UInt8", np.dtype("int32"): "Int32", np.dtype("int64"): "Int64",
              np.dtype("float32"): "Float32", np.dtype("float64"): "Float64"}


def _data_array(name, values, components=1):
    values = np.ascontiguousarray(values)
    if values.dtype not in _VTK_TYPES:
        values = values.astype(np.float64 if values.dtype.kind == "f" else np.int64)
    raw = values.astype(values.dtype.newbyteorder("<"), copy=False).tobytes()
    encoded = base64.b64encode(np.uint64(len(raw)).astype("<u8").tobytes() + raw).decode("ascii")
    return (f'<DataArray type="{_VTK_TYPES[values.dtype]}" Name="{name}" NumberOfComponents="{components}" '
            f'format="binary">{encoded}</DataArray>')


def write_vti(path, cells, spacing, origin=(0.0, 0.0, 0.0), cell_data=None, point_data=None):
    """Writes an image of `cells` = (nx, ny, nz) cells; cell_data and
    point_data map names to arrays of nx*ny*nz (or (nx+1)(ny+1)(nz+1))
    entries in x-fastest order, or of that many rows of 3 components."""
    nx, ny, nz = (int(c) for c in cells)
    if nx * ny * nz > MAX_IMAGE_CELLS:
        raise ArtifactError(f"{path}: {nx} x {ny} x {nz} cells is more than the {MAX_IMAGE_CELLS} an image "
                            "export takes")
    parts = []
    for tag, data, count in (("PointData", point_data, (nx + 1) * (ny + 1) * (nz + 1)),
                             ("CellData", cell_data, nx * ny * nz)):
        arrays = []
        for name, values in (data or {}).items():
            values = np.asarray(values)
            components = 1 if values.ndim == 1 else values.shape[1]
            if values.shape[0] != count:
                raise ArtifactError(f"{path}: {tag} '{name}' has {values.shape[0]} entries, expected {count}")
            arrays.append(_data_array(name, values.reshape(-1), components))
        parts.append(f"<{tag}>" + "".join(arrays) + f"</{tag}>")
    extent = f"0 {nx} 0 {ny} 0 {nz}"
    text = ('<?xml version="1.0"?>\n<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" '
            f'header_type="UInt64"><ImageData WholeExtent="{extent}" '
            f'Origin="{origin[0]!r} {origin[1]!r} {origin[2]!r}" '
            f'Spacing="{spacing[0]!r} {spacing[1]!r} {spacing[2]!r}"><Piece Extent="{extent}">' + "".join(parts) +
            "</Piece></ImageData></VTKFile>\n")
    with open(path, "w") as f:
        f.write(text)


def read_vti(path):
    """(cells, spacing, origin, {name: array}) of a file write_vti wrote
    (inline binary arrays only; for tests and scripts)."""
    import xml.etree.ElementTree as ET

    root = ET.parse(path).getroot()
    image = root.find("ImageData")
    extent = [int(v) for v in image.get("WholeExtent").split()]
    cells = (extent[1], extent[3], extent[5])
    spacing = tuple(float(v) for v in image.get("Spacing").split())
    origin = tuple(float(v) for v in image.get("Origin").split())
    arrays = {}
    inverse = {v: k for k, v in _VTK_TYPES.items()}
    for array in image.iter("DataArray"):
        raw = base64.b64decode(array.text)
        size = int(np.frombuffer(raw[:8], "<u8")[0])
        values = np.frombuffer(raw[8:8 + size], inverse[array.get("type")].newbyteorder("<"))
        components = int(array.get("NumberOfComponents"))
        arrays[array.get("Name")] = values.reshape(-1, components) if components > 1 else values
    return cells, spacing, origin, arrays


def unpack_voxels(packed, bits, count):
    """Ids of `count` voxels packed `bits` bits each, least significant
    first (the toolkit's pack_voxels)."""
    flat = np.unpackbits(np.asarray(packed, dtype=np.uint8).reshape(-1), bitorder="little")[:count * bits]
    weights = (1 << np.arange(bits)).astype(np.int64)
    return flat.reshape(count, bits).astype(np.int64) @ weights


def _microstructures(a, path, structure):
    size = [int(v) for v in a["/size"]]
    per = size[0] * size[1] * size[2]
    packed = a.h5["/voxels"]
    bits = int(packed.attrs.get("bits_per_voxel", 1))
    n = packed.shape[0]
    picked = range(n) if structure is None else [structure]
    if structure is not None and not -n <= structure < n:
        raise ArtifactError(f"{a.path}: structure {structure} asked for, it holds {n}")
    # Side by side along x with one void voxel between neighbours, in rows
    # of about sqrt(N) structures along y.
    columns = len(picked) if structure is not None else max(1, math.ceil(math.sqrt(n)))
    rows = math.ceil(len(picked) / columns)
    nx, ny, nz = columns * (size[0] + 1) - 1, rows * (size[1] + 1) - 1, size[2]
    material = np.zeros((nz, ny, nx), dtype=np.uint8)
    index = np.full((nz, ny, nx), -1, dtype=np.int32)
    for slot, s in enumerate(picked):
        ids = unpack_voxels(packed[s], bits, per).reshape(size[2], size[1], size[0])
        x0, y0 = (slot % columns) * (size[0] + 1), (slot // columns) * (size[1] + 1)
        material[:, y0:y0 + size[1], x0:x0 + size[0]] = ids
        index[:, y0:y0 + size[1], x0:x0 + size[0]] = s % n
    h = 1.0 / size[0]
    write_vti(path, (nx, ny, nz), (h, h, h), cell_data={"material": material.reshape(-1), "structure": index.reshape(-1)})
    return f"{len(picked)} structures of {size[0]} x {size[1]} x {size[2]} voxels ({nx} x {ny} x {nz} cells)"


def _voxels(a, path):
    root = a.attrs("/")
    nx, ny, nz = (int(v) for v in root["size"])
    spacing = tuple(float(v) for v in root["voxel_size"])
    if nx * ny * nz > MAX_IMAGE_CELLS:
        raise ArtifactError(f"{a.path}: {nx} x {ny} x {nz} voxels is more than the {MAX_IMAGE_CELLS} an image "
                            "export takes; read it layer by layer (docs/artifacts.md, msfab.voxels)")
    packed = a.h5["/voxels"]
    bits = int(packed.attrs["bits_per_voxel"])
    material = np.empty((nz, nx * ny), dtype=np.uint8)
    for z in range(nz):
        material[z] = unpack_voxels(packed[z], bits, nx * ny)
    write_vti(path, (nx, ny, nz), spacing, cell_data={"material": material.reshape(-1)})
    return f"{nx} x {ny} x {nz} voxels"


def _grid(a):
    root = a.attrs("/")
    nx, ny, nz = (int(v) for v in root["grid"])
    h = float(root["cell_size"])
    return (nx, ny, nz), (h, h, h)


def _mapped(a, path):
    cells, spacing = _grid(a)
    data = {name: a[f"/cells/{name}"] for name in ("structure", "role", "distance", "property_gap", "mismatch")
            if f"/cells/{name}" in a}
    write_vti(path, cells, spacing, cell_data=data)
    return f"{cells[0]} x {cells[1]} x {cells[2]} cells, fields {sorted(data)}"


def _verify(a, path):
    cells, spacing = _grid(a)
    names = a.attrs("/cases").get("names", "") if "/cases" in a else ""
    names = [n for n in (names.split(",") if isinstance(names, str) else names) if n] or None
    homogenized = np.asarray(a["/nodes/displacement_homogenized"])
    full = np.asarray(a["/nodes/displacement_full"])
    data = {}
    for c in range(homogenized.shape[0]):
        label = names[c] if names and c < len(names) else f"case{c}"
        data[f"displacement_homogenized_{label}"] = homogenized[c]
        data[f"displacement_full_{label}"] = full[c]
    if "/nodes/sample_kind" in a:
        data["sample_kind"] = a["/nodes/sample_kind"]
    write_vti(path, cells, spacing, point_data=data)
    return f"{cells[0]} x {cells[1]} x {cells[2]} cells, {homogenized.shape[0]} load cases"


IMAGE_SCHEMAS = ("msfab.microstructures", "msfab.voxels", "msfab.mapped", "msfab.verify_map")


def export_image(artifact, out_path, structure=None):
    """Writes a voxel or cell-grid artifact as .vti; returns a summary line."""
    if not out_path.endswith(".vti"):
        raise ArtifactError(f"{out_path}: a {artifact.schema} artifact is exported as VTK image data (.vti)")
    if artifact.schema == "msfab.microstructures":
        return _microstructures(artifact, out_path, structure)
    if structure is not None:
        raise ArtifactError(f"{artifact.path}: --structure applies to microstructure sets only")
    if artifact.schema == "msfab.voxels":
        return _voxels(artifact, out_path)
    if artifact.schema == "msfab.mapped":
        return _mapped(artifact, out_path)
    if artifact.schema == "msfab.verify_map":
        return _verify(artifact, out_path)
    raise ArtifactError(f"{artifact.path}: {artifact.schema} is not a voxel or cell-grid artifact")
