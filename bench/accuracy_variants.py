#!/usr/bin/env python3
"""The accuracy of a synthetic scene as a distribution, not one trajectory.

A run's trajectory depends on the last bits of its input, so one run's MAE is a draw. This
runs `manisweep reconstruct` (the defaults, or the options given after --) on variants of one
scene that must not matter: synth seeds 1-4 (texture, layout), each read as scene.h5 and as a
COLMAP text model, and seed 1 also as a COLMAP binary model and as an NVM file. Each closed
`final.ply` (and `refined.ply` unless --no-refine) is evaluated against the ground truth as the
paper's Table 1 (view 0, camera z, Sigma 0.06), and OUT/accuracy_SCENE.json gets every run with
the median and the worst (machine, commit, command, once). The open street (`--scene city`) is
made with 2 grey levels of image noise and evaluated from views 10, 30 and 50 (Sigma 0.47), and
its JSON adds how far each closed mesh lies below the initial manifold.

    bench/accuracy_variants.py --scene pyramid-down [--out bench_results] [--no-refine]
        [--seeds 1,2,3,4] [--formats h5,text,bin,nvm] [-- --sweep.ncc-threshold 0.97 ...]
"""
import argparse
import datetime
import json
import os
import platform
import shlex
import shutil
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Seed 1 is read in every format; the other seeds as scene.h5 and COLMAP text.
FORMATS_SEED_1 = ["h5", "text", "bin", "nvm"]
FORMATS_OTHER_SEEDS = ["h5", "text"]


class Scene:
    """How a synth scene is made and measured: the paper's Table 1 for the pyramids (view 0,
    Sigma 0.06), docs/design/accuracy.md's open street otherwise."""

    def __init__(self, name):
        self.name = name
        if name == "city":
            self.synth_options = ["--image-noise", "2"]
            self.views, self.sigma = ["10", "30", "50"], "0.47"
        else:
            self.synth_options = []
            self.views, self.sigma = ["0"], "0.06"

    def metric(self):
        return (f"MAE of every ground-truth pixel from view(s) {', '.join(self.views)}, "
                f"camera z, Sigma {self.sigma} (m)")


def run(cmd, log_path):
    with open(log_path, "a") as log:
        log.write("+ " + " ".join(cmd) + "\n")
        log.flush()
        subprocess.run(cmd, check=True, stdout=log, stderr=subprocess.STDOUT)


def make_dataset(manisweep, scene, seed, work, log):
    """The synth dataset of (scene, seed) with its model in every format; returns its folder."""
    d = os.path.join(work, f"{scene.name}-{seed}")
    if os.path.exists(os.path.join(d, "synth.json")):
        return d
    shutil.rmtree(d, ignore_errors=True)
    run([manisweep, "synth", scene.name, "--seed", str(seed), "--output", d]
        + scene.synth_options, log)
    # A COLMAP binary model and an NVM file, each beside a link to the same images.
    os.makedirs(os.path.join(d, "binary", "sparse"))
    run([manisweep, "convert", "--input", os.path.join(d, "scene.h5"), "--output",
         os.path.join(d, "binary", "sparse"), "--to", "colmap-binary"], log)
    os.symlink("../images", os.path.join(d, "binary", "images"))
    os.makedirs(os.path.join(d, "nvm"))
    run([manisweep, "convert", "--input", os.path.join(d, "scene.h5"), "--output",
         os.path.join(d, "nvm", "model.nvm"), "--to", "nvm"], log)
    for name in sorted(os.listdir(os.path.join(d, "images"))):
        os.symlink(os.path.join("..", "images", name), os.path.join(d, "nvm", name))
    return d


def model_path(dataset, fmt):
    return {
        "h5": os.path.join(dataset, "scene.h5"),
        "text": dataset,  # the synth folder: sparse/ (COLMAP text) beside images/
        "bin": os.path.join(dataset, "binary"),
        "nvm": os.path.join(dataset, "nvm", "model.nvm"),
    }[fmt]


def evaluate(manisweep, scene, dataset, mesh, out_json, log):
    run([manisweep, "evaluate", "--mesh", mesh, "--ground-truth",
         os.path.join(dataset, "gt.ply"), "--input", os.path.join(dataset, "scene.h5"),
         "--camera", *scene.views, "--sigma", scene.sigma, "--json", out_json], log)
    with open(out_json) as f:
        total = json.load(f)["meshes"][0]["total"]
    # mae_all counts a pixel the mesh misses as 10 Sigma; mae is over the covered pixels (the
    # surface proper, without the Steiner faces, covers fewer).
    return {"mae_all": total["mae_all"], "mae": total["mae"], "rms": total["rms"],
            "coverage": total["coverage"]}


