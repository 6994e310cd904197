#!/usr/bin/env python3
"""The sweep's and refinement's figures on one machine, in one command and one JSON; meant for a
GPU node, and run the same way on a CPU one.

  - the machine: nvidia-smi, the CPU, `manisweep info` (GL renderer, the kernel auto picks);
  - bench/sweep_kernels_bench: hypotheses/s of each kernel (default: GLSL, and the CPU kernel
    on all cores) at each size, medians of interleaved rounds;
  - bench/multiply_add_peak_bench: one core's multiply-add ceiling (x86-64 only);
  - fountain-P11 `reconstruct` (its COLMAP sparse model) at half size (1536×1024) and full size
    (3072×2048), with each worker count: seconds of every iteration from summary.json;
  - `refine` of the last half-size run's final.ply at 1536×1024 (3 iterations, one level) with
    each refinement kernel: wall seconds.

  bench/sweep_machine.py --out docs/results/sweep_machine_HOST.json [--skip-setup]
      [--bin-dir DIR] [--data ../shared/data] [--iterations 2] [--workers 1 2]
      [--kernel auto] [--kernels glsl,cpu:N] [--sizes 640x480,1536x1024,3072x2048]
  bench/sweep_machine.py --table docs/results/sweep_machine_HOST.json

Without --bin-dir it sets up and builds first (deploy/setup.sh) unless --skip-setup. On a node
without Debian's packages: `deploy/bundle.sh OUT_DIR` on the build machine, then
`bench/sweep_machine.py --bin-dir OUT_DIR/bin --data ... --out ...` there (Python 3 only).
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from accuracy_variants import parse_bench_args, provenance, run, write_result  # noqa: E402


def output_of(cmd):
    """stdout of cmd, or None where it cannot run."""
    try:
        return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def machine(manisweep):
    return {"nvidia_smi": output_of(["nvidia-smi", "--query-gpu=name,driver_version,memory.total",
                                     "--format=csv,noheader"]),
            "manisweep_info": output_of([manisweep, "info"])}


def kernels(bench, args, work):
    tsv = os.path.join(work, "kernels.tsv")
    run([bench, "--sizes", args.sizes, "--kernels", args.kernels, "--rounds",
             str(args.rounds), "--output", tsv], os.path.join(work, "kernels.log"))
    rows = list(csv.DictReader(open(tsv), delimiter="\t"))
    for r in rows:
        for k, v in r.items():
            for number in (int, float):
                try:
                    r[k] = number(v)
                    break
                except ValueError:
                    pass
    return rows


def multiply_add_peak(bench_dir):
    path = os.path.join(bench_dir, "multiply_add_peak_bench")
    return output_of([path]) if os.access(path, os.X_OK) else None


def fountain_runs(manisweep, fountain, args, work):
    rows = []
    for size in (1600, 0):
        for workers in args.workers:
            out = os.path.join(work, f"run_{size}_{workers}")
            print(f"sweep_machine: fountain-P11, max-image-dimension {size}, {workers} workers",
                  flush=True)
            run([manisweep, "reconstruct", "--input", fountain, "--output", out, "--workers",
                     str(workers), "--kernel", args.kernel, "--max-iterations",
                     str(args.iterations), "--sweep.max-image-dimension", str(size),
                     "--no-refine", "--no-report"], out + ".log")
            summary = json.load(open(os.path.join(out, "summary.json")))
            rows.append({"max_image_dimension": size, "workers": workers, "iterations": [
                {k: it.get(k) for k in ("iteration", "seconds_total", "seconds_sweep",
                                        "seconds_kernel", "seconds_insert", "points_found",
                                        "vertices")}
                for it in summary["iterations"] if it["iteration"] > 0]})
    return rows


def refinements(manisweep, fountain, mesh, work):
    rows = []
    for kernel in ("auto", "cpu"):
        print(f"sweep_machine: refine, --refine.kernel {kernel}", flush=True)
        start = time.perf_counter()
        run([manisweep, "refine", "--input", fountain, "--mesh", mesh, "--output",
                 os.path.join(work, f"refined_{kernel}.ply"), "--refine.iterations", "3",
                 "--refine.levels", "1", "--refine.kernel", kernel],
                os.path.join(work, f"refine_{kernel}.log"))
        rows.append({"kernel": kernel, "iterations": 3,
                     "seconds": round(time.perf_counter() - start, 2)})
    return rows


def table(result):
    m = result["machine"]
    lines = [f"{m.get('nvidia_smi') or 'no NVIDIA GPU'}; {m['cpu']}, {m['cores']} cores; "
             f"commit {result['commit']}", "",
             "| size | kernel | threads | hypotheses/s (wall) | per CPU second | wall s |",
             "|---|---|---|---|---|---|"]
    for r in result["kernels"]:
        lines.append(f"| {r['size']} | {r['kernel']} | {r['threads']} | "
                     f"{r['hyp_per_s_wall'] / 1e6:,.0f} M | {r['hyp_per_s_cpu'] / 1e6:,.0f} M | "
                     f"{r['wall_s']:.3f} |")
    if result.get("multiply_add_peak"):
        lines += ["", result["multiply_add_peak"]]
    lines += ["", "| fountain-P11 swept at | workers | seconds of iterations 1, 2, ... |",
              "|---|---|---|"]
    for r in result["fountain"]:
        size = "3072×2048" if r["max_image_dimension"] == 0 else "1536×1024"
        seconds = ", ".join(f"{it['seconds_total']:.2f}" for it in r["iterations"])
        lines.append(f"| {size} | {r['workers']} | {seconds} |")
    lines += ["", "| refinement, 3 iterations at 1536×1024 | seconds |", "|---|---|"]
    for r in result["refine"]:
        lines.append(f"| `--refine.kernel {r['kernel']}` | {r['seconds']:.1f} |")
    return "\n".join(lines)


def main():
    a = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    a.add_argument("--bin-dir", help="run the programs there (a deploy/bundle.sh bin/), no setup")
    a.add_argument("--skip-setup", action="store_true", help="use build/ as it is")
    a.add_argument("--data", default=os.path.join(ROOT, "..", "shared", "data"))
    a.add_argument("--iterations", type=int, default=2)
    a.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    a.add_argument("--kernel", default="auto", help="the workers' --kernel")
    a.add_argument("--kernels", default=f"glsl,cpu:{os.cpu_count()}",
                   help="sweep_kernels_bench --kernels")
    a.add_argument("--sizes", default="640x480,1536x1024,3072x2048")
    a.add_argument("--rounds", type=int, default=3)
    args = parse_bench_args(a, table)
    if args.bin_dir:
        manisweep = os.path.join(args.bin_dir, "manisweep")
        bench_dir = args.bin_dir
    else:
        if not args.skip_setup:
            subprocess.run([os.path.join(ROOT, "deploy/setup.sh")], check=True)
        manisweep = os.path.join(ROOT, "build/app/manisweep")
        bench_dir = os.path.join(ROOT, "build/bench")
    bench = os.path.join(bench_dir, "sweep_kernels_bench")
    for tool in (manisweep, bench):
        if not os.access(tool, os.X_OK):
            raise SystemExit(f"sweep_machine: {tool} is not built (deploy/setup.sh)")
    fountain = os.path.join(args.data, "fountain-P11", "sparse")
    if not os.path.isdir(fountain):
        raise SystemExit(f"sweep_machine: no fountain-P11 model at {fountain} (--data)")
    work = tempfile.mkdtemp(prefix="sweep_machine.")
    try:
        result = provenance("sweep_machine")
        result["machine"].update(machine(manisweep))
        print("sweep_machine: sweep_kernels_bench", flush=True)
        result["kernels"] = kernels(bench, args, work)
        result["multiply_add_peak"] = multiply_add_peak(bench_dir)
        result["fountain"] = fountain_runs(manisweep, fountain, args, work)
        mesh = os.path.join(work, f"run_1600_{args.workers[-1]}", "final.ply")
        result["refine"] = refinements(manisweep, fountain, mesh, work)
        write_result(args.out, result, table)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
