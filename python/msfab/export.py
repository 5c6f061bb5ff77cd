"""Exporting artifacts with a hex mesh to files ParaView and meshio read.

Point fields are the datasets of one group whose first dimension is the
number of nodes (the root of an ``msfab.result``, a frame group
``/frames/<kkkkkk>`` of an ``msfab.trajectory``); cell fields those whose first
dimension is the number of elements, and the element tag. Written through
meshio (python3-meshio), so any format it writes works: ``.vtu``, ``.vtk``,
``.xdmf``, ...
"""

import numpy as np

from .artifact import ArtifactError


def frame_groups(artifact):
    """The frame groups of a trajectory, in time order: [(time, group path)]."""
    if "/frames/time" not in artifact:
        return []
    times = np.atleast_1d(artifact["/frames/time"])
    return [(float(t), f"/frames/{k:06d}") for k, t in enumerate(times)]


def fields_of(artifact, group, count):
    """Datasets directly in `group` whose first dimension is `count`."""
    fields = {}
    node = artifact.h5[group]
    for name, item in node.items():
        if hasattr(item, "shape") and len(item.shape) >= 1 and item.shape[0] == count and item.dtype.kind in "fiu":
            fields[name] = np.asarray(item[()])
    return fields


def to_meshio(artifact, frame=None, group=None):
    """A meshio.Mesh of the artifact's mesh with its fields.

    `frame` picks a trajectory frame by index (negative from the end);
    `group` names the group holding the point fields (default: the frame's
    group, or the root).
    """
    import meshio

    mesh = artifact.mesh()
    if mesh is None:
        raise ArtifactError(f"{artifact.path}: {artifact.schema} holds no hex mesh group '/mesh'")
    if group is None:
        frames = frame_groups(artifact)
        if frame is not None:
            if not frames:
                raise ArtifactError(f"{artifact.path}: has no frames (frame {frame} asked for)")
            try:
                group = frames[frame][1]
            except IndexError:
                raise ArtifactError(f"{artifact.path}: frame {frame} asked for, it has {len(frames)}") from None
        else:
            group = "/"
    n_nodes, n_elems = len(mesh.nodes), len(mesh.elements)
    point_data = fields_of(artifact, group, n_nodes)
    cell_data = {name: [value] for name, value in fields_of(artifact, group, n_elems).items() if name not in point_data}
    cell_data["element_tag"] = [np.asarray(mesh.element_tag)]
    return meshio.Mesh(np.asarray(mesh.nodes, dtype=np.float64), [("hexahedron", np.asarray(mesh.elements_vtk))],
                       point_data=point_data, cell_data=cell_data)


def export_mesh(artifact, out_path, frame=None, group=None):
    """Writes to_meshio(...) to `out_path` (format from its extension)."""
    import meshio

    m = to_meshio(artifact, frame=frame, group=group)
    meshio.write(out_path, m)
    return m
