#!/usr/bin/env bash
# Starts and stops a throwaway one-node Slurm cluster on this machine, entirely under one
# folder, by hand (no systemd, nothing in /etc or /run), so that scripts which drive Slurm
# (sbatch, job arrays, dependencies) can be tested without a real cluster.
#
#   bash tools/slurm-local.sh start DIR   # munged, slurmctld and slurmd under DIR; returns once
#                                         # the node is idle; then `source DIR/env`
#   bash tools/slurm-local.sh stop DIR    # stops exactly what start started; safe to repeat
#
# How long a finished job is remembered (slurm.conf's MinJobAge) is a trade-off, so
# SLURM_LOCAL_MIN_JOB_AGE may set it (seconds, at least 2; 5 unless set):
# - `sbatch --wait` polls after 2 s, then every 8 s, then every 32 s unless MinJobAge is under
#   6; at 5 it polls every 2 s throughout, so a short job's sbatch --wait returns in about 2 s
#   rather than 10 or 42.
# - But Slurm lifts a dependency on a job it has forgotten (or never knew): a job submitted
#   with afterok on a failed job runs once that job is forgotten, some 5-10 s after it ends
#   at 5. Submit dependants while what they depend on is queued or running (a dependant
#   already waiting is failed before the purge), or set 300, Slurm's default.
# - `sbatch --wait` on a job cancelled because its dependency failed returns 0, not an error;
#   check what the job should have written instead (its record is soon forgotten, as above).
#
# Needs root (slurmd launches jobs as their owner) and Debian's packages slurmctld, slurmd,
# slurm-client and munge (tested with Slurm 22.05 and munge 0.5.15). DIR may be fresh from
# `mktemp -d`; start creates it if missing. Only one such cluster is meant to run at a time,
# but each start picks free ports, so a leftover cluster elsewhere does not get in its way.
#
# What DIR holds afterwards:
#   env                      `export SLURM_CONF=...`: all the client commands need
#   slurm.conf               the cluster's configuration (its AuthInfo names munge's socket,
#                            which is how sbatch, squeue, slurmctld and slurmd all find it)
#   pids                     "NAME PID" for each daemon start launched; stop reads it
#   munge/                   munged's own key, socket, pid, log and seed files
#   log/                     slurmctld.log and slurmd.log
#   state/, spool/           slurmctld's saved state and slurmd's spool
#   slurmctld.pid, slurmd.pid  the daemons' own pid files
set -euo pipefail

me="slurm-local"

usage() {
  echo "usage: bash tools/slurm-local.sh start|stop DIR" >&2
  exit 2
}

die() {
  echo "$me: error: $*" >&2
  exit 1
}

[ $# -eq 2 ] || usage
action=$1
dir=$2
case "$action" in start | stop) ;; *) usage ;; esac
[ -n "$dir" ] || usage

# Names the daemons go by in /proc/PID/comm, and where each writes its pid file.
daemons=(slurmd slurmctld munged)
pidfile_of() {
  case "$1" in
    munged) echo "$dir/munge/munged.pid" ;;
    *) echo "$dir/$1.pid" ;;
  esac
}

# Whether PID is alive and is the daemon NAME that this DIR started. Matching the command
# line against DIR as well as the name keeps a recycled pid, or the same daemon of another
# cluster, from ever being signalled. A daemon that has exited but is not yet reaped (a
# zombie, with an empty command line) counts as gone.
is_ours() {
  local name=$1 pid=$2
  [[ $pid =~ ^[0-9]+$ ]] || return 1
  [ -r "/proc/$pid/comm" ] || return 1
  [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = "$name" ] || return 1
  local cmdline
  cmdline=$(tr '\0' ' ' 2>/dev/null <"/proc/$pid/cmdline") || return 1
  [[ $cmdline == *"$dir/"* ]]
}

# Every pid this DIR's daemons are known by: those start recorded in DIR/pids, and those in
# the daemons' own pid files (which cover a start that failed before it could record them).
# Prints "NAME PID" lines for the ones still alive and ours.
live_daemons() {
  local name pid f
  local known=""
  if [ -r "$dir/pids" ]; then known=$(cat "$dir/pids"); fi
  for name in "${daemons[@]}"; do
    f=$(pidfile_of "$name")
    if [ -r "$f" ]; then known+=$'\n'"$name $(tr -dc '0-9' 2>/dev/null <"$f" || true)"; fi
  done
  while read -r name pid; do
    if [ -n "$name" ] && is_ours "$name" "$pid"; then echo "$name $pid"; fi
  done < <(sort -u <<<"$known")
}

# Whether daemon NAME of this DIR is still running.
alive() {
  [[ $'\n'"$(live_daemons)" == *$'\n'"$1 "* ]]
}

