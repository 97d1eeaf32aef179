#!/usr/bin/env bash
# A single-node Slurm cluster on loopback in a private state directory, for
# tests and trying `cellbake submit` on one machine (see
# tested with Debian 12's Slurm 22.05 and munge 0.5, run as root).
#
#   scripts/slurm-local.sh start    # munged + slurmctld + slurmd, waits for an idle node
#   scripts/slurm-local.sh status   # daemons alive? node state
#   scripts/slurm-local.sh stop     # cancels jobs, stops the daemons it started (by pid file)
#
# Environment: CELLBAKE_SLURM_DIR (state directory, default /tmp/cellbake-slurm),
# CELLBAKE_SLURM_PORT (slurmctld port, slurmd uses the next one; default 6817).
# Slurm client commands need SLURM_CONF=$CELLBAKE_SLURM_DIR/slurm.conf; `start`
# prints the line to export.
set -euo pipefail

dir=${CELLBAKE_SLURM_DIR:-/tmp/cellbake-slurm}
port=${CELLBAKE_SLURM_PORT:-6817}
conf=$dir/slurm.conf
scripts=$(cd "$(dirname "$0")" && pwd)
host=$(hostname -s)
export SLURM_CONF=$conf

say() { echo "[slurm-local] $*"; }
die() { echo "[slurm-local] error: $*" >&2; exit 1; }

# The pid in a pid file if that process is alive and is the named program, else nothing.
live_pid() {
  local file=$1 name=$2 pid
  [ -f "$file" ] || return 0
  pid=$(cat "$file" 2>/dev/null || true)
  [[ "$pid" =~ ^[0-9]+$ ]] || return 0
  if [ -d "/proc/$pid" ] && grep -q "$name" "/proc/$pid/comm" 2>/dev/null; then echo "$pid"; fi
}

# Ends the process of a pid file: TERM, up to 5 s grace, then KILL.
stop_pid_file() {
  local file=$1 name=$2 pid i
  pid=$(live_pid "$file" "$name")
  if [ -n "$pid" ]; then
    kill -TERM "$pid" 2>/dev/null || true
    for i in $(seq 50); do
      [ -d "/proc/$pid" ] || break
      sleep 0.1
    done
    if [ -d "/proc/$pid" ]; then
      say "$name ($pid) did not stop; killing it"
      kill -KILL "$pid" 2>/dev/null || true
    fi
  fi
  rm -f "$file"
}

write_config() {
  mkdir -p "$dir"/{munge,run,log,state,spool,cgroup/systemd}
  chmod 700 "$dir"
  chmod 755 "$dir/munge"  # munged's socket directory
  if [ ! -f "$dir/munge/munge.key" ]; then
    dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
    chmod 400 "$dir/munge/munge.key"
  fi
  # CPUs, boards, sockets, cores, threads as slurmd sees them; memory below the machine's.
  local hw mem
  hw=$(slurmd -C | head -n1 | tr ' ' '\n' | grep -E '^(CPUs|Boards|SocketsPerBoard|CoresPerSocket|ThreadsPerCore)=' | tr '\n' ' ')
  mem=$(slurmd -C | head -n1 | tr ' ' '\n' | sed -n 's/^RealMemory=//p')
  mem=$(( mem > 2048 ? mem - 1024 : mem / 2 ))
  cat > "$conf" <<EOF
# Written by scripts/slurm-local.sh: one node on loopback, private state.
ClusterName=cellbake
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
CommunicationParameters=EnableIPv6
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
MpiDefault=none
MailProg=/bin/true
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/log/jobcomp.txt
MinJobAge=300
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 ${hw}RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  # slurmd 22.05 always initialises a cgroup plugin: point it at an empty
  # hierarchy of our own that has the v1 systemd subdirectory.
  cat > "$dir/cgroup.conf" <<EOF
CgroupPlugin=cgroup/v1
CgroupMountpoint=$dir/cgroup
CgroupAutomount=no
EOF
}

wait_for() {
  local what=$1 seconds=$2 i
  shift 2
  for i in $(seq $((seconds * 10))); do
    if "$@" >/dev/null 2>&1; then return 0; fi
    sleep 0.1
  done
  die "timed out after ${seconds}s waiting for $what (logs in $dir/log)"
}

node_idle() { [ "$(sinfo -h -n "$host" -o %T 2>/dev/null)" = idle ]; }

start() {
  local p
  for p in munged slurmctld slurmd scontrol sinfo sbatch; do
    if ! command -v "$p" >/dev/null; then
      say "$p not found: installing the Slurm packages"
      bash "$scripts/install-deps.sh" slurm || die "cannot install slurmctld slurmd slurm-client munge"
      break
    fi
  done
  for p in munged slurmctld slurmd scontrol sinfo sbatch; do
    command -v "$p" >/dev/null || die "$p not found after installing the Slurm packages"
  done
  if [ -n "$(live_pid "$dir/run/slurmctld.pid" slurmctld)" ]; then
    say "already running in $dir"
    echo "export SLURM_CONF=$conf"
    return 0
  fi
  local t0=$SECONDS
  write_config
  if [ -z "$(live_pid "$dir/run/munged.pid" munged)" ]; then
    munged --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
      --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed" --force
  fi
  wait_for "munged" 10 test -S "$dir/munge/munge.socket"
  slurmctld -f "$conf"
  wait_for "slurmctld (scontrol ping)" 30 sh -c 'scontrol ping | grep -q UP'
  slurmd -f "$conf"
  wait_for "node $host to be idle" 30 node_idle
  say "node $host idle after $((SECONDS - t0)) s; state in $dir"
  echo "export SLURM_CONF=$conf"
}

stop() {
  if [ -n "$(live_pid "$dir/run/slurmctld.pid" slurmctld)" ]; then
    scancel --full --quiet --user="$(id -un)" 2>/dev/null || true
    scontrol shutdown >/dev/null 2>&1 || true
  fi
  stop_pid_file "$dir/run/slurmd.pid" slurmd
  stop_pid_file "$dir/run/slurmctld.pid" slurmctld
  stop_pid_file "$dir/run/munged.pid" munged
  say "stopped (state kept in $dir)"
}

status() {
  local name file pid up=0
  for name in munged slurmctld slurmd; do
    file="$dir/run/$name.pid"
    pid=$(live_pid "$file" "$name")
    if [ -n "$pid" ]; then echo "$name: running (pid $pid)"; up=$((up + 1)); else echo "$name: not running"; fi
  done
  if [ "$up" -eq 3 ]; then
    echo "node $host: $(sinfo -h -n "$host" -o %T 2>/dev/null || echo unknown)"
    echo "export SLURM_CONF=$conf"
  fi
  [ "$up" -eq 3 ]
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  status) status ;;
  *) echo "usage: $0 start|stop|status   (state dir: \$CELLBAKE_SLURM_DIR, default /tmp/cellbake-slurm)" >&2; exit 2 ;;
esac
