#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for tests and trials of campaign scripts:
#   scripts/local-slurm.sh start DIR   # munged, slurmctld and slurmd on localhost; prints SLURM_CONF
#   scripts/local-slurm.sh stop DIR
# Everything lives in DIR (config, state, logs); needs root (slurmd runs jobs as their user) and
# Debian's slurm-wlm and munge (scripts/install-deps.sh). Not for production clusters.
set -euo pipefail
cmd=${1:?usage: local-slurm.sh start|stop DIR}
dir=$(realpath -m "${2:?usage: local-slurm.sh start|stop DIR}")
host=$(hostname -s)
conf="$dir/slurm.conf"

stop() {
  # slurmctld's helper (slurmscriptd) is its child: remember it before the parent goes.
  helpers=""
  if [ -f "$dir/slurmctld.pid" ]; then helpers=$(pgrep -P "$(cat "$dir/slurmctld.pid")" || true); fi
  for pidfile in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munged.pid"; do
    if [ -f "$pidfile" ]; then
      pid=$(cat "$pidfile")
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 1 50); do  # up to 5 s for a clean exit, then no more waiting
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
      done
      kill -9 "$pid" 2>/dev/null || true
      rm -f "$pidfile"
    fi
  done
  for pid in $helpers; do kill -9 "$pid" 2>/dev/null || true; done
}

if [ "$cmd" = stop ]; then
  stop
  exit 0
fi
[ "$cmd" = start ] || { echo "local-slurm.sh: unknown command '$cmd'; expected start or stop" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "local-slurm.sh: needs root (slurmd)" >&2; exit 1; }
for b in munged slurmctld slurmd sinfo; do
  command -v "$b" >/dev/null || { echo "local-slurm.sh: $b not found; run scripts/install-deps.sh" >&2; exit 1; }
done

mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
chmod 0755 "$dir"  # munged runs as user munge and must reach its folder (and DIR's parents must let it)
chown munge:munge "$dir/munge" && chmod 0700 "$dir/munge"
key="$dir/munge/munge.key"
if [ ! -f "$key" ]; then
  dd if=/dev/urandom bs=1 count=1024 of="$key" status=none
  chown munge:munge "$key" && chmod 0400 "$key"
fi
socket="$dir/munge/munge.socket"
runuser -u munge -- munged --key-file="$key" --socket="$socket" --pid-file="$dir/munge/munged.pid" \
  --log-file="$dir/munge/munged.log" --seed-file="$dir/munge/munged.seed" --force
cp "$dir/munge/munged.pid" "$dir/munged.pid"

cpus=$(nproc)
cat > "$conf" <<CONF
ClusterName=rotorguard-local
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
NodeName=$host CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$conf"
slurmctld -f "$conf"
slurmd -f "$conf"
for _ in $(seq 1 100); do
  if sinfo -h -o %t 2>/dev/null | grep -q idle; then
    echo "SLURM_CONF=$conf"
    exit 0
  fi
  sleep 0.2
done
echo "local-slurm.sh: the node did not come up; see $dir/slurmctld.log and $dir/slurmd.log" >&2
stop
exit 1
