#!/usr/bin/env bash
# Homogenization side by side with the published 149-line MATLAB code
# homo3D (Dong, Tang, Zhao 2018; github.com/GuoyingDong/homogenization),
# run in GNU Octave on the same gamut structures in the same run.
#
#   HOMO3D_DIR=/path/to/homogenization bash tools/bench_homo3d.sh [BIN] [OUT] [COUNT]
#
# BIN: msfab binaries (default build/bin); OUT: work folder (default
# out/bench/homo3d); COUNT: structures per resolution (default 8).
# The structures are the first COUNT solid/void structures of the small
# cubic gamut (configs/gamut/cubic3d_bar.yaml, seed 1) at 16^3, and the
# same structures refined to 32^3. msfab homogenizes them in batch mode
# (one structure per thread) with its default solver and with
# use_symmetry: false (six cases on the whole cell); homo3D runs one
# structure after the other (Octave's sparse kernels use the BLAS threads).
# Prints a Markdown table: seconds per structure, structures per second,
# and the largest relative difference |C_msfab - C_homo3D|_F / |C_homo3D|_F.
# homo3D removes void from the system; msfab gives it 1e-6 of the solid's
# stiffness by default, a bias of that order relative to the solid (more
# relative to a light structure's C), so a row with 1e-9 is added.
set -euo pipefail
BIN=${1:-build/bin}
OUT=${2:-out/bench/homo3d}
COUNT=${3:-8}
if [[ -z "${HOMO3D_DIR:-}" || ! -f "${HOMO3D_DIR}/homo3D.m" ]]; then
  echo "bench_homo3d: set HOMO3D_DIR to a folder with homo3D.m (github.com/GuoyingDong/homogenization); skipped" >&2
  exit 0
fi
command -v octave >/dev/null || { echo "bench_homo3d: octave not found (apt-get install octave); skipped" >&2; exit 0; }
PY=${PYTHON:-/usr/bin/python3}  # Debian's, with h5py and numpy
mkdir -p "$OUT"
export OMP_WAIT_POLICY=PASSIVE

"$BIN/msfab-gamut-sample" --config configs/gamut/cubic3d_bar.yaml --seed 1 --quiet \
  --out "$OUT/bar.gamut.h5" --structures "$OUT/bar16.microstructures.h5" >/dev/null
"$BIN/msfab-homogenize" --structures "$OUT/bar16.microstructures.h5" --set refine=2 --quiet \
  --out "$OUT/bar32.microstructures.h5" >/dev/null

now() { date +%s.%N; }
echo "| n | structures | code | seconds per structure | structures/s | max rel. difference of C vs homo3D |"
echo "|---|---|---|---|---|---|"
for n in 16 32; do
  # The first COUNT structures: a set of their own for msfab, text for Octave.
  "$PY" - "$OUT/bar$n.microstructures.h5" "$OUT/first$n.microstructures.h5" "$OUT/cells$n.txt" "$COUNT" <<'EOF'
import sys, h5py, numpy as np
src, dst, txt, count = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
with h5py.File(src, "r") as s, h5py.File(dst, "w") as d:
    total = s["voxels"].shape[0]
    for k, v in s.attrs.items():
        d.attrs[k] = v
    for k in s.keys():
        data = s[k][:]
        if k != "size" and data.ndim >= 1 and data.shape[0] == total:
            data = data[:count]
        d.create_dataset(k, data=data)
        for a, b in s[k].attrs.items():
            d[k].attrs[a] = b
    nx, ny, nz = (int(v) for v in s["size"][:])
    bits = int(s["voxels"].attrs["bits_per_voxel"])
    rows = s["voxels"][:count]
with open(txt, "w") as out:
    out.write(f"{count} {nx} {ny} {nz}\n")
    for row in rows:
        flat = np.unpackbits(row, bitorder="little")[: nx * ny * nz * bits]
        ids = flat.reshape(-1, bits) @ (1 << np.arange(bits))
        out.write(" ".join(str(int(v)) for v in ids) + "\n")
EOF
  # msfab: default, and without the symmetry reductions.
  rm -f "$OUT/msfab$n.times"
  for variant in default void9 whole; do
    case $variant in
      default) settings=() ;;
      void9) settings=(--set void_stiffness=1e-9) ;;   # closer to homo3D's removed void
      whole) settings=(--set use_symmetry=false) ;;
    esac
    t0=$(now)
    "$BIN/msfab-homogenize" --structures "$OUT/first$n.microstructures.h5" "${settings[@]}" --quiet \
      --out "$OUT/msfab$n-$variant.microstructures.h5" >/dev/null
    echo "$variant $(echo "$(now) - $t0" | bc -l)" >> "$OUT/msfab$n.times"
  done
  # homo3D in Octave on the same cells, one after the other.
  cat > "$OUT/run_homo3d.m" <<EOF
addpath('${HOMO3D_DIR}');
fid = fopen('$OUT/cells$n.txt'); head = fscanf(fid, '%d', 4); count = head(1); dims = head(2:4)';
E = 1.0e6; nu = 0.3; lambda = E*nu/((1+nu)*(1-2*nu)); mu = E/(2*(1+nu));
C = zeros(count, 36); seconds = 0;
for s = 1:count
  voxel = reshape(fscanf(fid, '%d', prod(dims)), dims);
  t = tic; CH = homo3D(1, 1, 1, lambda, mu, voxel); seconds = seconds + toc(t);
  C(s, :) = reshape(CH', 1, 36);
end
fclose(fid);
dlmwrite('$OUT/homo3d$n.txt', C, 'precision', '%.17g');
fid = fopen('$OUT/homo3d$n.times', 'w'); fprintf(fid, '%.6f\n', seconds); fclose(fid);
EOF
  octave --no-gui --quiet "$OUT/run_homo3d.m" >"$OUT/octave$n.log" 2>&1
  "$PY" - "$OUT" "$n" "$COUNT" <<'EOF'
import sys, os, h5py, numpy as np
out, n, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
ref = np.loadtxt(os.path.join(out, f"homo3d{n}.txt"), delimiter=",").reshape(count, 36)
times = dict(line.split() for line in open(os.path.join(out, f"msfab{n}.times")))
peer = float(open(os.path.join(out, f"homo3d{n}.times")).read())
def difference(variant):
    with h5py.File(os.path.join(out, f"msfab{n}-{variant}.microstructures.h5"), "r") as f:
        ours = f["C"][:].reshape(count, 36)
    return f"{np.max(np.linalg.norm(ours - ref, axis=1) / np.linalg.norm(ref, axis=1)):.1e}"
rows = [("msfab, default (one octant, 2 cases; void 1e-6)", float(times["default"]), difference("default")),
        ("msfab, void_stiffness 1e-9", float(times["void9"]), difference("void9")),
        ("msfab, use_symmetry: false (whole cell, 6 cases)", float(times["whole"]), difference("whole")),
        ("homo3D in Octave (ichol + pcg, void removed)", peer, "(reference)")]
for name, seconds, d in rows:
    print(f"| {n}³ | {count} | {name} | {seconds / count:.3f} | {count / seconds:.3g} | {d} |")
EOF
done
