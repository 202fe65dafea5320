#!/usr/bin/env bash
# docs/slurm-array.sh on a real Slurm, end to end. Brings up a one-node Slurm 22.05
# (munged, slurmctld, slurmd from Debian's slurm-wlm and munge, installed with apt-get
# when missing) on this machine, and then:
#
#   1. submits docs/slurm-array.sh, unchanged, as a 3-task array for a small sweep of the
#      quick spec, and the collect step after it (--dependency=afterany), as the README
#      tells a user to; prints squeue while they run and sacct once they have ended;
#   2. runs the same spec in one process outside Slurm and compares the two results
#      folders byte for byte (the files that hold wall-clock times are compared without
#      them);
#   3. submits the array again for a spec whose EM3 diverges: the task that trains it
#      fails, collect exits 2 naming it, and every other task's work is kept.
#
# The job's resources are set on sbatch's command line (a 2-core machine cannot give the
# script's 8 CPUs and 16G), and DCNET_RESULTS, DCNET_LOG_EVERY and PATH are passed to
# the jobs in the environment. It stops the daemons it started, by their PID files,
# and leaves nothing running. Exit 0 when everything held; otherwise 1, naming the
# step that failed. Needs root (apt-get, slurmd). Run from anywhere:
#
#   sudo scripts/slurm-e2e.sh   (with cargo on root's PATH, or a built target/release)
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
started=$SECONDS

step=setup
work=""
step() {
    step=$1
    echo
    echo "== $step ($((SECONDS - started)) s)"
}
fail() {
    echo "slurm-e2e: $*" >&2
    exit 1
}

