#!/usr/bin/env bash
# A real, single-machine Slurm cluster (Debian 12: Slurm 22.05, MUNGE 0.5.15) that scripts and CI
# can start and stop, so that the sbatch scripts softbake generates can be run for real.
#
#   scripts/slurm_local.sh install                 install what is missing of slurm-wlm and munge
#                                                  (apt-get; sudo only when not root)
#   scripts/slurm_local.sh start DIR [--slots N]   configure and start a one-node cluster in DIR
#                                                  (created if missing); prints the line to eval:
#                                                    export SLURM_CONF=DIR/slurm.conf
#   scripts/slurm_local.sh stop DIR                cancel its jobs, stop slurmd, slurmctld, munged;
#                                                  DIR is left for the caller to delete
#   scripts/slurm_local.sh status DIR              sinfo/squeue of the cluster in DIR
#   scripts/slurm_local.sh selftest                install, start in a mktemp -d folder (2 slots),
#                                                  run an array job and a dependent job, stop
#
# Typical use:   exports=$(scripts/slurm_local.sh start "$dir" --slots 4) && eval "$exports"
#                sbatch --parsable job.sh ...    # (or export SLURM_CONF="$dir/slurm.conf")
#                scripts/slurm_local.sh stop "$dir"; rm -rf "$dir"
# Clients (sbatch, squeue, sinfo, scontrol, scancel) find the cluster only through SLURM_CONF; a
# system-wide /etc/slurm is neither read nor changed. start and stop need root (the daemons run as
# root: SlurmUser=root; jobs run as the submitting user).
#
# What start configures, everything inside DIR (nothing under /etc, /run or /var, no systemd):
#   munge.key, munged (socket, pid, log, seed in DIR, run with --foreground in the background);
#   slurm.conf: node = `hostname -s` at 127.0.0.1 (no DNS needed), CPUs=N (default: nproc),
#     RealMemory from /proc/meminfo, SlurmdParameters=config_overrides (N may exceed the cores),
#     partition `local` (Default=YES), select/cons_tres + CR_CPU (N one-CPU tasks at once),
#     proctrack/linuxproc + task/none (no cgroups), no accounting, AuthType=auth/munge with
#     AuthInfo=socket=DIR/munge/munge.socket, MpiDefault=none, ReturnToService=2, and free TCP
#     ports picked from 6817 up (two clusters can run side by side);
#   slurmctld -D and slurmd -D started in the background; their pids, and munged's, in DIR/pids.
# Environment: SLURM_LOCAL_TIMEOUT (seconds to wait for the node / the daemons, default 60),
#   SLURM_LOCAL_KEEP=1 (selftest: keep its folder).
#
# Sourced (. scripts/slurm_local.sh), it defines only these, and leaves the shell's options alone:
#   slurm_local_start DIR [--slots N]   start, then export SLURM_CONF in the calling shell
#   slurm_local_stop DIR                stop
if [ "${BASH_SOURCE[0]}" != "$0" ]; then
  SLURM_LOCAL_SCRIPT=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/$(basename "${BASH_SOURCE[0]}")
  slurm_local_start() {
    local exports
    exports=$("$SLURM_LOCAL_SCRIPT" start "$@") || return
    eval "$exports"
  }
  slurm_local_stop() { "$SLURM_LOCAL_SCRIPT" stop "$@"; }
  return 0
fi
set -euo pipefail

readonly SLURM_LOCAL_PACKAGES=(slurmctld slurmd slurm-client munge)
TIMEOUT=${SLURM_LOCAL_TIMEOUT:-60}

say() { echo "slurm_local: $*" >&2; }
die() { say "error: $*"; exit 1; }

need_root() {
  [ "$(id -u)" -eq 0 ] || die "'$1' runs the daemons as root: run it as root (e.g. with sudo)"
}

