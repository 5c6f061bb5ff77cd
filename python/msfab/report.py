"""An HTML report of msfab artifacts: speed against error, solver
convergence, dynamics traces, designs, gamuts, microstructure families and
DAC calibrations, drawn with matplotlib. The stages draw no charts
themselves: this is where their pictures come from.

    python3 -m msfab report out/report.html out/        # every artifact below out/
    python3 -m msfab report demo.html a.h5 b.h5

Writes the page, its pictures in ``<stem>_files/`` and the numbers each
picture shows in ``<stem>_files/data.json`` (for scripts and tests).
Artifacts it does not draw are listed with their producer.
"""

import html
import json
import os

import numpy as np

from .artifact import ArtifactError, open_artifact

ERROR_DEFINITION = ("error: mean distance between the fine model's vertices and the coarse model's displacement "
                    "interpolated to them, over the longest side of the body (thesis §2.5.2); 1e-2 is 1% of the body")


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _find_artifacts(paths):
    found = []
    for p in paths:
        if os.path.isdir(p):
            for root, dirs, files in os.walk(p):
                dirs.sort()
                found += [os.path.join(root, f) for f in sorted(files) if f.endswith(".h5")]
        elif os.path.isfile(p):
            found.append(p)
        else:
            raise ArtifactError(f"{p}: no such file or folder")
    return found


def _label(path):
    return os.path.basename(path)[:-3] if path.endswith(".h5") else os.path.basename(path)


class _Page:
    def __init__(self, out_html):
        self.out_html = out_html
        stem = os.path.splitext(os.path.basename(out_html))[0]
        self.files_name = stem + "_files"
        self.files = os.path.join(os.path.dirname(os.path.abspath(out_html)), self.files_name)
        os.makedirs(self.files, exist_ok=True)
        self.parts = []
        self.data = {}
        self.figures = 0

    def heading(self, text):
        self.parts.append(f"<h2>{html.escape(text)}</h2>")

    def paragraph(self, text):
        self.parts.append(f"<p>{html.escape(text)}</p>")

    def table(self, header, rows):
        head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
        body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
        self.parts.append(f"<table><tr>{head}</tr>{body}</table>")

    def figure(self, fig, name, caption, data):
        self.figures += 1
        file_name = f"{self.figures:02d}_{name}.png"
        fig.savefig(os.path.join(self.files, file_name), dpi=110)
        _pyplot().close(fig)
        self.data[file_name] = data
        self.parts.append(f'<figure><img src="{self.files_name}/{file_name}" alt="{html.escape(caption)}">'
                          f"<figcaption>{html.escape(caption)}</figcaption></figure>")

    def write(self, title):
        style = ("body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
                 "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;"
                 "text-align:right}th{background:#eee}figure{margin:1.5em 0}img{max-width:100%}"
                 "figcaption{font-size:90%;color:#555}")
        text = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
                f"<style>{style}</style></head><body><h1>{html.escape(title)}</h1>\n" + "\n".join(self.parts) +
                "\n</body></html>\n")
        tmp = self.out_html + ".tmp"
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, self.out_html)
        with open(os.path.join(self.files, "data.json"), "w") as f:
            json.dump(self.data, f, indent=1, default=float)


# -- speed against error -------------------------------------------------------

def _coarse_point(a):
    """(scene, label, speedup, error) of a coarsened run compared with its fine run, or None."""
    if a.schema == "msfab.result" and "/coarsening" in a:
        c = a.attrs("/coarsening")
        if "error_vs_fine" not in c or "fine_newton_seconds" not in c:
            return None
        seconds = float(a.attrs("/timings")["newton_total"])
        if c.get("adaptive", 0):
            label = f"adaptive, target {float(c['target_error']):.3g}"
        else:
            label = f"level {int(c['level'])}, {c['material']}"
            if c.get("element", "trilinear") != "trilinear":
                label += f", {c['element']}"
        return (a.attrs("/")["scene"], label, float(c["fine_newton_seconds"]) / seconds, float(c["error_vs_fine"]))
    if a.schema == "msfab.trajectory" and "/comparison" in a:
        c = a.attrs("/comparison")
        k = a.attrs("/coarsening") if "/coarsening" in a else {}
        label = f"level {int(k.get('level', 0))}, {k.get('material', '?')} (dynamics, max over frames)"
        return (a.attrs("/")["scene"], label, float(c["fine_seconds_per_step"]) / float(c["seconds_per_step"]),
                float(c["error_max"]))
    return None


