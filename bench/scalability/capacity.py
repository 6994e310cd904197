#!/usr/bin/python3
"""The coordinator's capacity without the compute (docs/design/scalability.md, "Capacity").

One command: synthesises a city (`manisweep synth city`, small images), records a real run of
it (`reconstruct`, sweeping workers), then drives the real coordinator through the same run
again and again with W = 1 ... 64 workers that replay the recorded points after a fixed delay
(`worker --kernel replay`, `coordinator --no-images`): the coordinator at GPU-cluster speed on a
small machine. Every replayed run must reproduce the recorded final.ply byte for byte, or the
figures are refused.

Writes OUT/capacity.json and OUT/capacity.csv (one row per worker count and iteration: jobs,
job message bytes, the coordinator's serial steps, sweep time, jobs/s, efficiency, coordinator
peak RSS) and OUT/capacity.png.

  capacity.py --manisweep build/app/manisweep --out /tmp/capacity [--views 1024]
              [--workers 1 2 4 8 16 32 64] [--delay 0.3] [--iterations 3]

Efficiency of an iteration with W workers = (jobs x delay / W) / iteration wall time: 1 when
every worker is busy the whole iteration, lower for the coordinator's serial steps (the rest of
the insertion after the last result, extracting the surface) and for the tail of the sweep.
Jobs are built while the sweep runs and the checkpoint is written during the next one: their
seconds are reported apart, and their cost shows where they slow what runs beside them.
"""
import filecmp
import json
import os
import shutil
import subprocess
import sys
import time

from bench_common import argument_parser, pyplot, free_port, run, write_figures

# The coordinator's steps while no job is out: the rest of the insertion and the surface. Jobs
# are built while the sweep runs (seconds_jobs) and the checkpoint is written during the next
# sweep (seconds_checkpoint), so neither is among them; both are reported.
SERIAL = ["seconds_insert", "seconds_extract"]
OVERLAPPED = ["seconds_jobs", "seconds_checkpoint"]


def peak_rss_kib(time_file):
    with open(time_file) as f:
        return int(f.read().strip().splitlines()[-1])


def replay(args, scene, recorded, workers, log):
    """One replayed run with `workers` workers; returns its summary and the coordinator's RSS."""
    out = os.path.join(args.out, f"replay_w{workers}")
    shutil.rmtree(out, ignore_errors=True)
    port = free_port()
    rss_file = os.path.join(args.out, f"replay_w{workers}.rss")
    coordinator = subprocess.Popen(
        ["/usr/bin/time", "-f", "%M", "-o", rss_file, args.manisweep, "coordinator", "--input",
         scene, "--output", out, "--bind", f"tcp://127.0.0.1:{port}", "--no-images",
         "--max-iterations", str(args.iterations), "--lease", "600",
         "--progress-interval", "10"] + args.sweep, stdout=log, stderr=subprocess.STDOUT)
    procs = [subprocess.Popen(
        [args.manisweep, "worker", "--connect", f"tcp://127.0.0.1:{port}", "--id", f"r{i}",
         "--kernel", "replay", "--replay.run", os.path.join(recorded, "run.h5"),
         "--replay.delay-s", str(args.delay), "--give-up-after", "120"],
        stdout=subprocess.DEVNULL, stderr=log) for i in range(workers)]
    while coordinator.poll() is None:
        time.sleep(0.5)
        if all(p.poll() not in (None, 0) for p in procs):
            coordinator.kill()
            sys.exit(f"every replaying worker failed (see {log.name})")
    status = coordinator.returncode
    for p in procs:
        try:
            p.wait(timeout=60)
        except subprocess.TimeoutExpired:
            p.kill()
    if status != 0:
        sys.exit(f"the coordinator with {workers} replaying workers exited with {status}")
    if not filecmp.cmp(os.path.join(recorded, "final.ply"), os.path.join(out, "final.ply"),
                       shallow=False):
        sys.exit(f"the run replayed by {workers} workers differs from the recorded one: the "
                 "replay is not faithful, its figures would not be the coordinator's")
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f), peak_rss_kib(rss_file)


def rows_of(workers, delay, summary, rss_kib):
    rows = []
    for it in summary["iterations"][1:]:
        serial = sum(it[k] for k in SERIAL)
        total = it["seconds_sweep"] + serial  # first job out -> the next iteration's first
        ideal = it["jobs"] * delay / workers
        rows.append({
            "workers": workers, "iteration": it["iteration"], "jobs": it["jobs"],
            "points_found": it["points_found"], "points_inserted": it["points_inserted"],
            "vertices": it["vertices"], "job_bytes": it.get("job_bytes", 0),
            "job_max_bytes": it.get("job_max_bytes", 0),
            **{k: it[k] for k in SERIAL + OVERLAPPED + ["seconds_sweep"]},
            "seconds_iteration": total, "seconds_serial": serial,
            "serial_fraction": serial / total, "jobs_per_s": it["jobs"] / it["seconds_sweep"],
            "efficiency": ideal / total, "coordinator_peak_rss_mib": rss_kib / 1024})
    return rows


