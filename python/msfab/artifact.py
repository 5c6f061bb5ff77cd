"""Reading msfab artifacts (docs/artifacts.md) into numpy.

Every artifact is one HDF5 file whose root attributes carry its provenance:
``schema``, ``schema_version``, ``producer``, ``config``, ``inputs``,
``seed`` and ``created``. :class:`Artifact` exposes those as attributes and
every dataset as a numpy array, without knowing the schema: what a dataset
means is documented per schema in docs/artifacts.md.
"""

import hashlib
import os
from dataclasses import dataclass

import h5py
import numpy as np

ROOT_ATTRIBUTES = ("schema", "schema_version", "producer", "config", "inputs", "seed", "created")


class ArtifactError(Exception):
    """A file that is not the artifact asked for; the message names the file."""


@dataclass(frozen=True)
class Input:
    """One input an artifact was made from, as recorded when it was made."""

    sha256: str
    path: str


@dataclass(frozen=True)
class InputState:
    """An input compared with the file now at its path."""

    path: str
    state: str  # "unchanged", "changed" or "missing"
    recorded_sha256: str
    current_sha256: str = ""


@dataclass(frozen=True)
class Mesh:
    """A hexahedral mesh group (docs/artifacts.md, "msfab.mesh group")."""

    nodes: np.ndarray         # (n_nodes, 3) float64, rest positions, m
    elements: np.ndarray      # (n_elems, 8) int32, toolkit node order (Table 2.1)
    elements_vtk: np.ndarray  # (n_elems, 8) int32, VTK hexahedron order
    element_tag: np.ndarray   # (n_elems,) int32


def _text(value):
    return value.decode("utf-8") if isinstance(value, bytes) else str(value)


def sha256_of(path):
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


class Artifact:
    """An open msfab artifact.

    ``schema`` (e.g. ``"msfab.result"``) and ``versions`` (an int or a
    collection of ints) are checked when given; a mismatch, a file that is
    not HDF5 or lacks the provenance attributes raises :class:`ArtifactError`
    naming the file. Use as a context manager or call :meth:`close`.
    """

    def __init__(self, path, schema=None, versions=None):
        self.path = os.fspath(path)
        try:
            self._file = h5py.File(self.path, "r")
        except (OSError, ValueError) as e:
            raise ArtifactError(f"{self.path}: not a readable HDF5 file ({e})") from None
        attrs = self._file.attrs
        missing = [a for a in ROOT_ATTRIBUTES if a not in attrs]
        if missing:
            self._file.close()
            raise ArtifactError(f"{self.path}: not an msfab artifact (root attribute '{missing[0]}' missing)")
        self.schema = _text(attrs["schema"])
        self.schema_version = int(attrs["schema_version"])
        self.producer = _text(attrs["producer"])
        self.config = _text(attrs["config"])
        self.seed = int(attrs["seed"])
        self.created = _text(attrs["created"])
        self.inputs = []
        for line in _text(attrs["inputs"]).splitlines():
            if line.strip():
                digest, _, name = line.partition("  ")
                self.inputs.append(Input(digest, name))
        if isinstance(versions, int):
            versions = (versions,)
        if (schema is not None and self.schema != schema) or (
                versions is not None and self.schema_version not in versions):
            found = f"schema '{self.schema}' version {self.schema_version}"
            self._file.close()
            wanted = f"schema '{schema}'" if schema is not None else "a schema"
            if versions is not None:
                wanted += " version " + " or ".join(str(v) for v in versions)
            raise ArtifactError(f"{self.path}: expected {wanted}, found {found}")

    # -- access --------------------------------------------------------------
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        self._file.close()

    @property
    def h5(self):
        """The underlying read-only h5py.File, for anything not wrapped here."""
        return self._file

    def datasets(self):
        """Every dataset path, sorted."""
        names = []
        self._file.visititems(lambda name, obj: names.append("/" + name) if isinstance(obj, h5py.Dataset) else None)
        return sorted(names)

    def __contains__(self, path):
        return path in self._file

    def __getitem__(self, path):
        """A dataset as a numpy array (strings as str); KeyError naming the file otherwise."""
        if path not in self._file or not isinstance(self._file[path], h5py.Dataset):
            raise KeyError(f"{self.path}: dataset '{path}' not found")
        value = self._file[path][()]
        if isinstance(value, bytes):
            return value.decode("utf-8")
        if isinstance(value, np.ndarray) and value.dtype.kind == "O":
            return np.array([_text(v) for v in value.ravel()], dtype=object).reshape(value.shape)
        return value

    def attrs(self, path="/"):
        """The attributes of a group or dataset as a dict (strings as str)."""
        if path not in self._file:
            raise KeyError(f"{self.path}: object '{path}' not found")
        out = {}
        for key, value in self._file[path].attrs.items():
            if isinstance(value, bytes):
                value = value.decode("utf-8")
            elif isinstance(value, np.ndarray) and value.dtype.kind == "O":
                value = [_text(v) for v in value]
            out[key] = value
        return out

    def to_dict(self):
        """Every dataset by path, as numpy arrays."""
        return {name: self[name] for name in self.datasets()}

    def mesh(self, group="/mesh"):
        """The hexahedral mesh stored in `group`, or None when there is none."""
        if group + "/nodes" not in self._file or group + "/elements" not in self._file:
            return None
        elements = self[group + "/elements"]
        vtk = self[group + "/elements_vtk"] if group + "/elements_vtk" in self._file else to_vtk_order(elements)
        tag = self[group + "/element_tag"] if group + "/element_tag" in self._file else np.zeros(len(elements), np.int32)
        return Mesh(self[group + "/nodes"], elements, vtk, tag)

    def check_inputs(self, base="."):
        """Each recorded input against the file now at its path (relative paths from `base`)."""
        states = []
        for entry in self.inputs:
            where = entry.path if os.path.isabs(entry.path) else os.path.join(base, entry.path)
            if not os.path.isfile(where):
                states.append(InputState(entry.path, "missing", entry.sha256))
                continue
            now = sha256_of(where)
            states.append(InputState(entry.path, "unchanged" if now == entry.sha256 else "changed", entry.sha256, now))
        return states

    def __repr__(self):
        return f"Artifact('{self.path}', {self.schema} v{self.schema_version}, {self.producer})"


# Toolkit hex node (4x + 2y + z) at each VTK corner (docs/artifacts.md).
TOOLKIT_NODE_AT_VTK_CORNER = (0, 4, 6, 2, 1, 5, 7, 3)


def to_vtk_order(elements):
    """(n, 8) connectivity in toolkit order -> VTK hexahedron order."""
    return np.asarray(elements)[:, list(TOOLKIT_NODE_AT_VTK_CORNER)]


def open_artifact(path, schema=None, versions=None):
    """Opens an artifact; see :class:`Artifact`."""
    return Artifact(path, schema, versions)