def _speed_against_error(page, points):
    if not points:
        return
    plt = _pyplot()
    page.heading("Speed against error")
    page.paragraph("Each coarse model against the fine solution of the same scene, solved in the same run or "
                   "read as its reference. Speedup: the fine model's Newton time over the coarse model's "
                   "(per time step for dynamics). " + ERROR_DEFINITION + ".")
    for scene in sorted({p[0] for p in points}):
        mine = sorted((p for p in points if p[0] == scene), key=lambda p: p[2])
        fig, ax = plt.subplots(figsize=(6.4, 4.2), constrained_layout=True)
        markers = "osD^v<>ph*"
        for n, (_, label, speed, error) in enumerate(mine):
            ax.loglog([speed], [max(error, 1e-16)], markers[n % len(markers)], ms=8, alpha=0.8, label=label)
        # Decades around the points, so that a few close points are not
        # stretched over the whole axis.
        speeds = [p[2] for p in mine] + [1.0]
        errors = [max(p[3], 1e-16) for p in mine]
        ax.set_xlim(min(speeds) / 2, max(speeds) * 2)
        ax.set_ylim(min(errors) / 3, max(errors) * 3)
        ax.axvline(1.0, color="0.5", ls="--", lw=1, label="the fine model's speed")
        ax.set_xlabel("speedup over the fine model (×)")
        ax.set_ylabel("error (fraction of the body's longest side)")
        ax.set_title(f"{scene}: speed against error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="best", framealpha=0.9)
        page.figure(fig, f"speed_error_{scene}", f"{scene}: speedup and error of each coarse model",
                    [{"label": l, "speedup": s, "error": e} for _, l, s, e in mine])
        page.table(["model", "speedup (×)", "error"], [(l, f"{s:.2f}", f"{e:.3g}") for _, l, s, e in mine])


# -- static solves -------------------------------------------------------------

def _static_results(page, results):
    if not results:
        return
    plt = _pyplot()
    page.heading("Static solves (msfab-simulate)")
    rows, fig_data = [], []
    fig, ax = plt.subplots(figsize=(6.4, 4.2), constrained_layout=True)
    for path, a in results:
        newton = a.attrs("/newton")
        residual = np.asarray(a["/newton/residual"], dtype=float)
        u = np.asarray(a["/displacement"])
        root = a.attrs("/")
        timings = a.attrs("/timings")
        model = "fine"
        if "/coarsening" in a:
            c = a.attrs("/coarsening")
            model = "adaptive" if c.get("adaptive", 0) else f"level {int(c['level'])} {c['material']}"
        rows.append((_label(path), root["scene"], model, int(root["elements"]), int(root["dofs"]),
                     int(newton["iterations"]), f"{float(timings['newton_total']):.3f}",
                     f"{np.abs(u).max():.4g}"))
        ax.semilogy(np.arange(1, len(residual) + 1), np.maximum(residual, 1e-300), ".-", label=_label(path))
        fig_data.append({"artifact": _label(path), "residual": residual.tolist()})
    ax.set_xlabel("Newton iteration (all load steps)")
    ax.set_ylabel("free residual / force scale")
    ax.set_title("Newton convergence")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    page.table(["artifact", "scene", "model", "elements", "DOFs", "Newton iterations", "Newton s", "max |u| (m)"],
               rows)
    page.figure(fig, "newton", "Newton convergence of each static solve (the residual drops at each converged "
                "load step, then restarts with the next increment)", fig_data)


# -- dynamics ------------------------------------------------------------------

def _trajectory(page, path, a):
    plt = _pyplot()
    t = np.asarray(a["/samples/time"], dtype=float)
    phase = np.asarray(a["/samples/phase"])
    energies = {k: np.asarray(a[f"/samples/{k}"], dtype=float) for k in ("kinetic", "elastic", "gravity", "total")}
    com = np.asarray(a["/samples/center_of_mass"], dtype=float)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True, constrained_layout=True)
    for name, e in energies.items():
        top.plot(t, e, label=name, lw=1.6 if name == "total" else 1.0)
    names = ["quasistatic", "elastic", "rigid"]
    for p, colour in ((0, "#dde6f5"), (2, "#f5e6dd")):
        inside = phase == p
        if inside.any():
            for ax in (top, bottom):
                ax.fill_between(t, 0, 1, where=inside, color=colour, transform=ax.get_xaxis_transform(), lw=0,
                                label=names[p] if ax is top else None)
    top.set_ylabel("energy (J)")
    top.legend(fontsize=8, ncol=3, loc="best")
    top.grid(True, alpha=0.3)
    bottom.plot(t, 1e3 * com[:, 2], color="k")
    bottom.set_ylabel("centre of mass z (mm)")
    bottom.set_xlabel("time (s)")
    bottom.grid(True, alpha=0.3)
    scene = a.attrs("/")["scene"]
    top.set_title(f"{scene} ({_label(path)})")
    page.figure(fig, f"trajectory_{_label(path)}", f"{_label(path)}: energies and centre-of-mass height over time; "
                "shaded: quasistatic preload (blue) and rigid flight (orange)",
                {"time": t[::max(1, len(t) // 200)].tolist(), "total": energies["total"][::max(1, len(t) // 200)].tolist()})


# -- topology optimization -------------------------------------------------------

def _design(page, path, a):
    plt = _pyplot()
    root = a.attrs("/")
    grid = [int(g) for g in root["grid"]]
    names = [n.strip() for n in str(root["property_names"]).split(",")]
    raw = np.asarray(a["/cells/raw"], dtype=float)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.0), gridspec_kw={"width_ratios": [1, 1.4]},
                                      constrained_layout=True)
    data = {}
    if "/history/objective" in a:
        objective = np.asarray(a["/history/objective"], dtype=float)
        left.plot(np.arange(len(objective)), objective, "-")
        if np.all(objective > 0):
            left.set_yscale("log")
        left.set_xlabel("optimizer iteration")
        left.set_ylabel("objective")
        left.grid(True, which="both", alpha=0.3)
        data["objective"] = objective.tolist()
        if "/history/max_violation" in a:
            violation = np.asarray(a["/history/max_violation"], dtype=float)
            if np.any(violation > 0):
                twin = left.twinx()
                twin.semilogy(np.arange(len(violation)), np.maximum(violation, 1e-16), ":", color="tab:red")
                twin.set_ylabel("largest constraint violation", color="tab:red")
                data["max_violation"] = violation.tolist()
    left.set_title("convergence")
    if "rho" in names:
        field, what = raw[:, names.index("rho")], "density ρ"
    else:
        field, what = raw[:, 0], names[0]
    nx, ny, nz = grid
    values = field.reshape(nz, ny, nx)
    k = nz // 2
    image = right.imshow(values[k], origin="lower", cmap="viridis", aspect="equal",
                         extent=(0, nx, 0, ny), vmin=min(0.0, values.min()), vmax=max(values.max(), 1e-12))
    right.set_xlabel("cell x")
    right.set_ylabel("cell y")
    right.set_title(what + (f", slice z = {k} of {nz}" if nz > 1 else ""))
    fig.colorbar(image, ax=right, label=what)
    data.update({"field": what, "min": float(values.min()), "max": float(values.max()), "grid": grid})
    page.figure(fig, f"design_{_label(path)}", f"{_label(path)} ({root['space']}, {nx}×{ny}×{nz} cells): "
                "objective (and, dotted, the largest constraint violation) over the iterations, and the design", data)


# -- gamuts ----------------------------------------------------------------------

def _microstructures(page, path, a):
    plt = _pyplot()
    names = [n.strip() for n in str(a.attrs("/")["property_names"]).split(",")]
    unit = np.asarray(a["/unit_properties"], dtype=float)
    cycle = np.asarray(a["/cycle"]) if "/cycle" in a else np.zeros(len(unit))
    d = unit.shape[1]
    pairs = [(i, j) for i in range(d) for j in range(i + 1, d)][:3]
    fig, axes = plt.subplots(1, len(pairs), figsize=(4.4 * len(pairs), 3.9), squeeze=False, constrained_layout=True)
    for ax, (i, j) in zip(axes[0], pairs):
        points = ax.scatter(unit[:, i], unit[:, j], c=cycle, s=6, cmap="plasma")
        ax.set_xlabel(f"{names[i]} (normalized)")
        ax.set_ylabel(f"{names[j]} (normalized)")
        ax.set_xlim(-0.02, 1.02)
        ax.set_ylim(-0.02, 1.02)
        ax.grid(True, alpha=0.3)
    fig.colorbar(points, ax=axes[0].tolist(), label="sampling cycle")
    fig.suptitle(f"{_label(path)}: {len(unit)} structures")
    page.figure(fig, f"gamut_{_label(path)}", f"{_label(path)}: the structures' properties in the normalized "
                "material space, pairs of coordinates, coloured by the cycle that found them",
                {"structures": len(unit), "names": names, "min": unit.min(axis=0).tolist(),
                 "max": unit.max(axis=0).tolist()})


def _property_axes(names):
    """Indices of the stiffness and Poisson coordinates drawn against each
    other: (E, ν) for cubic and isotropic spaces, (Ex, ν_xy) for orthotropic."""
    lower = [n.lower() for n in names]
    e = next((i for i, n in enumerate(lower) if n.startswith("e")), 0)
    nu = next((i for i, n in enumerate(lower) if n.startswith("nu")), 1 if len(names) > 1 else 0)
    return e, nu


def _gamut(page, path, a):
    """The level set's zero contour projected on (E, ν) — inside where some
    structure with those two properties exists, whatever the others — over
    the structures of the set written beside it, and the coverage per cycle."""
    plt = _pyplot()
    root = a.attrs("/")
    names = [n.strip() for n in str(root["property_names"]).split(",")]
    phi = np.asarray(a["/level_set/phi"], dtype=float)
    ls = a.attrs("/level_set")
    d, n = phi.ndim, phi.shape[0]
    lower, spacing = float(ls["lower"]), float(ls["spacing"])
    ie, inu = _property_axes(names)
    # phi is C-ordered over (p_{d-1}, ..., p_0): axis d-1-k holds coordinate k.
    other = tuple(ax for ax in range(d) if ax not in (d - 1 - ie, d - 1 - inu))
    table = phi.min(axis=other) if other else phi
    if d - 1 - ie < d - 1 - inu:  # keep [nu index, E index] for contour(x=E, y=nu)
        table = table.T
    nodes = lower + (np.arange(n) + 0.5) * spacing
    history = {k: np.asarray(a[f"/history/{k}"], dtype=float) for k in ("cycle", "coverage", "samples")
               if f"/history/{k}" in a}
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [1.2, 1]},
                                      constrained_layout=True)
    data = {"dimension": d, "cells": n, "inside_fraction_of_projection": float((table < 0).mean())}
    left.contourf(nodes, nodes, table, levels=[table.min() - 1, 0], colors=["#dde6f5"])
    left.contour(nodes, nodes, table, levels=[0], colors="k", linewidths=1.2)
    sibling = path[:-len(".gamut.h5")] + ".microstructures.h5" if path.endswith(".gamut.h5") else None
    if sibling and os.path.isfile(sibling):
        try:
            with open_artifact(sibling) as m:
                unit = np.asarray(m["/unit_properties"], dtype=float)
                step = np.asarray(m["/step"]) if "/step" in m else np.zeros(len(unit), int)
            steps = {0: "initial", 1: "discrete", 2: "continuous", 3: "void variant", 4: "directed push",
                     5: "at a design's target"}
            for k in np.unique(step):
                inside = step == k
                left.scatter(unit[inside, ie], unit[inside, inu], s=6, label=f"{steps.get(int(k), k)} "
                             f"({int(inside.sum())})")
            left.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), markerscale=2, title="step")
            data["structures"] = len(unit)
        except ArtifactError:
            pass
    left.set_xlabel(f"{names[ie]} (normalized)")
    left.set_ylabel(f"{names[inu]} (normalized)")
    left.set_xlim(0, 1)
    left.set_ylim(0, 1)
    left.set_title("gamut: the level set's zero contour, projected")
    left.grid(True, alpha=0.3)
    if "coverage" in history:
        right.plot(history["cycle"], history["coverage"], "o-", ms=3)
        right.set_xlabel("sampling cycle")
        right.set_ylabel("coverage (fraction of the unit cube inside)")
        right.set_ylim(bottom=0)
        right.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
        right.grid(True, alpha=0.3)
        data["coverage"] = history["coverage"].tolist()
    right.set_title("coverage per cycle")
    page.figure(fig, f"gamut_level_set_{_label(path)}",
                f"{_label(path)} ({root['space']}, {d}-dimensional level set on {n} cells per axis): the zero "
                f"contour of its minimum over the other coordinates in the ({names[ie]}, {names[inu]}) plane, "
                "with the structures sampled (by the step that found them), and the coverage after each cycle", data)


