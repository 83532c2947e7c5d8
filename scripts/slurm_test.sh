#!/usr/bin/env bash
# A split render on a real SLURM cluster of one node, started here: the
# deploy/slurm/ scripts run as a 4-task job array and a merge job
# (--dependency=afterok), and the merged image must equal a one-machine
# `rt-view render` bit for bit. Then a part is lost (as when a task is
# killed): the merge must name it, and resubmitting that one index
# (--array=K) must complete the image.
#
#   scripts/slurm_test.sh [RT_VIEW]      (default: target/debug/rt-view, built if missing)
#
# Runs as root. Installs Debian's slurm-wlm and munge if missing, writes a
# slurm.conf and a munge key into a temporary folder, starts munged,
# slurmctld and slurmd from it (own ports, own socket: nothing of the
# machine's is used or touched), and stops exactly those daemons on exit,
# by their pid files. Exit status 0 only when every step passed; when SLURM
# cannot be installed or started it fails loudly (status 1), never skips.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)

fail() {
  echo "slurm_test: FAILED: $*" >&2
  exit 1
}
step() { echo "== $*"; }

[[ $(id -u) -eq 0 ]] || fail "must run as root (it starts slurmctld, slurmd and munged)"

rt_view=${1:-target/debug/rt-view}
if [[ ! -x $rt_view ]]; then
  step "building rt-view"
  cargo build -p rt-view
fi
rt_view=$(realpath "$rt_view")

step "SLURM and munge (Debian packages slurm-wlm, munge)"
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null ||
  ! command -v munged >/dev/null; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq || fail "apt-get update"
  apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null || fail "cannot install slurm-wlm and munge"
fi
slurmctld -V

work=$(mktemp -d /tmp/rt-slurm.XXXXXX)
chmod 755 "$work"
started=()
stop_daemons() {
  local status=$?
  for pidfile in "${started[@]}"; do
    [[ -f $pidfile ]] || continue
    local pid
    pid=$(cat "$pidfile")
    # Only the process this script started: its pid file, its command name.
    if [[ -n $pid ]] && kill -0 "$pid" 2>/dev/null; then
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -0 "$pid" 2>/dev/null && kill -9 "$pid" 2>/dev/null || true
    fi
  done
  if [[ $status -ne 0 ]]; then
    for log in "$work"/*.log "$work"/out/logs/*; do
      [[ -f $log ]] && { echo "--- $log"; tail -n 30 "$log"; }
    done >&2
  fi
  rm -rf "$work"
  exit "$status"
}
trap stop_daemons EXIT

step "munged with a new key in $work"
mkdir -p "$work/munge"
chmod 700 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
socket=$work/munge/munge.socket
started+=("$work/munge/munged.pid")
munged --force --key-file="$work/munge/munge.key" --socket="$socket" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/munged.log" --seed-file="$work/munge/seed" ||
  fail "munged does not start"
for _ in $(seq 50); do [[ -S $socket ]] && break; sleep 0.1; done
[[ -S $socket ]] || fail "munged made no socket"
munge --socket="$socket" -n | unmunge --socket="$socket" >/dev/null || fail "munge cannot encode and decode a credential"

step "slurm.conf: one node, $(nproc) cores"
host=$(hostname -s)
cpus=$(nproc)
port=$((20000 + RANDOM % 20000))
mkdir -p "$work/state" "$work/spool" "$work/out"
export SLURM_CONF=$work/slurm.conf
cat >"$SLURM_CONF" <<CONF
ClusterName=rtview
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmdTimeout=30
MinJobAge=30
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES
CONF
# slurmctld and slurmd require a cgroup.conf only for cgroup plugins (not used).

step "slurmctld and slurmd"
started+=("$work/slurmctld.pid" "$work/slurmd.pid")
slurmctld -c -f "$SLURM_CONF" || fail "slurmctld does not start"
slurmd -f "$SLURM_CONF" -N "$host" || fail "slurmd does not start"
ready=
for _ in $(seq 100); do
  if sinfo -h -o '%T' 2>/dev/null | grep -q -E '^(idle|mixed|allocated)'; then
    ready=1
    break
  fi
  sleep 0.2
done
[[ -n $ready ]] || fail "the node did not come up: $(sinfo 2>&1 || true)"
sinfo

# A small global-illumination scene (every pixel lit by paths).
scene=$repo/scenes/cornell_box.ron
size=(--width 64 --height 48 --spp 32)
out=$work/out
export RT_VIEW=$rt_view

# Waits until job $1 (every task of an array) has ended; fails unless each
# task COMPLETED. Polls scontrol four times a second: `sbatch --wait`
# polls ever more slowly, up to half a minute after a job has ended.
wait_job() {
  local id=$1 states
  for _ in $(seq 2400); do
    states=$(scontrol -o show job "$id" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2 | sort -u | tr '\n' ' ')
    if [[ -n $states && ! $states =~ (PENDING|RUNNING|CONFIGURING|COMPLETING|REQUEUED|RESIZING|SUSPENDED) ]]; then
      [[ $states == "COMPLETED " ]] && return 0
      echo "job $id ended: $states" >&2
      return 1
    fi
    sleep 0.25
  done
  echo "job $id still not done after 10 minutes" >&2
  return 1
}

step "job array of 4 parts, then the merge (afterok)"
start=$(date +%s.%N)
array=$(sbatch --parsable --array=0-3 --output="$out/render-%a.log" \
  deploy/slurm/render.sbatch "$scene" "$out" 4 "${size[@]}") || fail "cannot submit the job array"
array=${array%%;*}
merge=$(sbatch --parsable --dependency=afterok:"$array" --output="$out/merge.log" \
  deploy/slurm/merge.sbatch "$out" 4 "$out/merged.exr") || fail "cannot submit the merge job"
merge=${merge%%;*}
wait_job "$array" || fail "the job array failed"
wait_job "$merge" || fail "the merge job failed: $(cat "$out/merge.log")"
echo "array $array and merge $merge done in $(echo "$(date +%s.%N) - $start" | bc) s"
cat "$out"/render-*.log "$out/merge.log"

step "the one-machine render, compared bit for bit"
"$rt_view" render "$scene" "${size[@]}" -o "$out/whole.exr"
cmp "$out/merged.exr" "$out/whole.exr" || fail "the merged image differs from the one-machine render"
echo "merged.exr == whole.exr, byte for byte"

step "a lost part is named, and resubmitting its index alone completes the image"
rm "$out/part-2-of-4.rtpart"
if "$rt_view" merge "$out"/part-*-of-4.rtpart -o "$out/again.exr" 2>"$out/missing.txt"; then
  fail "the merge of 3 of 4 parts succeeded"
fi
cat "$out/missing.txt"
grep -q "missing part 2 of 4" "$out/missing.txt" || fail "the merge did not name part 2"
again=$(sbatch --parsable --array=2 --output="$out/render-again-%a.log" \
  deploy/slurm/render.sbatch "$scene" "$out" 4 "${size[@]}") || fail "cannot resubmit part 2"
wait_job "${again%%;*}" || fail "the resubmitted task failed"
"$rt_view" merge "$out"/part-*-of-4.rtpart -o "$out/again.exr"
cmp "$out/again.exr" "$out/whole.exr" || fail "the image completed by the resubmitted part differs"

echo "slurm_test: OK"
