#!/bin/bash
# msfab-inspect: provenance, the stored config, each input with its hash
# and whether the file is still the one that was read; only its own options.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
I="$BIN/msfab-inspect"

tiny_cubic3d_set 1
cp "$WORK/set.microstructures.h5" "$WORK/in.h5"
check "homogenize a set" -- "$BIN/msfab-homogenize" --structures "$WORK/in.h5" --out "$WORK/run.h5" --quiet
"$I" "$WORK/run.h5" > "$WORK/inspect.txt"
check "inspect names the schema and producer" -- grep -q "schema    msfab.microstructures" "$WORK/inspect.txt"
check "inspect prints the stored config" -- grep -q "^config:" "$WORK/inspect.txt"
check "the input is listed with its hash, unchanged, and its producer" -- \
  grep -q "input .*in.h5  sha256 [0-9a-f]\{64\}  (unchanged, made by msfab-gamut-sample" "$WORK/inspect.txt"
printf 'x' >> "$WORK/in.h5"
check "an edited input reads as changed" -- bash -c "'$I' '$WORK/run.h5' | grep -q 'in.h5 .*(changed since'"
rm "$WORK/in.h5"
check "a removed input reads as missing" -- bash -c "'$I' '$WORK/run.h5' | grep -q 'in.h5 .*(missing now)'"
check "--no-config leaves the config out" -- bash -c "! '$I' --no-config '$WORK/run.h5' | grep -q '^config:'"
check "--version works" -- "$I" --version
expect_exit 2 "threads" -- "$I" "$WORK/run.h5" --threads 2
expect_exit 2 "out" -- "$I" "$WORK/run.h5" --out "$WORK/x.h5"
finish