need_commands() {
  local missing=() command
  for command in "$@"; do command -v "$command" >/dev/null || missing+=("$command"); done
  ((${#missing[@]} == 0)) ||
    die "missing ${missing[*]}: run '$0 install' first (Debian packages slurm-wlm, munge)"
}

# ---------------------------------------------------------------------------------------- install
cmd_install() {
  local missing=() package
  for package in "${SLURM_LOCAL_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
      missing+=("$package")
  done
  if ((${#missing[@]} == 0)); then
    say "install: $(slurm_version) and munge are installed"
    return 0
  fi
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || die "install: run as root or install sudo"
    sudo=sudo
  fi
  say "install: installing ${missing[*]}"
  # The packages' postinst scripts try to start munge, slurmctld and slurmd as system services.
  # Without an init system that fails or, worse, starts daemons on the default ports; a
  # policy-rc.d that answers 101 ("action forbidden") makes invoke-rc.d skip them. Docker images
  # ship one already; otherwise one is put in place for the install and removed afterwards.
  local policy=/usr/sbin/policy-rc.d made_policy=false
  if [ ! -e "$policy" ]; then
    printf '#!/bin/sh\nexit 101\n' | $sudo tee "$policy" >/dev/null
    $sudo chmod 755 "$policy"
    made_policy=true
  fi
  local status=0
  $sudo apt-get update -qq || status=$?
  if ((status == 0)); then
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
      "${missing[@]}" >/dev/null || status=$?
  fi
  if $made_policy; then $sudo rm -f "$policy"; fi
  ((status == 0)) || die "install: apt-get failed (exit $status)"
  say "install: $(slurm_version) and munge installed"
}

# (sinfo --version wants a configuration even to print its version; dpkg does not.)
slurm_version() { echo "slurm $(dpkg-query -W -f='${Version}' slurm-client 2>/dev/null || echo '(unknown)')"; }

# ------------------------------------------------------------------------------------------ start
port_in_use() { (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }

# Two consecutive free ports from 6817 up: slurmctld's and slurmd's. Another local cluster (or a
# system slurmctld) on 6817/6818 then does not clash with this one.
pick_ports() {
  local port=6817
  while port_in_use "$port" || port_in_use $((port + 1)); do
    port=$((port + 2))
    ((port < 7817)) || die "start: no free TCP port pair in 6817..7816"
  done
  echo "$port"
}

# The pid in DIR/pids/NAME.pid, if that process is still running the expected program.
live_pid() {
  local dir=$1 name=$2 pid comm
  [ -s "$dir/pids/$name.pid" ] || return 1
  pid=$(<"$dir/pids/$name.pid")
  [[ "$pid" =~ ^[0-9]+$ ]] || return 1
  comm=$(cat "/proc/$pid/comm" 2>/dev/null) || return 1
  [ "$comm" = "$name" ] || return 1 # a pid reused by another program is not ours
  # An exited daemon whose parent has not reaped it yet (a zombie) is not running either.
  [ "$(awk '{ print $3 }' "/proc/$pid/stat" 2>/dev/null)" != Z ] || return 1
  echo "$pid"
}

# Starts NAME (a daemon run in the foreground) in the background, in its own session (a Ctrl-C
# or hang-up for the calling shell does not reach it), and records its pid.
launch() {
  local dir=$1 name=$2
  shift 2
  # setsid execs in place (the job is not a process-group leader), so $! is the daemon's pid.
  SLURM_CONF="$dir/slurm.conf" setsid "$@" </dev/null >>"$dir/log/$name.stdout" 2>&1 &
  local pid=$! i
  echo "$pid" >"$dir/pids/$name.pid"
  # Until the exec, the child's name is bash's or setsid's: wait for it (at most 5 s), so that
  # live_pid tells "not started yet" from "exited".
  for ((i = 0; i < 100; i++)); do
    [ "$(cat "/proc/$pid/comm" 2>/dev/null)" != "$name" ] || return 0
    kill -0 "$pid" 2>/dev/null || return 0
    sleep 0.05
  done
}

show_log() {
  local file=$1
  [ -s "$file" ] || return 0
  say "--- last lines of $file"
  tail -n 15 "$file" >&2
}

fail_start() {
  local dir=$1
  shift
  say "error: start: $*"
  local file
  # A daemon run with -D logs to stderr (DIR/log/NAME.stdout) as well as to its log file; the
  # former also has what it said before it could open the latter.
  for file in "$dir"/log/*.stdout; do show_log "$file"; done
  cmd_stop "$dir" >/dev/null 2>&1 || true
  exit 1
}

# Waits (up to TIMEOUT seconds) until "$@" succeeds, while DAEMON (in DIR) runs; returns 1 on
# timeout or when DAEMON has exited.
wait_for() {
  local dir=$1 daemon=$2
  shift 2
  local deadline=$((SECONDS + TIMEOUT))
  until "$@" >/dev/null 2>&1; do
    live_pid "$dir" "$daemon" >/dev/null || { say "$daemon exited"; return 1; }
    ((SECONDS < deadline)) || { say "timed out after ${TIMEOUT}s"; return 1; }
    sleep 0.25
  done
}

write_slurm_conf() {
  local dir=$1 host=$2 slots=$3 memory=$4 port=$5
  cat >"$dir/slurm.conf" <<EOF
# Written by scripts/slurm_local.sh start: a one-node cluster, everything under this folder.
ClusterName=softbake-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket

StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
MailProg=/bin/true
PlugStackConfig=$dir/plugstack.conf

SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SwitchType=switch/none
# The node reports what is written here, not what it detects: N slots may exceed the cores.
SlurmdParameters=config_overrides
ReturnToService=2
# Finished jobs stay visible to scontrol show job for 5 minutes.
MinJobAge=300
KillWait=5
InactiveLimit=0
# Schedule as soon as a job ends (the default waits up to 3 s between batch job launches).
SchedulerParameters=batch_sched_delay=0

AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none

NodeName=$host NodeHostname=$host NodeAddr=127.0.0.1 CPUs=$slots RealMemory=$memory State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF
  : >"$dir/plugstack.conf" # not /etc/slurm/plugstack.conf
}

node_idle() {
  local dir=$1 host=$2 state
  state=$(SLURM_CONF="$dir/slurm.conf" sinfo -h -N -n "$host" -o '%T' 2>/dev/null) || return 1
  [ "$state" = "idle" ]
}

cmd_start() {
  local dir="" slots=""
  while (($#)); do
    case "$1" in
      --slots) (($# >= 2)) || die "start: --slots needs a number"; slots=$2; shift 2 ;;
      --slots=*) slots=${1#--slots=}; shift ;;
      -*) die "start: unknown option '$1'" ;;
      *) [ -z "$dir" ] || die "start: one DIR only"; dir=$1; shift ;;
    esac
  done
  [ -n "$dir" ] || die "usage: $0 start DIR [--slots N]"
  slots=${slots:-$(nproc)}
  [[ "$slots" =~ ^[1-9][0-9]*$ ]] || die "start: --slots must be a positive integer, not '$slots'"
  need_root start
  need_commands munged slurmctld slurmd sinfo

  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd -P) # absolute: the paths go into slurm.conf and SLURM_CONF
  # slurm.conf has no quoting, and a Unix socket path has at most 107 bytes.
  [[ "$dir" != *[[:space:]\#=]* ]] || die "start: DIR must not contain blanks, '#' or '=': '$dir'"
  ((${#dir} <= 80)) || die "start: DIR path too long for munged's socket (over 80 characters): $dir"
  local daemon
  for daemon in slurmd slurmctld munged; do
    if live_pid "$dir" "$daemon" >/dev/null; then
      die "start: $daemon of a cluster in $dir is running; run '$0 stop $dir' first"
    fi
  done
  # munged refuses a socket or key in a folder others may write to (unless it is sticky), and
  # every user who submits jobs has to reach the socket: DIR and DIR/munge are 755, the key 400.
  chmod 755 "$dir"
  rm -rf "$dir/pids" "$dir/run" "$dir/state" "$dir/spool"
  mkdir -p "$dir"/{munge,pids,run,state,spool,log}
  chmod 755 "$dir/munge"

  local host
  host=$(hostname -s 2>/dev/null || true)
  # A Slurm node name has to be a plain name; a missing or odd hostname falls back to localhost.
  [[ "$host" =~ ^[A-Za-z0-9][A-Za-z0-9-]*$ ]] || host=localhost
  local memory
  memory=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)
  ((memory >= 1)) || memory=1
  local port
  port=$(pick_ports)
  write_slurm_conf "$dir" "$host" "$slots" "$memory" "$port"

  # MUNGE: a key of our own; munged with key, socket, pid, seed and log in DIR.
  if [ ! -s "$dir/munge/munge.key" ]; then
    if command -v mungekey >/dev/null; then
      mungekey --create --keyfile="$dir/munge/munge.key" --bits=1024 >/dev/null
    else
      dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
    fi
  fi
  chmod 400 "$dir/munge/munge.key"
  rm -f "$dir/munge/munge.socket" "$dir/munge/munge.socket.lock"
  launch "$dir" munged munged --foreground --force \
    --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
    --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" \
    --seed-file="$dir/munge/munged.seed"
  wait_for "$dir" munged munge_works "$dir" || fail_start "$dir" "munged did not answer on $dir/munge/munge.socket"

  launch "$dir" slurmctld slurmctld -D -f "$dir/slurm.conf"
  wait_for "$dir" slurmctld controller_up "$dir" || fail_start "$dir" "slurmctld did not answer (scontrol ping)"
  launch "$dir" slurmd slurmd -D -f "$dir/slurm.conf" -N "$host"
  wait_for "$dir" slurmd node_idle "$dir" "$host" ||
    fail_start "$dir" "node $host not idle: $(SLURM_CONF="$dir/slurm.conf" \
      sinfo -h -N -o '%T %E' 2>&1 | head -n 3)"
  for daemon in munged slurmctld slurmd; do
    live_pid "$dir" "$daemon" >/dev/null || fail_start "$dir" "$daemon exited"
  done
  say "start: cluster up in $dir (node $host, $slots slots, ports $port/$((port + 1)))"
  printf 'export SLURM_CONF=%q\n' "$dir/slurm.conf"
}

munge_works() {
  local dir=$1
  live_pid "$dir" munged >/dev/null || return 1
  munge -S "$dir/munge/munge.socket" -n | unmunge -S "$dir/munge/munge.socket" >/dev/null
}

controller_up() {
  local dir=$1
  live_pid "$dir" slurmctld >/dev/null || return 1
  SLURM_CONF="$dir/slurm.conf" scontrol ping | grep -q UP
}

# ------------------------------------------------------------------------------------------- stop
# Sends TERM, waits up to 15 s, then KILL.
stop_pid() {
  local pid=$1 name=$2 i
  kill -TERM "$pid" 2>/dev/null || return 0
  for ((i = 0; i < 150; i++)); do
    kill -0 "$pid" 2>/dev/null || return 0
    [ "$(awk '{ print $3 }' "/proc/$pid/stat" 2>/dev/null)" != Z ] || return 0
    sleep 0.1
  done
  say "stop: $name ($pid) did not end on TERM; sending KILL"
  kill -KILL "$pid" 2>/dev/null || true
}

# slurmstepd processes of this cluster (launched by its slurmd, so SLURM_CONF is this slurm.conf).
stepd_pids() {
  local conf=$1 file pid
  for file in /proc/[0-9]*/comm; do
    [ "$(cat "$file" 2>/dev/null)" = slurmstepd ] || continue
    pid=${file#/proc/}
    pid=${pid%/comm}
    tr '\0' '\n' 2>/dev/null <"/proc/$pid/environ" | grep -qxF "SLURM_CONF=$conf" && echo "$pid"
  done
  return 0
}

cmd_stop() {
  (($# == 1)) || die "usage: $0 stop DIR"
  local dir=$1
  [ -d "$dir" ] || die "stop: no folder $dir"
  dir=$(cd "$dir" && pwd -P)
  [ -d "$dir/pids" ] || die "stop: $dir holds no cluster started by $0"
  local conf=$dir/slurm.conf pid jobs
  # Cancel the jobs first, so that their processes end with them rather than outlive slurmd.
  if live_pid "$dir" slurmctld >/dev/null && live_pid "$dir" slurmd >/dev/null; then
    jobs=$(SLURM_CONF="$conf" timeout 10 squeue -h -o '%A' 2>/dev/null | sort -u | tr '\n' ' ') || jobs=""
    if [ -n "${jobs// /}" ]; then
      say "stop: cancelling jobs $jobs"
      # shellcheck disable=SC2086  # one job id a word
      SLURM_CONF="$conf" timeout 10 scancel $jobs 2>/dev/null || true
      local deadline=$((SECONDS + 15))
      while ((SECONDS < deadline)) && [ -n "$(stepd_pids "$conf")" ]; do sleep 0.5; done
    fi
  fi
  local daemon stopped=()
  for daemon in slurmd slurmctld munged; do
    if pid=$(live_pid "$dir" "$daemon"); then
      stop_pid "$pid" "$daemon"
      stopped+=("$daemon")
    fi
    rm -f "$dir/pids/$daemon.pid"
  done
  for pid in $(stepd_pids "$conf"); do stop_pid "$pid" slurmstepd; done
  if ((${#stopped[@]})); then say "stop: stopped ${stopped[*]} ($dir)"; else say "stop: nothing was running in $dir"; fi
}

cmd_status() {
  (($# == 1)) || die "usage: $0 status DIR"
  local dir
  dir=$(cd "$1" && pwd -P) || die "status: no folder $1"
  local daemon pid
  for daemon in munged slurmctld slurmd; do
    if pid=$(live_pid "$dir" "$daemon"); then echo "$daemon: running ($pid)"; else echo "$daemon: not running"; fi
  done
  SLURM_CONF="$dir/slurm.conf" sinfo -N
  SLURM_CONF="$dir/slurm.conf" squeue
}

# --------------------------------------------------------------------------------------- selftest
SELFTEST_DIR="" SELFTEST_RUNNING=false
selftest_cleanup() {
  local status=$?
  trap - EXIT INT TERM
  if [ -n "$SELFTEST_DIR" ] && [ -d "$SELFTEST_DIR" ]; then
    if ((status != 0)); then
      local file
      for file in "$SELFTEST_DIR"/log/*.stdout "$SELFTEST_DIR"/logs/*; do show_log "$file"; done
    fi
    if $SELFTEST_RUNNING; then cmd_stop "$SELFTEST_DIR" || true; fi
    if [ "${SLURM_LOCAL_KEEP:-0}" = 1 ]; then say "selftest: kept $SELFTEST_DIR"; else rm -rf "$SELFTEST_DIR"; fi
  fi
  ((status == 0)) || say "selftest: FAILED"
  exit "$status"
}

# The distinct states of a job's tasks (one word for a plain job or a uniform array), "" if gone.
job_state() {
  scontrol -o show job "$1" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2 | sort -u |
    paste -sd, -
}

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

cmd_selftest() {
  local begin
  begin=$(now)
  cmd_install
  need_root selftest
  SELFTEST_DIR=$(mktemp -d "${TMPDIR:-/tmp}/slurm_local.XXXXXX")
  trap selftest_cleanup EXIT
  trap 'exit 130' INT
  trap 'exit 143' TERM
  local dir=$SELFTEST_DIR
  local started exports
  started=$(now)
  SELFTEST_RUNNING=true
  exports=$(cmd_start "$dir" --slots 2) || die "selftest: start failed"
  eval "$exports"
  say "selftest: start took $(since "$started") s"
  [ "$SLURM_CONF" = "$dir/slurm.conf" ] || die "selftest: start printed a wrong SLURM_CONF"

  mkdir -p "$dir/logs" "$dir/shared"
  cat >"$dir/array.sh" <<'EOF'
#!/bin/bash
set -euo pipefail
echo "task $SLURM_ARRAY_TASK_ID of job $SLURM_ARRAY_JOB_ID on $(hostname -s)"
sleep 1
echo "$SLURM_ARRAY_TASK_ID" >"$1/task_$SLURM_ARRAY_TASK_ID.txt"
EOF
  cat >"$dir/check.sh" <<'EOF'
#!/bin/bash
set -euo pipefail
for i in 1 2 3 4; do
  [ "$(cat "$1/task_$i.txt")" = "$i" ] || { echo "task $i's file is missing or wrong" >&2; exit 1; }
done
echo ok >"$1/check.ok"
EOF
  local array_id check_id
  array_id=$(sbatch --parsable --job-name=array --array=1-4 --ntasks=1 --cpus-per-task=1 \
    --output="$dir/logs/%x_%A_%a.out" "$dir/array.sh" "$dir/shared") ||
    die "selftest: sbatch of the array job failed"
  array_id=${array_id%%;*}
  check_id=$(sbatch --parsable --job-name=check --dependency="afterok:$array_id" \
    --kill-on-invalid-dep=yes --output="$dir/logs/%x_%j.out" "$dir/check.sh" "$dir/shared") ||
    die "selftest: sbatch of the check job failed"
  check_id=${check_id%%;*}
  say "selftest: submitted array job $array_id (tasks 1-4) and check job $check_id (afterok)"

  # Both are done once squeue (which lists pending, running and completing jobs) has neither.
  local deadline=$((SECONDS + 120)) most=0 running
  while [ -n "$(squeue -h -j "$array_id,$check_id" -o '%i' 2>/dev/null)" ]; do
    running=$(squeue -h -j "$array_id" -t RUNNING -o '%i' 2>/dev/null | wc -l)
    ((running > most)) && most=$running
    ((SECONDS < deadline)) || die "selftest: jobs not done after 120 s: $(squeue -h -j "$array_id,$check_id" 2>&1)"
    sleep 0.5
  done
  local array_state check_state
  array_state=$(job_state "$array_id")
  check_state=$(job_state "$check_id")
  say "selftest: array job $array_id: ${array_state:-gone}; check job $check_id: ${check_state:-gone}; at most $most array tasks ran at once"
  [ "$array_state" = COMPLETED ] || die "selftest: array job state '$array_state', expected COMPLETED"
  [ "$check_state" = COMPLETED ] || die "selftest: check job state '$check_state', expected COMPLETED"
  [ -f "$dir/shared/check.ok" ] || die "selftest: the check job wrote no marker"
  local task
  for task in 1 2 3 4; do
    grep -q "^task $task of job $array_id" "$dir/logs/array_${array_id}_$task.out" ||
      die "selftest: no log $dir/logs/array_${array_id}_$task.out"
  done
  local stop_begin
  stop_begin=$(now)
  SELFTEST_RUNNING=false
  cmd_stop "$dir"
  say "selftest: stop took $(since "$stop_begin") s"
  for daemon in munged slurmctld slurmd; do
    [ ! -e "$dir/pids/$daemon.pid" ] || die "selftest: $daemon still recorded after stop"
  done
  say "selftest: passed in $(since "$begin") s (wall time, install check included)"
}

# ------------------------------------------------------------------------------------------- main
main() {
  (($#)) || { sed -n '2,38s/^# \{0,1\}//p' "$0" >&2; exit 2; }
  local command=$1
  shift
  case "$command" in
    install) (($# == 0)) || die "usage: $0 install"; cmd_install ;;
    start) cmd_start "$@" ;;
    stop) cmd_stop "$@" ;;
    status) cmd_status "$@" ;;
    selftest) (($# == 0)) || die "usage: $0 selftest"; cmd_selftest ;;
    -h | --help | help) sed -n '2,38s/^# \{0,1\}//p' "$0"; exit 0 ;;
    *) die "unknown command '$command' (install, start, stop, status, selftest)" ;;
  esac
}

main "$@"
