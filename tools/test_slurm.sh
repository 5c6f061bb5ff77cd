#!/bin/bash
# make -f Makefile.pipeline test-slurm: brings up a single-node Slurm
# (slurmctld, slurmd and munge from Debian's packages, installed when
# missing; root), submits the tiny DDFEM database build as a 2-rank job
# through pipelines/slurm/stage.sbatch (sbatch, then srun --mpi=pmix inside
# it), builds the same database locally on one rank, and checks that the
# two are equal dataset for dataset, bit for bit (wall times aside). Everything it writes is
# under WORK (default out/test-slurm): its own slurm.conf (SLURM_CONF; the
# system's /etc/slurm is left alone), spool folders, logs and both
# databases. The daemons it started are stopped when it ends.
#   tools/test_slurm.sh BUILD WORK
set -euo pipefail
BUILD=${1:-build}
WORK=$(mkdir -p "${2:-out/test-slurm}" && cd "${2:-out/test-slurm}" && pwd)
ROOT=$(pwd)
say() { echo "test-slurm: $*"; }
fail() { echo "test-slurm: FAIL: $*" >&2; exit 1; }

# -- packages ---------------------------------------------------------------
missing=$(for p in slurm-wlm munge; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || echo "$p"; done)
if [ -n "$missing" ]; then
  [ "$(id -u)" = 0 ] || { echo "test-slurm: need root to install: $missing" >&2; exit 2; }
  say "installing Debian packages: $missing"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq && apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi
[ "$(id -u)" = 0 ] || { echo "test-slurm: the daemons run as root here; run as root" >&2; exit 2; }

# -- munge (the authentication Slurm's daemons and clients share) -----------
started=()
cleanup() {
  for pid in "${started[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
}
trap cleanup EXIT
if ! munge -n </dev/null >/dev/null 2>&1; then
  [ -s /etc/munge/munge.key ] || { say "creating /etc/munge/munge.key"; mungekey --create --force; }
  chown munge:munge /etc/munge/munge.key 2>/dev/null || true
  chmod 400 /etc/munge/munge.key
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge 2>/dev/null || true
  say "starting munged"
  if id munge >/dev/null 2>&1 && command -v runuser >/dev/null; then
    runuser -u munge -- munged
  else
    munged --force
  fi
  for _ in $(seq 50); do munge -n </dev/null >/dev/null 2>&1 && break; sleep 0.2; done
  munge -n </dev/null | unmunge >/dev/null || fail "munged does not answer"
  started+=("$(cat /run/munge/munged.pid 2>/dev/null || pgrep -n munged)")
fi

# -- slurm.conf for this node -------------------------------------------------
host=$(hostname -s)
node=$(slurmd -C | head -1)   # NodeName=<host> CPUs=... RealMemory=... as slurmd sees them
mkdir -p "$WORK/etc" "$WORK/spool/ctld" "$WORK/spool/d" "$WORK/log"
export SLURM_CONF=$WORK/etc/slurm.conf
cat > "$SLURM_CONF" <<EOF
# Written by tools/test_slurm.sh: one node, root daemons, no cgroups.
ClusterName=msfab-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
StateSaveLocation=$WORK/spool/ctld
SlurmdSpoolDir=$WORK/spool/d
SlurmctldPidFile=$WORK/spool/slurmctld.pid
SlurmdPidFile=$WORK/spool/slurmd.pid
SlurmctldLogFile=$WORK/log/slurmctld.log
SlurmdLogFile=$WORK/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
SchedulerType=sched/builtin
$node NodeAddr=127.0.0.1
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

say "starting slurmctld and slurmd (logs in $WORK/log)"
slurmctld -D -i >"$WORK/log/slurmctld.out" 2>&1 &
started+=($!)
slurmd -D >"$WORK/log/slurmd.out" 2>&1 &
started+=($!)
for _ in $(seq 120); do
  state=$(sinfo -h -o %t 2>/dev/null | head -1 || true)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || { tail -20 "$WORK/log/slurmctld.log" "$WORK/log/slurmd.log" >&2 || true; fail "the node is not idle (state '$state')"; }
say "node $host is up: $(sinfo -h -o '%c CPUs, %m MB')"

# -- the same database through Slurm (2 ranks) and locally (1 rank) ---------
rm -rf "$WORK/slurm" "$WORK/local"
target=ddfem/tiny.coarse_db.h5
say "sbatch -n 2 -c 1 pipelines/slurm/stage.sbatch ($target, 2 MPI ranks)"
sbatch --wait -n 2 -c 1 --chdir="$ROOT" --output="$WORK/log/job-%j.log" \
  --export=ALL,TARGET="$WORK/slurm/$target",OUT="$WORK/slurm",BUILD="$BUILD" \
  pipelines/slurm/stage.sbatch > "$WORK/log/sbatch.out" || {
  cat "$WORK"/log/job-*.log >&2 || true; fail "the job failed"; }
job=$(awk '{ print $NF }' "$WORK/log/sbatch.out")
log=$WORK/log/job-$job.log
grep -q "2 rank(s)" "$log" || { cat "$log" >&2; fail "the job's database build did not run on 2 ranks"; }
say "job $job ran on 2 ranks (log $log)"
make -s -f Makefile.pipeline BUILD="$BUILD" OUT="$WORK/local" RANKS=1 "$WORK/local/$target" > "$WORK/log/local.log" 2>&1 || {
  cat "$WORK/log/local.log" >&2; fail "the local build failed"; }

PYTHON=${PYTHON:-$( [ -x /usr/bin/python3 ] && echo /usr/bin/python3 || echo python3)}
"$PYTHON" - "$WORK/slurm/$target" "$WORK/local/$target" <<'EOF' || fail "the Slurm and local databases differ"
import sys, h5py, numpy as np
a, b = (h5py.File(p, "r") for p in sys.argv[1:])
names = []
a.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
other = []
b.visititems(lambda n, o: other.append(n) if isinstance(o, h5py.Dataset) else None)
if sorted(names) != sorted(other):
    sys.exit(f"dataset lists differ: {sorted(set(names) ^ set(other))}")
timings = [n for n in names if n.endswith("seconds")]  # wall times, the one thing allowed to differ
for n in names:
    if n in timings:
        continue
    x, y = a[n][()], b[n][()]
    if np.asarray(x).tobytes() != np.asarray(y).tobytes() or np.shape(x) != np.shape(y):
        sys.exit(f"/{n} differs")
print(f"test-slurm: {len(names) - len(timings)} datasets equal bit for bit "
      f"(not compared: the timings {', '.join('/' + n for n in timings)})")
EOF
say "passed"