stop_cluster() {
  local name n pid left i
  if [ ! -d "$dir" ]; then
    echo "$me: $dir does not exist; nothing to stop"
    return 0
  fi
  if [ -z "$(live_daemons)" ]; then
    rm -f "$dir/pids"
    echo "$me: no daemon of $dir is running; nothing to stop"
    return 0
  fi
  # Jobs still running have slurmstepd processes and job scripts that slurmd does not stop
  # when it exits, so cancel them through Slurm first while slurmctld can still do it.
  if alive slurmctld && [ -r "$dir/slurm.conf" ]; then
    local jobs
    jobs=$(SLURM_CONF="$dir/slurm.conf" timeout 10 squeue -h -o %i 2>/dev/null || true)
    if [ -n "$jobs" ]; then
      echo "$me: cancelling the jobs still queued or running"
      # shellcheck disable=SC2086  # one argument per job id
      SLURM_CONF="$dir/slurm.conf" timeout 10 scancel $jobs 2>/dev/null || true
      for ((i = 0; i < 20; i++)); do
        [ -z "$(SLURM_CONF="$dir/slurm.conf" timeout 5 squeue -h -t R,CG -o %i 2>/dev/null)" ] && break
        sleep 0.5
      done
    fi
  fi
  # slurmd and slurmctld first, munged last: the Slurm daemons still authenticate through
  # munge while they shut down.
  for name in "${daemons[@]}"; do
    while read -r n pid; do
      if [ "$n" = "$name" ]; then kill -TERM "$pid" 2>/dev/null || true; fi
    done < <(live_daemons)
    for ((i = 0; i < 20; i++)); do
      alive "$name" || break
      sleep 0.5
    done
  done
  left=$(live_daemons)
  if [ -n "$left" ]; then
    echo "$me: still running 10 s after TERM, so killing: $(paste -sd, - <<<"$left" | sed 's/,/, /g')" >&2
    while read -r name pid; do kill -KILL "$pid" 2>/dev/null || true; done <<<"$left"
    sleep 0.5
    left=$(live_daemons)
    [ -z "$left" ] || die "could not stop $(paste -sd, - <<<"$left" | sed 's/,/, /g'); kill them by hand (kill -KILL PID)"
  fi
  rm -f "$dir/pids"
  echo "$me: stopped the cluster under $dir"
}

# Prints the end of each log, for a start that failed.
show_logs() {
  local f
  for f in "$dir/munge/munged.log" "$dir/log/slurmctld.log" "$dir/log/slurmd.log"; do
    [ -s "$f" ] || continue
    echo "---- last lines of $f ----" >&2
    tail -n 15 "$f" >&2
  done
}

# Waits up to $2 seconds for file $1 to appear and hold a pid, then records that pid as
# daemon $3's.
record_pid() {
  local f=$1 secs=$2 name=$3 i pid
  for ((i = 0; i < secs * 10; i++)); do
    pid=""
    if [ -r "$f" ]; then pid=$(tr -dc '0-9' 2>/dev/null <"$f" || true); fi
    if [ -n "$pid" ] && is_ours "$name" "$pid"; then
      echo "$name $pid" >>"$dir/pids"
      return 0
    fi
    sleep 0.1
  done
  die "$name did not start (no live process in its pid file $f after $secs s); see the logs below"
}

# Whether TCP port $1 is in use in any state (listening, or a connection even in TIME-WAIT).
port_busy() {
  [ -n "$(ss -Htan "( sport = :$1 or dport = :$1 )")" ]
}

