#!/bin/bash
# The layers of common/: every #include of a file in common/<module>/ names
# the module itself or one it links (directly or through others) in
# common/CMakeLists.txt, as the build wrote them to module_deps.txt; and
# docs/modules.md shows the same table (tools/module_table.sh). Each stage's
# includes are among the modules its build links and lists.
BIN=$1 SRC=$(cd "$2" && pwd)
source "$SRC/tests/stage/lib.sh"
DEPS="$BIN/../module_deps.txt"
check "the build wrote the module table" -- test -s "$DEPS"

# closure MODULE: the module and everything it links, one per line.
closure() {
  local todo=("$1") seen=" "
  while [ ${#todo[@]} -gt 0 ]; do
    local m=${todo[0]}
    todo=("${todo[@]:1}")
    case "$seen" in *" $m "*) continue ;; esac
    seen="$seen$m "
    for d in $(awk -F': *' -v m="$m" '$1 == m { print $2 }' "$DEPS"); do todo+=("$d"); done
  done
  echo "$seen" | tr ' ' '\n' | sed '/^$/d'
}

# included_modules FILE...: the folders named by the files' #include lines.
included_modules() { cat "$@" 2>/dev/null | sed -n 's|^#include "\([a-z_]*\)/.*|\1|p' | sort -u; }
# tally OK MESSAGE: a pass when OK is 0, otherwise a failure printing MESSAGE.
tally() {
  if [ "$1" = 0 ]; then PASSES=$((PASSES + 1)); else echo "FAIL: $2"; FAILURES=$((FAILURES + 1)); fi
}

modules=$(awk -F: '{ print $1 }' "$DEPS")
for m in $modules; do
  allowed=$(closure "$m")
  for f in "$SRC"/common/"$m"/*.hpp "$SRC"/common/"$m"/*.cpp; do
    [ -e "$f" ] || continue
    for used in $(included_modules "$f"); do
      grep -qx "$used" <<<"$allowed"
      tally $? "${f#$SRC/} includes $used/, which $m does not link (common/CMakeLists.txt)"
    done
  done
done
# Each stage links the modules its files include (stages/CMakeLists.txt), and
# its identity lists their files: an #include added since the build was
# configured would escape both.
for dir in "$SRC"/stages/*/; do
  stage=$(basename "$dir") list="$BIN/../identity/msfab-$stage.files"
  [ -f "$dir/main.cpp" ] || continue
  check "the build lists the sources of msfab-$stage" -- test -s "$list"
  for used in $(included_modules "$dir"/*.cpp "$dir"/*.hpp); do
    [ -d "$SRC/common/$used" ] || continue
    grep -q "^common/$used/" "$list"
    tally $? "stages/$stage includes $used/, which its build does not list (re-run cmake)"
  done
done
check "every module of common/ is in the table" -- bash -c "for d in '$SRC'/common/*/; do grep -q \"^\$(basename \$d):\" '$DEPS' || exit 1; done"
bash "$SRC/tools/module_table.sh" "$DEPS" > "$WORK/modules.md"
check "docs/modules.md shows the build's table (regenerate: tools/module_table.sh build/module_deps.txt)" -- \
  bash -c "sed -n '/<!-- modules:begin -->/,/<!-- modules:end -->/p' '$SRC/docs/modules.md' | sed '1d;\$d' | diff - '$WORK/modules.md'"
finish
