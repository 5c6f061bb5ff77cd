#!/usr/bin/python3
"""B.3: a quasistatic press against the same press applied dynamically.

Reads two msfab.trajectory artifacts of one scene: QUASISTATIC (its first
frame is the pressed equilibrium) and DYNAMIC (press.mode: dynamic; its
last frame is where the ramped-on load has brought the body once the motion
has damped out). Prints the symmetric Hausdorff distance between the two
node sets (absolute, and relative to the rest body's bounding-box diagonal
and to the largest press displacement), the elastic energies and their
relative difference, the kinetic energy left in the dynamic run, and the
wall-time ratio of the two solves.

  tools/compare_press.py QUASISTATIC.h5 DYNAMIC.h5 [--at SECONDS]

--at compares the dynamic run's frame nearest that time instead of its last.
"""
import argparse
import sys

import h5py
import numpy as np


def frame_names(f):
    return sorted(k for k in f["frames"].keys() if k != "time")


def hausdorff(a, b):
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return max(d.min(axis=1).max(), d.min(axis=0).max())


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("quasistatic")
    p.add_argument("dynamic")
    p.add_argument("--at", type=float, default=None)
    a = p.parse_args()
    with h5py.File(a.quasistatic, "r") as q, h5py.File(a.dynamic, "r") as d:
        for f, name in ((q, a.quasistatic), (d, a.dynamic)):
            if f.attrs.get("schema") != "msfab.trajectory":
                sys.exit(f"{name}: not an msfab.trajectory artifact")
        rest = q["mesh/nodes"][:]
        if d["mesh/nodes"].shape != rest.shape or not np.allclose(d["mesh/nodes"][:], rest):
            sys.exit(f"{a.dynamic}: another mesh than {a.quasistatic}")
        frame_times = d["frames/time"][:]
        k = len(frame_times) - 1 if a.at is None else int(np.argmin(abs(frame_times - a.at)))
        x_q = q["frames/" + frame_names(q)[0] + "/positions"][:]
        x_d = d["frames/" + frame_names(d)[k] + "/positions"][:]
        t_d = frame_times[k]
        times = d["samples/time"][:]
        s = int(np.argmin(abs(times - t_d)))
        e_q, e_d = q["samples/elastic"][0], d["samples/elastic"][s]
        kinetic = d["samples/kinetic"][s]
        qs_seconds = q["timings"].attrs["quasistatic"] if "quasistatic" in q["timings"].attrs else None
        dyn_seconds = d["samples/seconds"][: s + 1].sum()
    diag = np.linalg.norm(rest.max(axis=0) - rest.min(axis=0))
    umax = np.linalg.norm(x_q - rest, axis=1).max()
    h = hausdorff(x_q, x_d)
    print(f"dynamic frame at t = {t_d:.4f} s (kinetic energy {kinetic:.3e} J)")
    print(f"Hausdorff distance {h:.4e} m = {100 * h / diag:.3f}% of the bounding-box diagonal "
          f"({diag:.4f} m), {100 * h / umax:.2f}% of the largest press displacement ({umax:.4e} m)")
    print(f"elastic energy: quasistatic {e_q:.6e} J, dynamic {e_d:.6e} J, difference {100 * (e_d / e_q - 1):+.3f}%")
    if qs_seconds is not None:
        print(f"time: quasistatic press {qs_seconds:.3f} s, dynamic run to t = {t_d:.3f} s {dyn_seconds:.3f} s, "
              f"ratio {dyn_seconds / qs_seconds:.1f}x")


if __name__ == "__main__":
    main()
