#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for the test of scripts/city.sbatch
# (python/tests/test_city_slurm.py): munged, slurmctld and slurmd with a configuration of their own in DIR
# (default /tmp/semslam-slurm), the node being this host with its cores and memory. Needs root or sudo, and
# the packages `scripts/install-deps.sh --slurm` adds.
#   scripts/slurm-local.sh start [DIR]   # then: export SLURM_CONF=DIR/slurm.conf (printed)
#   scripts/slurm-local.sh stop [DIR]
# A machine's own Slurm (/etc/slurm) is left alone: clients reach this one through SLURM_CONF, and its daemons
# listen on ports of their own (the first free ones from 6917 and 6918, not Slurm's 6817 and 6818). munged is
# started only when none answers, and then stopped by `stop`.
set -euo pipefail
usage="usage: scripts/slurm-local.sh start|stop [DIR]"
action="${1:-}"
if [ $# -gt 2 ]; then
  echo "$usage" >&2
  exit 2
fi
# Absolute: the daemons do not run in the caller's folder, and SLURM_CONF must hold from anywhere.
dir="$(realpath -m -- "${2:-/tmp/semslam-slurm}")"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
conf="$dir/slurm.conf"
# The configuration's path as a literal in pgrep's extended regular expression.
# shellcheck disable=SC2001  # one substitution over a whole class of characters
conf_pattern="$(sed 's/[][\.*^$+?(){}|]/\\&/g' <<<"$conf")"
munged_mark="$dir/munged.started"

# The daemons started with this configuration, found by their command line (a daemon that failed to start may
# have written its pid file over that of the one running).
daemons() {
  pgrep -f -x "(slurmctld|slurmd) -f $conf_pattern"
}

stop() {
  local pids
  pids=$(daemons || true)
  if [ -n "$pids" ]; then
    # shellcheck disable=SC2086  # one pid per word
    "${sudo_cmd[@]}" kill $pids 2>/dev/null || true
    local gone=
    for _ in $(seq 60); do  # gone, and their ports free
      if ! daemons >/dev/null; then gone=1; break; fi
      sleep 0.5
    done
    if [ -z "$gone" ]; then
      echo "slurm-local: the daemons of $conf did not stop: $pids" >&2
      return 1
    fi
  fi
  # The munged `start` started (none answered then); a machine's own is left alone.
  if [ -e "$munged_mark" ]; then
    "${sudo_cmd[@]}" runuser -u munge -- munged --stop >/dev/null 2>&1 || true
    "${sudo_cmd[@]}" rm -f "$munged_mark"
  fi
}

# The first port from $1 on that nothing listens on (a connection to it is refused).
free_port() {
  local port=$1
  while (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; do
    port=$((port + 1))
  done
  echo "$port"
}

case "$action" in
  stop) stop; exit 0 ;;
  start) ;;
  *) echo "$usage" >&2; exit 2 ;;
esac

# slurm.conf has no quoting: a value ends at a space.
if [[ $dir =~ [[:space:]#] ]]; then
  echo "slurm-local: DIR must not hold a space or '#' (slurm.conf cannot quote them): $dir" >&2
  exit 2
fi
for tool in munged slurmctld slurmd sinfo; do
  command -v "$tool" >/dev/null || PATH="$PATH:/usr/sbin"
  if ! command -v "$tool" >/dev/null; then
    echo "slurm-local: $tool not found (scripts/install-deps.sh --slurm)" >&2
    exit 1
  fi
done
stop
# Ctrl-C while starting: nothing is left half up.
trap 'trap "" INT TERM; echo "slurm-local: interrupted; stopping what was started" >&2; stop || true; exit 130' INT
trap 'trap "" INT TERM; stop || true; exit 143' TERM
host=$(hostname -s)
cpus=$(nproc)
memory_mib=$(( $(awk '/^MemTotal:/ { print $2 }' /proc/meminfo) / 1024 * 9 / 10 ))
ctld_port=$(free_port 6917)
slurmd_port=$(free_port $((ctld_port + 1)))
"${sudo_cmd[@]}" mkdir -p "$dir/state" "$dir/spool" "$dir/log"
# Every daemon as root (SlurmUser) on the loopback address (no name service needed), tasks tracked by their
# process tree and not bound (no cgroups needed), cores given out one by one so that a job's tasks share the
# node.
"${sudo_cmd[@]}" tee "$conf" >/dev/null <<EOC
ClusterName=semslam-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
AuthType=auth/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory_mib State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOC

# munged with the key the munge package made; one already running (the machine's own) is used as it is.
if ! munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
  "${sudo_cmd[@]}" mkdir -p /run/munge
  "${sudo_cmd[@]}" chown munge:munge /run/munge
  "${sudo_cmd[@]}" runuser -u munge -- munged
  "${sudo_cmd[@]}" touch "$munged_mark"
fi
"${sudo_cmd[@]}" slurmctld -f "$conf"
"${sudo_cmd[@]}" slurmd -f "$conf"
# Up when this cluster's partition lists this node idle; given up at once when a daemon has ended.
for _ in $(seq 60); do
  if SLURM_CONF="$conf" sinfo --noheader --partition=local --nodes="$host" --states=idle 2>/dev/null | grep -q .
  then
    echo "slurm-local: node $host ($cpus cores) up (ports $ctld_port, $slurmd_port); export SLURM_CONF=$conf"
    exit 0
  fi
  if [ "$(daemons | wc -l)" -lt 2 ]; then
    echo "slurm-local: a daemon ended while starting" >&2
    break
  fi
  sleep 1
done
echo "slurm-local: the node did not come up; $dir/log holds the daemons' logs:" >&2
tail -n 20 "$dir"/log/*.log >&2 || true
stop || true  # nothing left half up
exit 1
