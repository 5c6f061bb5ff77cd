#!/bin/bash
# Artifacts depend on their stage's identity, not on its binary's time
# stamp (Makefile.pipeline, tools/stage_identity.sh). On a copy of the
# sources, with stand-ins for the binaries that run the real ones:
# a finished target is up to date (make -q); an edit to one stage's source
# reruns that stage's artifacts and no other; a touched file, or an edit to
# a module neither stage links, reruns nothing; an edit to a module both
# link reruns both. --version and the artifacts' producer name the identity.
BIN=$(cd "$1" && pwd) SRC=$(cd "$2" && pwd)
source "$SRC/tests/stage/lib.sh"
IDS=$(cd "$BIN/.." && pwd)/identity

check "the build lists the sources of each stage" -- test -s "$IDS/msfab-simulate.files" -a -s "$IDS/msfab-ddfem-build.files"
check "the listed files are the identity the build recorded" -- \
  test "$(bash "$SRC/tools/stage_identity.sh" print "$SRC" "$IDS/msfab-simulate.files")" = "$(cat "$IDS/msfab-simulate.id")"
id=$(cat "$IDS/msfab-simulate.id")
check "--version prints the stage identity" -- bash -c "'$BIN/msfab-simulate' --version | grep -q 'stage identity $id'"
check "simulate's identity covers its own main" -- grep -qx stages/simulate/main.cpp "$IDS/msfab-simulate.files"
check "... and no other stage's files" -- bash -c "! grep -v '^stages/simulate/' '$IDS/msfab-simulate.files' | grep -q '^stages/[a-z-]*/'"
# A module the demo's two stages do not link, and a file both do.
unlinked=$(for m in "$SRC"/common/*/; do m=$(basename "$m");
  grep -q "^common/$m/" "$IDS/msfab-simulate.files" "$IDS/msfab-ddfem-build.files" || { echo "$m"; break; }; done)
check "some module is linked by neither simulate nor ddfem-build" -- test -n "$unlinked"
check "both link core/" -- bash -c "grep -q '^common/core/types.hpp' '$IDS/msfab-simulate.files' && grep -q '^common/core/types.hpp' '$IDS/msfab-ddfem-build.files'"

# The copy: sources and pipeline, a build folder whose binaries are
# wrappers (STAGE_BUILD touches a wrapper instead of compiling), the lists
# the real build wrote.
T=$WORK/tree B=$WORK/build
mkdir -p "$T" "$B/bin" "$B/identity"
(cd "$SRC" && cp -r CMakeLists.txt Makefile.pipeline cmake common configs pipelines python stages tools "$T/")
cp "$IDS"/*.files "$IDS"/stages.mk "$B/identity/"
for s in simulate ddfem-build; do
  printf '#!/bin/bash\nexec %q "$@"\n' "$BIN/msfab-$s" > "$B/bin/msfab-$s"
  chmod +x "$B/bin/msfab-$s"
done
touch "$B/.deps-ok"
# A database of one material: a second's build (the demo's tiny one takes 8).
cat > "$T/configs/ddfem/cache_one.yaml" <<'Y'
palette:
  - {name: soft, E: 1.0e5, nu: 0.45, density: 1000}
voxel_size: 0.001
sampling: {sphere_directions: 2, magnitudes: 2, max_strain: 0.1, seed: 1}
anisotropy: {directions: 6, strain: 0.05, seed: 7}
fit: {regularization: 0.02, heldout_fraction: 0.2, split_seed: 11, anisotropic: true, pinch_weight: 0.1}
Y
targets=("$WORK/out/ddfem/cache_one.coarse_db.h5" "$WORK/out/demo/bar.result.h5")
DB=${targets[0]} BAR=${targets[1]}
pipeline() {
  make -s -C "$T" -f Makefile.pipeline BUILD="$B" OUT="$WORK/out" MPIRUN= JOBS=2 QUIET=--quiet \
    STAGE_BUILD='touch $@' "$@"
}
stamp() { stat -c %Y.%y "$1"; }

check "the pipeline makes both artifacts" -- pipeline "${targets[@]}" > "$WORK/first.log" 2>&1
check "a finished target is up to date (make -q)" -- pipeline -q "${targets[@]}"
check "the artifact's producer names the identity" -- bash -c \
  "'$BIN/msfab-inspect' '$BAR' | grep -q 'stage ${id:0:12}'"

# stamps_after DESCRIPTION EXPECT_DB EXPECT_BAR: make both, then check which
# artifacts were rewritten (1) or left alone (0), and that all is up to date.
stamps_after() {
  local what=$1 want_db=$2 want_bar=$3 db0 bar0
  db0=$(stamp "$DB") bar0=$(stamp "$BAR")
  sleep 1.1  # a rewrite gets a later second
  pipeline "${targets[@]}" > "$WORK/run.log" 2>&1 || { echo "FAIL: $what: make failed"; tail -5 "$WORK/run.log"; FAILURES=$((FAILURES + 1)); return; }
  local got_db=0 got_bar=0
  [ "$(stamp "$DB")" = "$db0" ] || got_db=1
  [ "$(stamp "$BAR")" = "$bar0" ] || got_bar=1
  check "$what: database rerun $want_db, bar rerun $want_bar (got $got_db, $got_bar)" -- \
    test "$got_db$got_bar" = "$want_db$want_bar"
  check "$what: up to date afterwards" -- pipeline -q "${targets[@]}"
}

echo "// an edit" >> "$T/stages/simulate/main.cpp"
stamps_after "an edit to simulate's main" 0 1
check "the edit changed simulate's identity" -- test "$(cat "$B/identity/msfab-simulate.id")" != "$id"
touch "$T/stages/ddfem-build/main.cpp"
stamps_after "ddfem-build's main touched" 0 0
f=$(ls "$T/common/$unlinked/"*.hpp | head -1)
echo "// an edit" >> "$f"
stamps_after "an edit to common/$unlinked/, linked by neither" 0 0
echo "// an edit" >> "$T/common/core/types.hpp"
stamps_after "an edit to common/core/, linked by both" 1 1
finish