def _families(page, path, a):
    """Isomap embedding and property coverage of the selected structures,
    coloured by family, and a table of the families."""
    plt = _pyplot()
    root = a.attrs("/")
    selection = np.asarray(a["/selection"], dtype=np.int64)
    family = np.asarray(a["/clusters/family"], dtype=int)
    embedding = np.asarray(a["/embedding/coordinates"], dtype=float)
    count = int(root["families"])
    properties = None
    for entry in a.inputs:  # the input set, for E, ν and G of the selected structures
        where = entry.path if os.path.isabs(entry.path) else os.path.join(os.path.dirname(path), entry.path)
        for candidate in (entry.path, where):
            if os.path.isfile(candidate):
                try:
                    with open_artifact(candidate) as m:
                        if m.schema == "msfab.microstructures":
                            properties = np.asarray(m["/properties"], dtype=float)[selection]
                except (ArtifactError, IndexError):
                    properties = None
                break
        if properties is not None:
            break
    panels = 3 if properties is not None and properties.shape[1] >= 3 else 1
    fig, axes = plt.subplots(1, panels, figsize=(4.6 * panels, 4.0), squeeze=False, constrained_layout=True)
    colours = plt.get_cmap("tab10")

    def scatter(ax, x, y):
        other = family < 0
        if other.any():
            ax.scatter(x[other], y[other], s=5, color="#bbbbbb", label=f"no family ({int(other.sum())})")
        for f in range(count):
            mine = family == f
            ax.scatter(x[mine], y[mine], s=9, color=colours(f % 10), label=f"family {f + 1} ({int(mine.sum())})")
        ax.grid(True, alpha=0.3)

    y = embedding[:, 1] if embedding.shape[1] > 1 else np.zeros(len(embedding))
    scatter(axes[0][0], embedding[:, 0], y)
    axes[0][0].set_xlabel("Isomap coordinate 1")
    axes[0][0].set_ylabel("Isomap coordinate 2")
    axes[0][0].set_title("embedding of the selected structures")
    axes[0][0].legend(fontsize=7, loc="best", markerscale=2)
    data = {"selected": len(selection), "families": count}
    if panels == 3:
        E, nu, G = properties[:, 0], properties[:, 1], properties[:, 2]
        log_e = np.log10(E / float(root["E_stiff"]))
        shear = 2 * G * (1 + nu) / E
        scatter(axes[0][1], nu, log_e)
        axes[0][1].set_xlabel("Poisson's ratio ν")
        axes[0][1].set_ylabel("log10 E / E_stiff")
        axes[0][1].set_title("coverage: E and ν")
        scatter(axes[0][2], nu, shear)
        axes[0][2].set_xlabel("Poisson's ratio ν")
        axes[0][2].set_ylabel("shear ratio G' = 2G(1+ν)/E")
        axes[0][2].set_title("coverage: ν and G'")
    page.figure(fig, f"families_{_label(path)}", f"{_label(path)}: the {len(selection)} selected structures in "
                "their Isomap embedding" + (" and in property space" if panels == 3 else
                                             " (the input set was not found, so no property panels)") +
                ", coloured by family", data)
    rows = []
    for f in range(count):
        g = f"/families/{f}"
        if g not in a:
            continue
        at = a.attrs(g)
        members = len(np.atleast_1d(a[g + "/members"]))
        fmt = lambda r: "–".join(f"{float(v):.3g}" for v in np.atleast_1d(r))  # noqa: E731
        rows.append((f + 1, members, int(at["beams"]), fmt(at["E_range"]), fmt(at["nu_range"]),
                     fmt(at["shear_ratio_range"]), f"{float(at['representative_difference']):.3g}",
                     "yes" if int(at.get("has_reduced", 0)) else "no"))
    page.table(["family", "members", "template beams", "E / E_stiff", "ν", "G'", "template voxel difference",
                "reduced parameters"], rows)


