#!/bin/bash
# `make -f Makefile.pipeline help`: the usage lines of Makefile.pipeline
# and of each pipelines/*.mk header ("#   make -f Makefile.pipeline TARGET
# what it does", with their continuation lines), grouped by file, then every
# .PHONY target that no usage line names ("undocumented: ..."; the test
# tests/stage/test_make_help.sh fails on any). Usage: make_help.sh FILE...
set -euo pipefail
awk '
  FNR == 1 { if (NR > 1) print ""; print FILENAME ":"; usage = 0; continued = 0 }
  /^\.PHONY:/ || continued {
    line = $0; sub(/^\.PHONY:/, "", line); continued = (line ~ /\\$/); sub(/\\$/, "", line)
    n = split(line, names, /[ \t]+/)
    for (i = 1; i <= n; ++i) if (names[i] != "" && !(names[i] in phony)) { phony[names[i]] = 1; order[++count] = names[i] }
    next
  }
  /^#   make -f Makefile\.pipeline / {
    text = $0; sub(/^#   make -f Makefile\.pipeline /, "", text)
    split(text, words, /[ \t]+/); documented[words[1]] = 1
    print "  " text; usage = 1; next
  }
  usage && /^#      +[^ ]/ { text = $0; sub(/^#/, "", text); print "  " text; next }
  { usage = 0 }
  END {
    for (i = 1; i <= count; ++i) if (!(order[i] in documented)) { print "undocumented: " order[i]; missing = 1 }
  }
' "$@"
