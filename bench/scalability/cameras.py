#!/usr/bin/python3
"""Time per step against the number of cameras (the paper's Figure 9; docs/design/scalability.md).

One command: for each camera count N, a complete `manisweep reconstruct` (coordinator + sweeping
workers on this machine) of
  city:   `manisweep synth city --views N` (a street that grows with N, photo-textured when
          --texture-photos is given, optional image noise), or
  castle: the first N images (by name) of ../shared/data/castle-P30's COLMAP model, with the
          points seen by at least 2 of them,
then per iteration the seconds of every step (jobs, sweep, kernel, insert, extract, checkpoint),
vertices, points found/inserted, job message bytes, the coordinator's peak RSS (reconstruct's
own process, from summary.json) and the largest process's (GNU time: usually a worker, whose
decoded-image cache grows with the cameras it has swept).

Writes OUT/cameras.json, OUT/cameras.csv and OUT/cameras.png: seconds per iteration and per
camera against cameras for each step, with the least-squares line of the total and its R^2.

  cameras.py --manisweep build/app/manisweep --out /tmp/cameras --scene city
             [--cameras 16 32 64 128 256] [--iterations 3] [--workers 2] [--width 640 --height 480]
  cameras.py --manisweep build/app/manisweep --out /tmp/castle --scene castle
             --data ../shared/data [--cameras 5 10 15 20 25 30]
"""
import argparse
import json
import os
import shutil
import sys

from bench_common import argument_parser, pyplot, run, write_figures

STEPS = ["seconds_jobs", "seconds_sweep", "seconds_insert", "seconds_extract",
         "seconds_checkpoint"]
# An iteration's wall time: jobs are built and the previous checkpoint written while it sweeps.
ITERATION = ["seconds_sweep", "seconds_insert", "seconds_extract"]


def castle_subset(data, n, out):
    """The first n images of castle-P30's COLMAP text model and the points 2 of them see."""
    model = os.path.join(data, "castle-P30", "sparse")
    if not os.path.exists(os.path.join(model, "images.txt")):
        sys.exit(f"castle-P30's COLMAP text model is missing: {model}/images.txt")
    with open(os.path.join(model, "images.txt")) as f:
        lines = [l for l in f.read().splitlines() if not l.startswith("#")]
    images = [(lines[i], lines[i + 1]) for i in range(0, len(lines) - 1, 2)]
    images.sort(key=lambda pair: pair[0].split()[-1])
    kept = images[:n]
    ids = {int(header.split()[0]) for header, _ in kept}
    points = []
    with open(os.path.join(model, "points3D.txt")) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            fields = line.split()
            track = [(int(fields[i]), fields[i + 1]) for i in range(8, len(fields), 2)]
            track = [(i, k) for i, k in track if i in ids]
            if len({i for i, _ in track}) >= 2:
                points.append(" ".join(fields[:8] + [f"{i} {k}" for i, k in track]))
    kept_points = {int(p.split()[0]) for p in points}
    sparse = os.path.join(out, "sparse")
    os.makedirs(sparse, exist_ok=True)
    shutil.copy(os.path.join(model, "cameras.txt"), sparse)
    with open(os.path.join(sparse, "images.txt"), "w") as f:
        for header, observations in kept:
            values = observations.split()
            for i in range(2, len(values), 3):
                if int(values[i]) not in kept_points:
                    values[i] = "-1"
            f.write(header + "\n" + " ".join(values) + "\n")
    with open(os.path.join(sparse, "points3D.txt"), "w") as f:
        f.write("\n".join(points) + "\n")
    images_link = os.path.join(out, "images")
    if not os.path.exists(images_link):
        os.symlink(os.path.abspath(os.path.join(data, "castle-P30", "images")), images_link)
    return sparse


