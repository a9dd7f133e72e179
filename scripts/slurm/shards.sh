#!/usr/bin/env bash
# A real Slurm run on this machine: installs Slurm from Debian's packages (slurm-wlm, munge),
# starts a one-node cluster on localhost (munged, slurmctld, slurmd started directly: no
# systemd, no cgroups), submits a 4-task job array rendering the 4 shards of a render
# (`chainlight render ... --shard K/4`), merges the parts (`chainlight merge`) and compares the
# bytes with the single-process render of the same seed and --spp. Then, if the
# zsolnai_large_step example is built, runs a small sweep through its generated job-array
# script (`--emit-jobs`) and compares every image with the same sweep run in one process.
#
# Exit status: 0 when everything matched, or "skipped: <reason>" when the packages cannot be
# installed in time, the daemons cannot start or a job never ran (the environment, not
# chainlight); 1 only for a real mismatch or a chainlight command failing under Slurm.
# Until `chainlight render` has --shard, every task renders the whole image and each is
# compared with the single-process render instead.
#
# Environment: CHAINLIGHT (binary, default target/release/chainlight, built if missing),
# CHAINLIGHT_SLURM_WORK (work directory, default target/slurm), CHAINLIGHT_SLURM_INSTALL_TIMEOUT
# (seconds, default 240), CHAINLIGHT_SLURM_INTEGRATORS (default "pt bdpt pssmlt"),
# CHAINLIGHT_SLURM_SWEEP=0 (skip the sweep), CHAINLIGHT_SLURM_KEEP=1 (leave the daemons running).
set -u
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
WORK=${CHAINLIGHT_SLURM_WORK:-$ROOT/target/slurm}
case $WORK in /*) ;; *) WORK=$ROOT/$WORK ;; esac
INSTALL_TIMEOUT=${CHAINLIGHT_SLURM_INSTALL_TIMEOUT:-240}
INTEGRATORS=${CHAINLIGHT_SLURM_INTEGRATORS:-pt bdpt pssmlt}
CL=${CHAINLIGHT:-$ROOT/target/release/chainlight}
case $CL in /*) ;; *) CL=$ROOT/$CL ;; esac
RENDER_ARGS=(--spp 4 --width 32 --height 32 --max-depth 5)
SEED=7
STARTED=()   # pid files of the daemons this script started

say() { echo "slurm: $*"; }
cleanup() {
    [ "${CHAINLIGHT_SLURM_KEEP:-0}" = 1 ] && return
    local f pid pids=()
    for f in "${STARTED[@]}"; do
        pid=$(cat "$f" 2>/dev/null) || continue
        [ -n "$pid" ] && kill "$pid" 2>/dev/null && pids+=("$pid")
    done
    # Wait (at most 10 s) until they are gone, so that a next run starts clean.
    local alive
    for _ in $(seq 20); do
        alive=0
        for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
        [ $alive = 0 ] && break
        sleep 0.5
    done
}
trap cleanup EXIT
skip() { say "skipped: $*"; exit 0; }
fail() { say "FAIL: $*"; exit 1; }
# Stops the daemon of a pid file left by an earlier run of this script (CHAINLIGHT_SLURM_KEEP).
stop_old() { local pid; pid=$(cat "$1" 2>/dev/null) && kill "$pid" 2>/dev/null && sleep 1; rm -f "$1"; }

[ "$(id -u)" = 0 ] || skip "not root (installing packages and starting daemons needs root)"
command -v apt-get >/dev/null || skip "no apt-get: not a Debian system"
mkdir -p "$WORK"

# --- Install ---------------------------------------------------------------------------------
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
    || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    say "installing slurm-wlm and munge (apt-get, at most ${INSTALL_TIMEOUT}s)"
    start=$SECONDS
    DEBIAN_FRONTEND=noninteractive timeout "$INSTALL_TIMEOUT" bash -c \
        'apt-get update -qq || true; apt-get install -y -qq --no-install-recommends slurm-wlm munge' \
        >"$WORK/apt.log" 2>&1
    rc=$?
    [ $rc = 124 ] && skip "apt-get did not install slurm-wlm and munge within ${INSTALL_TIMEOUT}s"
    [ $rc = 0 ] || skip "apt-get could not install slurm-wlm and munge (exit $rc): $(tail -n 2 "$WORK/apt.log" | tr '\n' ' ')"
    say "installed in $((SECONDS - start))s: $(dpkg-query -W -f='${Package} ${Version}, ' slurmctld slurmd slurm-client munge 2>/dev/null)"
fi
for c in slurmctld slurmd sbatch squeue sinfo scontrol munged munge unmunge; do
    command -v "$c" >/dev/null || skip "$c is missing after the install"
done

# --- munge -----------------------------------------------------------------------------------
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    key=/etc/munge/munge.key
    if [ ! -s "$key" ]; then
        mkdir -p /etc/munge
        mungekey --create --keyfile="$key" 2>/dev/null \
            || dd if=/dev/urandom of="$key" bs=1024 count=1 2>/dev/null || skip "cannot create $key"
    fi
    id munge >/dev/null 2>&1 || skip "no munge user after the install"
    mkdir -p /run/munge /var/lib/munge /var/log/munge
    chown munge:munge "$key" /run/munge /var/lib/munge /var/log/munge
    chmod 400 "$key"
    chmod 755 /run/munge
    runuser -u munge -- munged >"$WORK/munged.out" 2>&1 || skip "munged could not start: $(tail -n 2 "$WORK/munged.out" | tr '\n' ' ')"
    [ -s /run/munge/munged.pid ] && STARTED+=(/run/munge/munged.pid)
    for _ in $(seq 20); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.5; done
    munge -n 2>/dev/null | unmunge >/dev/null 2>&1 || skip "munge does not authenticate"
fi

# --- slurmctld and slurmd: one node, this machine, our own config and ports --------------------
HOST=$(hostname -s 2>/dev/null || cat /proc/sys/kernel/hostname)
NCPU=$(nproc)
export SLURM_CONF=$WORK/slurm.conf
stop_old "$WORK/slurmd.pid"
stop_old "$WORK/slurmctld.pid"
rm -rf "$WORK/state" "$WORK/spool" "$WORK/out" "$WORK"/sweep-*
mkdir -p "$WORK/state" "$WORK/spool" "$WORK/out"
cat >"$SLURM_CONF" <<CONF
ClusterName=chainlight
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
KillWait=5
MinJobAge=600
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$NCPU State=UNKNOWN
PartitionName=chainlight Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld >"$WORK/slurmctld.out" 2>&1 || skip "slurmctld could not start: $(tail -n 3 "$WORK/slurmctld.log" "$WORK/slurmctld.out" 2>/dev/null | tr '\n' ' ')"
STARTED+=("$WORK/slurmctld.pid")
slurmd -N "$HOST" >"$WORK/slurmd.out" 2>&1 || skip "slurmd could not start: $(tail -n 3 "$WORK/slurmd.log" "$WORK/slurmd.out" 2>/dev/null | tr '\n' ' ')"
STARTED+=("$WORK/slurmd.pid")
state=
for i in $(seq 60); do
    state=$(sinfo -h -n "$HOST" -o %T 2>/dev/null | head -n 1)
    case $state in
        idle*|mixed*|allocated*) break ;;
        down*|drain*) scontrol update nodename="$HOST" state=resume >/dev/null 2>&1 ;;
    esac
    sleep 1
done
case $state in
    idle*|mixed*|allocated*) say "one-node cluster up: node $HOST ($NCPU CPUs) $state, $(sinfo -V)" ;;
    *) skip "the node did not become idle (state '${state:-none}'): $(tail -n 3 "$WORK/slurmd.log" 2>/dev/null | tr '\n' ' ')" ;;
esac

# --- chainlight ------------------------------------------------------------------------------
if [ ! -x "$CL" ]; then
    command -v cargo >/dev/null || skip "no chainlight binary at $CL and no cargo to build it"
    say "building chainlight"
    cargo build --release --bin chainlight >"$WORK/build.log" 2>&1 || fail "cargo build --release --bin chainlight failed (see $WORK/build.log)"
fi
SHARDS=0
if "$CL" render --help 2>/dev/null | grep -q -- '--shard' && "$CL" merge --help >/dev/null 2>&1; then
    SHARDS=1
fi
OUT=$WORK/out
for i in $INTEGRATORS; do
    "$CL" render --integrator "$i" "${RENDER_ARGS[@]}" --seed $SEED --threads 2 -o "$OUT/single-$i.exr" \
        >"$OUT/single-$i.log" 2>&1 || fail "the single-process $i render failed: $(tail -n 2 "$OUT/single-$i.log" | tr '\n' ' ')"
done
# Negative control of the comparison: another seed must give other bytes.
first=${INTEGRATORS%% *}
"$CL" render --integrator "$first" "${RENDER_ARGS[@]}" --seed $((SEED + 1)) --threads 2 -o "$OUT/other-seed.exr" >/dev/null 2>&1 \
    || fail "the $first render with seed $((SEED + 1)) failed"
cmp -s "$OUT/single-$first.exr" "$OUT/other-seed.exr" && fail "negative control: seeds $SEED and $((SEED + 1)) gave identical EXRs, so cmp proves nothing"

# Each task writes rc-<integrator>-<k> with chainlight's exit code: a missing file means Slurm
# never ran the task (the environment), a non-zero one that chainlight failed.
cat >"$WORK/shards.sbatch" <<SBATCH
#!/bin/bash
#SBATCH --job-name=chainlight-shards
#SBATCH --array=0-3
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=1
#SBATCH --chdir=$ROOT
#SBATCH --output=$OUT/task-%a.log
k=\$SLURM_ARRAY_TASK_ID
for i in $INTEGRATORS; do
    if [ $SHARDS = 1 ]; then
        "$CL" render --integrator "\$i" ${RENDER_ARGS[*]} --seed $SEED --threads 1 --shard "\$k/4" -o "$OUT/part-\$i-\$k.clpart"
    else
        "$CL" render --integrator "\$i" ${RENDER_ARGS[*]} --seed $SEED --threads 1 -o "$OUT/full-\$i-\$k.exr"
    fi
    rc=\$?
    echo \$rc >"$OUT/rc-\$i-\$k"
    [ \$rc = 0 ] || exit \$rc
done
SBATCH
if [ $SHARDS = 1 ]; then
    say "submitting a 4-task job array: shard k/4 of each of: $INTEGRATORS"
else
    say "chainlight render has no --shard yet: the 4 array tasks each render the whole image of: $INTEGRATORS"
fi
start=$SECONDS
timeout 300 sbatch --wait "$WORK/shards.sbatch" >"$OUT/sbatch.out" 2>&1
rc=$?
say "job array finished in $((SECONDS - start))s (sbatch exit $rc): $(head -n 1 "$OUT/sbatch.out")"
[ $rc = 124 ] && skip "the job array did not finish within 300s"
for i in $INTEGRATORS; do
    for k in 0 1 2 3; do
        [ -f "$OUT/rc-$i-$k" ] || skip "array task $k never rendered $i (sbatch: $(tr '\n' ' ' <"$OUT/sbatch.out"); task log: $(tail -n 2 "$OUT/task-$k.log" 2>/dev/null | tr '\n' ' '))"
        [ "$(cat "$OUT/rc-$i-$k")" = 0 ] || fail "chainlight failed under Slurm (task $k, $i): $(tail -n 3 "$OUT/task-$k.log" | tr '\n' ' ')"
    done
    if [ $SHARDS = 1 ]; then
        "$CL" merge "$OUT"/part-"$i"-{0,1,2,3}.clpart -o "$OUT/merged-$i.exr" >"$OUT/merge-$i.log" 2>&1 \
            || fail "chainlight merge of the $i parts failed: $(tail -n 2 "$OUT/merge-$i.log" | tr '\n' ' ')"
        cmp "$OUT/single-$i.exr" "$OUT/merged-$i.exr" || fail "$i: the merged 4-shard EXR differs from the single-process render"
        say "$i: 4 shards rendered by the Slurm array, merged: bit-identical to the single-process render ($(stat -c %s "$OUT/merged-$i.exr") bytes)"
    else
        for k in 0 1 2 3; do
            cmp "$OUT/single-$i.exr" "$OUT/full-$i-$k.exr" || fail "$i: array task $k's EXR differs from the single-process render"
        done
        say "$i: the 4 array tasks' EXRs (1 thread each) are bit-identical to the single-process render (2 threads)"
    fi
done

# --- A sweep through its generated job-array script ------------------------------------------
Z=$ROOT/target/release/examples/zsolnai_large_step
if [ "${CHAINLIGHT_SLURM_SWEEP:-1}" = 0 ]; then
    say "sweep: skipped (CHAINLIGHT_SLURM_SWEEP=0)"
elif [ ! -x "$Z" ]; then
    say "sweep: skipped (no $Z; cargo build --release --example zsolnai_large_step)"
elif ! "$Z" --help 2>/dev/null | grep -q -- '--emit-jobs'; then
    say "sweep: skipped ($Z predates --emit-jobs; rebuild it)"
else
    SW=(--quick --spp 1 --seeds 2 --threads 1 --no-report cornell)
    "$Z" "${SW[@]}" --out "$WORK/sweep-local" >"$WORK/sweep-local.log" 2>&1 || fail "the sweep run in one process failed (see $WORK/sweep-local.log)"
    "$Z" "${SW[@]}" --out "$WORK/sweep-slurm" --emit-jobs "$WORK/sweep-jobs" >"$WORK/sweep-emit.log" 2>&1 || fail "--emit-jobs failed (see $WORK/sweep-emit.log)"
    n=$(wc -l <"$WORK/sweep-jobs/jobs.jsonl")
    say "sweep: $n runs emitted; submitting $WORK/sweep-jobs/slurm.sbatch"
    start=$SECONDS
    CHAINLIGHT=$CL timeout 300 sbatch --wait "$WORK/sweep-jobs/slurm.sbatch" >"$WORK/sweep-sbatch.out" 2>&1
    rc=$?
    [ $rc = 124 ] && skip "the sweep's job array did not finish within 300s"
    "$CL" sweep status "$WORK/sweep-jobs" | sed 's/^/slurm: sweep: /'
    [ -d "$WORK/sweep-jobs/status" ] || skip "the sweep's array tasks never ran (sbatch: $(tr '\n' ' ' <"$WORK/sweep-sbatch.out"))"
    [ $rc = 0 ] || fail "the sweep's job array failed (sbatch exit $rc; chainlight sweep status $WORK/sweep-jobs)"
    say "sweep: job array finished in $((SECONDS - start))s"
    "$Z" "${SW[@]}" --out "$WORK/sweep-slurm" --collect >"$WORK/sweep-collect.log" 2>&1 || fail "--collect failed: $(tail -n 2 "$WORK/sweep-collect.log" | tr '\n' ' ')"
    count=0
    for f in "$WORK"/sweep-local/cornell/*.exr; do
        cmp "$f" "$WORK/sweep-slurm/cornell/$(basename "$f")" || fail "sweep: $(basename "$f") differs between the Slurm sweep and the run in one process"
        count=$((count + 1))
    done
    # The per-run CSV without its timing columns (seconds, samples/s, load) and the example's
    # own table: what equal samples make identical wherever the runs ran.
    untimed() { cut -d, -f1-4,6,8-19 "$1"; }
    cmp <(untimed "$WORK/sweep-local/results.csv") <(untimed "$WORK/sweep-slurm/results.csv") \
        || fail "sweep: results.csv differs beyond the timing columns"
    own() { sed -n '/^## Automatic/,$p' "$1"; }
    cmp <(own "$WORK/sweep-local/results.md") <(own "$WORK/sweep-slurm/results.md") \
        || fail "sweep: the example's own table in results.md differs"
    say "sweep: $count EXRs bit-identical to the run in one process; results.csv (but for timings) and the example's table identical"
fi
say "passed"
