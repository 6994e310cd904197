#!/usr/bin/python3
"""A full disk in the middle of a run: the coordinator's writes fail (RLIMIT_FSIZE with SIGXFSZ
ignored, so every write beyond the limit fails with EFBIG as on a full disk). It must stop with one
clear error line naming the file, leave the previous checkpoint intact, and `--resume` with the
space back must finish to the mesh of an undisturbed run, byte for byte.

  full_disk_test.py --manisweep BIN --workdir DIR
"""
import filecmp
import os
import subprocess
import sys

from run_helpers import (HEARTBEAT, SWEEP, argument_parser, free_port, fresh_workdir, make_scene,
                         start_worker)


def main():
    parser = argument_parser(__doc__)
    args = parser.parse_args()
    ms, work = args.manisweep, args.workdir
    log = fresh_workdir(work)
    scene = make_scene(ms, work, log)
    iterations = ["--max-iterations", "6"]
    subprocess.run([ms, "reconstruct", "--input", scene, "--output", os.path.join(work, "undisturbed"),
                    "--workers", "2", "--no-refine"] + iterations + SWEEP, check=True, stdout=log,
                   stderr=log)
    # Limits between the first checkpoint's size and the last one's, so that different writes
    # fail: an early or late run.h5, a mesh, the summary.
    final_size = os.path.getsize(os.path.join(work, "undisturbed", "run.h5"))
    all_ok = True
    for fraction in (0.35, 0.6, 0.85, 0.97):
        limit_kb = max(1, int(final_size * fraction) // 1024)
        all_ok = run_with_limit(ms, work, log, scene, iterations, limit_kb, f"full{fraction}") and all_ok
    return 0 if all_ok else 1


def run_with_limit(ms, work, log, scene, iterations, limit_kb, name):
    out = os.path.join(work, name)
    port = free_port()
    coordinator = [ms, "coordinator", "--input", scene, "--bind", f"tcp://127.0.0.1:{port}",
                   "--output", out, "--resume"] + HEARTBEAT
    coordinator += iterations + SWEEP

    def start_workers(tag):
        return [start_worker(ms, port, f"{tag}{i}", work, log) for i in range(2)]

    def wait_all(workers):
        for w in workers:
            try:
                w.wait(timeout=30)
            except subprocess.TimeoutExpired:
                w.kill()

    workers = start_workers("full")
    limited = subprocess.run(["bash", "-c", f"trap '' XFSZ; ulimit -f {limit_kb}; exec \"$@\"", "-"]
                             + coordinator, capture_output=True, text=True)
    wait_all(workers)  # told to shut down by the failing coordinator
    errors = [line for line in limited.stderr.splitlines() if "error" in line]
    print(f"limit {limit_kb} KiB: exit {limited.returncode}; {errors[0][:160] if errors else 'no error'}")
    ok = True
    if limited.returncode == 0:
        print("   (the run fit within the limit)")
    elif limited.returncode != 2 or len(errors) != 1 or out not in errors[0]:
        print("   FAIL: expected exit 2 and one error line naming a file in the output")
        ok = False
    leftovers = [f for f in os.listdir(out) if ".tmp-" in f]
    if leftovers:
        print(f"   FAIL: temporary files left behind: {leftovers}")
        ok = False
    workers = start_workers("space")
    resumed = subprocess.run(coordinator, stdout=log, stderr=log)
    wait_all(workers)
    if resumed.returncode != 0:
        print(f"   FAIL: the resumed run exited with {resumed.returncode}")
        return False
    same = filecmp.cmp(os.path.join(work, "undisturbed", "final.ply"), os.path.join(out, "final.ply"),
                       shallow=False)
    print(("   ok" if same else "   FAIL") + ": after --resume final.ply is " +
          ("byte-identical to" if same else "different from") + " the undisturbed run's")
    return ok and same

if __name__ == "__main__":
    sys.exit(main())
