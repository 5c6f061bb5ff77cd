#!/usr/bin/env python3
"""Writes configs/topopt/s_beam.yaml (thesis Fig. 3-18) to standard output.

The S-beam's targets are one displacement per node of the top and bottom
boundary: u_x = -squeeze x / L (the beam shortens) and u_y = A sin(2 pi x / L)
(the S). Usage: python3 tools/s_beam_targets.py [nx ny A squeeze] > configs/topopt/s_beam.yaml
"""
import math
import sys


def main():
    nx, ny, amplitude, squeeze = 32, 8, 1.0, 0.5
    if len(sys.argv) == 5:
        nx, ny, amplitude, squeeze = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
    elif len(sys.argv) != 1:
        sys.exit("usage: s_beam_targets.py [nx ny amplitude squeeze]")
    targets = []
    for i in range(nx + 1):
        ux = -squeeze * i / nx
        uy = amplitude * math.sin(2 * math.pi * i / nx)
        for j in (0, ny):
            targets.append(f"      - {{node: [{i}, {j}], displacement: [{ux:.4f}, {uy:.4f}], weight: 1}}")
    print(f"""# The S-beam of thesis Fig. 3-18: a beam of {nx} x {ny} cells, clamped at its
# left end and pressed at its right end, asked to bend into an S instead of
# shortening uniformly. Target-deformation objective (Eq. 3.8) with targets
# on the nodes of the top and bottom boundary only (as in the thesis, to
# avoid over-fitting): u_x = -{squeeze} x / {nx} and u_y = {amplitude} sin(2 pi x / {nx}), inside
# the 2D cubic gamut of a stiff and a soft material (make gamut-2d).
# Written by tools/s_beam_targets.py (one target per boundary node).
#   msfab-topopt --config configs/topopt/s_beam.yaml --out out/topopt/s_beam.design.h5
# With `--set space=isotropic2d` every cell is one isotropic material of the
# gamut (the thesis's "homogeneous material" column).
grid: {{size: [{nx}, {ny}], cell_size: 1.0}}
space: cubic2d
gamut: ../../out/gamut/cubic2d.gamut.h5   # relative to this file
supports:
  - {{box: {{min: [0, 0], max: [0, {ny}]}}, fix: [x, y]}}
loads:
  - name: squeeze
    objective: target
    forces: [{{box: {{min: [{nx}, 0], max: [{nx}, {ny}]}}, force: [-20000, 0], distribute: total}}]
    targets:""")
    print("\n".join(targets))
    print("""mass: {volume_fraction: 0.5}
filter: {radius: 1.5}
optimizer: {max_iterations: 3000}   # Ipopt converges in 331-1057 iterations on four of these scenes (docs/BENCHMARKS.md)""")


if __name__ == "__main__":
    main()
