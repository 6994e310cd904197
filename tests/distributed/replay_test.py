#!/usr/bin/python3
"""Replaying workers drive the real coordinator through a recorded run: a `reconstruct` of the
small pyramid is recorded, then a coordinator started with --no-images on the same scene and
options is served by 3 workers with --kernel replay (no image read anywhere). The replayed run
must insert exactly the recorded batches: final.ply byte-identical, the same points per
iteration. A sweeping worker handed a job without images refuses it by name. This is what the
capacity benchmark (bench/scalability/capacity.py) rests on.

  replay_test.py --manisweep BIN --workdir DIR
"""
import filecmp
import json
import os
import subprocess
import sys

from run_helpers import (HEARTBEAT, SWEEP, argument_parser, free_port, fresh_workdir, make_scene,
                         start_worker)

ITERATIONS = ["--max-iterations", "4"]


def main():
    parser = argument_parser(__doc__)
    args = parser.parse_args()
    ms, work = args.manisweep, args.workdir
    logs = fresh_workdir(work)
    scene = make_scene(ms, work, logs)
    recorded = os.path.join(work, "recorded")
    subprocess.run([ms, "reconstruct", "--input", scene, "--output", recorded, "--workers", "2", "--no-refine"]
                   + ITERATIONS + SWEEP, check=True, stdout=logs, stderr=subprocess.STDOUT)

    port = free_port()
    replayed = os.path.join(work, "replayed")
    coordinator = subprocess.Popen(
        [ms, "coordinator", "--input", scene, "--bind", f"tcp://127.0.0.1:{port}", "--output",
         replayed, "--no-images", "--lease", "60"] + HEARTBEAT + ITERATIONS + SWEEP,
        stdout=logs, stderr=subprocess.STDOUT)
    workers = [subprocess.Popen(
        [ms, "worker", "--connect", f"tcp://127.0.0.1:{port}", "--id", f"replay{i}",
         "--kernel", "replay", "--replay.run", os.path.join(recorded, "run.h5"),
         "--replay.delay-s", "0.02", "--give-up-after", "60"] + HEARTBEAT,
        stdout=logs, stderr=subprocess.STDOUT) for i in range(3)]
    status = coordinator.wait(timeout=240)
    for w in workers:
        w.wait(timeout=30)
    failures = []
    if status != 0 or any(w.returncode != 0 for w in workers):
        failures.append(f"exit statuses: coordinator {status}, workers "
                        f"{[w.returncode for w in workers]} (see {logs.name})")
    else:
        if not filecmp.cmp(os.path.join(recorded, "final.ply"),
                           os.path.join(replayed, "final.ply"), shallow=False):
            failures.append("final.ply of the replayed run differs from the recorded run's")

        def inserted(run):
            with open(os.path.join(run, "summary.json")) as f:
                return [(i["iteration"], i["points_found"], i["points_inserted"])
                        for i in json.load(f)["iterations"]]
        if inserted(recorded) != inserted(replayed):
            failures.append(f"points per iteration differ: recorded {inserted(recorded)}, "
                            f"replayed {inserted(replayed)}")
        elif sum(found for _, found, _ in inserted(recorded)[1:]) == 0:
            failures.append("the recorded run found no point: nothing was replayed")

    # A sweeping worker cannot take a job without images: it says why (the coordinator then
    # counts the job as bad).
    port = free_port()
    coordinator = subprocess.Popen(
        [ms, "coordinator", "--input", scene, "--bind", f"tcp://127.0.0.1:{port}", "--output",
         os.path.join(work, "sweeping"), "--no-images", "--max-iterations", "1"] + HEARTBEAT
        + SWEEP, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker_log = os.path.join(work, "sweeping_worker.log")
    with open(worker_log, "w") as log:
        worker = start_worker(ms, port, "sweeper", work, log)
        coordinator.wait(timeout=120)
        worker.wait(timeout=30)
    text = open(worker_log).read()
    if "the job carries no image (the coordinator runs with --no-images)" not in text:
        failures.append(f"a sweeping worker took a job without images (see {worker_log})")

    for f in failures:
        print("FAIL: " + f)
    if not failures:
        print("ok: 3 replaying workers reproduced the recorded run byte for byte with no image")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
