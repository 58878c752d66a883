#!/usr/bin/env bash
# CI step: scale-out on a real Slurm cluster of one node (this machine).
#
# 1. installs Debian's slurm-wlm and munge when missing (apt-get, quietly);
# 2. starts munged and a one-node cluster on localhost (slurmctld + slurmd) whose
#    configuration, state, spool, sockets and logs all live in one temporary directory;
# 3. runs a small grandstand study unsharded (the reference);
# 4. submits scripts/slurm-study.sh as a 3-task job array on the same study, waits, merges with
#    `host-harness merge` and checks every CSV of the merged study (summary.csv first) against
#    the reference byte for byte;
# 5. requeue case: submits the array again, requeues task 2 (`scontrol requeue JOB_2`) while
#    it is running and has checkpointed some but not all of its runs, checks that the requeued
#    task resumed (its log says "resuming ... N runs already done, M to go" with N, M > 0), and
#    that the merged outputs are still byte-identical;
# 6. stops every daemon it started, by pid (trap on exit), and removes the temporary directory
#    (kept, with its path printed, when a check failed).
#
# Settings (environment): HOST_HARNESS (binary; default target/debug/host-harness, the one the
# CI test step builds, else target/release/host-harness), CI_SLURM_RUNS (96: 32 runs per task,
# a window of a few seconds for the requeue even on a fast machine; 8 per task took 0.6 s),
# CI_SLURM_EXPOSURES (40,180), CI_SLURM_SEED (3), CI_SLURM_TIMEOUT (seconds per wait, 300),
# CI_SLURM_KEEP=1 keeps the temporary directory (logs, outputs, slurm.conf).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
RUNS=${CI_SLURM_RUNS:-96}
EXPOSURES=${CI_SLURM_EXPOSURES:-40,180}
SEED=${CI_SLURM_SEED:-3}
TIMEOUT=${CI_SLURM_TIMEOUT:-300}
TASKS=3
STARTED=$(date +%s)

say() { echo "[ci-slurm +$(($(date +%s) - STARTED))s] $*"; }

if [ -n "${HOST_HARNESS:-}" ]; then
  HH=$HOST_HARNESS
elif [ -x target/debug/host-harness ]; then
  HH=$ROOT/target/debug/host-harness
elif [ -x target/release/host-harness ]; then
  HH=$ROOT/target/release/host-harness
else
  say "building target/debug/host-harness"
  cargo build -q -p host-harness
  HH=$ROOT/target/debug/host-harness
fi
HH=$(readlink -f "$HH")
[ -x "$HH" ] || { echo "ci-slurm: $HH is not an executable" >&2; exit 1; }

