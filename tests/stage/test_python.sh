#!/bin/bash
# The msfab Python package (python/msfab): artifacts of seven kinds made by
# the stages, read in Python and checked against msfab-inspect (the C++
# reader); meshes exported to .vtu through meshio and read back; bad files
# refused; the command line.
BIN=$1 SRC=$(cd "$2" && pwd)
source "$SRC/tests/stage/lib.sh"
cd "$WORK"
# Debian's interpreter: python3-h5py, python3-numpy and python3-meshio are its packages.
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
export PYTHONPATH="$SRC/python" PYTHONDONTWRITEBYTECODE=1

"$BIN/msfab-simulate" --quiet --out result.h5 > /dev/null
"$BIN/msfab-simulate" --quiet --coarsen 1 --coarse-material naive --reference result.h5 --out coarse.h5 > /dev/null
"$BIN/msfab-dynamics" --quiet --set simulation.duration=0.004 --out drop.h5 > /dev/null
"$BIN/msfab-homogenize" --quiet --out cell.h5 > /dev/null
"$BIN/msfab-ddfem-build" --quiet --config "$SRC/configs/ddfem/tiny.yaml" --out tiny.coarse_db.h5 > /dev/null
"$BIN/msfab-gamut-sample" --quiet --config "$SRC/configs/gamut/tiny2d.yaml" --out tiny.gamut.h5 > /dev/null
"$BIN/msfab-topopt" --quiet --out design.h5 > /dev/null
check "the Python reader agrees with msfab-inspect on every artifact kind made here" -- "$PY" \
  "$SRC/tests/python/check_reader.py" "$BIN/msfab-inspect" result.h5:msfab.result coarse.h5:msfab.result \
  drop.h5:msfab.trajectory cell.h5:msfab.homogenized tiny.coarse_db.h5:msfab.coarse_db \
  tiny.gamut.h5:msfab.gamut tiny.microstructures.h5:msfab.microstructures design.h5:msfab.design

"$PY" -m msfab info result.h5 > info.txt
check "python3 -m msfab info names the schema and the producer" -- grep -q "result.h5: msfab.result version 1" info.txt
check "... and lists the displacement" -- grep -q "/displacement  (.*, 3) float64" info.txt
check "python3 -m msfab export writes a .vtu" -- "$PY" -m msfab export drop.h5 drop.vtu --frame -1
check "... that is VTK XML" -- grep -q '<VTKFile type="UnstructuredGrid"' drop.vtu
check "python3 -m msfab inputs: the coarse run's reference is unchanged" -- "$PY" -m msfab inputs coarse.h5
expect_exit 1 "changed +result.h5" -- bash -c "echo >> result.h5; '$PY' -m msfab inputs coarse.h5"
expect_exit 2 "frame 99 asked for, it has" -- "$PY" -m msfab export drop.h5 x.vtu --frame 99
expect_exit 2 "msfab.homogenized holds no hex mesh" -- "$PY" -m msfab export cell.h5 x.vtu
expect_exit 2 "missing.h5: not a readable HDF5 file" -- "$PY" -m msfab info missing.h5
finish
