#!/usr/bin/env bash
# scripts/slurm_batch.sh on a real one-node Slurm (Debian slurm-wlm and munge), brought up by
# this test in its own folder with its own ports: the example batch (data/batch/manifest.json)
# as 4 shards of an array plus the merge job; then shard 1 alone resubmitted after its jobs'
# records were removed. Both merged tables must equal a local run's (all columns but the run
# time), and the resubmission must run exactly shard 1's jobs again.
#
#   SlurmReal.sh ENGAGE SOURCE_DIR WORK
# Needs root (the daemons run as root here); without root or Slurm it says why and exits 77
# (ctest: skipped).
set -uo pipefail
engage=$(realpath "$1")
src=$(realpath "$2")
work=$3
for tool in slurmctld slurmd munged sbatch squeue sinfo; do
  if ! command -v "$tool" >/dev/null; then
    echo "slurm-real: $tool not installed (apt-get install slurm-wlm munge): skipped"
    exit 77
  fi
done
if [ "$(id -u)" -ne 0 ]; then
  echo "slurm-real: needs root to run the Slurm daemons: skipped"
  exit 77
fi

rm -rf "$work"
mkdir -p "$work"/{state,spool,log}
work=$(realpath "$work")
export SLURM_CONF=$work/slurm.conf
cleanup() {
  scancel --full -u root >/dev/null 2>&1
  for p in slurmd slurmctld; do
    [ -f "$work/$p.pid" ] && kill "$(cat "$work/$p.pid")" 2>/dev/null
  done
  munged -s --socket="$work/munge.socket" >/dev/null 2>&1
}
trap cleanup EXIT

head -c 1024 /dev/urandom >"$work/munge.key"
chmod 400 "$work/munge.key"
if ! munged --force --socket="$work/munge.socket" --key-file="$work/munge.key" \
  --log-file="$work/log/munged.log" --pid-file="$work/munged.pid" \
  --seed-file="$work/munged.seed"; then
  echo "slurm-real: munged does not start here: skipped"
  exit 77
fi
host=$(hostname -s)
cat >"$SLURM_CONF" <<EOF
ClusterName=engagetest
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge.socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldPort=16917
SlurmdPort=16918
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
NodeName=$host CPUs=$(nproc) RealMemory=1000 State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -f "$SLURM_CONF" && slurmd -f "$SLURM_CONF" || {
  echo "slurm-real: the Slurm daemons do not start here: skipped"
  exit 77
}
for _ in $(seq 60); do
  sinfo -h -o %t 2>/dev/null | grep -q idle && break
  sleep 0.5
done
if ! sinfo -h -o %t 2>/dev/null | grep -q idle; then
  echo "slurm-real: the node did not come up (see $work/log): skipped"
  exit 77
fi

failures=0
check() {  # check WHAT COMMAND...
  if "${@:2}"; then echo "ok: $1"; else
    echo "FAIL: $1"
    failures=$((failures + 1))
  fi
}
wait_idle() {  # until no job is queued or running (at most 10 minutes)
  for _ in $(seq 1200); do
    [ -z "$(squeue -h 2>/dev/null)" ] && return 0
    sleep 0.5
  done
  return 1
}
table() { cut -d, -f1-5,7- "$1"; } # batch.csv without run_time_s
manifest=$src/data/batch/manifest.json

"$engage" batch "$manifest" --out "$work/local" --quiet >/dev/null 2>&1
ENGAGE="$engage" CPUS=1 "$src/scripts/slurm_batch.sh" submit "$manifest" "$work/slurm" 4
check "the array and the merge ran" wait_idle
check "the merge wrote batch.csv" test -f "$work/slurm/batch.csv"
check "4 shards: the merged table equals the local run's" \
  cmp <(table "$work/local/batch.csv") <(table "$work/slurm/batch.csv")
check "each shard has its log in OUT/logs" test "$(ls "$work"/slurm/logs/shard-*.log | wc -l)" -eq 4

# Shard 1 alone again: its jobs (indices 1, 5, 9, ...) lose their records and are run anew.
mapfile -t names < <(awk -F, 'NR > 1 && ($1 - 1) % 4 == 1 { gsub(/"/, "", $2); print $2 }' \
  "$work/slurm/batch.csv")
for n in "${names[@]}"; do rm -rf "$work/slurm/jobs/$n"; done
rm -f "$work/slurm/batch.csv"
ENGAGE="$engage" CPUS=1 "$src/scripts/slurm_batch.sh" submit "$manifest" "$work/slurm" 4 --array=1
check "the resubmitted shard and the merge ran" wait_idle
check "shard 1 ran its ${#names[@]} jobs again" \
  bash -c "for n in ${names[*]}; do test -f '$work/slurm/jobs/'\$n/job.json || exit 1; done"
check "resubmitted: the merged table equals the local run's" \
  cmp <(table "$work/local/batch.csv") <(table "$work/slurm/batch.csv")
echo "slurm-real: $failures failed"
[ "$failures" -eq 0 ]