# ---- teardown: runs however the script ends ----------------------------------------
stop_daemon() { # NAME PIDFILE
    local pid
    [ -s "$2" ] || return 0
    pid=$(cat "$2")
    kill "$pid" 2>/dev/null || return 0
    for _ in $(seq 50); do
        kill -0 "$pid" 2>/dev/null || return 0
        sleep 0.2
    done
    echo "slurm-e2e: $1 (pid $pid) did not stop on SIGTERM; killed" >&2
    kill -9 "$pid" 2>/dev/null || true
    return 1
}
stop_daemons() { # fails if a daemon had to be killed
    local stopped=0
    stop_daemon slurmd "$work/slurmd.pid" || stopped=1
    stop_daemon slurmctld "$work/slurmctld.pid" || stopped=1
    stop_daemon munged "$work/munge/munged.pid" || stopped=1
    return "$stopped"
}
teardown() {
    local status=$? stopped=0
    trap - EXIT
    [ "$status" -eq 0 ] || status=1
    [ "$status" -eq 0 ] || echo "slurm-e2e: FAILED at step: $step" >&2
    if [ -n "$work" ]; then
        if [ "$status" -ne 0 ]; then
            for log in "$work"/slurmctld.log "$work"/slurmd.log "$work"/munge/munged.log \
                "$work"/logs/*.out; do
                [ -s "$log" ] && { echo "--- last lines of $log" >&2; tail -n 15 "$log" >&2; }
            done
        fi
        # Jobs still running (a failed check, a deadline, an interrupt) are cancelled
        # while the controller is up: their steps are not slurmd's children.
        if [ -s "$work/slurmctld.pid" ] && squeue -h -o %i 2>/dev/null | grep -q .; then
            scancel --full -u root 2>/dev/null || true
            for _ in $(seq 50); do
                squeue -h -o %i 2>/dev/null | grep -q . || break
                sleep 0.2
            done
        fi
        stop_daemons || stopped=1
        if [ "$status" -eq 0 ] && [ "$stopped" -eq 0 ]; then
            rm -rf "$work"
        else
            echo "slurm-e2e: files left in $work" >&2
        fi
    fi
    [ "$stopped" -eq 0 ] || status=1
    exit "$status"
}
trap teardown EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
trap 'exit 129' HUP

# ---- 1. Slurm and munge ------------------------------------------------------------
step "install slurm-wlm and munge"
[ "$(id -u)" -eq 0 ] || fail "run as root: it installs packages and starts slurmd"
missing=()
for command in munged munge slurmctld slurmd sbatch squeue sacct sinfo; do
    command -v "$command" >/dev/null || missing+=("$command")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "missing: ${missing[*]}; installing"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        slurm-wlm munge >/dev/null
fi
slurmctld -V

step "build dcnet-exp"
target_dir=${CARGO_TARGET_DIR:-target}
[[ "$target_dir" = /* ]] || target_dir=$repo/$target_dir
bin_dir=$target_dir/release
if command -v cargo >/dev/null; then
    (cd "$repo" && cargo build --release --quiet)
fi
[ -x "$bin_dir/dcnet-exp" ] || fail "no dcnet-exp in $bin_dir"
export PATH="$bin_dir:$PATH"

work=$(mktemp -d /tmp/dcnet-slurm-e2e.XXXXXX)
chmod 755 "$work"
echo "work folder: $work"

step "start munged"
mkdir -m 711 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
munged --force --socket="$work/munge/munge.socket" --key-file="$work/munge/munge.key" \
    --pid-file="$work/munge/munged.pid" --log-file="$work/munge/munged.log" \
    --seed-file="$work/munge/munged.seed"
munge -n -S "$work/munge/munge.socket" | unmunge -S "$work/munge/munge.socket" >/dev/null
echo "munged $(cat "$work/munge/munged.pid"): a credential round-trips"

step "write slurm.conf"
host=$(hostname -s)
cpus=$(nproc)
memory_mb=$(awk '/^MemTotal/ { print int($2 / 1024 * 0.9) }' /proc/meminfo)
mkdir "$work/state" "$work/spool"
export SLURM_CONF=$work/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=dcnet-e2e
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
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
JobCompType=jobcomp/filetxt
JobCompLoc=$work/jobcomp.txt
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
MessageTimeout=5
MinJobAge=3600
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory_mb State=UNKNOWN
PartitionName=e2e Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
echo "one node, $host: $cpus CPUs, $memory_mb MB"

step "start slurmctld and slurmd"
slurmctld
slurmd -N "$host"
# slurmd writes its PID file once its plugins are loaded, after it has daemonized.
deadline=$((SECONDS + 30))
until [ -s "$work/slurmctld.pid" ] && [ -s "$work/slurmd.pid" ]; do
    [ "$SECONDS" -lt "$deadline" ] || fail "slurmctld or slurmd wrote no PID file in 30 s"
    sleep 0.2
done
pids="$(cat "$work/munge/munged.pid") $(cat "$work/slurmctld.pid") $(cat "$work/slurmd.pid")"
deadline=$((SECONDS + 30))
while [ "$(sinfo -h -n "$host" -o %T 2>/dev/null)" != idle ] && [ "$SECONDS" -lt "$deadline" ]; do
    for pid in $pids; do kill -0 "$pid" 2>/dev/null || fail "daemon $pid died"; done
    sleep 0.5
done
sinfo
[ "$(sinfo -h -n "$host" -o %T)" = idle ] || fail "node $host did not come up idle"

# ---- 2. The specs ------------------------------------------------------------------
# A small sweep of the quick spec: two dropout rates, 40 epochs, so that each shard
# trains for some seconds and logs progress lines.
cd "$work"
mkdir experiments logs
quick=$(cat "$repo/experiments/quick.toml")
sweep=${quick/name = \"quick\"/name = \"slurm-e2e\"}
sweep=${sweep/epochs = 20/epochs = 40}
diverging=${sweep/name = \"slurm-e2e\"/name = \"slurm-e2e-diverging\"}
diverging=${diverging/EM3 = 5e-4/EM3 = 1e30}
sweep_values='[sweep.values]
"model.dropout" = [0.2, 0.3]'
printf '%s\n\n%s\n' "$sweep" "$sweep_values" >experiments/sweep.toml
printf '%s\n\n%s\n' "$diverging" "$sweep_values" >experiments/diverging.toml
grep -q 'epochs = 40' experiments/sweep.toml || fail "quick.toml no longer has 'epochs = 20'"
grep -q 'EM3 = 1e30' experiments/diverging.toml || fail "quick.toml no longer has 'EM3 = 5e-4'"
dcnet-exp validate experiments/sweep.toml >/dev/null
dcnet-exp plan experiments/sweep.toml --out shared/results | tail -n 1

# ---- 3. The array and its collect step ---------------------------------------------
export DCNET_LOG_EVERY=1

# The state and exit code slurm recorded for JOB (an array task as ID_K).
state_of() {
    scontrol show job "$1" | awk '{ for (i = 1; i <= NF; i++) if ($i ~ /^(JobState|ExitCode)=/) printf "%s ", $i }'
}

# Submits the array for SPEC into RESULTS and the collect step after it; waits for both
# and prints squeue as the tasks change state. Sets array_job and collect_job.
submit_and_wait() { # SPEC RESULTS
    local spec=$1 results=$2 seen="" now deadline=$((SECONDS + 240))
    array_job=$(DCNET_RESULTS=$results sbatch --parsable --array=0-2 \
        --cpus-per-task=1 --mem=2G "$repo/docs/slurm-array.sh" "$spec")
    collect_job=$(sbatch --parsable --dependency="afterany:$array_job" \
        --job-name=dcnet-collect --mem=2G --output="logs/collect-%j.out" \
        --wrap "dcnet-exp collect '$spec' --out '$results' --plots '$results/plots'")
    echo "array job $array_job (3 tasks), collect job $collect_job after it"
    while :; do
        now=$(squeue -h -r -j "$array_job,$collect_job" -o '%i %j %T %r' | sort)
        [ -n "$now" ] || break
        if [ "$now" != "$seen" ]; then
            echo "--- squeue at $((SECONDS - started)) s"
            squeue -r -j "$array_job,$collect_job" -o '%.12i %.14j %.10T %.8M %R'
            seen=$now
        fi
        [ "$SECONDS" -lt "$deadline" ] || fail "the jobs of $spec did not end in 240 s"
        sleep 0.5
    done
    echo "--- squeue, every state, once they have ended"
    squeue -t all -r -j "$array_job,$collect_job" -o '%.12i %.14j %.10T %.8M %R'
    echo "--- scontrol show job: each task's end"
    for job in "${array_job}_0" "${array_job}_1" "${array_job}_2" "$collect_job"; do
        printf '%12s %s\n' "$job" "$(state_of "$job")"
    done
    echo "--- sacct (job completion records)"
    # sacct -c of 22.05 does not parse the array fields its jobcomp/filetxt writes, and
    # says so on each record; the records themselves are read.
    sacct -c -j "$array_job,$collect_job" \
        --format=JobID,JobName%16,State,ExitCode,Elapsed,NodeList 2>&1 |
        grep -v 'Unknown type Array' || true
}

step "submit docs/slurm-array.sh as a 3-task array, then collect"
submit_and_wait experiments/sweep.toml "$work/shared/results"
for k in 0 1 2; do
    [[ "$(state_of "${array_job}_$k")" == "JobState=COMPLETED ExitCode=0:0 " ]] ||
        fail "array task ${array_job}_$k: $(state_of "${array_job}_$k")"
done
[[ "$(state_of "$collect_job")" == "JobState=COMPLETED ExitCode=0:0 " ]] ||
    fail "collect: $(state_of "$collect_job")"
echo "--- task 1's log (logs/dcnet-exp-${array_job}_1.out), first lines"
head -n 12 "logs/dcnet-exp-${array_job}_1.out"
grep -q 'samples/s, ETA' "logs/dcnet-exp-${array_job}_1.out" ||
    fail "task 1's log has no progress line"
grep -q ': trained; best validation loss' "logs/dcnet-exp-${array_job}_1.out" ||
    fail "task 1's log has no line for a training's end"
echo "--- collect's log, last lines"
tail -n 4 "logs/collect-$collect_job.out"

step "the same spec in one process, outside Slurm"
dcnet-exp run experiments/sweep.toml --out one/results --plots one/results/plots 2>one.log
tail -n 2 one.log

step "compare the results byte for byte"
python=python3
if ! python3 -c 'import pyarrow' 2>/dev/null; then
    echo "pyarrow (to read training.parquet without its wall-clock columns): installing"
    python3 -m venv venv
    venv/bin/pip install --quiet pyarrow
    python=venv/bin/python
fi
for folder in slurm-e2e plots/slurm-e2e; do
    "$python" "$repo/scripts/same_results.py" "one/results/$folder" "shared/results/$folder"
done

# ---- 4. A task that fails ----------------------------------------------------------
step "submit the array for a spec whose EM3 diverges"
submit_and_wait experiments/diverging.toml "$work/failing/results"
failed=0
for k in 0 1 2; do
    case "$(state_of "${array_job}_$k")" in
        "JobState=COMPLETED ExitCode=0:0 ") ;;
        "JobState=FAILED ExitCode=2:0 ") failed=$((failed + 1)) ;;
        *) fail "array task ${array_job}_$k: $(state_of "${array_job}_$k")" ;;
    esac
done
[ "$failed" -ge 1 ] || fail "no array task failed on the diverging EM3"
[[ "$(state_of "$collect_job")" == "JobState=FAILED ExitCode=2:0 " ]] ||
    fail "collect after a failed task: $(state_of "$collect_job"), not exit 2"
echo "--- collect's log, last lines"
tail -n 4 "logs/collect-$collect_job.out"
grep -q 'DCNet EM3: the training loss became' "logs/collect-$collect_job.out" ||
    fail "collect does not name the diverged EM3"
echo "--- what is kept: the plan of the diverging spec"
dcnet-exp plan experiments/diverging.toml --out failing/results >plan.txt
grep -c 'failed (--force tries again)' plan.txt | sed 's/$/ tasks failed (EM3 and its blocks)/'
tail -n 1 plan.txt
grep -q ', 0 to do;' plan.txt || fail "the failed run lost work: tasks to do again"
for point in dropout=0.2 dropout=0.3; do
    test -s "failing/results/slurm-e2e-diverging/$point/evaluation.parquet" ||
        fail "collect wrote no results for $point"
done

step "stop the daemons"
stop_daemons || fail "a daemon had to be killed"
for pid in $pids; do
    ! kill -0 "$pid" 2>/dev/null || fail "daemon $pid still running"
done
command -v pgrep >/dev/null || fail "no pgrep to check that no job is left"
if pgrep -f -- "--out $work/" >/dev/null; then
    fail "dcnet-exp jobs still running: $(pgrep -af -- "--out $work/")"
fi
echo "munged, slurmctld and slurmd ($pids) stopped"
echo "slurm-e2e: ok in $((SECONDS - started)) s"