def _dac_model(page, path, a):
    """A DAC calibration: the coarse rig's frequencies before and after the
    modulus fit, against the target, and the fitted constants."""
    plt = _pyplot()
    root = a.attrs("/")
    eig = np.sqrt(np.maximum(np.atleast_1d(np.asarray(a["/coarse_eigenvalues"], dtype=float)), 0)) / (2 * np.pi)
    scale = np.sqrt(float(root["youngs_modulus"]) / float(root["reference_modulus"]))
    fig, ax = plt.subplots(figsize=(6.4, 3.6), constrained_layout=True)
    k = np.arange(1, len(eig) + 1)
    ax.plot(k, eig, "o", label=f"coarse mesh, E_m = {float(root['reference_modulus']):.3g} Pa")
    ax.plot(k, eig * scale, "s", label=f"calibrated, E_n = {float(root['youngs_modulus']):.3g} Pa")
    ax.axhline(float(root["target_frequency"]), color="k", lw=0.8, ls="--",
               label=f"target {float(root['target_frequency']):.4g} Hz")
    ax.set_xlabel("mode")
    ax.set_ylabel("frequency (Hz)")
    ax.set_xticks(k)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{_label(path)}: {root['material']}")
    page.figure(fig, f"dac_{_label(path)}", f"{_label(path)}: the coarse rig's modal frequencies with the reference "
                "modulus and with the calibrated one (frequencies scale with √E), against the target (DAC, "
                "thesis §4.4)", {"frequencies": eig.tolist(), "scale": float(scale)})
    page.table(["material", "E_n (Pa)", "damping a (1/s)", "damping b (s)", "target f (Hz)", "target decay (1/s)",
                "coarse elements", "voxel size (m)"],
               [(root["material"], f"{float(root['youngs_modulus']):.4g}", f"{float(root['damping_a']):.4g}",
                 f"{float(root['damping_b']):.4g}", f"{float(root['target_frequency']):.4g}",
                 f"{float(root['target_decay']):.4g}", int(root["elements"]), f"{float(root['voxel_size']):.3g}")])


