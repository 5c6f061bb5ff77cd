#!/bin/bash
# Every kind of bad input against every stage executable (docs/cli.md, "Bad
# input, kind by kind"): each case must exit 2 with a message naming the
# file or key, write nothing into its (fresh) output folder, and finish
# within 20 seconds. The cases share one set of files: a config with a
# syntax error, an alias bomb, /dev/zero, a truncated HDF5 file, a text
# file posing as an artifact, and a valid artifact of the wrong schema.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"

STAGES=(assign dac-calibrate ddfem-build ddfem-compress dynamics families family-generate fill-targets
        gamut-sample homogenize inspect jump-design map simulate topopt verify-map)
check "every stage executable is in the matrix" -- \
  test "$(ls "$BIN" | grep -c '^msfab-')" = "${#STAGES[@]}"

# Arguments each stage needs to get as far as its inputs; ART stands for
# the artifact under test (every artifact option gets it, so whichever the
# stage opens first is the bad one).
artifact_args() {
  case $1 in
    assign|families|homogenize) echo "--structures ART" ;;
    fill-targets|map) echo "--design ART --structures ART" ;;
    verify-map) echo "--design ART --mapped ART --structures ART" ;;
    ddfem-compress) echo "--database ART" ;;
    simulate) echo "--coarsen 1 --database ART" ;;
    family-generate) echo "--families ART --family 1" ;;
    topopt) echo "--set space=cubic2d --set gamut=ART" ;;
    inspect) echo "ART" ;;
    *) echo "" ;;
  esac
}
# Stages whose run needs no artifact: the config kinds apply to their
# built-in defaults.
NEEDS_NOTHING=(dac-calibrate ddfem-build dynamics gamut-sample homogenize simulate topopt)

# bad NAME PATTERN -- command...: exit 2, PATTERN in the output, nothing in
# the output folder $OUTDIR, within 20 s.
bad() {
  local name=$1 pattern=$2
  shift 3
  local out rc
  rm -rf "$OUTDIR" && mkdir -p "$OUTDIR"
  out=$(timeout 20 "$@" 2>&1) && rc=0 || rc=$?
  if [ "$rc" = 124 ]; then
    echo "FAIL: $name: no answer within 20 s: $*"; FAILURES=$((FAILURES + 1)); return
  fi
  if [ "$rc" != 2 ]; then
    echo "FAIL: $name: expected exit 2, got $rc: $*"; echo "$out" | tail -3; FAILURES=$((FAILURES + 1)); return
  fi
  if ! grep -Eq -- "$pattern" <<<"$out"; then
    echo "FAIL: $name: output lacks /$pattern/: $*"; echo "$out" | tail -3; FAILURES=$((FAILURES + 1)); return
  fi
  if [ -n "$(ls -A "$OUTDIR")" ]; then
    echo "FAIL: $name: wrote into the output folder: $(ls -A "$OUTDIR")"; FAILURES=$((FAILURES + 1)); return
  fi
  PASSES=$((PASSES + 1))
}
OUTDIR="$WORK/out"

# The shared bad files.
printf 'a: [1, 2\nb: 3\n' > "$WORK/syntax.yaml"
{
  echo "l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"
  for i in 1 2 3 4 5 6 7 8; do p="*l$((i - 1))"; echo "l$i: &l$i [$p, $p, $p, $p, $p, $p, $p, $p, $p]"; done
} > "$WORK/bomb.yaml"
check "a valid artifact to damage" -- "$BIN/msfab-gamut-sample" --config "$SRC/configs/gamut/tiny2d.yaml" \
  --set cycles=1 --out "$WORK/good.gamut.h5" --quiet
head -c 400 "$WORK/good.gamut.h5" > "$WORK/truncated.h5"
echo "not an artifact" > "$WORK/text.h5"
printf '# precious\n{}\n' > "$WORK/keep.yaml"
cp "$WORK/keep.yaml" "$WORK/keep.ref"

