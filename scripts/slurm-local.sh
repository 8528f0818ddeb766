#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for the test of scripts/city.sbatch
# (python/tests/test_city_slurm.py): munged, slurmctld and slurmd with a configuration of their own in DIR
# (default /tmp/semslam-slurm), the node being this host with its cores and memory. Needs root or sudo, and
# the packages `scripts/install-deps.sh --slurm` adds.
#   scripts/slurm-local.sh start [DIR]   # then: export SLURM_CONF=DIR/slurm.conf (printed)
#   scripts/slurm-local.sh stop [DIR]
# A machine's own Slurm (/etc/slurm) is left alone: clients reach this one through SLURM_CONF.
set -euo pipefail
action="${1:-}"
dir="${2:-/tmp/semslam-slurm}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
conf="$dir/slurm.conf"

# The daemons started with this configuration, found by their command line (a daemon that failed to start may
# have written its pid file over that of the one running).
stop() {
  local pids
  pids=$(pgrep -f -x "(slurmctld|slurmd) -f $conf" || true)
  [ -n "$pids" ] || return 0
  # shellcheck disable=SC2086  # one pid per word
  "${sudo_cmd[@]}" kill $pids 2>/dev/null || true
  for _ in $(seq 60); do  # gone, and their ports free
    pgrep -f -x "(slurmctld|slurmd) -f $conf" >/dev/null || return 0
    sleep 0.5
  done
  echo "slurm-local: the daemons of $conf did not stop: $pids" >&2
  return 1
}

case "$action" in
  stop) stop; exit 0 ;;
  start) ;;
  *) echo "usage: scripts/slurm-local.sh start|stop [DIR]" >&2; exit 2 ;;
esac

for tool in munged slurmctld slurmd sinfo; do
  command -v "$tool" >/dev/null || PATH="$PATH:/usr/sbin"
  if ! command -v "$tool" >/dev/null; then
    echo "slurm-local: $tool not found (scripts/install-deps.sh --slurm)" >&2
    exit 1
  fi
done
stop
host=$(hostname -s)
cpus=$(nproc)
memory_mib=$(( $(awk '/^MemTotal:/ { print $2 }' /proc/meminfo) / 1024 * 9 / 10 ))
"${sudo_cmd[@]}" mkdir -p "$dir/state" "$dir/spool" "$dir/log"
# Every daemon as root (SlurmUser) on the loopback address (no name service needed), tasks tracked by their
# process tree and not bound (no cgroups needed), cores given out one by one so that a job's tasks share the
# node.
"${sudo_cmd[@]}" tee "$conf" >/dev/null <<EOF
ClusterName=semslam-local
SlurmctldHost=$host(127.0.0.1)
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
EOF

# munged with the key the munge package made; one already running (the machine's own) is used as it is.
if ! munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
  "${sudo_cmd[@]}" mkdir -p /run/munge
  "${sudo_cmd[@]}" chown munge:munge /run/munge
  "${sudo_cmd[@]}" runuser -u munge -- munged
fi
"${sudo_cmd[@]}" slurmctld -f "$conf"
"${sudo_cmd[@]}" slurmd -f "$conf"
for _ in $(seq 60); do
  if SLURM_CONF="$conf" sinfo --noheader --states=idle 2>/dev/null | grep -q .; then
    echo "slurm-local: node $host ($cpus cores) up; export SLURM_CONF=$conf"
    exit 0
  fi
  sleep 1
done
echo "slurm-local: the node did not come up; $dir/log holds the daemons' logs:" >&2
tail -n 20 "$dir"/log/*.log >&2 || true
exit 1