def summary(values):
    return {"median": statistics.median(values), "worst": max(values), "best": min(values)}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scene", default="pyramid-down")
    p.add_argument("--seeds", default="1,2,3,4")
    p.add_argument("--formats", default=",".join(FORMATS_SEED_1),
                   help="formats read for seed 1; other seeds use h5 and text among them")
    p.add_argument("--out", default=os.path.join(ROOT, "bench_results"))
    p.add_argument("--work", default=None, help="datasets and runs (default OUT/work)")
    p.add_argument("--workers", default="2")
    p.add_argument("--no-refine", action="store_true")
    p.add_argument("--label", default="defaults", help="names this configuration in the JSON")
    p.add_argument("--manisweep", default=os.path.join(ROOT, "build", "app", "manisweep"))
    p.add_argument("options", nargs="*", help="after --: options passed to reconstruct")
    a = p.parse_args()
    manisweep = os.path.abspath(a.manisweep)
    if not os.access(manisweep, os.X_OK):
        sys.exit(f"error: {manisweep} is not built (run deploy/setup.sh)")
    os.makedirs(a.out, exist_ok=True)
    work = os.path.abspath(a.work or os.path.join(a.out, "work"))
    os.makedirs(work, exist_ok=True)
    log = os.path.join(work, f"{a.scene}_{a.label}.log")
    formats = a.formats.split(",")
    scene = Scene(a.scene)
    variants = []
    for seed in [int(s) for s in a.seeds.split(",")]:
        for fmt in formats if seed == 1 else [f for f in FORMATS_OTHER_SEEDS if f in formats]:
            variants.append((seed, fmt))

    rows = []
    for seed, fmt in variants:
        dataset = make_dataset(manisweep, scene, seed, work, log)
        out = os.path.join(work, "runs", a.label, f"{a.scene}-{seed}-{fmt}")
        shutil.rmtree(out, ignore_errors=True)
        cmd = [manisweep, "reconstruct", "--input", model_path(dataset, fmt), "--output", out,
               "--workers", a.workers] + (["--no-refine"] if a.no_refine else []) + a.options
        start = time.monotonic()
        run(cmd, log)
        row = {"seed": seed, "format": fmt, "seconds": round(time.monotonic() - start, 1)}
        with open(os.path.join(out, "summary.json")) as f:
            # The sweep iterations run (summary.json lists each one's statistics).
            row["iterations"] = max(i["iteration"] for i in json.load(f)["iterations"])
        for name in ["initial", "final", "final_surface"] + ([] if a.no_refine else ["refined"]):
            row[name] = evaluate(manisweep, scene, dataset, os.path.join(out, f"{name}.ply"),
                                 os.path.join(out, f"eval_{name}.json"), log)
        # How far each closed mesh lies below the initial manifold (the street's goal).
        for name in ["final"] + ([] if a.no_refine else ["refined"]):
            row[name]["below_initial"] = 1 - row[name]["mae_all"] / row["initial"]["mae_all"]
        rows.append(row)
        print(f"{a.scene} seed {seed} {fmt:4s}: " + ", ".join(
            f"{n} {row[n]['mae_all']:.4f}" for n in ("initial", "final", "refined") if n in row),
            flush=True)

    meshes = ["initial", "final", "final_surface"] + ([] if a.no_refine else ["refined"])
    result = {
        **provenance("accuracy_variants"),
        "scene": a.scene,
        "label": a.label,
        "reconstruct_options": a.options,
        "metric": scene.metric(),
        # Every pixel for the closed meshes; the covered pixels for the surface proper.
        "summary": {m: {**summary([r[m]["mae" if m == "final_surface" else "mae_all"]
                                   for r in rows]),
                        "coverage_worst": min(r[m]["coverage"] for r in rows),
                        **({"below_initial_median":
                            statistics.median(r[m]["below_initial"] for r in rows),
                            "below_initial_worst": min(r[m]["below_initial"] for r in rows)}
                           if m in ("final", "refined") else {})}
                    for m in meshes},
        "runs": rows,
    }
    path = os.path.join(a.out, f"accuracy_{a.scene}_{a.label}.json")
    with open(path, "w") as f:
        json.dump(result, f, indent=1)
    for m in meshes:
        s = result["summary"][m]
        below = (f"; below the initial manifold: median {s['below_initial_median']:.1%}, "
                 f"worst {s['below_initial_worst']:.1%}" if "below_initial_median" in s else "")
        print(f"{a.scene} {m}: median {s['median']:.4f}, worst {s['worst']:.4f} "
              f"over {len(rows)} runs{below}")
    print(f"wrote {path}")


def print_table_if_asked(path, render):
    """`--table PATH`: print PATH's table with `render` and say so (the caller then exits)."""
    if not path:
        return False
    with open(path) as f:
        print(render(json.load(f)))
    return True


def provenance(bench):
    """What every bench JSON starts with: the bench, where, at which commit, when, and the command
    line that wrote it."""
    return {
        "bench": bench,
        "machine": {"host": platform.node(), "cpu": cpu_name(), "cores": os.cpu_count()},
        "commit": git_commit(),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": shlex.join([os.path.relpath(sys.argv[0], ROOT)] + sys.argv[1:]),
    }


def split_run_options(argv):
    """A bench's own arguments, and the options after `--` it passes to every manisweep run."""
    if "--" not in argv:
        return argv, []
    return argv[:argv.index("--")], argv[argv.index("--") + 1:]


def parse_bench_args(parser, table):
    """Adds --out and --table to a bench's parser and parses. With --table it prints that JSON
    as TABLE renders it and exits; otherwise --out is required."""
    parser.add_argument("--out", help="JSON to write")
    parser.add_argument("--table", help="print the table of this JSON and exit")
    args = parser.parse_args()
    if print_table_if_asked(args.table, table):
        sys.exit(0)
    if not args.out:
        parser.error("--out or --table is required")
    return args


def write_result(path, result, table):
    """Writes a bench's RESULT as JSON to PATH and prints it as TABLE renders it."""
    with open(path, "w") as f:
        json.dump(result, f, indent=1)
    print(table(result))


def cpu_name():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def git_commit():
    """HEAD's short hash, with "-dirty" when tracked files differ from it (a binary built from
    the working tree is then not that commit's)."""
    try:
        return subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty",
                               "--abbrev=7", "--exclude", "*"], check=True,
                              capture_output=True, text=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


if __name__ == "__main__":
    main()
