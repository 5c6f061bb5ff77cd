# Helpers shared by the msfab-simulate benchmarks (bench_ddfem.sh,
# bench_adaptive.sh). Needs BIN (the stage binaries) set by the caller.

attr() {  # attr FILE OBJECT NAME -> value (first element)
  h5dump -a "$2/$3" "$1" | sed -n 's/^ *(0): *//p' | head -n1
}
run() {  # run OUT ARGS...: msfab-simulate quietly, log kept next to OUT
  local out=$1
  shift
  timeout "${BENCH_RUN_LIMIT:-900}" "$BIN/msfab-simulate" --out "$out" --log-level warn "$@" > "${out%.h5}.log" 2>&1 ||
    { echo "bench: failed, see ${out%.h5}.log" >&2; tail -3 "${out%.h5}.log" >&2; return 1; }
}
