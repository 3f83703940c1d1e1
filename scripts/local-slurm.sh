#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for trying the farm (docs/farm.md) and for tests/slurm.rs:
#
#   sudo scripts/local-slurm.sh start    # install slurm-wlm and munge if missing, start the daemons
#   sudo scripts/local-slurm.sh status   # which daemons run, and sinfo
#   sudo scripts/local-slurm.sh stop     # cancel every job, stop the daemons, remove the state
#
# Runs as root, and `start` and `stop` may be repeated. Debian 12 packages Slurm 22.05. The daemons
# (munged, unless one already answers; slurmctld; slurmd) run from a state folder, by default
# /var/lib/caustica-slurm (LOCAL_SLURM_DIR), with a slurm.conf describing this machine as `slurmd -C`
# sees it: its cores and memory, one partition `main` (the default), and a `gpu` gres so that jobs
# asking `--gpus=1` run: the machine's /dev/nvidia* or /dev/dri/renderD* devices where there are
# some, else one placeholder (File=/dev/null; caustica then finds whatever Vulkan device there is,
# lavapipe included). Slurm's commands find the cluster through SLURM_CONF (printed by `start`);
# /etc/slurm/slurm.conf is linked to it as well when that file does not exist.
#
# Single node, so the simplest plugins: processes tracked by parent id (proctrack/linuxproc), no CPU
# binding or cgroups (task/none), no accounting database. A requeued job may start again after
# cred_expire seconds (Slurm's default is 120; 5 here, so a requeue is tried at once).
set -euo pipefail

dir=${LOCAL_SLURM_DIR:-/var/lib/caustica-slurm}
conf="$dir/slurm.conf"
etc_conf=/etc/slurm/slurm.conf
export SLURM_CONF="$conf"

say() { echo "local-slurm: $*"; }
die() {
    echo "local-slurm: error: $*" >&2
    exit 1
}

# The pid in FILE if that process is alive.
alive() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

munge_answers() { munge -n 2>/dev/null | unmunge >/dev/null 2>&1; }

