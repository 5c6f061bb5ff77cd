"""Checks the msfab Python package against the toolkit's own reader.

    check_reader.py INSPECT_BINARY ARTIFACT:SCHEMA ...

For each artifact: the provenance and the dataset tree the package reads
equal what msfab-inspect (the C++ reader) prints; every dataset loads into
numpy with the shape it lists. Artifacts with a hex mesh are exported to
.vtu through meshio and read back bit for bit, and every hexahedron of the
export has a positive volume in VTK's corner order. Bad files are refused
naming the file. Exits 1 on the first failed check, printing it.
"""

import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

import msfab

failures = 0


def check(what, ok, detail=""):
    global failures
    print(("ok:   " if ok else "FAIL: ") + what + (f" ({detail})" if detail and not ok else ""))
    if not ok:
        failures += 1


def inspect_tree(binary, path):
    """msfab-inspect's header fields and {dataset path: shape tuple}."""
    text = subprocess.run([binary, path, "--no-config"], check=True, capture_output=True, text=True).stdout
    header, datasets, stack = {}, {}, []
    inputs = []
    in_contents = False
    for line in text.splitlines():
        if line.startswith("contents:"):
            in_contents = True
            continue
        if not in_contents:
            m = re.match(r"^  (schema|producer|created|seed)\s+(.*)$", line)
            if m:
                header[m.group(1)] = m.group(2).strip()
            m = re.match(r"^  input\s+(\S+)\s+sha256 ([0-9a-f]{64})", line)
            if m:
                inputs.append((m.group(1), m.group(2)))
            continue
        depth = (len(line) - len(line.lstrip(" "))) // 2 - 1
        entry = line.strip()
        if not entry:
            continue
        del stack[depth:]
        if entry.endswith("/"):
            stack.append(entry[:-1])
            continue
        m = re.match(r"^(\S+)\s+\[([^\]]*)\]", entry)
        if m:
            shape = tuple(int(x) for x in m.group(2).split(" x ")) if m.group(2).strip() else ()
            datasets["/" + "/".join(stack + [m.group(1)])] = shape
        else:
            datasets["/" + "/".join(stack + [entry.split()[0]])] = None
    header["inputs"] = inputs
    return header, datasets


def hex_volumes_vtk(points, cells):
    """Volumes of hexahedra in VTK corner order (0-1-2-3 bottom, counter-clockwise seen from above)."""
    p = points[cells]
    # The Jacobian at the centre from the mean edge vectors along the three
    # axes: exact for parallelepipeds (voxels), positive only in VTK's order.
    a = (p[:, 1] + p[:, 2] + p[:, 5] + p[:, 6]) - (p[:, 0] + p[:, 3] + p[:, 4] + p[:, 7])
    b = (p[:, 2] + p[:, 3] + p[:, 6] + p[:, 7]) - (p[:, 0] + p[:, 1] + p[:, 4] + p[:, 5])
    c = (p[:, 4] + p[:, 5] + p[:, 6] + p[:, 7]) - (p[:, 0] + p[:, 1] + p[:, 2] + p[:, 3])
    return np.einsum("ij,ij->i", a, np.cross(b, c)) / 64.0