def fit(xs, ys):
    """Least-squares line y = a + b x and its R^2."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    a = my - b * mx
    ss_tot = sum((y - my) ** 2 for y in ys)
    ss_res = sum((y - a - b * x) ** 2 for x, y in zip(xs, ys))
    return a, b, 1 - ss_res / ss_tot if ss_tot > 0 else 1.0


def plot(per_n, line, path, title):
    plt = pyplot()
    ns = [p["cameras"] for p in per_n]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for step in STEPS + ["seconds_iteration"]:
        a.plot(ns, [p[step] for p in per_n], "o-", label=step[8:])
        b.plot(ns, [p[step] / p["cameras"] for p in per_n], "o-", label=step[8:])
    a.plot(ns, [line[0] + line[1] * n for n in ns], "k:",
           label=f"fit: {line[0]:.2f} + {line[1]:.3f} N, R² {line[2]:.3f}")
    a.set_xlabel("cameras")
    a.set_ylabel("seconds per iteration (mean)")
    a.set_title(title)
    a.legend(fontsize=8)
    b.set_xlabel("cameras")
    b.set_yscale("log")
    b.set_ylabel("seconds per iteration per camera (log)")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def table(saved):
    """The markdown table of a cameras.json: mean seconds per iteration and step, per size."""
    lines = ["| cameras | iteration | per camera | sweep | jobs | insert | extract | checkpoint | "
             "vertices | coordinator peak RSS |", "|---" * 10 + "|"]
    for p in saved["per_cameras"]:
        lines.append(f"| {p['cameras']} | {p['seconds_iteration']:.2f} | "
                     f"{p['seconds_iteration'] / p['cameras']:.3f} | {p['seconds_sweep']:.2f} | "
                     f"{p['seconds_jobs']:.3f} | {p['seconds_insert']:.3f} | "
                     f"{p['seconds_extract']:.3f} | {p['seconds_checkpoint']:.3f} | "
                     f"{p['vertices']:,} | {p['coordinator_peak_rss_mib']:.0f} MiB |")
    line = saved["fit_total_vs_cameras"]
    lines += ["", f"Fit {line['intercept_s']:.2f} + {line['slope_s_per_camera']:.3f} × cameras "
              f"seconds per iteration, R² = {line['r2']:.3f}, seconds per camera within "
              f"±{100 * saved['per_camera_spread']:.0f}% of their mean."]
    if "machine" in saved:
        lines += [f"{saved['machine']['cpu']}, {saved['machine']['cores']} cores, commit "
                  f"{saved['commit']}: `{saved['command']}`"]
    return "\n".join(lines)


def main():
    parser = argument_parser(__doc__)
    parser.add_argument("--scene", choices=["city", "castle"], default="city")
    parser.add_argument("--cameras", type=int, nargs="+")
    parser.add_argument("--iterations", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--width", type=int, default=640, help="city images")
    parser.add_argument("--height", type=int, default=480, help="city images")
    parser.add_argument("--image-noise", type=float, default=0, help="city, grey levels")
    parser.add_argument("--texture-photos", help="city: photographs mixed into the texture")
    parser.add_argument("--data", default="../shared/data", help="castle: the datasets folder")
    parser.add_argument("--table", action="store_true",
                        help="print the table of OUT/cameras.json and exit")
    parser.add_argument("--plot-only", action="store_true",
                        help="redraw OUT/cameras.png from OUT/cameras.json")
    parser.add_argument("--sweep", nargs=argparse.REMAINDER, default=[],
                        help="options passed to reconstruct (last): e.g. --sweep.tile-size-px 32")
    args = parser.parse_args()
    cameras = args.cameras or ([16, 32, 64, 128, 256] if args.scene == "city"
                               else [5, 10, 15, 20, 25, 30])
    if args.table:
        with open(os.path.join(args.out, "cameras.json")) as f:
            print(table(json.load(f)))
        return
    if args.plot_only:
        with open(os.path.join(args.out, "cameras.json")) as f:
            saved = json.load(f)
        line = saved["fit_total_vs_cameras"]
        plot(saved["per_cameras"], (line["intercept_s"], line["slope_s_per_camera"], line["r2"]),
             os.path.join(args.out, "cameras.png"),
             f"{saved['scene']}, {saved['iterations']} iterations, {saved['workers']} workers")
        return
    os.makedirs(args.out, exist_ok=True)
    log = open(os.path.join(args.out, "cameras.log"), "a")
    rows, per_n = [], []
    for n in cameras:
        scene_dir = os.path.join(args.out, f"{args.scene}{n}")
        if args.scene == "city":
            scene = os.path.join(scene_dir, "scene.h5")
            if not os.path.exists(scene):
                cmd = [args.manisweep, "synth", "city", "--views", str(n), "--width",
                       str(args.width), "--height", str(args.height), "--image-noise",
                       str(args.image_noise), "--output", scene_dir]
                if args.texture_photos:
                    cmd += ["--texture-photos", args.texture_photos]
                run(cmd, log)
        else:
            scene = castle_subset(args.data, n, scene_dir)
        out = os.path.join(args.out, f"run{n}")
        shutil.rmtree(out, ignore_errors=True)
        rss_file = out + ".rss"
        run(["/usr/bin/time", "-f", "%M", "-o", rss_file, args.manisweep, "reconstruct",
             "--input", scene, "--output", out, "--workers", str(args.workers),
             "--max-iterations", str(args.iterations), "--no-refine"] + args.sweep, log)
        with open(rss_file) as f:
            largest_rss_mib = int(f.read().split()[-1]) / 1024
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        rss_mib = summary["peak_rss_bytes_this_process"] / 1048576
        its = summary["iterations"][1:]
        if not its:
            sys.exit(f"{out}: no iteration ran ({summary.get('stop_reason')})")
        for it in its:
            rows.append({"cameras": n, "iteration": it["iteration"], "jobs": it["jobs"],
                         **{k: it[k] for k in STEPS + ["seconds_kernel"]},
                         "seconds_iteration": sum(it[k] for k in ITERATION),
                         "vertices": it["vertices"], "points_found": it["points_found"],
                         "points_inserted": it["points_inserted"],
                         "job_bytes_mean": it.get("job_bytes", 0) / max(1, it["jobs"]),
                         "job_max_bytes": it.get("job_max_bytes", 0),
                         "coordinator_peak_rss_mib": rss_mib,
                         "largest_process_peak_rss_mib": largest_rss_mib})
        mean = {k: sum(it[k] for it in its) / len(its) for k in STEPS}
        mean["seconds_iteration"] = sum(sum(it[k] for k in ITERATION) for it in its) / len(its)
        vertices = its[-1]["vertices"]
        per_n.append({"cameras": n, **mean, "vertices": vertices,
                      "coordinator_peak_rss_mib": rss_mib,
                      "largest_process_peak_rss_mib": largest_rss_mib,
                      "coordinator_rss_bytes_per_vertex": rss_mib * 1048576 / max(1, vertices),
                      "seconds_total_run": summary.get("seconds_this_process", 0)})
        print(f"N={n}: {mean['seconds_iteration']:.1f} s per iteration "
              f"({mean['seconds_iteration'] / n:.3f} s per camera), {vertices} vertices, "
              f"coordinator RSS {rss_mib:.0f} MiB (largest process {largest_rss_mib:.0f} MiB)",
              flush=True)
    ns = [p["cameras"] for p in per_n]
    line = fit(ns, [p["seconds_iteration"] for p in per_n]) if len(ns) > 1 else (0, 0, 1)
    per_camera = [p["seconds_iteration"] / p["cameras"] for p in per_n]
    spread = max(abs(x / (sum(per_camera) / len(per_camera)) - 1) for x in per_camera)
    # The images' own size; reconstruct sweeps them at --sweep.max-image-dimension (default
    # 1600: castle-P30's 3072x2048 at 1536x1024) unless `options` says otherwise.
    setup = {"scene": args.scene, "iterations": args.iterations, "workers": args.workers,
             "image_size": [args.width, args.height] if args.scene == "city" else [3072, 2048],
             "options": args.sweep, "per_cameras": per_n,
             "fit_total_vs_cameras": {"intercept_s": line[0], "slope_s_per_camera": line[1],
                                      "r2": line[2]},
             "per_camera_spread": spread}
    write_figures(args.out, "cameras", setup, rows)
    print(f"fit: {line[0]:.2f} s + {line[1]:.3f} s x cameras, R^2 {line[2]:.3f}; seconds per "
          f"camera within ±{100 * spread:.0f}% of their mean")
    plot(per_n, line, os.path.join(args.out, "cameras.png"),
         f"{args.scene}, {args.iterations} iterations, {args.workers} workers")
    print(f"wrote {args.out}/cameras.json, cameras.csv, cameras.png")


if __name__ == "__main__":
    main()
