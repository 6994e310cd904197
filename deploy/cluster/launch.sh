#!/usr/bin/env bash
# manisweep on machines reachable by ssh (no batch system): the coordinator runs here, sweep
# workers on every listed host. Hosts need the same manisweep version (same protocol version);
# they do not need this machine's files: images are fetched by content hash when a worker cannot
# read them at the coordinator's path.
#
#   deploy/cluster/launch.sh --scene SCENE --output DIR --hosts "node1 node2" \
#       [--workers-per-host N] [--threads T] [--port P] [--manisweep PATH] \
#       [--remote-manisweep PATH] [--keys DIR | --insecure] [-- coordinator options...]
#
# --keys DIR: CURVE keys as for deploy/slurm/manisweep.sbatch (coordinator.key_secret,
# coordinator.key, worker.key_secret, allowed/worker.key); by default .curve-keys in the --output
# directory, made on its first run and kept for resumes. The worker keys are copied to the hosts
# with scp. --insecure: no CURVE (any process reaching the port can send results).
# Worker logs: ~/manisweep-worker-<port>-<i>.log on each host.
# Ctrl-C stops the coordinator (the checkpoint stays valid: rerun with the same arguments to
# resume, --resume is always passed) and the workers (they also give up on their own).
set -euo pipefail

scene="" out="" hosts="" per_host=1 threads=0 port=5555
manisweep=${MANISWEEP:-manisweep}
remote_manisweep=""
keys="" insecure=""
while [ $# -gt 0 ]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --output) out=$2; shift 2 ;;
    --hosts) hosts=$2; shift 2 ;;
    --workers-per-host) per_host=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --port) port=$2; shift 2 ;;
    --manisweep) manisweep=$2; shift 2 ;;
    --remote-manisweep) remote_manisweep=$2; shift 2 ;;
    --keys) keys=$2; shift 2 ;;
    --insecure) insecure=1; shift ;;
    --) shift; break ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "launch.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
if [ -z "$scene" ] || [ -z "$out" ] || [ -z "$hosts" ]; then
  echo "launch.sh: --scene, --output and --hosts are required (see --help)" >&2
  exit 2
fi
remote_manisweep=${remote_manisweep:-$manisweep}
here=$(hostname -f 2>/dev/null || hostname)

coordinator_security=(--insecure)
worker_security=""
if [ -z "$keys" ] && [ -z "$insecure" ]; then
  # CURVE by default: the coordinator listens on the network.
  keys="$out/.curve-keys"
  if [ ! -f "$keys/coordinator.key_secret" ]; then
    mkdir -p "$keys/allowed"
    chmod 700 "$keys"
    "$manisweep" keygen --output "$keys/coordinator" >/dev/null
    "$manisweep" keygen --output "$keys/worker" >/dev/null
    cp "$keys/worker.key" "$keys/allowed/"
  fi
fi
if [ -n "$keys" ]; then
  coordinator_security=(--curve-secret-key "$keys/coordinator.key_secret"
                        --curve-public-keys "$keys/allowed")
  worker_security="--curve-server-key ~/.manisweep-keys/coordinator.key --curve-secret-key ~/.manisweep-keys/worker.key_secret"
  for host in $hosts; do
    ssh "$host" 'mkdir -p ~/.manisweep-keys && chmod 700 ~/.manisweep-keys'
    scp -q "$keys/coordinator.key" "$keys/worker.key_secret" "$host:.manisweep-keys/"
  done
fi

"$manisweep" coordinator --input "$scene" --output "$out" --bind "tcp://*:$port" --resume \
    "${coordinator_security[@]}" "$@" &
coordinator=$!

started=()
for host in $hosts; do
  for i in $(seq 1 "$per_host"); do
    log="manisweep-worker-$port-$i.log"
    # nohup + background on the remote side: ssh returns at once; the pid comes back on stdout.
    pid=$(ssh -n "$host" "nohup $remote_manisweep worker --connect tcp://$here:$port \
        --id $host-$i --threads $threads --give-up-after 120 $worker_security \
        > $log 2>&1 < /dev/null & echo \$!")
    started+=("$host:$pid")
    echo "launch.sh: worker $host-$i (pid $pid, log ~/$log on $host)"
  done
done

stop_workers() {
  for entry in "${started[@]}"; do
    ssh -n "${entry%%:*}" "kill ${entry##*:} 2>/dev/null || true" || true
  done
}
trap 'kill -TERM $coordinator 2>/dev/null; wait $coordinator; stop_workers; exit 130' INT TERM

status=0
wait $coordinator || status=$?
# Workers have been told to shut down; make sure none lingers (e.g. after a coordinator error).
sleep 2
stop_workers
exit $status
