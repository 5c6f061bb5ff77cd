#!/bin/bash
# The module table of docs/modules.md from the build's module_deps.txt
# (written by common/CMakeLists.txt): each module, what it links directly
# and which modules link it.
#   tools/module_table.sh build/module_deps.txt
set -euo pipefail
DEPS=${1:-build/module_deps.txt}
echo "| module | links | linked by |"
echo "|---|---|---|"
while IFS=: read -r module deps; do
  deps=$(echo $deps)
  users=$(awk -F': *' -v m="$module" '{ n = split($2, d, " "); for (i = 1; i <= n; ++i) if (d[i] == m) print $1 }' "$DEPS" | tr '\n' ' ')
  echo "| $module | ${deps:-—} | $(echo ${users:-—}) |"
done < "$DEPS"