def _verify_map(page, checks):
    if not checks:
        return
    page.heading("Full-resolution checks (msfab-verify-map)")
    page.paragraph("Each mapped design's homogenized model against its voxel model (thesis Table 3.1): the mean "
                   "displacement difference and the energy difference relative to the voxel model, per load case.")
    rows, data = [], []
    for path, a in checks:
        names = a.attrs("/cases").get("names", "")
        names = names.split(",") if isinstance(names, str) else list(names)
        displacement = np.atleast_1d(a["/cases/relative_displacement_difference"])
        energy = np.atleast_1d(a["/cases/relative_energy_difference"])
        for c in range(len(displacement)):
            label = names[c] if c < len(names) and names[c] else f"case {c}"
            rows.append((_label(path), label, f"{100 * displacement[c]:.1f}%", f"{100 * energy[c]:.1f}%"))
            data.append({"artifact": _label(path), "case": label, "displacement": float(displacement[c]),
                         "energy": float(energy[c])})
    page.table(["check", "load case", "displacement difference", "energy difference"], rows)
    page.data["verify_map"] = data


def _mapped(page, path, a):
    if "/cells/property_gap" not in a:
        return
    plt = _pyplot()
    gap = np.asarray(a["/cells/property_gap"], dtype=float)
    role = np.asarray(a["/cells/role"])
    gap = gap[role == 0]
    fig, ax = plt.subplots(figsize=(6.4, 3.8), constrained_layout=True)
    ax.hist(gap, bins=30, color="#4477aa")
    ax.set_xlabel("property gap |C(structure) - C(target)| / |C(target)|")
    ax.set_ylabel("design cells")
    ax.set_title(f"{_label(path)}: {len(gap)} design cells")
    ax.grid(True, alpha=0.3)
    page.figure(fig, f"mapped_{_label(path)}", f"{_label(path)}: how far each mapped structure's stiffness is from "
                "the optimized cell's", {"cells": len(gap), "max": float(gap.max()) if len(gap) else 0.0,
                                         "mean": float(gap.mean()) if len(gap) else 0.0})