start_cluster() {
  local tool host p i ctld_port slurmd_port state
  [ "$(id -u)" -eq 0 ] || die "this must run as root (slurmd launches jobs as their owner); run it with sudo"
  for tool in munged munge unmunge slurmctld slurmd sinfo squeue scancel sdiag ss dd; do
    command -v "$tool" >/dev/null ||
      die "$tool is not installed; install it with: apt-get install munge slurmctld slurmd slurm-client iproute2"
  done
  local min_job_age=${SLURM_LOCAL_MIN_JOB_AGE:-5}
  [[ $min_job_age =~ ^[0-9]+$ ]] && [ "$min_job_age" -ge 2 ] ||
    die "SLURM_LOCAL_MIN_JOB_AGE is '$min_job_age'; it must be a whole number of seconds, at least 2 (Slurm 22.05 refuses less)"
  # slurm.conf takes its paths unquoted, so a space or # would split or end them.
  [[ ! $dir =~ [[:space:]#=,] ]] || die "DIR '$dir' has a space, #, = or comma, which slurm.conf cannot hold; pick another folder"

  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd -P)
  if [ -n "$(live_daemons)" ]; then
    die "a cluster is already running under $dir ($(live_daemons | paste -sd, - | sed 's/,/, /g')); run: bash tools/slurm-local.sh stop $dir"
  fi

  # From here on, a failure shows the logs and stops whatever had started.
  trap 'rc=$?; if [ $rc -ne 0 ]; then show_logs; echo "$me: start failed; stopping what it started" >&2; stop_cluster >&2 || true; fi' EXIT

  # munged refuses a socket unless every folder on its path is searchable by all users
  # (mktemp -d makes DIR 0700). Searching is all that is granted: nothing becomes readable.
  chmod 0755 "$dir"
  p=$(dirname "$dir")
  while [ "$p" != / ]; do
    if [ -z "$(find "$p" -maxdepth 0 -perm -o+x)" ]; then
      echo "$me: note: making $p searchable by all users (chmod a+x), which munged's socket needs"
      chmod a+x "$p"
    fi
    p=$(dirname "$p")
  done

  # A clean slate: no jobs, node states or keys from an earlier run in this DIR.
  rm -rf "$dir/munge" "$dir/state" "$dir/spool" "$dir/log" "$dir/pids" "$dir/env" \
    "$dir/slurm.conf" "$dir/slurmctld.pid" "$dir/slurmd.pid"
  mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
  chmod 0755 "$dir/munge"

  # munge: a key of its own, so this cluster trusts nothing signed elsewhere (nor the
  # reverse), and a socket of its own, so it needs no /run/munge and leaves a system
  # munged alone. As root, munged 0.5.15 runs without --force.
  dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  chmod 0400 "$dir/munge/munge.key"
  local sock="$dir/munge/munge.socket"
  munged --key-file="$dir/munge/munge.key" --socket="$sock" \
    --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
    --seed-file="$dir/munge/munged.seed" ||
    die "munged failed to start; its log $dir/munge/munged.log says why"
  record_pid "$dir/munge/munged.pid" 10 munged
  munge -n -S "$sock" | unmunge -S "$sock" >/dev/null ||
    die "munged started but its socket $sock does not answer; see $dir/munge/munged.log"

  # Two free ports next to each other, picked at random so a leftover cluster (or its
  # connections still in TIME-WAIT) cannot clash with this one.
  ctld_port=""
  for ((i = 0; i < 100; i++)); do
    p=$((20000 + RANDOM % 9999))
    if ! port_busy "$p" && ! port_busy $((p + 1)); then
      ctld_port=$p
      slurmd_port=$((p + 1))
      break
    fi
  done
  [ -n "$ctld_port" ] || die "found no two free TCP ports in 20000-29999 after 100 tries; check \`ss -tan\`"

  # slurmd finds its node by the short hostname; everything talks over 127.0.0.1.
  host=$(hostname -s)
  cat >"$dir/slurm.conf" <<EOF
# A one-node cluster on loopback, written by tools/slurm-local.sh; every path is under
# $dir.
ClusterName=relume-local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
# auth/munge and cred/munge both take munge's socket from here: no client needs more than
# SLURM_CONF to find it.
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$sock
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
# No cgroups: processes are tracked through /proc and tasks are not bound.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
# Quiets slurmctld's complaint that it has no mail program.
MailProg=/bin/true
# Pending jobs start on slurmctld's next 1 s tick after they are submitted or a CPU frees
# up, rather than up to 3 s later (batch_sched_delay's default). sched/builtin rather than
# backfill: one node has nothing to backfill.
SchedulerType=sched/builtin
SchedulerParameters=batch_sched_delay=0
# How long slurmctld remembers a finished job (SLURM_LOCAL_MIN_JOB_AGE, 5 s unless set; see
# the top of tools/slurm-local.sh).
MinJobAge=$min_job_age
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
# The node's CPUs and memory are taken as written, even on a smaller machine.
SlurmdParameters=config_overrides
NodeName=$host NodeAddr=127.0.0.1 CPUs=2 RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF="$dir/slurm.conf"

  # -c: start with no jobs, whatever the state folder holds.
  slurmctld -c -f "$SLURM_CONF" || die "slurmctld failed to start; its log $dir/log/slurmctld.log says why"
  record_pid "$dir/slurmctld.pid" 15 slurmctld
  slurmd -f "$SLURM_CONF" -N "$host" || die "slurmd failed to start; its log $dir/log/slurmd.log says why"
  record_pid "$dir/slurmd.pid" 15 slurmd

  state=""
  for ((i = 0; i < 120; i++)); do
    state=$(timeout 5 sinfo -h -N -n "$host" -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.5
  done
  [ "$state" = idle ] ||
    die "node $host is not idle after 60 s (sinfo says '${state:-nothing}'); see the logs below"

  # slurmctld's scheduler first runs some 3 s after it starts (then on a 1 s tick); a job
  # submitted before that waits for it, so wait here instead, where it costs every caller
  # the same. Not fatal: jobs would still start, only later.
  local cycles=""
  for ((i = 0; i < 30; i++)); do
    cycles=$(timeout 5 sdiag 2>/dev/null | awk '/^Main schedule/ {m = 1} m && /Total cycles:/ {print $3; exit}' || true)
    [ "${cycles:-0}" -ge 1 ] 2>/dev/null && break
    sleep 0.5
  done
  [ "${cycles:-0}" -ge 1 ] 2>/dev/null ||
    echo "$me: note: slurmctld's scheduler has not run yet after 15 s (sdiag); the first job may wait" >&2

  echo "export SLURM_CONF=$SLURM_CONF" >"$dir/env"
  trap - EXIT
  echo "$me: cluster up under $dir: node $host idle, slurmctld on port $ctld_port, slurmd on $slurmd_port"
  echo "$me: for the client commands, run: source $dir/env"
}

if [ "$action" = start ]; then
  start_cluster
else
  # Resolve DIR the way start did, so the command lines match; a missing DIR has nothing.
  [ -d "$dir" ] && dir=$(cd "$dir" && pwd -P)
  stop_cluster
fi