for s in "${STAGES[@]}"; do
  x="$BIN/msfab-$s"
  read -r -a args <<<"$(artifact_args "$s")"
  with() { local a=() v; for v in "${args[@]}"; do a+=("${v//ART/$1}"); done; echo "${a[@]}"; }
  # msfab-inspect reads no config and writes nothing: only its own options.
  out=(--out "$OUTDIR/o.h5")
  [ "$s" != inspect ] || out=()
  if [ "$s" != inspect ]; then
  # Config kinds (with the stage's artifact options pointing at a valid
  # file: the config is read first).
  read -r -a good <<<"$(with "$WORK/good.gamut.h5")"
  bad "$s: missing config" "none.yaml: no such file" -- "$x" "${good[@]}" --config "$WORK/none.yaml" --out "$OUTDIR/o.h5"
  bad "$s: YAML syntax" "syntax.yaml: line [0-9]+, column [0-9]+" -- \
    "$x" "${good[@]}" --config "$WORK/syntax.yaml" --out "$OUTDIR/o.h5"
  bad "$s: alias bomb" "bomb.yaml: YAML aliases expand" -- "$x" "${good[@]}" --config "$WORK/bomb.yaml" --out "$OUTDIR/o.h5"
  bad "$s: device as config" "/dev/zero: is a character device" -- \
    "$x" "${good[@]}" --config /dev/zero --out "$OUTDIR/o.h5"
  bad "$s: bad --seed" "seed.*larger than" -- "$x" "${good[@]}" --seed 18446744073709551616 --out "$OUTDIR/o.h5"
  bad "$s: bad --memory-limit" "memory-limit 'lots'" -- "$x" "${good[@]}" --memory-limit lots --out "$OUTDIR/o.h5"
  else
    read -r -a good <<<"$(with "$WORK/good.gamut.h5")"
    for option in --config --seed --memory-limit --out --threads; do
      bad "$s: $option is not its option" "$option" -- "$x" "${good[@]}" "$option" 1
    done
  fi
  bad "$s: unknown option" "zzz-option" -- "$x" "${good[@]}" --zzz-option "${out[@]}"
  if [ "$s" != inspect ]; then
    bad "$s: output folder missing" "output folder does not exist" -- "$x" "${good[@]}" --out "$OUTDIR/none/o.h5"
    bad "$s: output is the config" "--config '.*keep.yaml' and --out '.*keep.yaml' name the same file" -- \
      "$x" "${good[@]}" --config "$WORK/keep.yaml" --out "$WORK/keep.yaml"
    check "$s: the config survives" -- cmp -s "$WORK/keep.yaml" "$WORK/keep.ref"
  fi
  if [[ " ${NEEDS_NOTHING[*]} " == *" $s "* ]]; then
    bad "$s: unknown key" "unknown key 'zzz_unknown_key'" -- "$x" --set zzz_unknown_key=1 --out "$OUTDIR/o.h5"
  fi
  # Artifact kinds.
  if [ ${#args[@]} -gt 0 ]; then
    read -r -a a <<<"$(with "$WORK/truncated.h5")"
    bad "$s: truncated artifact" "truncated.h5: not a valid HDF5 file" -- "$x" "${a[@]}" "${out[@]}"
    read -r -a a <<<"$(with "$WORK/text.h5")"
    bad "$s: text as artifact" "text.h5: not a valid HDF5 file" -- "$x" "${a[@]}" "${out[@]}"
    read -r -a a <<<"$(with "$WORK/none.h5")"
    bad "$s: missing artifact" "none.h5: no such file" -- "$x" "${a[@]}" "${out[@]}"
    read -r -a a <<<"$(with /dev/zero)"
    bad "$s: device as artifact" "/dev/zero: is a character device" -- "$x" "${a[@]}" "${out[@]}"
  fi
done
# A valid artifact of another schema.
for s in assign families homogenize fill-targets map verify-map ddfem-compress; do
  read -r -a args <<<"$(artifact_args "$s")"
  a=("${args[@]//ART/$WORK/good.gamut.h5}")
  bad "$s: wrong schema" "good.gamut.h5: expected schema .*found schema 'msfab.gamut'" -- \
    "$BIN/msfab-$s" "${a[@]}" --out "$OUTDIR/o.h5"
done
# A NaN written into the level set of a valid gamut (its contiguous
# storage patched in place): refused where it is read, naming the dataset.
cp "$WORK/good.gamut.h5" "$WORK/nan.gamut.h5"
offset=$(h5dump -p -H -d /level_set/phi "$WORK/nan.gamut.h5" | awk '/OFFSET/ { print $2 }')
printf '\x00\x00\x00\x00\x00\x00\xf8\x7f' | dd of="$WORK/nan.gamut.h5" bs=1 seek=$((offset + 40)) conv=notrunc 2>/dev/null
bad "topopt: NaN inside an artifact" "nan.gamut.h5: dataset '/level_set/phi' holds NaN at index 5" -- \
  "$BIN/msfab-topopt" --set space=cubic2d --set gamut="$WORK/nan.gamut.h5" --out "$OUTDIR/o.h5"
bad "inspect: wrong schema" "good.gamut.h5: expected schema 'msfab.result'" -- \
  "$BIN/msfab-inspect" "$WORK/good.gamut.h5" --schema msfab.result
finish
