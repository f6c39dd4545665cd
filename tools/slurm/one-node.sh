#!/usr/bin/env bash
# A real one-node Slurm cluster on this machine, and a campaign flown through it.
#
#   tools/slurm/one-node.sh [--runs N] [--array K] [--keep]
#
# 1. installs Slurm (slurm-wlm: slurmctld, slurmd, sbatch, squeue, scancel)
#    and munge from the distribution's packages (apt-get; needs root);
# 2. writes a slurm.conf for one node, this machine, on 127.0.0.1, with a
#    fresh munge key, and starts munged, slurmctld and slurmd;
# 3. waits until `sinfo` shows the node idle;
# 4. flies a small campaign through it (`helicon mc --slurm`: a job array of
#    K shard tasks and a merge job after them), cancels one task of a second
#    submission and resubmits only what is missing, then flies the same
#    campaign locally and compares runs.csv, traces.csv, stats.json and
#    stats.md byte for byte;
# 5. stops the daemons and removes its files (unless --keep).
#
# Any failure, an install that fails included, exits non-zero with a message:
# nothing is skipped.
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
RUNS=24
ARRAY=4
KEEP=0
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) RUNS=$2; shift 2 ;;
    --array) ARRAY=$2; shift 2 ;;
    --keep) KEEP=1; shift ;;
    *) echo "one-node.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
say() { echo "one-node: $*"; }
die() { echo "one-node: FAILED: $*" >&2; exit 1; }

[ "$(id -u)" = 0 ] || die "needs root (apt-get, daemons)"
BIN=${HELICON:-$ROOT/target/release/helicon}
if [ ! -x "$BIN" ] && [ -z "${HELICON:-}" ]; then
  say "building helicon"
  cargo build --release -q -p helicon-cli || die "cargo build --release -p helicon-cli"
fi
[ -x "$BIN" ] || die "no helicon binary at $BIN"

# 1. packages
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null || ! command -v sbatch >/dev/null; then
  say "installing slurm-wlm and munge"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq || die "apt-get update"
  apt-get install -y -qq slurm-wlm munge >/dev/null || die "apt-get install slurm-wlm munge"
fi
for c in slurmctld slurmd munged sbatch squeue scancel sinfo; do
  command -v "$c" >/dev/null || die "$c missing after the install"
done