install_packages() {
    local need=()
    for pkg in slurm-wlm munge; do
        dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
    done
    [ ${#need[@]} -eq 0 ] && return
    command -v apt-get >/dev/null || die "${need[*]} missing and no apt-get to install them"
    say "installing ${need[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq || die "apt-get update failed"
    apt-get install -y -qq "${need[@]}" >/dev/null || die "apt-get install ${need[*]} failed"
}

# gres.conf lines for the node's GPUs, and their count.
gpu_devices() {
    local devices=()
    local d
    for d in /dev/nvidia[0-9]* /dev/dri/renderD[0-9]*; do
        [ -c "$d" ] && devices+=("$d")
    done
    # One kind only: NVIDIA's when present (a machine with both shows its display GPU as renderD too).
    local nvidia=()
    for d in "${devices[@]}"; do [[ $d == /dev/nvidia* ]] && nvidia+=("$d"); done
    [ ${#nvidia[@]} -gt 0 ] && devices=("${nvidia[@]}")
    [ ${#devices[@]} -eq 0 ] && devices=(/dev/null)
    printf '%s\n' "${devices[@]}"
}

write_config() {
    local host node gpus
    host=$(hostname -s)
    # slurmd -C: "NodeName=host CPUs=.. Boards=.. SocketsPerBoard=.. CoresPerSocket=.. ThreadsPerCore=..
    # RealMemory=.." then "UpTime=..". Leave memory for the daemons and the system.
    node=$(slurmd -C | head -n 1)
    [[ $node == NodeName=* ]] || die "slurmd -C did not describe this machine: $node"
    local memory=${node##*RealMemory=}
    memory=${memory%% *}
    local usable=$((memory > 2048 ? memory - 1024 : memory * 3 / 4))
    node="${node% RealMemory=*} RealMemory=$usable"
    mapfile -t gpus < <(gpu_devices)
    {
        echo "# Written by scripts/local-slurm.sh on $(date -u +%Y-%m-%dT%H:%M:%SZ): a one-node cluster."
        for g in "${gpus[@]}"; do echo "Name=gpu File=$g"; done
    } >"$dir/gres.conf"
    cat >"$conf" <<EOF
# Written by scripts/local-slurm.sh on $(date -u +%Y-%m-%dT%H:%M:%SZ): a one-node cluster.
ClusterName=caustica-local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=cred_expire=5
StateSaveLocation=$dir/slurmctld
SlurmdSpoolDir=$dir/slurmd
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/builtin
# Look at pending jobs every second (default 60 s): a requeued job starts again at once.
SchedulerParameters=sched_interval=1
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
GresTypes=gpu
ReturnToService=2
# Finished jobs stay visible to scontrol for 10 minutes (tests read their state).
MinJobAge=600
# SIGTERM, then SIGKILL this many seconds later (scancel, requeue, time limit).
KillWait=30
$node Gres=gpu:${#gpus[@]} NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=main Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
}

start() {
    [ "$(id -u)" -eq 0 ] || die "must run as root (it starts munged, slurmctld and slurmd)"
    install_packages
    mkdir -p "$dir/slurmctld" "$dir/slurmd"
    if alive "$dir/slurmctld.pid" && alive "$dir/slurmd.pid" && munge_answers; then
        say "already running"
        say "export SLURM_CONF=$conf"
        return
    fi
    if ! munge_answers; then
        [ -f /etc/munge/munge.key ] || runuser -u munge -- mungekey --create
        mkdir -p /run/munge /var/log/munge /var/lib/munge
        chown munge:munge /run/munge /var/log/munge /var/lib/munge
        runuser -u munge -- munged
        echo "$(cat /run/munge/munged.pid)" >"$dir/munged.pid"
        for _ in $(seq 50); do munge_answers && break || sleep 0.1; done
        munge_answers || die "munged started but does not answer"
    fi
    alive "$dir/slurmctld.pid" || alive "$dir/slurmd.pid" || write_config
    if [ ! -e "$etc_conf" ] || [ "$(readlink "$etc_conf")" = "$conf" ]; then
        mkdir -p /etc/slurm
        ln -sfn "$conf" "$etc_conf"
    fi
    alive "$dir/slurmctld.pid" || slurmctld -f "$conf" -c || die "slurmctld did not start: see $dir/slurmctld.log"
    alive "$dir/slurmd.pid" || slurmd -f "$conf" || die "slurmd did not start: see $dir/slurmd.log"
    # Wait for the node to register and be idle.
    local state=""
    for _ in $(seq 100); do
        state=$(sinfo -h -o %t 2>/dev/null | head -n 1)
        [ "$state" = idle ] && break
        sleep 0.2
    done
    [ "$state" = idle ] || die "the node is '${state:-unknown}', not idle: see $dir/slurmctld.log and $dir/slurmd.log"
    say "running: $(sinfo -h -N -o '%N %c CPUs %m MB %G')"
    say "export SLURM_CONF=$conf"
}

stop_daemon() {
    local name=$1 pidfile=$2
    alive "$pidfile" || return 0
    kill "$(cat "$pidfile")"
    for _ in $(seq 100); do alive "$pidfile" || break; sleep 0.1; done
    alive "$pidfile" && kill -KILL "$(cat "$pidfile")"
    say "stopped $name"
}

stop() {
    [ "$(id -u)" -eq 0 ] || die "must run as root"
    if alive "$dir/slurmctld.pid"; then
        scancel --quiet --full --signal=KILL --user=root 2>/dev/null || true
        scancel --quiet --user="$(id -un)" 2>/dev/null || true
        scancel --quiet $(squeue -h -o %A 2>/dev/null) 2>/dev/null || true
    fi
    stop_daemon slurmd "$dir/slurmd.pid"
    stop_daemon slurmctld "$dir/slurmctld.pid"
    # Job step daemons left by slurmd (they outlive it by design).
    local pid
    for pid in $(pgrep -x slurmstepd 2>/dev/null || true); do
        kill -KILL "$pid" 2>/dev/null || true
    done
    stop_daemon munged "$dir/munged.pid"
    [ "$(readlink "$etc_conf" 2>/dev/null)" = "$conf" ] && rm -f "$etc_conf"
    rm -rf "$dir"
    say "stopped"
}

status() {
    local ok=0
    for daemon in munged slurmctld slurmd; do
        if alive "$dir/$daemon.pid"; then
            say "$daemon running (pid $(cat "$dir/$daemon.pid"))"
        elif [ $daemon = munged ] && munge_answers; then
            say "munged running (not started by this script)"
        else
            say "$daemon not running"
            ok=1
        fi
    done
    [ $ok -eq 0 ] && sinfo -N -o '%N %t %c %m %G'
    return $ok
}

case "${1:-}" in
start) start ;;
stop) stop ;;
status) status ;;
*)
    echo "usage: $0 start|stop|status" >&2
    exit 2
    ;;
esac
