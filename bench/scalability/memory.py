#!/usr/bin/python3
"""The coordinator's memory and job messages on large scenes (docs/design/scalability.md, "Memory").

For each SCENE (VIEWS:POINTS), synthesises a street with that many cameras and sparse points
(`manisweep synth city --no-images`, reused when OUT/city_VIEWS_POINTS holds it already), then
starts the real coordinator on it (`coordinator --no-images`) and waits until its first
iteration starts: the scene, the initial manifold and the iteration's mesh are then in memory.
Then it lets the coordinator build and hand out every job of that iteration: WORKERS replay
workers (`worker --kernel replay`) take them from it and refuse each at once (they replay the
coordinator's own first checkpoint, which has no iteration 1: a kernel refusal, after which the
camera gives no points), so the coordinator builds all its jobs at the pace of a fast cluster
and logs their sizes. Jobs are built as they are handed out and freed once sent, so only the
jobs in flight are ever held.

Reads the coordinator's resident memory from /proc (at the start of the iteration, and the
largest sample while the jobs go out), its own `memory after ...` log lines (heap in use after
each step) and the jobs line (total and largest job message), kills it and writes
OUT/memory.json and OUT/memory.csv.

  memory.py --manisweep build/app/manisweep --out /tmp/memory [--scenes 4096:1000000]
            [--workers 4]

Bytes per point are divided by the scene's sparse points (the coordinator's own count after
merging is in the log).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import time

from bench_common import write_figures

MIB = 1024.0 * 1024.0


def status_bytes(pid, field):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    return 0


def synthesise(args, views, points):
    folder = os.path.join(args.out, f"city_{views}_{points}")
    scene = os.path.join(folder, "scene.h5")
    if not os.path.exists(scene):
        cmd = [args.manisweep, "synth", "city", "--views", str(views), "--points", str(points),
               "--no-images", "--output", folder]
        print("+ " + " ".join(cmd), flush=True)
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return scene


def measure(args, views, points):
    scene = synthesise(args, views, points)
    out = os.path.join(args.out, f"coordinator_{views}_{points}")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    log_path = os.path.join(out, "coordinator.log")
    start = time.monotonic()
    def polls_until(pattern, process):
        """Yields every half second until a line of the log matches `pattern`."""
        while True:
            time.sleep(0.5)
            if process.poll() is not None:
                sys.exit(f"the coordinator exited with {process.returncode} (see {log_path})")
            with open(log_path) as f:
                if any(re.search(pattern, line) for line in f):
                    return
            yield

    with open(log_path, "w") as log:
        coordinator = subprocess.Popen(
            [args.manisweep, "coordinator", "--input", scene, "--output", out, "--no-images",
             "--bind", "tcp://127.0.0.1:*", "--progress-interval", "60"],
            stdout=log, stderr=subprocess.STDOUT)
        for _ in polls_until(r"iteration 1/\d+: \d+ jobs", coordinator):
            pass
        row = {"views": views, "points": points,
               "resident_at_start_mib": status_bytes(coordinator.pid, "VmRSS") / MIB,
               "peak_before_jobs_mib": status_bytes(coordinator.pid, "VmHWM") / MIB,
               "seconds_to_first_iteration": time.monotonic() - start}
        with open(log_path) as f:
            endpoint = re.search(r"coordinator listening on (\S+)", f.read()).group(1)
        recording = os.path.join(out, "iteration0.h5")
        shutil.copyfile(os.path.join(out, "run.h5"), recording)
        workers = [subprocess.Popen(
            [args.manisweep, "worker", "--connect", endpoint, "--id", f"m{i}", "--kernel",
             "replay", "--replay.run", recording, "--replay.delay-s", "0", "--give-up-after",
             "60"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            for i in range(args.workers)]
        resident = row["resident_at_start_mib"]
        for _ in polls_until(r"iteration 1: \d+ jobs swept", coordinator):
            resident = max(resident, status_bytes(coordinator.pid, "VmRSS") / MIB)
        row["resident_while_sweeping_mib"] = resident
        row["peak_mib"] = status_bytes(coordinator.pid, "VmHWM") / MIB
        coordinator.kill()
        coordinator.wait(timeout=120)
        for w in workers:
            w.kill()
            w.wait()
    with open(log_path) as f:
        text = f.read()
    for step in ["the scene", "the initial manifold", "the initial meshes"]:
        m = re.search(rf"memory after {step}: (\d+) MiB in use, (\d+) MiB resident", text)
        key = step.replace("the ", "").replace(" ", "_")
        row[f"in_use_after_{key}_mib"] = float(m.group(1)) if m else None
    m = re.search(r"memory at the start of iteration 1: (\d+) MiB in use", text)
    row["in_use_at_start_mib"] = float(m.group(1)) if m else None
    m = re.search(r"manifold about (\d+) MiB", text)
    row["manifold_estimate_mib"] = float(m.group(1)) if m else None
    m = re.search(r"iteration 1: (\d+) jobs swept \((\d+) visible faces, ([\d.]+) MiB, the "
                  r"largest (\d+) KiB", text)
    if not m:
        sys.exit(f"no jobs line in {log_path}")
    row["jobs"] = int(m.group(1))
    row["job_mib_total"] = float(m.group(3))
    row["job_kib_mean"] = float(m.group(3)) * 1024 / max(int(m.group(1)), 1)
    row["job_kib_max"] = float(m.group(4))
    m = re.search(r"initial mesh: (\d+) vertices", text)
    row["mesh_vertices"] = int(m.group(1)) if m else None
    row["bytes_per_point_resident"] = row["resident_while_sweeping_mib"] * MIB / points
    row["bytes_per_point_peak"] = row["peak_mib"] * MIB / points
    print(f"{views} cameras, {points} points: resident while the jobs go out "
          f"{row['resident_while_sweeping_mib']:.0f} MiB "
          f"({row['bytes_per_point_resident']:.0f} B/point), peak {row['peak_mib']:.0f} MiB "
          f"({row['bytes_per_point_peak']:.0f} B/point); jobs {row['jobs']}, "
          f"{row['job_kib_mean']:.0f} KiB mean, {row['job_kib_max']:.0f} KiB largest", flush=True)
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--manisweep", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--scenes", nargs="+", default=["4096:1000000"],
                        help="VIEWS:POINTS for each scene (default 4096:1000000)")
    parser.add_argument("--workers", type=int, default=4,
                        help="replay workers that take the jobs (default 4)")
    args = parser.parse_args()
    args.manisweep = os.path.abspath(args.manisweep)
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for spec in args.scenes:
        try:
            views, points = (int(x) for x in spec.split(":"))
        except ValueError:
            sys.exit(f"--scenes: {spec} is not VIEWS:POINTS")
        rows.append(measure(args, views, points))
    write_figures(args.out, "memory", {"scenes": args.scenes}, rows)
    print(f"wrote {args.out}/memory.json, memory.csv")


if __name__ == "__main__":
    main()
