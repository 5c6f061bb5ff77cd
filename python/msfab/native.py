"""The core calls a researcher scripts, run by the stages' own code through
the compiled module ``msfab_bindings`` (built with the project when
pybind11-dev is installed; it lives in ``<build>/python``).

    import numpy as np, msfab
    ids = np.full((8, 8, 8), 2); ids[:, 3:5, 3:5] = 1
    cell = msfab.homogenize(ids, [{"id": 1, "model": "linear", "E": 1e6, "nu": 0.3},
                                  {"id": 2, "model": "linear", "E": 1e4, "nu": 0.3}])
    cell["C"]                                   # 6 x 6 Voigt, as msfab-homogenize's /C
    run = msfab.simulate("configs/scenes/user/bracket.yaml", set=["loads[0].force=[0,0,-0.05]"])
    run["displacement"]                         # (nodes, 3), as msfab-simulate's /displacement

At the same thread count the results equal the executables' artifacts bit
for bit (tests/stage/test_python.sh).
"""

import importlib
import json
import os
import sys


def _bindings():
    try:
        return importlib.import_module("msfab_bindings")
    except ImportError:
        pass
    # A source checkout: <repo>/python/msfab -> <repo>/<build>/python.
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    candidates = [os.environ.get("MSFAB_BUILD", ""), os.path.join(repo, "build")]
    for build in candidates:
        folder = os.path.join(build, "python") if build else ""
        if folder and os.path.isdir(folder) and folder not in sys.path:
            sys.path.append(folder)
            try:
                return importlib.import_module("msfab_bindings")
            except ImportError:
                continue
    raise ImportError("msfab's compiled bindings (msfab_bindings) were not found: build the project with "
                      "pybind11-dev installed (make -f Makefile.pipeline build) and put <build>/python on "
                      "PYTHONPATH, or set MSFAB_BUILD to the build folder")


def homogenize(ids, materials, *, voxel_size=None, void_stiffness=None, linear_solver=None, linear_tolerance=None,
               linear_max_iterations=None, use_symmetry=None, threads=1, solver=None, multigrid_tolerance=None):
    """Periodic homogenization of a voxel cell, as msfab-homogenize.

    ids: integer array of shape (nx, ny, nz), ids[i, j, k] the material of
    voxel (i, j, k), 0 = void; shape (nx, ny) is a 2D cell (plane strain).
    materials: the palette as in a config, e.g. [{"id": 1, "model":
    "linear", "E": 1e6, "nu": 0.3}, ...]. The keyword options are the
    stage's config keys (docs/homogenization.md); None keeps its default.
    solver and multigrid_tolerance are the earlier names of linear_solver
    and linear_tolerance, still read (with a warning).
    Returns a dict: C (6 x 6), C_plane (3 x 3, 2D cells), solid_fraction,
    pieces, solver, unknowns, seconds. Raises msfab.InputError (a
    ValueError) naming the key on bad input.
    """
    config = {"materials": list(materials)}
    for key, value in (("voxel_size", voxel_size), ("void_stiffness", void_stiffness),
                       ("linear_solver", linear_solver), ("linear_tolerance", linear_tolerance),
                       ("linear_max_iterations", linear_max_iterations), ("use_symmetry", use_symmetry),
                       ("solver", solver), ("multigrid_tolerance", multigrid_tolerance)):
        if value is not None:
            config[key] = value
    return _bindings().homogenize(ids, json.dumps(config, default=float), threads)


def open_database(path):
    """A DDFEM database (msfab.coarse_db) as msfab-simulate reads it:
    ``.level``, ``.materials``, ``.entries``, and at level 1
    ``.lookup(ids)``: the coarse material of a 2 x 2 x 2 block whose
    children (hex8 order, child c = 4 i + 2 j + k at offset (i, j, k)) have
    palette ids ``ids`` (0 = void), as a dict of numpy arrays (mu, lambda,
    C per coarse quadrature point, v their spring directions, fit errors),
    or None where the database has no fit. Raises msfab.InputError on a bad
    file, naming the dataset.
    """
    return _bindings().CoarseDatabase(os.fspath(path))


def simulate(config, *, set=(), threads=1):
    """A static scene (YAML file) solved as msfab-simulate solves it without
    coarsening; ``set`` takes --set assignments ("solver.tolerance=1e-8").
    Returns a dict: nodes (n x 3 rest positions), elements (m x 8, the
    toolkit's node order), displacement (n x 3, m), newton_iterations,
    load_steps, newton_seconds. Raises msfab.InputError on a bad scene and
    msfab.NumericalError when Newton does not converge.
    """
    return _bindings().simulate(os.fspath(config), [str(s) for s in set], threads)

