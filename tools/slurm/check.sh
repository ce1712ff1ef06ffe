#!/usr/bin/env bash
# Runs the Slurm recipe of docs/distributed.md for real. Starts a throwaway
# one-node Slurm cluster (munged, slurmctld, slurmd) entirely under a temp
# directory, submits tools/slurm/render.sbatch unchanged as an array of 4 and
# the documented merge job after it, renders the same scene in one process
# and compares the two images byte for byte. Stops every daemon it started
# and removes the temp directory on exit, whatever happens.
#
# Usage: tools/slurm/check.sh [STRATA_BINARY]   (default: target/release/strata)
# Needs root and the Debian packages slurm-wlm and munge; installs nothing.
# Exit status: 0 pass, 1 fail, 77 skipped (Slurm or munge missing, not root).
set -euo pipefail

PATH=$PATH:/usr/local/sbin:/usr/sbin:/sbin
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
strata=${1:-$repo/target/release/strata}
started=$SECONDS

skip() {
    echo "slurm check: SKIPPED: $*"
    exit 77
}

for tool in munged munge slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
    command -v "$tool" >/dev/null || skip "no $tool: install slurm-wlm and munge"
done
[ "$(id -u)" = 0 ] || skip "needs root (slurmd starts each job as its user)"
[ -x "$strata" ] || { echo "slurm check: FAIL: no strata binary at $strata"; exit 1; }
strata=$(cd "$(dirname "$strata")" && pwd)/$(basename "$strata")

# Nothing of a Slurm job this may run inside may leak into the test cluster.
while read -r var; do unset "$var"; done < <(compgen -e | grep -E '^(SLURM|SBATCH|SALLOC|SRUN)_' || true)

tmp=$(mktemp -d "${TMPDIR:-/tmp}/strata-slurm.XXXXXX")
munged_pid='' slurmctld_pid='' slurmd_pid='' jobs='' reason=''

