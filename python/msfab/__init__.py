"""msfab from Python: read any artifact into numpy with its provenance, and
export meshes with their fields for ParaView and meshio.

    import msfab
    with msfab.open_artifact("out/demo/bar.result.h5", "msfab.result") as a:
        u = a["/displacement"]          # (n_nodes, 3) numpy array, m
        print(a.producer, a.inputs)
        msfab.export_mesh(a, "bar.vtu")

Command line: ``python3 -m msfab info FILE`` and ``python3 -m msfab export FILE OUT.vtu``.

With the compiled bindings built (pybind11-dev): ``msfab.homogenize(ids,
materials)`` and ``msfab.simulate(scene)`` run the stages' own code
(native.py).
"""

from .artifact import Artifact, ArtifactError, Input, InputState, Mesh, open_artifact, sha256_of, to_vtk_order
from .export import export_mesh, frame_groups, to_meshio
from .image import export_image, read_vti, write_vti
from .native import homogenize, open_database, simulate

__all__ = ["Artifact", "ArtifactError", "Input", "InputState", "Mesh", "open_artifact", "sha256_of", "to_vtk_order",
           "export_mesh", "frame_groups", "to_meshio", "homogenize", "simulate", "open_database", "export_image", "read_vti", "write_vti"]


def __getattr__(name):  # the bindings' error types, loaded on first use
    if name in ("InputError", "NumericalError"):
        from . import native
        return getattr(native._bindings(), name)
    raise AttributeError(name)
