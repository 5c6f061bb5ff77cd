#!/bin/bash
# python3 -m msfab report: an HTML page whose pictures show what the
# artifacts hold. The numbers each picture draws (report_files/data.json)
# are checked against the artifacts themselves; every picture is a PNG that
# matplotlib reads back; artifacts it does not draw are listed, unreadable
# files too.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
PY=/usr/bin/python3
export PYTHONPATH="$SRC/python:$SRC/tests/stage" PYTHONDONTWRITEBYTECODE=1
cd "$WORK"
mkdir art
"$BIN/msfab-simulate" --quiet --out art/fine.h5 > /dev/null
"$BIN/msfab-simulate" --quiet --coarsen 1 --coarse-material naive --reference art/fine.h5 --out art/naive.h5 > /dev/null
"$BIN/msfab-simulate" --quiet --coarsen 2 --coarse-material averaged --reference art/fine.h5 --out art/avg2.h5 > /dev/null
"$BIN/msfab-dynamics" --quiet --set simulation.duration=0.01 --out art/drop.h5 > /dev/null
"$BIN/msfab-homogenize" --quiet --out art/cell.h5 > /dev/null
"$BIN/msfab-gamut-sample" --quiet --config "$SRC/configs/gamut/tiny2d.yaml" --out art/tiny.gamut.h5 > /dev/null
"$BIN/msfab-topopt" --quiet --set optimizer.max_iterations=20 --out art/design.h5 > /dev/null
echo "not hdf5" > art/broken.h5

expect_exit 0 "report.html: 6 pictures" -- "$PY" -m msfab report report.html art
check "the page shows every picture" -- bash -c 'test $(grep -o "report_files/[0-9][0-9]_[^\"]*\.png" report.html | sort -u | wc -l) = 6'
check "the gamut's level set has its own picture" -- grep -q "gamut_level_set_tiny.gamut.png" report.html
check "an unreadable file is named" -- grep -q "broken.h5.*not read" report.html

check "pictures show the artifacts' numbers" -- "$PY" - <<'PY'
import glob, json, sys
import h5py
import matplotlib.image
import numpy as np
data = json.load(open("report_files/data.json"))
from expectations import expect, finish
for name in data:
    image = matplotlib.image.imread("report_files/" + name)
    expect(f"{name} is a picture", image.ndim == 3 and image.shape[0] > 200 and image.shape[1] > 300)
speed = data[next(n for n in data if "speed_error" in n)]
for run, label in (("naive", "level 1, naive"), ("avg2", "level 2, averaged")):
    with h5py.File(f"art/{run}.h5") as f:
        c, t = f["/coarsening"].attrs, f["/timings"].attrs
        point = [p for p in speed if p["label"] == label]
        expect(f"{run} drawn once", len(point) == 1)
        expect(f"{run} error", point and point[0]["error"] == float(c["error_vs_fine"]))
        expect(f"{run} speedup", point and abs(point[0]["speedup"] - c["fine_newton_seconds"] / t["newton_total"]) < 1e-12)
newton = data[next(n for n in data if "newton" in n)]
expect("three static solves", len(newton) == 3)
with h5py.File("art/fine.h5") as f:
    fine = [r for r in newton if r["artifact"] == "fine"][0]
    expect("fine residual history", np.array_equal(fine["residual"], f["/newton/residual"][()]))
design = data[next(n for n in data if "design" in n)]
with h5py.File("art/design.h5") as f:
    names = f.attrs["property_names"]
    names = (names.decode() if isinstance(names, bytes) else str(names)).split(",")
    rho = f["/cells/raw"][()][:, names.index("rho")]
    expect("design objective history", np.array_equal(design["objective"], f["/history/objective"][()]))
    violation = f["/history/max_violation"][()]
    expect("constraint violation drawn when there is some", ("max_violation" in design) == bool((violation > 0).any()))
    expect("... as recorded", "max_violation" not in design or np.array_equal(design["max_violation"], violation))
    expect("design density range", design["min"] == rho.min() and design["max"] == rho.max())
gamut = data[next(n for n in data if "gamut_tiny.microstructures" in n)]
level_set = data[next(n for n in data if "gamut_level_set" in n)]
with h5py.File("art/tiny.gamut.h5") as f:
    expect("coverage per cycle drawn", np.array_equal(level_set["coverage"], f["/history/coverage"][()]))
    phi = f["/level_set/phi"][()]
    expect("the projection holds the inside", 0 < level_set["inside_fraction_of_projection"] <= 1 and (phi < 0).any())
with h5py.File("art/tiny.microstructures.h5") as f:
    expect("every structure drawn", gamut["structures"] == len(f["/unit_properties"]))
finish()
PY
expect_exit 2 "error" -- "$PY" -m msfab report report.html nowhere
finish
