#!/usr/bin/env bash
# A throw-away single-node Slurm cluster on this machine, to try manisweep.sbatch for real
# (docs/guides/cluster.md "Slurm"). Needs root (munged and slurmd run as root here),
# Debian's slurm-wlm and munge; touches nothing in /etc: state, logs, sockets and the config live
# in $DIR (default /tmp/manisweep-slurm). Ports 16817/16818.
#
#   deploy/slurm/local-test-cluster.sh start     # then: export SLURM_CONF=$DIR/slurm.conf
#   MANISWEEP=$PWD/build/app/manisweep sbatch --nodes=1 --ntasks-per-node=2 --cpus-per-task=1 \
#       deploy/slurm/manisweep.sbatch SCENE OUTPUT --max-iterations 3
#   deploy/slurm/local-test-cluster.sh stop
set -euo pipefail
DIR=${DIR:-/tmp/manisweep-slurm}
NODE=$(hostname -s)
CPUS=$(nproc)

stop() {
  for pidfile in "$DIR/slurmd.pid" "$DIR/slurmctld.pid" "$DIR/munge/munged.pid"; do
    if [ -f "$pidfile" ]; then
      pid=$(cat "$pidfile")
      kill "$pid" 2>/dev/null || true
      # Wait for it to go, so that a new cluster can bind the same ports right away.
      for _ in $(seq 1 100); do
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
      done
      rm -f "$pidfile"
    fi
  done
}

case "${1:-}" in
  start)
    [ "$(id -u)" -eq 0 ] || { echo "local-test-cluster.sh: run as root" >&2; exit 2; }
    [ -r /etc/munge/munge.key ] || { echo "local-test-cluster.sh: no /etc/munge/munge.key" >&2; exit 2; }
    mkdir -p "$DIR/munge" "$DIR/state" "$DIR/spool" "$DIR/log"
    chmod 700 "$DIR/munge"
    install -m 400 /etc/munge/munge.key "$DIR/munge/munge.key"
    munged --force --socket="$DIR/munge/munge.socket" --key-file="$DIR/munge/munge.key" \
        --pid-file="$DIR/munge/munged.pid" --log-file="$DIR/log/munged.log" \
        --seed-file="$DIR/munge/munge.seed"
    touch "$DIR/plugstack.conf"
    cat > "$DIR/slurm.conf" <<CONF
ClusterName=manisweeptest
SlurmctldHost=$NODE
SlurmUser=root
SlurmdUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$DIR/munge/munge.socket
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
PlugStackConfig=$DIR/plugstack.conf
NodeName=$NODE CPUs=$CPUS RealMemory=4000 State=UNKNOWN
PartitionName=debug Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
CONF
    slurmctld -f "$DIR/slurm.conf"
    slurmd -f "$DIR/slurm.conf"
    sleep 2
    SLURM_CONF="$DIR/slurm.conf" sinfo
    echo "export SLURM_CONF=$DIR/slurm.conf"
    ;;
  stop) stop ;;
  *) echo "usage: $0 start|stop" >&2; exit 2 ;;
esac