def check_artifact(binary, path, schema, workdir):
    import meshio

    name = os.path.basename(path)
    header, tree = inspect_tree(binary, path)
    with msfab.open_artifact(path, schema) as a:
        check(f"{name}: schema and version as msfab-inspect reads them",
              header.get("schema") == f"{a.schema} v{a.schema_version}", f"{header.get('schema')} vs {a.schema}")
        check(f"{name}: producer, created, seed", header.get("producer") == a.producer and
              header.get("created") == a.created and header.get("seed") == str(a.seed))
        check(f"{name}: inputs and their hashes",
              header["inputs"] == [(i.path, i.sha256) for i in a.inputs], f"{header['inputs']} vs {a.inputs}")
        paths = a.datasets()
        check(f"{name}: the same {len(paths)} datasets", sorted(tree) == paths,
              f"only C++: {sorted(set(tree) - set(paths))[:3]}, only Python: {sorted(set(paths) - set(tree))[:3]}")
        bad = [p for p in paths if tree.get(p) is not None and np.shape(a[p]) != tree[p]]
        check(f"{name}: every dataset loads with the shape msfab-inspect lists", not bad, str(bad[:3]))
        check(f"{name}: the config is the stage's YAML", len(a.config) > 0 and ":" in a.config)
        mesh = a.mesh()
        if mesh is None:
            return
        check(f"{name}: toolkit and VTK connectivity agree",
              np.array_equal(msfab.to_vtk_order(mesh.elements), mesh.elements_vtk))
        frames = msfab.frame_groups(a)
        out = os.path.join(workdir, name + ".vtu")
        m = msfab.export_mesh(a, out, frame=-1 if frames else None)
        back = meshio.read(out)
        check(f"{name}: .vtu points and hexahedra read back bit for bit",
              np.array_equal(back.points, mesh.nodes) and np.array_equal(back.cells[0].data, mesh.elements_vtk))
        same = all(np.array_equal(back.point_data[k], v) for k, v in m.point_data.items())
        check(f"{name}: {len(m.point_data)} point fields read back bit for bit", same and len(back.point_data) == len(m.point_data))
        volumes = hex_volumes_vtk(back.points, back.cells[0].data)
        check(f"{name}: every exported hexahedron has a positive volume", bool(np.all(volumes > 0)),
              f"min {volumes.min() if len(volumes) else 'none'}")
        if frames:
            last = frames[-1][1]
            check(f"{name}: the last frame's displacement is exported",
                  np.array_equal(back.point_data["displacement"], a[last + "/displacement"]))


def check_refusals(path, workdir):
    try:
        msfab.open_artifact(path, "msfab.not_this")
        check("a wrong schema is refused", False)
    except msfab.ArtifactError as e:
        check("a wrong schema is refused naming the file and both schemas",
              path in str(e) and "msfab.not_this" in str(e), str(e))
    junk = os.path.join(workdir, "junk.h5")
    with open(junk, "w") as f:
        f.write("not hdf5\n")
    try:
        msfab.open_artifact(junk)
        check("a file that is not HDF5 is refused", False)
    except msfab.ArtifactError as e:
        check("a file that is not HDF5 is refused naming it", junk in str(e), str(e))
    cli = subprocess.run([sys.executable, "-m", "msfab", "info", junk], capture_output=True, text=True)
    check("python3 -m msfab exits 2 on a bad file", cli.returncode == 2 and junk in cli.stderr, cli.stderr)


def check_inputs_state(path, workdir):
    """An artifact whose input changes after it was made says so."""
    with msfab.open_artifact(path) as a:
        if not a.inputs:
            return
        base = os.path.dirname(os.path.abspath(path))
        states = a.check_inputs(base)
        check("recorded inputs are unchanged", all(s.state == "unchanged" for s in states), str(states))
        first = a.inputs[0].path
        where = first if os.path.isabs(first) else os.path.join(base, first)
        saved = os.path.join(workdir, "saved_input")
        shutil.copyfile(where, saved)
        with open(where, "ab") as f:
            f.write(b"\n")
        try:
            changed = [s.state for s in a.check_inputs(base)]
        finally:
            shutil.copyfile(saved, where)
        check("an input changed after the artifact was made reads as changed", changed[0] == "changed", str(changed))


def main():
    binary = sys.argv[1]
    specs = [s.rsplit(":", 1) for s in sys.argv[2:]]
    with tempfile.TemporaryDirectory() as workdir:
        for path, schema in specs:
            check_artifact(binary, path, schema, workdir)
        check_refusals(specs[0][0], workdir)
        for path, _ in specs:
            check_inputs_state(path, workdir)
    print(f"{failures} failed" if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
