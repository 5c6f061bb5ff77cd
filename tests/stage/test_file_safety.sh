#!/bin/bash
# Inputs and outputs every stage shares (docs/cli.md, "Files"): alias bombs,
# devices and FIFOs as inputs are refused at once; an output that is also an
# input, an existing folder, or lies in a missing folder is refused before
# any work; a symlink planted under a temporary's old fixed name is never
# followed. Each case is bounded in time, so a hang fails instead of
# stalling the suite.
BIN=$1 SRC=$2
source "$SRC/tests/stage/lib.sh"
SIM="$BIN/msfab-simulate"
H="$BIN/msfab-homogenize"
T="timeout 60"

# A YAML alias bomb: nine levels of nine aliases, 9^9 scalars in 700 bytes.
{
  echo "l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"
  for i in 1 2 3 4 5 6 7 8; do
    p="*l$((i - 1))"
    echo "l$i: &l$i [$p, $p, $p, $p, $p, $p, $p, $p, $p]"
  done
} > "$WORK/bomb.yaml"
expect_exit 2 "bomb.yaml: YAML aliases expand" -- $T "$SIM" --config "$WORK/bomb.yaml" --out "$WORK/o.h5"
expect_exit 2 "bomb.yaml: YAML aliases expand" -- $T "$H" --config "$WORK/bomb.yaml" --out "$WORK/o.h5"

# Devices and FIFOs as config or voxel files.
mkfifo "$WORK/pipe.yaml"
expect_exit 2 "/dev/zero: is a character device" -- $T "$SIM" --config /dev/zero --out "$WORK/o.h5"
expect_exit 2 "pipe.yaml: is a FIFO" -- $T "$SIM" --config "$WORK/pipe.yaml" --out "$WORK/o.h5"
printf 'materials:\n  - {id: 1, model: linear, E: 1.0e6, nu: 0.3}\ncell: {voxels: /dev/zero}\n' > "$WORK/zero.yaml"
expect_exit 2 "/dev/zero: is a character device" -- $T "$H" --config "$WORK/zero.yaml" --out "$WORK/o.h5"
sed "s|/dev/zero|$WORK/pipe.yaml|" "$WORK/zero.yaml" > "$WORK/fifo.yaml"
expect_exit 2 "pipe.yaml: is a FIFO" -- $T "$H" --config "$WORK/fifo.yaml" --out "$WORK/o.h5"
expect_exit 2 "/dev/zero: is a character device" -- $T "$BIN/msfab-inspect" /dev/zero
check "nothing written" -- test ! -e "$WORK/o.h5"

# An output that is also an input is refused before any work, the input
# left as it was: the same name, another spelling, a hard link, a symlink.
cp "$SRC/configs/scenes/demo_bar.yaml" "$WORK/scene.yaml"
cp "$WORK/scene.yaml" "$WORK/scene.ref"
ln "$WORK/scene.yaml" "$WORK/hard.yaml"
ln -s "$WORK/scene.yaml" "$WORK/soft.yaml"
mkdir "$WORK/sub"
for out in "$WORK/scene.yaml" "$WORK/sub/../scene.yaml" "$WORK/hard.yaml" "$WORK/soft.yaml"; do
  expect_exit 2 "--config '.*' and --out '.*' name the same file" -- $T "$SIM" --config "$WORK/scene.yaml" --out "$out"
done
check "config untouched" -- cmp -s "$WORK/scene.yaml" "$WORK/scene.ref"
echo "precious" > "$WORK/set.h5"
expect_exit 2 "--structures '.*set.h5' and --out '.*set.h5' name the same file" -- \
  $T "$H" --structures "$WORK/set.h5" --out "$WORK/set.h5"
check "structures untouched" -- bash -c "[ \"\$(cat '$WORK/set.h5')\" = precious ]"
expect_exit 2 "--structures '.*x.gamut.h5' and --out '.*x.gamut.h5' name the same file" -- \
  $T "$BIN/msfab-gamut-sample" --structures "$WORK/x.gamut.h5" --out "$WORK/x.gamut.h5"

# gamut-sample's second artifact is checked up front too.
expect_exit 2 "--structures .*output folder does not exist" -- \
  $T "$BIN/msfab-gamut-sample" --structures "$WORK/nowhere/s.h5" --out "$WORK/g.gamut.h5"

# An output path that is a folder, or in a missing folder: exit 2 at once.
mkdir "$WORK/folder.h5"
expect_exit 2 "--out .*folder.h5: is a folder" -- $T "$SIM" --out "$WORK/folder.h5"
expect_exit 2 "output folder does not exist" -- $T "$SIM" --out "$WORK/nowhere/o.h5"

# Symlinks planted under the old fixed temporary names are not followed:
# the file they point to survives, and the outputs are regular files.
echo "victim" > "$WORK/victim.txt"
ln -s "$WORK/victim.txt" "$WORK/r.h5.tmp"
ln -s "$WORK/victim.txt" "$WORK/r.xmf.tmp"
expect_exit 0 "" -- $T "$SIM" --out "$WORK/r.h5" --quiet
check "planted symlink not followed" -- bash -c "[ \"\$(cat '$WORK/victim.txt')\" = victim ]"
check "outputs are regular files" -- bash -c "[ -f '$WORK/r.h5' ] && [ ! -L '$WORK/r.h5' ] && [ -f '$WORK/r.xmf' ] && [ ! -L '$WORK/r.xmf' ]"
check "no temporary of ours left" -- bash -c "! ls '$WORK' | grep -Eq '\.[0-9a-f]{16}\.tmp$'"
finish