def _jump_design(page, path, a):
    plt = _pyplot()
    start = np.asarray(a["/evaluations/start"])
    objective = np.asarray(a["/evaluations/objective"], dtype=float)
    simulated = np.asarray(a["/evaluations/simulated"]).astype(bool)
    fig, ax = plt.subplots(figsize=(6.4, 3.8), constrained_layout=True)
    for s in np.unique(start):
        index = np.nonzero(start == s)[0]
        ok = simulated[index]
        ax.plot(np.arange(1, len(index) + 1)[ok], objective[index][ok], "o-", ms=3, label=f"start {int(s)}")
    if np.all(objective[simulated] > 0):
        ax.set_yscale("log")
    ax.set_xlabel("evaluation")
    ax.set_ylabel("objective")
    root = a.attrs("/")
    ax.set_title(f"{_label(path)}: task {root['task']}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    data = {"objective": objective.tolist(), "final": float(a.attrs("/final")["objective"])}
    caption = f"{_label(path)}: the objective of every evaluation of each COBYLA start"
    if "/robustness" in a:
        data["success_fraction"] = float(a.attrs("/robustness")["success_fraction"])
        caption += f"; print variation: {100 * data['success_fraction']:.0f}% of the samples meet the goal"
    page.figure(fig, f"jump_{_label(path)}", caption, data)


def _homogenized(page, cells):
    if not cells:
        return
    page.heading("Homogenized cells (msfab-homogenize)")
    rows = []
    for path, a in cells:
        C = np.asarray(a["/C"], dtype=float)
        rows.append((_label(path),) + tuple(f"{C[i, i]:.4g}" for i in range(6)) + (f"{C[0, 1]:.4g}",))
    page.table(["artifact", "C11", "C22", "C33", "C44", "C55", "C66", "C12"], rows)
    page.paragraph("C^H in Voigt order xx, yy, zz, yz, xz, xy with engineering shear strains, in the materials' "
                   "units (Pa).")


def build_report(paths, out_html, title="msfab report"):
    """Writes the report of the artifacts under `paths` (files or folders) to
    `out_html`; returns {picture file: numbers drawn}."""
    page = _Page(out_html)
    points, results, cells, checks, others, drawn = [], [], [], [], [], []
    opened = []
    try:
        for path in _find_artifacts(paths):
            try:
                a = open_artifact(path)
            except ArtifactError as e:
                others.append((path, f"not read: {e}"))
                continue
            opened.append(a)
            p = _coarse_point(a)
            if p:
                points.append(p)
            if a.schema == "msfab.result":
                results.append((path, a))
            elif a.schema == "msfab.homogenized":
                cells.append((path, a))
            elif a.schema == "msfab.verify_map":
                checks.append((path, a))
            elif a.schema in ("msfab.trajectory", "msfab.design", "msfab.microstructures", "msfab.gamut",
                              "msfab.mapped", "msfab.jump_design", "msfab.families", "msfab.dac_model"):
                drawn.append((path, a))
            else:
                others.append((path, f"{a.schema} v{a.schema_version}, made by {a.producer}"))
        _speed_against_error(page, points)
        _static_results(page, results)
        kinds = {"msfab.trajectory": ("Dynamics (msfab-dynamics)", _trajectory),
                 "msfab.design": ("Designs (msfab-topopt)", _design),
                 "msfab.gamut": ("Gamuts (msfab-gamut-sample)", _gamut),
                 "msfab.microstructures": ("Microstructure sets (msfab-gamut-sample, msfab-family-generate)",
                                           _microstructures),
                 "msfab.families": ("Microstructure families (msfab-families)", _families),
                 "msfab.dac_model": ("Dynamics-aware coarsening (msfab-dac-calibrate)", _dac_model),
                 "msfab.mapped": ("Mapped designs (msfab-map)", _mapped),
                 "msfab.jump_design": ("Design loops (msfab-jump-design)", _jump_design)}
        for schema, (heading, draw) in kinds.items():
            mine = [(p, a) for p, a in drawn if a.schema == schema]
            if mine:
                page.heading(heading)
                for p, a in mine:
                    draw(page, p, a)
        _verify_map(page, checks)
        _homogenized(page, cells)
        if others:
            page.heading("Other artifacts")
            page.table(["file", "kind"], [(p, what) for p, what in others])
    finally:
        for a in opened:
            a.close()
    if not page.parts:
        page.paragraph("No artifacts found.")
    page.write(title)
    return page.data