show_logs() {
    local f
    for f in "$tmp"/work/*.out "$tmp"/*.log "$tmp"/*.stderr; do
        [ -s "$f" ] || continue
        # A daemon's stderr repeats its log; it matters when no log was opened.
        [ "${f%.stderr}" = "$f" ] || [ ! -f "${f%.stderr}.log" ] || continue
        echo "----- ${f#"$tmp"/} (last 30 lines)"
        tail -n 30 "$f"
    done
}

stop() { # stop PID: TERM, up to 10 s, then KILL
    local pid=$1
    [ -n "$pid" ] || return 0
    kill "$pid" 2>/dev/null || return 0
    for _ in $(seq 100); do
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
    done
    kill -9 "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
}

cleanup() {
    local status=$?
    set +e
    if [ "$status" != 0 ] && [ "$status" != 77 ]; then
        show_logs
        echo "slurm check: FAIL: ${reason:-exit status $status} (after $((SECONDS - started)) s)"
    fi
    if [ "$status" != 0 ] && [ -n "$jobs" ]; then
        # shellcheck disable=SC2086 # one word per job id
        scancel $jobs 2>/dev/null
        for _ in $(seq 50); do
            [ -z "$(squeue -h -j "${jobs// /,}" 2>/dev/null)" ] && break
            sleep 0.2
        done
    fi
    stop "$slurmd_pid"
    stop "$slurmctld_pid"
    stop "$munged_pid"
    # Whatever still runs in the temp dir (a job step scancel could not reach).
    cd /
    for p in /proc/[0-9]*; do
        case $(readlink "$p/cwd" 2>/dev/null) in
        "$tmp" | "$tmp"/*) kill -9 "${p#/proc/}" 2>/dev/null ;;
        esac
    done
    rm -rf "$tmp"
    exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

die() {
    reason=$*
    exit 1
}

# wait_for SECONDS WHAT COMMAND...: poll COMMAND every 0.2 s until it succeeds.
wait_for() {
    local limit=$1 what=$2 deadline=$((SECONDS + $1))
    shift 2
    until "$@" >/dev/null 2>&1; do
        [ "$SECONDS" -lt "$deadline" ] || die "$what not within $limit s"
        sleep 0.2
    done
}

port_free() { # no socket in /proc/net/tcp{,6} uses this port
    local hex
    hex=$(printf ':%04X ' "$1")
    ! grep -qF "$hex" /proc/net/tcp /proc/net/tcp6 2>/dev/null
}
port=$((20000 + $$ % 12000)) # below the usual ephemeral range (32768-)
until port_free "$port" && port_free $((port + 1)); do port=$((port + 2)); done

host=$(uname -n)
host=${host%%.*} # the short name, which Slurm compares with SlurmctldHost
cpus=$(nproc)
mkdir -p "$tmp"/{munge,state,spool,bin,work}
chmod 711 "$tmp/munge" # munged wants its socket directory searchable

# munge: a fresh key and its own socket.
if command -v mungekey >/dev/null; then
    mungekey --create --keyfile="$tmp/munge/munge.key"
else
    dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
fi
chmod 600 "$tmp/munge/munge.key"
socket=$tmp/munge/munge.socket.2
munged --foreground --force --socket="$socket" --key-file="$tmp/munge/munge.key" \
    --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/munged.seed" \
    --log-file="$tmp/munged.log" >"$tmp/munged.stderr" 2>&1 &
munged_pid=$!
munge_ok() { munge -n -S "$socket" | unmunge -S "$socket"; }
wait_for 20 "munged up" munge_ok

export SLURM_CONF=$tmp/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=stratacheck
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
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
MailProg=/bin/true
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=check Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

slurmctld -D -i -f "$SLURM_CONF" >"$tmp/slurmctld.stderr" 2>&1 &
slurmctld_pid=$!
wait_for 30 "slurmctld up" scontrol ping
slurmd -D -N "$host" -f "$SLURM_CONF" >"$tmp/slurmd.stderr" 2>&1 &
slurmd_pid=$!
node_idle() { [ "$(sinfo -h -n "$host" -o %t)" = idle ]; }
wait_for 30 "node $host idle" node_idle
echo "slurm check: cluster up on $host (port $port) in $((SECONDS - started)) s"

# The recipe: strata on PATH, a small render of a repository scene, the
# array of 4 (the script asks for 8 CPUs a task; this node may have fewer).
ln -s "$strata" "$tmp/bin/strata"
export PATH=$tmp/bin:$PATH
export STRATA_SCENE=$repo/scenes/seed.toml
export STRATA_ARGS="--width 160 --height 120 --spp 16"
cd "$tmp/work"
jobid=$(sbatch --parsable --array=0-3 --cpus-per-task=1 "$here/render.sbatch")
jobid=${jobid%%;*}
jobs=$jobid
mergeid=$(sbatch --parsable --dependency=afterok:"$jobid" --wrap 'strata merge parts/part_*.strata -o out.exr')
mergeid=${mergeid%%;*}
jobs="$jobid $mergeid"
echo "slurm check: submitted array job $jobid and merge job $mergeid"

gone() { [ -z "$(squeue -h -j "$jobid,$mergeid")" ]; }
# A failed array task leaves the merge pending forever: stop waiting then.
never() { squeue -h -j "$mergeid" -o %r | grep -q DependencyNeverSatisfied; }
deadline=$((SECONDS + 150))
until gone; do
    never && die "an array task failed; the merge job can never run"
    [ "$SECONDS" -lt "$deadline" ] || die "jobs not finished within 150 s"
    sleep 0.5
done

completed=$(scontrol -o show job "$jobid" | grep -c 'JobState=COMPLETED' || true)
[ "$completed" = 4 ] || die "$completed of 4 array tasks completed"
scontrol -o show job "$mergeid" | grep -q 'JobState=COMPLETED' || die "the merge job did not complete"
for k in 0 1 2 3; do
    [ -f "parts/part_$k.strata" ] || die "no parts/part_$k.strata"
done
[ -f out.exr ] || die "the merge job wrote no out.exr"

# shellcheck disable=SC2086 # STRATA_ARGS is split into words on purpose
# The single render goes through merge too, so that both EXRs are written
# alike: a render's own EXR header also records how long it took.
strata render "$STRATA_SCENE" $STRATA_ARGS --quiet -o single.strata
strata merge single.strata -o single.exr --quiet
cmp out.exr single.exr || die "merged image differs from the single-process render"
echo "slurm check: PASS: 4 Slurm array tasks merged equal one render, bit for bit ($((SECONDS - started)) s)"