# --- 1. packages -----------------------------------------------------------------------------
missing=()
command -v slurmctld >/dev/null || missing+=(slurm-wlm)
command -v munged >/dev/null || missing+=(munge)
if [ ${#missing[@]} -gt 0 ]; then
  say "installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo -n"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq >/dev/null
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
for c in munged mungekey slurmctld slurmd sbatch squeue scontrol; do
  command -v "$c" >/dev/null || { echo "ci-slurm: $c not found after installing" >&2; exit 1; }
done
say "$(slurmctld -V), munge $(munged -V 2>&1 | awk '{print $2; exit}'), binary $HH"

# --- 2. one-node cluster ---------------------------------------------------------------------
T=$(mktemp -d /tmp/vibcam-slurm.XXXXXX)
chmod 700 "$T"
mkdir -p "$T/munge" "$T/state" "$T/spool" "$T/logs" "$T/out"
PIDS=()
KEEP=${CI_SLURM_KEEP:-0}

dump_logs() {
  for f in "$T"/slurmctld.log "$T"/slurmd.log "$T"/munge/munged.log "$T"/logs/*; do
    [ -f "$f" ] || continue
    echo "----- $f (last 40 lines) -----"
    tail -n 40 "$f"
  done
}

fail() {
  echo "[ci-slurm] FAILED: $*" >&2
  dump_logs >&2
  # said again after the logs: a CI summary that keeps only the tail still shows why
  echo "[ci-slurm] FAILED: $*" >&2
  KEEP=1
  exit 1
}

cleanup() {
  local rc=$?
  # stop our daemons (and only them), newest first, by pid
  for ((i = ${#PIDS[@]} - 1; i >= 0; i--)); do
    kill "${PIDS[i]}" 2>/dev/null || true
  done
  for p in "${PIDS[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$p" 2>/dev/null || true
  done
  if [ $rc -ne 0 ] || [ $KEEP -ne 0 ]; then
    echo "[ci-slurm] kept $T for inspection" >&2
  else
    rm -rf "$T"
  fi
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# wait_for SECONDS WHAT CMD...: polls CMD every 0.2 s until it succeeds
wait_for() {
  local limit=$1 what=$2
  shift 2
  local end=$(($(date +%s) + limit))
  until "$@" >/dev/null 2>&1; do
    [ "$(date +%s)" -lt "$end" ] || fail "timed out after ${limit}s waiting for $what"
    sleep 0.2
  done
}

# two free TCP ports for slurmctld and slurmd (several CI jobs may share a machine)
port_free() { ! grep -qi ":$(printf '%04X' "$1") " /proc/net/tcp /proc/net/tcp6 2>/dev/null; }
CTLD_PORT=0
for _ in $(seq 50); do
  p=$((20000 + RANDOM % 20000))
  if port_free "$p" && port_free $((p + 1)); then CTLD_PORT=$p; break; fi
done
[ "$CTLD_PORT" -ne 0 ] || fail "no free TCP port pair found"
SLURMD_PORT=$((CTLD_PORT + 1))

say "munged (key, socket, pid and log in $T/munge)"
mungekey --create --keyfile="$T/munge/munge.key" 2>/dev/null ||
  dd if=/dev/urandom of="$T/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$T/munge/munge.key"
SOCK=$T/munge/munge.socket
munged --foreground --force --socket="$SOCK" --key-file="$T/munge/munge.key" \
  --pid-file="$T/munge/munged.pid" --log-file="$T/munge/munged.log" \
  --seed-file="$T/munge/munged.seed" >"$T/munge/stdout.log" 2>&1 &
PIDS+=($!)
wait_for 20 "the munge socket" test -S "$SOCK"
wait_for 20 "munge to encode and decode a credential" \
  sh -c "munge --socket='$SOCK' -n | unmunge --socket='$SOCK'"

NODE=$(hostname -s)
CPUS=$(nproc)
MEM_MB=$(awk '/MemTotal/ {print int($2 / 1024 * 0.8)}' /proc/meminfo)
export SLURM_CONF=$T/slurm.conf
cat >"$SLURM_CONF" <<EOF
# one-node cluster for CI, written by scripts/ci-slurm.sh
ClusterName=vibcamci
SlurmctldHost=$NODE(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$SOCK
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$T/jobcomp.txt
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
JobRequeue=1
MinJobAge=600
KillWait=5
InactiveLimit=0
SlurmctldTimeout=60
SlurmdTimeout=60
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$MEM_MB State=UNKNOWN
PartitionName=ci Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF

say "slurmctld and slurmd ($CPUS CPUs, ${MEM_MB} MB, ports $CTLD_PORT/$SLURMD_PORT, node $NODE)"
slurmctld -D -i -f "$SLURM_CONF" >"$T/slurmctld.stdout" 2>&1 &
PIDS+=($!)
wait_for 30 "slurmctld to answer" scontrol ping
slurmd -D -N "$NODE" -f "$SLURM_CONF" >"$T/slurmd.stdout" 2>&1 &
PIDS+=($!)
node_idle() { sinfo -h -n "$NODE" -o %T | grep -qx idle; }
wait_for 60 "node $NODE to become idle" node_idle
say "cluster up: $(sinfo -h -o '%P %D %T %C')"

# --- 3. reference: the unsharded study -------------------------------------------------------
STUDY=(--preset grandstand --runs "$RUNS" --exposures-ms "$EXPOSURES" --seed "$SEED")
say "reference: unsharded study, $RUNS runs x exposures $EXPOSURES ms, seed $SEED"
t0=$(date +%s)
"$HH" study "${STUDY[@]}" --threads "$CPUS" --out "$T/out/reference" --no-plots \
  >"$T/logs/reference.log" 2>&1 || fail "the reference study failed (see $T/logs/reference.log)"
say "reference done in $(($(date +%s) - t0)) s"

# --- 4. the job array ------------------------------------------------------------------------
# submit NAME: submits the array (one CPU per task, resumable) and prints its job id
submit() {
  # the study's settings travel in the environment (--export=ALL; a comma list cannot be
  # passed as --export=VAR=a,b)
  HOST_HARNESS=$HH OUT=$T/out/$1 RUNS=$RUNS SEED=$SEED EXPOSURES=$EXPOSURES \
    sbatch --parsable --array=1-$TASKS --cpus-per-task=1 --mem=512M --time=00:10:00 \
    --job-name="vibcam-$1" --chdir="$ROOT" --open-mode=append \
    --output="$T/logs/$1-%A_%a.log" --export=ALL scripts/slurm-study.sh
}

# states of the array's tasks, one "TASKID STATE" line each
task_states() { squeue -h -j "$1" --states=all -r -o '%K %T' 2>/dev/null | sort -n; }

# wait_array JOB: waits until every task has left the queue, fails unless all COMPLETED
wait_array() {
  local job=$1 end=$(($(date +%s) + TIMEOUT)) states last=""
  while :; do
    states=$(task_states "$job")
    if [ "$states" != "$last" ]; then
      say "job $job: $(echo "$states" | tr '\n' ' ')"
      last=$states
    fi
    if [ "$(echo "$states" | grep -c .)" -eq $TASKS ] &&
      ! echo "$states" | grep -Eq 'PENDING|CONFIGURING|RUNNING|COMPLETING|REQUEUE|SUSPENDED|RESIZING|SIGNALING|STAGE_OUT'; then
      break
    fi
    [ "$(date +%s)" -lt "$end" ] || fail "job $job not finished after ${TIMEOUT}s: $states"
    sleep 1
  done
  if echo "$states" | grep -vq 'COMPLETED$'; then
    scontrol show job "$job" >&2 || true
    fail "job $job: not every task completed: $states"
  fi
}

# merge_and_check NAME: merges the shards of NAME and compares its CSVs with the reference
merge_and_check() {
  local name=$1 shards=()
  for k in $(seq $TASKS); do shards+=("$T/out/$name/shard-$k"); done
  "$HH" merge "${shards[@]}" --out "$T/out/$name/merged" --no-plots >"$T/logs/$name-merge.log" 2>&1 ||
    fail "merge of $name failed (see $T/logs/$name-merge.log)"
  local files=(summary.csv) f
  for f in "$T/out/reference"/*.csv; do
    [ "$(basename "$f")" = summary.csv ] || files+=("$(basename "$f")")
  done
  for f in "${files[@]}"; do
    cmp "$T/out/reference/$f" "$T/out/$name/merged/$f" || {
      diff "$T/out/reference/$f" "$T/out/$name/merged/$f" | head -20 >&2 || true
      fail "$name: $f differs from the unsharded run"
    }
  done
  say "$name: merged outputs byte-identical to the unsharded run (${files[*]})"
}

say "submitting scripts/slurm-study.sh as a $TASKS-task array"
JOB=$(submit array) || fail "sbatch refused the job"
t0=$(date +%s)
wait_array "$JOB"
say "array job $JOB done in $(($(date +%s) - t0)) s"
merge_and_check array

# --- 5. requeue one task mid-run -------------------------------------------------------------
say "requeue case: submitting the array again"
JOB=$(submit requeue) || fail "sbatch refused the job"
RUNS2=$T/out/requeue/shard-2/runs.jsonl
# shard 2 of 3 holds the runs r with r mod 3 = 1
PER_SHARD=$(((RUNS + TASKS - 2) / TASKS))
lines() { if [ -f "$1" ]; then grep -c '^{.*}$' "$1" || true; else echo 0; fi; }
end=$(($(date +%s) + TIMEOUT))
while :; do
  before=$(lines "$RUNS2")
  [ "$before" -lt "$PER_SHARD" ] ||
    fail "task 2 finished all $PER_SHARD runs before it could be requeued; raise CI_SLURM_RUNS"
  if [ "$before" -ge 1 ] && task_states "$JOB" | grep -qx '2 RUNNING'; then break; fi
  [ "$(date +%s)" -lt "$end" ] || fail "timed out after ${TIMEOUT}s waiting for task 2 of job $JOB to checkpoint its first run"
  sleep 0.1
done
scontrol requeue "${JOB}_2" || fail "scontrol requeue ${JOB}_2 failed"
say "requeued task ${JOB}_2 after $before of its $PER_SHARD runs"
# A requeued job waits for its begin time (Slurm sets one in the future); release it so CI does
# not sit idle. Right after `scontrol requeue` squeue may still show the old RUNNING state, and
# an update sent before the job is PENDING is refused, so keep releasing until it runs again.
end=$(($(date +%s) + 120))
while :; do
  st=$(squeue -h -j "${JOB}_2" -o '%T %r' 2>/dev/null || true)
  case $st in
  PENDING*) scontrol update JobId="${JOB}_2" StartTime=now >/dev/null 2>&1 || true ;;
  esac
  # started again: its log has the line of a restarted task (scripts/slurm-study.sh)
  grep -q ', restart [1-9]' "$T"/logs/requeue-*_2.log 2>/dev/null && break
  [ "$(date +%s)" -lt "$end" ] || fail "the requeued task ${JOB}_2 did not start again within 120 s (state: ${st:-gone})"
  sleep 0.5
done
say "requeued task ${JOB}_2 released: $st"
wait_array "$JOB"
LOG2=$(ls "$T"/logs/requeue-*_2.log)
restarts=$(scontrol show job "${JOB}_2" | grep -o 'Restarts=[0-9]*' | cut -d= -f2)
[ "${restarts:-0}" -ge 1 ] || fail "task 2 of job $JOB was not restarted (Restarts=${restarts:-?})"
resumed=$(grep -E 'resuming .*: [0-9]+ runs already done, [0-9]+ to go' "$LOG2" | tail -n 1) ||
  fail "the requeued task did not resume (no 'resuming' line in $LOG2)"
echo "$resumed" | grep -Eq ': [1-9][0-9]* runs already done, [1-9][0-9]* to go' ||
  fail "the requeued task was not interrupted mid-run: $resumed"
say "task 2 restarted $restarts time(s): $(echo "$resumed" | sed 's/.*: //'); its log:"
grep -E '^task |^resuming|runs in' "$LOG2" | sed 's/^/    /'

merge_and_check requeue

say "passed in $(($(date +%s) - STARTED)) s"
