# Shared by the DAC benchmark scripts (tools/bench_dac_*.sh), sourced first.

# bench_folders BIN OUT: sets BIN (the stage binaries) and OUT (created) as
# absolute paths and SRC (the source tree), moves into OUT, one thread.
bench_folders() {
  BIN=$(cd "$1" && pwd)
  SRC=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
  mkdir -p "$2"
  OUT=$(cd "$2" && pwd)
  cd "$OUT"
  export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
}

# modes SCENE MATERIAL ARTIFACT: the first 10 frequencies of SCENE with the
# material's own modulus, one per line (the target given here only labels
# msfab-dac-calibrate's printout).
modes() {
  printf 'scene: %s\nmaterial: %s\ntarget: {frequency: 100.0, decay: 1.0}\nmodes: 10\n' "$1" "$2" > modes.yaml
  "$BIN/msfab-dac-calibrate" --config modes.yaml --out "$3" | awk '/^  mode/ { print $6 }'
}

# dac_fit SCENE MATERIAL F1 ARTIFACT: fits E_n and b of MATERIAL in SCENE to
# the first frequency F1 of a reference mesh and the Rayleigh decay that the
# scene's own stiffness damping gives it (Eq. 4.16-4.18); prints E_n / E_m.
dac_fit() {
  local b d1
  b=$(awk -v m="name: $2," 'index($0, m) { for (i = 1; i <= NF; ++i) if ($i == "damping_b:") print $(i + 1) }' "$1" | tr -d '}')
  d1=$(awk -v f="$3" -v b="$b" 'BEGIN { l = (2 * 3.141592653589793 * f)^2; print b * l / 2 }')
  printf 'scene: %s\nmaterial: %s\ntarget: {frequency: %s, decay: %s}\nmodes: 10\n' "$1" "$2" "$3" "$d1" > dac.yaml
  "$BIN/msfab-dac-calibrate" --config dac.yaml --out "$4" > dac.txt
  awk '/E_n =/ { for (i = 1; i <= NF; ++i) if ($i ~ /^\(x/) { gsub(/[(x),]/, "", $i); print $i } }' dac.txt
}

# frequency_errors LABEL REFERENCE FREQUENCIES SCALE: mean and largest
# relative error of FREQUENCIES (times sqrt(SCALE), the DAC eigenvalue
# scaling) against REFERENCE.
frequency_errors() {
  paste "$2" "$3" | awk -v l="$1" -v s="$4" '{ e = ($2 * sqrt(s) - $1) / $1; e = e < 0 ? -e : e; se += e; if (e > me) me = e; n++ }
    END { printf "%-28s mean %.1f%%, max %.1f%% over %d modes\n", l, 100 * se / n, 100 * me, n }'
}

# convergence SCENE MATERIAL LEVELS [MODES]: modes of SCENE at its voxel
# size and LEVELS halvings of it (msfab-dac-calibrate's search), the
# converged frequencies of the first MODES (default 4) modes by Richardson
# extrapolation, each level's error against them, and the accurate mesh
# (thesis Fig. 4-11: within 5% of the converged values). Sets ACCURATE to
# its voxel size (empty when no level is accurate).
convergence() {
  printf 'scene: %s\nmaterial: %s\ntarget: {frequency: 100.0, decay: 0.0}\nmodes: %s\nsearch_levels: %s\n' \
    "$1" "$2" "${4:-4}" "$3" > convergence.yaml
  "$BIN/msfab-dac-calibrate" --config convergence.yaml --out convergence.h5 > convergence.txt 2> convergence.log
  grep -o "level [0-9]*: .*" convergence.log || true
  grep -E "converged frequencies|accurate mesh" convergence.txt
  ACCURATE=$(awk '/accurate mesh: level/ { for (i = 1; i <= NF; ++i) if ($i == "voxel") print $(i + 1) }' convergence.txt)
}

# reference_meshes SCENE MATERIAL NAME: the convergence table of SCENE (a
# 2 mm scene) over LEVELS halvings (default 3), then NAME_ref.yaml at
# REFERENCE (a voxel size; default the accurate mesh) and NAME_1mm.yaml.
# Sets REF to the reference's voxel size.
reference_meshes() {
  echo "mesh convergence (2 mm and ${LEVELS:-3} halvings):"
  convergence "$1" "$2" "${LEVELS:-3}"
  REF=${REFERENCE:-$ACCURATE}
  [ -n "$REF" ] || { echo "no accurate mesh among the levels: give REFERENCE" >&2; exit 1; }
  echo "reference: the $3 at $REF m (accurate mesh: ${ACCURATE:-none})"
  sed "s/voxel_size: 0.002/voxel_size: $REF/" "$1" > "$3_ref.yaml"
  sed "s/voxel_size: 0.002/voxel_size: 0.001/" "$1" > "$3_1mm.yaml"
}

# timed_run NAME SCENE ARGS...: msfab-dynamics with peak memory; prints
# time per elastic step, total time and memory.
timed_run() {
  local name=$1 scene=$2
  shift 2
  /usr/bin/time -f "%M" -o "$name.rss" "$BIN/msfab-dynamics" --config "$scene" --out "$name.h5" "$@" > "$name.txt"
  awk -v n="$name" -v r="$(cat "$name.rss")" '/elastic steps/ { ms = $7 } /highest z/ { z = $(NF - 1) }
    /^  time:/ { t = $(NF - 1) } END { printf "%-6s %s ms per elastic step, %s s in all, %.0f MB, highest centre of mass %s m\n", n, ms, t, r / 1024, z }' "$name.txt"
}