def plot(rows, path, delay, views):
    plt = pyplot()
    counts = sorted({r["workers"] for r in rows})

    def mean(key, w):
        values = [r[key] for r in rows if r["workers"] == w]
        return sum(values) / len(values)
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    a.plot(counts, [mean("efficiency", w) for w in counts], "o-", label="efficiency")
    a.plot(counts, [mean("serial_fraction", w) for w in counts], "s--",
           label="coordinator serial share")
    a.axhline(0.85, color="grey", lw=0.5)
    a.axhline(0.70, color="grey", lw=0.5)
    a.set_xscale("log", base=2)
    a.set_xlabel("replaying workers")
    a.set_ylim(0, 1.05)
    a.set_title(f"city, {views} cameras, {delay} s per job")
    a.legend()
    bottom = [0.0] * len(counts)
    for key in SERIAL + ["seconds_sweep"]:
        values = [mean(key, w) for w in counts]
        b.bar([str(w) for w in counts], values, bottom=bottom, label=key[8:])
        bottom = [x + y for x, y in zip(bottom, values)]
    b.set_xlabel("replaying workers")
    b.set_ylabel("seconds per iteration (mean)")
    b.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    parser = argument_parser(__doc__)
    parser.add_argument("--views", type=int, default=1024)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2, 4, 8, 16, 32, 64])
    parser.add_argument("--delay", type=float, default=0.3, help="seconds per job (a GPU's)")
    parser.add_argument("--iterations", type=int, default=3)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=240)
    parser.add_argument("--plot-only", nargs="+", metavar="JSON",
                        help="merge these capacity.json files (one scene and delay) into "
                        "OUT/capacity.json and OUT/capacity.png; runs nothing")
    parser.add_argument("--recorded", help="the recorded run and its scene to reuse (default: "
                        "OUT/recorded, OUT/cityN, made when missing)")
    args = parser.parse_args()
    if args.plot_only:
        merged = None
        for path in args.plot_only:
            with open(path) as f:
                saved = json.load(f)
            if merged is None:
                merged = saved
                merged["commands"] = [saved["command"]]
            else:
                merged["rows"] += saved["rows"]
                merged["commands"] += saved.get("commands", [saved["command"]])
        merged["rows"].sort(key=lambda r: (r["workers"], r["iteration"]))
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "capacity.json"), "w") as f:
            json.dump(merged, f, indent=1)
        plot(merged["rows"], os.path.join(args.out, "capacity.png"), merged["delay_s"],
             merged["views"])
        return
    # Tiles and window scaled to the small images (the defaults are for megapixel photographs).
    args.sweep = ["--sweep.tile-size-px", "16", "--sweep.gaussian-sigma-px", "4"]
    os.makedirs(args.out, exist_ok=True)
    log = open(os.path.join(args.out, "capacity.log"), "a")
    base = os.path.dirname(os.path.abspath(args.recorded)) if args.recorded else args.out
    scene_dir = os.path.join(base, f"city{args.views}")
    scene = os.path.join(scene_dir, "scene.h5")
    if not os.path.exists(scene):
        run([args.manisweep, "synth", "city", "--views", str(args.views), "--width",
             str(args.width), "--height", str(args.height), "--supersampling", "1", "--output",
             scene_dir], log)
    recorded = args.recorded or os.path.join(args.out, "recorded")
    if not os.path.exists(os.path.join(recorded, "final.ply")):
        shutil.rmtree(recorded, ignore_errors=True)
        run([args.manisweep, "reconstruct", "--input", scene, "--output", recorded, "--workers",
             "2", "--max-iterations", str(args.iterations), "--no-refine"] + args.sweep, log)
    rows = []
    for w in args.workers:
        started = time.time()
        summary, rss = replay(args, scene, recorded, w, log)
        rows += rows_of(w, args.delay, summary, rss)
        mine = [r for r in rows if r["workers"] == w]
        print(f"{w:3d} workers: " + ", ".join(
            f"it {r['iteration']}: {r['seconds_iteration']:.1f} s, {r['jobs_per_s']:.1f} jobs/s, "
            f"efficiency {r['efficiency']:.2f}, serial {r['seconds_serial']:.2f} s"
            for r in mine) + f"; RSS {rss / 1024:.0f} MiB ({time.time() - started:.0f} s)",
            flush=True)
    write_figures(args.out, "capacity",
                  {"views": args.views, "delay_s": args.delay, "iterations": args.iterations,
                   "image_size": [args.width, args.height], "sweep": args.sweep}, rows)
    plot(rows, os.path.join(args.out, "capacity.png"), args.delay, args.views)
    print(f"wrote {args.out}/capacity.json, capacity.csv, capacity.png")


if __name__ == "__main__":
    main()
