"""A strip of a dynamics run: the body at several moments drawn over one
another in a side view, with the obstacles it met and the path of its
centre of mass (the kind of picture thesis Fig. 4-17 shows of a jump).

    python3 -m msfab strip out/design/flipper.final.trajectory.h5 flipper.png
    python3 -m msfab strip run.h5 run.png --frames 10 --view y

The view looks along one axis (default y, so x runs to the right and z up);
the body is drawn by its boundary faces, later moments darker. Trajectories
written before obstacles were recorded are drawn with the ground at z = 0
only if --ground is given.
"""

import re

import numpy as np

from .artifact import ArtifactError, open_artifact

# The six faces of a hexahedron in toolkit node order (node = 4x + 2y + z),
# each as a cycle around the face.
HEX_FACES = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3))

_AXES = {"x": 0, "y": 1, "z": 2}


def boundary_faces(elements):
    """(m, 4) node cycles of the faces that belong to one element only."""
    faces = np.asarray(elements)[:, np.array(HEX_FACES)].reshape(-1, 4)
    key = np.sort(faces, axis=1)
    _, first, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[np.sort(first[count == 1])]


def _escaped_lines(text):
    """The lines the writer joined with line breaks, "\\" and "\\n" escaped inside them."""
    unescape = lambda m: "\n" if m.group(1) == "n" else m.group(1)  # noqa: E731
    return [re.sub(r"\\(.)", unescape, line) for line in text.split("\n")]


def obstacles_of(a):
    """[(kind, name, lo, hi)] from /obstacles; empty when the run recorded none."""
    if "/obstacles/lo" not in a:
        return []
    attrs = a.attrs("/obstacles")
    kinds, names = _escaped_lines(str(attrs["kind"])), _escaped_lines(str(attrs["name"]))
    lo, hi = np.asarray(a["/obstacles/lo"], float), np.asarray(a["/obstacles/hi"], float)
    if not (len(kinds) == len(names) == len(lo) == len(hi)):
        raise ArtifactError(f"{a.path}: /obstacles: {len(kinds)} kinds, {len(names)} names, {len(lo)} rows of lo, "
                            f"{len(hi)} of hi; expected one each per obstacle")
    return list(zip(kinds, names, lo, hi))


def pick_frames(times, count):
    """Indices of `count` frames spread evenly in time, first and last included."""
    if count < 2:
        raise ArtifactError("--frames must be at least 2")
    if len(times) <= count:
        return list(range(len(times)))
    wanted = np.linspace(times[0], times[-1], count)
    return sorted({int(np.argmin(np.abs(times - t))) for t in wanted})


def draw_strip(path, out_png, frames=8, view="y", ground=None):
    """Draws the strip of the trajectory at `path` into `out_png`; returns
    the numbers drawn (frame times, the centre-of-mass path in the picture's
    coordinates, obstacle names) for scripts and tests."""
    if view not in _AXES:
        raise ArtifactError(f"--view {view}: expected x, y or z")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Rectangle

    depth = _AXES[view]
    right, up = [k for k in range(3) if k != depth]
    with open_artifact(path, "msfab.trajectory") as a:
        mesh = a.mesh()
        times = np.asarray(a["/frames/time"], float)
        if len(times) == 0:
            raise ArtifactError(f"{path}: /frames/time is empty: the run stored no frames (simulation.output_every)")
        picked = pick_frames(times, frames)
        positions = [np.asarray(a[f"/frames/{k:06d}/positions"], float) for k in picked]
        com = np.asarray(a["/samples/center_of_mass"], float)
        obstacles = obstacles_of(a)
        scene = str(a.attrs("/")["scene"])
    if ground is not None:
        obstacles.append(("ground", "ground", np.array([0.0, 0.0, ground]), np.array([0.0, 0.0, ground])))
    faces = boundary_faces(mesh.elements)

    points = np.vstack(positions + [com])
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 0.08 * max(hi[right] - lo[right], hi[up] - lo[up])
    x0, x1 = lo[right] - pad, hi[right] + pad
    y0, y1 = lo[up] - pad, hi[up] + pad
    for kind, _, olo, ohi in obstacles:
        if kind == "box" and up == 2:
            y0 = min(y0, olo[2] - pad)

    width = 9.0
    height = float(np.clip(width * (y1 - y0) / (x1 - x0), 2.5, 7.0))
    fig, ax = plt.subplots(figsize=(width, height), constrained_layout=True)
    for kind, name, olo, ohi in obstacles:
        if kind == "ground" and up == 2:
            ax.axhspan(y0 - 1, olo[2], color="#c9c0b0", lw=0)
            ax.axhline(olo[2], color="#6b6150", lw=1.0)
        elif kind == "box":
            ax.add_patch(Rectangle((olo[right], olo[up]), ohi[right] - olo[right], ohi[up] - olo[up],
                                   facecolor="#b9b2a4", edgecolor="#6b6150", lw=1.0, zorder=1))
            ax.annotate(name, ((max(olo[right], x0) + min(ohi[right], x1)) / 2, min(ohi[up], y1)),
                        ha="center", va="bottom", fontsize=8, color="#4a4236")
    cmap = plt.get_cmap("viridis")
    for i, (k, x) in enumerate(zip(picked, positions)):
        s = i / max(1, len(picked) - 1)
        order = np.argsort(-x[faces][:, :, depth].mean(axis=1))  # far faces first
        polys = x[faces[order]][:, :, [right, up]]
        colour = cmap(0.15 + 0.7 * s)
        ax.add_collection(PolyCollection(polys, facecolors=colour, edgecolors="k", linewidths=0.2,
                                         alpha=0.35 + 0.6 * s, zorder=2 + i))
        c = x.mean(axis=0)
        ax.annotate(f"{1e3 * times[k]:.0f} ms", (c[right], x[:, up].max()), ha="center", va="bottom", fontsize=7,
                    zorder=50)
    ax.plot(com[:, right], com[:, up], ls="--", lw=0.8, color="#c0392b", zorder=40, label="centre of mass")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    names = "xyz"
    ax.set_xlabel(f"{names[right]} (m)")
    ax.set_ylabel(f"{names[up]} (m)")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"{scene}: {len(picked)} moments from {1e3 * times[picked[0]]:.0f} to {1e3 * times[picked[-1]]:.0f} ms")
    fig.savefig(out_png, dpi=120)
    plt.close(fig)
    return {"times": times[picked].tolist(), "com": com[:, [right, up]].tolist(),
            "obstacles": [name for _, name, _, _ in obstacles]}
