"""python3 -m msfab info FILE | export FILE OUT [--frame K] | inputs FILE | report OUT.html PATH... | stack OUT.npy IMAGE...
| strip TRAJECTORY.h5 OUT.png"""

import argparse
import sys

import numpy as np

from .artifact import ArtifactError, open_artifact
from .export import export_mesh
from .image import IMAGE_SCHEMAS, export_image


def info(args):
    with open_artifact(args.file) as a:
        print(f"{a.path}: {a.schema} version {a.schema_version}")
        print(f"  producer: {a.producer}\n  created:  {a.created}\n  seed:     {a.seed}")
        for entry in a.inputs:
            print(f"  input:    {entry.path} ({entry.sha256[:12]})")
        for name in a.datasets():
            d = a.h5[name]
            print(f"  {name}  {d.shape} {d.dtype}")


def inputs(args):
    with open_artifact(args.file) as a:
        states = a.check_inputs(args.base)
        for s in states:
            print(f"{s.state:9s} {s.path}")
        return 1 if any(s.state != "unchanged" for s in states) else 0


def export(args):
    with open_artifact(args.file) as a:
        if a.schema in IMAGE_SCHEMAS:
            if args.frame is not None:
                raise ArtifactError(f"{args.file}: --frame applies to trajectories only")
            print(f"{args.out}: {export_image(a, args.out, structure=args.structure)}")
            return 0
        if args.structure is not None:
            raise ArtifactError(f"{args.file}: --structure applies to microstructure sets only")
        m = export_mesh(a, args.out, frame=args.frame)
        print(f"{args.out}: {len(m.points)} nodes, {len(m.cells[0].data)} hexahedra, "
              f"point fields {sorted(m.point_data)}, cell fields {sorted(m.cell_data)}")


def report(args):
    from .report import build_report
    data = build_report(args.paths, args.out, title=args.title)
    print(f"{args.out}: {len(data)} pictures")


def stack(args):
    from .stack import parse_map, stack_to_ids, write_ids
    ids = stack_to_ids(args.images, parse_map(args.map) if args.map else None)
    write_ids(args.out, ids)
    counts = {int(v): int(c) for v, c in zip(*np.unique(ids, return_counts=True))}
    print(f"{args.out}: {ids.shape[0]} x {ids.shape[1]} x {ids.shape[2]} voxels, voxels per id {counts}")


def strip(args):
    from .strip import draw_strip
    drawn = draw_strip(args.file, args.out, frames=args.frames, view=args.view, ground=args.ground)
    print(f"{args.out}: {len(drawn['times'])} moments from {drawn['times'][0]:.4f} to {drawn['times'][-1]:.4f} s, "
          f"obstacles {drawn['obstacles']}")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m msfab", description="Read and export msfab artifacts.")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("info", help="provenance and datasets of an artifact")
    p.add_argument("file")
    p.set_defaults(run=info)
    p = sub.add_parser("inputs", help="each recorded input: unchanged, changed or missing (exit 1 unless all unchanged)")
    p.add_argument("file")
    p.add_argument("--base", default=".", help="folder the relative input paths are taken from")
    p.set_defaults(run=inputs)
    p = sub.add_parser("export", help="the mesh and its fields to a file meshio writes (.vtu, .vtk, .xdmf, ...); "
                       "voxel and cell-grid artifacts (microstructures, voxels, mapped, verify_map) to .vti")
    p.add_argument("file")
    p.add_argument("out")
    p.add_argument("--frame", type=int, help="trajectory frame index (negative from the end)")
    p.add_argument("--structure", type=int, help="one structure of a microstructure set (default: all, side by side)")
    p.set_defaults(run=export)
    p = sub.add_parser("stack", help="an image stack (one image per z layer) to a voxel-id .npy for scenes and cells")
    p.add_argument("out", help="the .npy to write")
    p.add_argument("images", nargs="+", help="the layers, z = 0 first (PNG; TIFF with Pillow)")
    p.add_argument("--map", nargs="+", metavar="GRAY:ID", help="gray level to material id, e.g. 0:0 255:1 128:2 "
                   "(default: >= 128 is 1, else void)")
    p.set_defaults(run=stack)
    p = sub.add_parser("report", help="an HTML page with matplotlib pictures of the artifacts under PATH...")
    p.add_argument("out", help="the page to write, e.g. out/report.html (pictures in out/report_files/)")
    p.add_argument("paths", nargs="+", help="artifacts, or folders searched for *.h5")
    p.add_argument("--title", default="msfab report")
    p.set_defaults(run=report)
    p = sub.add_parser("strip", help="a side view of a trajectory at several moments, with its obstacles (PNG)")
    p.add_argument("file", help="an msfab.trajectory artifact")
    p.add_argument("out", help="the PNG to write")
    p.add_argument("--frames", type=int, default=8, help="moments drawn, spread evenly in time (default 8)")
    p.add_argument("--view", default="y", help="the axis looked along: x, y or z (default y)")
    p.add_argument("--ground", type=float, help="draw a ground at this height (runs that recorded no obstacles)")
    p.set_defaults(run=strip)
    args = parser.parse_args(argv)
    try:
        return args.run(args) or 0
    except (ArtifactError, KeyError, OSError) as e:
        print(f"python3 -m msfab: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