# 2. configuration (everything under one temporary folder)
W=$(mktemp -d /tmp/helicon-slurm.XXXXXX)
chmod 755 "$W"
cleanup() {
  local rc=$?
  for f in "$W"/slurmd.pid "$W"/slurmctld.pid "$W"/munge/munged.pid; do
    [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null || true
  done
  sleep 1
  if [ $rc -ne 0 ]; then
    for l in slurmctld.log slurmd.log munge/munged.log; do
      [ -f "$W/$l" ] && { echo "--- $l (last lines)"; tail -n 20 "$W/$l"; } >&2
    done
  fi
  if [ "$KEEP" = 0 ]; then rm -rf "$W"; else say "kept $W"; fi
  exit $rc
}
trap cleanup EXIT
mkdir -p "$W/munge" "$W/munge-socket" "$W/spool/ctld" "$W/spool/d" "$W/out"
chown munge:munge "$W/munge" "$W/munge-socket"
chmod 700 "$W/munge"
chmod 755 "$W/munge-socket" # munged wants the socket's folder open to all
dd if=/dev/urandom of="$W/munge/munge.key" bs=1024 count=1 status=none
chown munge:munge "$W/munge/munge.key"
chmod 400 "$W/munge/munge.key"
SOCK=$W/munge-socket/munge.socket
HOST=$(hostname -s)
CPUS=$(nproc)
MEM=$(( $(awk '/MemTotal/{print $2}' /proc/meminfo) / 1024 / 2 ))
cat > "$W/slurm.conf" <<CONF
ClusterName=helicon-one-node
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmctldPort=6917
SlurmdPort=6918
AuthType=auth/munge
AuthInfo=socket=$SOCK
CredType=cred/munge
StateSaveLocation=$W/spool/ctld
SlurmdSpoolDir=$W/spool/d
SlurmctldPidFile=$W/slurmctld.pid
SlurmdPidFile=$W/slurmd.pid
SlurmctldLogFile=$W/slurmctld.log
SlurmdLogFile=$W/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MaxArraySize=100001
MinJobAge=600
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=debug Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$W/slurm.conf

# 3. daemons
say "starting munged, slurmctld and slurmd (config $SLURM_CONF)"
runuser -u munge -- munged --socket="$SOCK" --key-file="$W/munge/munge.key" \
  --pid-file="$W/munge/munged.pid" --log-file="$W/munge/munged.log" --seed-file="$W/munge/seed" \
  || die "munged did not start (see $W/munge/munged.log)"
munge -S "$SOCK" -n | unmunge -S "$SOCK" >/dev/null || die "munge round trip"
slurmctld -f "$SLURM_CONF" || die "slurmctld did not start"
slurmd -f "$SLURM_CONF" -N "$HOST" || die "slurmd did not start"
for i in $(seq 1 60); do
  state=$(sinfo -h -N -o '%t' 2>/dev/null | head -n1 || true)
  [ "$state" = idle ] && break
  [ "$i" = 20 ] && scontrol update nodename="$HOST" state=resume 2>/dev/null || true
  sleep 1
done
[ "${state:-}" = idle ] || die "node not idle after 60 s (sinfo: ${state:-nothing})"
say "node $HOST idle: $(sinfo -h -o '%P %a %D %t %C')"

# 4. a campaign through it
CAMP=$W/campaign.toml
sed -e "s/^runs = .*/runs = $RUNS/" "$ROOT/tools/slurm/ci-campaign.toml" > "$CAMP"
cp "$ROOT/tools/slurm/ci-scenario.toml" "$W/ci-scenario.toml"
OUT=$W/out/slurm
"$BIN" mc "$CAMP" --runs "$RUNS" --slurm --array "$ARRAY" --time 10 --out "$OUT" --dry-run >/dev/null \
  || die "helicon mc --slurm --dry-run"
[ -f "$OUT/slurm/array.sbatch" ] && [ -f "$OUT/slurm/merge.sbatch" ] || die "--dry-run wrote no batch scripts"
say "submitting the campaign: $RUNS runs as $ARRAY array tasks and a merge job"
"$BIN" mc "$CAMP" --runs "$RUNS" --slurm --array "$ARRAY" --time 10 --out "$OUT" | tee "$W/submit.txt" \
  || die "helicon mc --slurm"
wait_done() { # folder, seconds
  local t=0
  while :; do
    if "$BIN" mc status "$1" > "$W/status.txt" 2>&1 && grep -q '^merged: done' "$W/status.txt"; then return 0; fi
    if grep -q '^merged: never' "$W/status.txt"; then cat "$W/status.txt"; die "the merge job cannot run (a task failed)"; fi
    t=$((t + 2)); [ $t -ge "$2" ] && { cat "$W/status.txt"; squeue || true; die "campaign not merged after $2 s"; }
    sleep 2
  done
}
wait_done "$OUT" 600
cat "$W/status.txt"

# a second submission with a task cancelled while queued, then resubmitted
OUT2=$W/out/slurm-resume
scontrol update partitionname=debug state=down >/dev/null # hold the queue
"$BIN" mc "$CAMP" --runs "$RUNS" --slurm --array "$ARRAY" --time 10 --out "$OUT2" > "$W/submit2.txt" \
  || die "second submission"
AID=$(awk '/array job/{print $NF}' "$W/submit2.txt")
[ -n "$AID" ] || die "no array job id printed: $(cat "$W/submit2.txt")"
scancel "${AID}_1" || die "scancel ${AID}_1"
scontrol update partitionname=debug state=up >/dev/null
# the merge job can never start now (afterok on a cancelled task)
for i in $(seq 1 120); do
  "$BIN" mc status "$OUT2" > "$W/status2.txt" 2>&1 || true
  grep -q "^shards: $((ARRAY - 1)) done" "$W/status2.txt" && ! squeue -h -j "$AID" -t R,PD 2>/dev/null | grep -q . && break
  sleep 2
done
cat "$W/status2.txt"
grep -q "^shards: $((ARRAY - 1)) done" "$W/status2.txt" || die "expected $((ARRAY - 1)) shards done after the cancel"
say "resubmitting what is missing"
"$BIN" mc "$CAMP" --runs "$RUNS" --slurm --array "$ARRAY" --time 10 --out "$OUT2" | tee "$W/submit3.txt" \
  || die "resubmission"
grep -q "tasks 1 of" "$W/submit3.txt" || die "the resubmission did not submit task 1 only: $(cat "$W/submit3.txt")"
wait_done "$OUT2" 600

# 5. the same campaign locally
say "flying the same campaign locally"
"$BIN" mc "$CAMP" --runs "$RUNS" --out "$W/out/local" 2>/dev/null || die "local run"
for d in "$OUT" "$OUT2"; do
  for f in runs.csv traces.csv stats.json stats.md; do
    cmp -s "$W/out/local/$f" "$d/$f" || die "$d/$f differs from the local run's"
  done
done
say "ok: $RUNS runs through Slurm ($ARRAY array tasks + merge, and a cancelled task resubmitted) equal the local run (runs.csv, traces.csv, stats.json, stats.md identical)"
