#!/usr/bin/python3
"""Chaos run: a coordinator and 3 workers as real processes on loopback while a seeded driver
SIGKILLs workers (starting a new one each time) and the coordinator (restarting it with --resume)
at random moments: during kernels, image fetches, insertion, job building, checkpoint writes.
The final mesh must be byte-identical to an undisturbed `reconstruct` of the same scene and
options: no result lost or inserted twice. Prints the kills survived.

  chaos_test.py --manisweep BIN --workdir DIR [--seed 1] [--kills 20] [--iterations 4]
  [--option=--manifold.insertion=rebuild ...]
"""
import filecmp
import os
import random
import signal
import subprocess
import sys
import time

from run_helpers import (HEARTBEAT, SWEEP, argument_parser, free_port, fresh_workdir, make_scene,
                         start_worker)


def main():
    parser = argument_parser(__doc__)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--kills", type=int, default=20, help="kills in all (workers and coordinator)")
    parser.add_argument("--iterations", type=int, default=4)
    parser.add_argument("--time-limit", type=float, default=240)
    parser.add_argument("--option", action="append", default=[],
                        help="one more option for both runs, e.g. --option=--manifold.insertion=rebuild")
    args = parser.parse_args()
    ms, work = args.manisweep, args.workdir
    logs = fresh_workdir(work)

    def run(cmd):
        subprocess.run(cmd, check=True, stdout=logs, stderr=subprocess.STDOUT)

    scene = make_scene(ms, work, logs)
    run_options = ["--max-iterations", str(args.iterations)] + args.option + SWEEP
    run([ms, "reconstruct", "--input", scene, "--output", os.path.join(work, "undisturbed"),
         "--workers", "2", "--no-refine"] + run_options)

    port = free_port()
    out = os.path.join(work, "chaos")
    coordinator_cmd = [ms, "coordinator", "--input", scene, "--bind", f"tcp://127.0.0.1:{port}",
                       "--output", out, "--resume"] + HEARTBEAT + ["--lease", "60", "--progress-interval", "1",
                       # The driver kills workers mid-job on purpose: a job that loses 5 of them
                       # is not the poison job --max-attempts is there to stop.
                       "--max-attempts", "1000"] + run_options
    next_worker = [0]

    def new_worker():
        next_worker[0] += 1
        return start_worker(ms, port, f"w{next_worker[0]}", work, logs)

    def start_coordinator():
        return subprocess.Popen(coordinator_cmd, stdout=logs, stderr=subprocess.STDOUT)

    rng = random.Random(args.seed)
    coordinator = start_coordinator()
    workers = [new_worker() for _ in range(3)]
    killed = {"worker": 0, "coordinator": 0}
    deadline = time.time() + args.time_limit
    status = None
    while time.time() < deadline:
        time.sleep(rng.uniform(0.05, 0.5))
        status = coordinator.poll()
        if status is not None:
            break
        if killed["worker"] + killed["coordinator"] >= args.kills:
            continue
        if rng.random() < 0.3:
            coordinator.send_signal(signal.SIGKILL)
            coordinator.wait()
            killed["coordinator"] += 1
            coordinator = start_coordinator()
        else:
            victim = rng.randrange(len(workers))
            workers[victim].send_signal(signal.SIGKILL)
            workers[victim].wait()
            killed["worker"] += 1
            workers[victim] = new_worker()
    if status is None:
        coordinator.kill()
        print(f"FAIL: the run did not finish within {args.time_limit} s")
        return 1
    for w in workers:
        try:
            w.wait(timeout=20)
        except subprocess.TimeoutExpired:
            w.kill()
    print(f"chaos run (seed {args.seed}): {killed['worker']} workers and {killed['coordinator']} "
          f"coordinators killed with SIGKILL; coordinator exit status {status}")
    if status != 0:
        print(f"FAIL: the last coordinator exited with {status} (see {logs.name})")
        return 1
    same = filecmp.cmp(os.path.join(work, "undisturbed", "final.ply"),
                       os.path.join(out, "final.ply"), shallow=False)
    print(("ok" if same else "FAIL") + ": final.ply " +
          ("byte-identical to" if same else "differs from") + " the undisturbed run's")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
