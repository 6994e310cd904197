#!/usr/bin/python3
"""manisweep beside the peer (OpenMVS) on the same images and sparse points: one table of time,
peak memory, vertices, photo-consistency (of all pixels, and of the pixels the peer's mesh
covers), mesh validity, and, on a synth dataset with a ground truth, MAE and coverage.

Ours is a default `manisweep reconstruct` of DATASET (or a finished run folder, --run). The
peer is run when its binaries are given (--openmvs-bin: InterfaceCOLMAP, DensifyPointCloud,
ReconstructMesh, RefineMesh, at --openmvs-resolution-level), or measured from a mesh it made
(--peer-mesh; its time and memory are then not measured here). Writes one JSON (machine,
commit, date, command) and prints the markdown table docs/design/refine.md shows.

  bench/peer_compare.py --dataset ../shared/data/fountain-P11 \\
      --peer-mesh ../shared/data/fountain-P11/peers/openmvs-2.3/refined.ply \\
      --out docs/results/peer_fountain-P11.json [--run RUN_DIR] [--mesh LABEL=PATH ...]
      [--refine-variant "--refine.max-edge-px 16" ...]
      [-- RECONSTRUCT_OPTIONS...]
  bench/peer_compare.py --table docs/results/peer_fountain-P11.json
"""
import argparse
import glob
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from accuracy_variants import print_table_if_asked, provenance, write_result  # noqa: E402

OPENMVS_STEPS = ["InterfaceCOLMAP", "DensifyPointCloud", "ReconstructMesh", "RefineMesh"]


def timed(cmd, log_path, cwd=None):
    """Runs cmd under /usr/bin/time; returns (seconds, peak RSS in bytes of it or any child)."""
    timing = log_path + ".time"
    with open(log_path, "a") as log:
        log.write("+ " + " ".join(cmd) + "\n")
        log.flush()
        r = subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", timing] + cmd, cwd=cwd,
                           stdout=log, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        raise SystemExit(f"{cmd[0]} failed (exit {r.returncode}); see {log_path}")
    seconds, rss_kb = open(timing).read().split()[-2:]
    return float(seconds), int(rss_kb) * 1024


def model_of(dataset):
    """The scene manisweep reads: a synth dataset's scene.h5, else the folder's sparse model."""
    for candidate in ("scene.h5", "sparse"):
        path = os.path.join(dataset, candidate)
        if os.path.exists(path):
            return path
    return dataset


def run_ours(manisweep, dataset, work, extra):
    run_dir = os.path.join(work, "manisweep")
    seconds, peak = timed([manisweep, "reconstruct", "--input", model_of(dataset), "--output",
                           run_dir, "--workers", "2", "--no-report"] + extra,
                          os.path.join(work, "manisweep.log"))
    return run_dir, {"seconds": seconds, "peak_rss_bytes": peak,
                     "command": "`reconstruct " + " ".join(["--workers", "2"] + extra) + "`"}


def run_openmvs(bin_dir, dataset, work, level):
    """InterfaceCOLMAP -> DensifyPointCloud -> ReconstructMesh -> RefineMesh in work/openmvs;
    returns the refined mesh and the time and peak memory of each step."""
    mvs = os.path.join(work, "openmvs")
    os.makedirs(mvs, exist_ok=True)
    log = os.path.join(work, "openmvs.log")
    exe = {step: os.path.join(bin_dir, step) for step in OPENMVS_STEPS}
    for step, path in exe.items():
        if not os.access(path, os.X_OK):
            raise SystemExit(f"--openmvs-bin {bin_dir}: no executable {step}")
    level_args = ["--resolution-level", str(level)]
    commands = [
        [exe["InterfaceCOLMAP"], "-i", os.path.abspath(dataset), "-o", "scene.mvs",
         "--image-folder", os.path.join(os.path.abspath(dataset), "images"), "-w", mvs],
        [exe["DensifyPointCloud"], "scene.mvs", "-w", mvs] + level_args,
        [exe["ReconstructMesh"], "scene_dense.mvs", "-w", mvs],
        [exe["RefineMesh"], "scene_dense_mesh.mvs", "-w", mvs] + level_args,
    ]
    steps = {}
    for step, cmd in zip(OPENMVS_STEPS, commands):
        seconds, peak = timed(cmd, log, cwd=mvs)
        steps[step] = {"seconds": seconds, "peak_rss_bytes": peak}
    meshes = sorted(glob.glob(os.path.join(mvs, "*refine*.ply")), key=os.path.getmtime)
    if not meshes:
        raise SystemExit(f"RefineMesh wrote no *refine*.ply in {mvs}; see {log}")
    return meshes[-1], {
        "seconds": sum(s["seconds"] for s in steps.values()),
        "peak_rss_bytes": max(s["peak_rss_bytes"] for s in steps.values()),
        "steps": steps, "command": " -> ".join(OPENMVS_STEPS) + f" (resolution level {level})"}


def check_mesh(manisweep, mesh):
    r = subprocess.run([manisweep, "check-mesh", "--json", "-", mesh], capture_output=True,
                       text=True)
    if r.returncode not in (0, 3):
        raise SystemExit(f"check-mesh {mesh} failed: {r.stderr[-1000:]}")
    report = json.loads(r.stdout)
    return {key: report[key] for key in ("valid", "closed_manifold", "vertices", "faces",
                                         "boundary_edges", "components", "self_intersections")}


def open3d_check(mesh):
    """Open3D's verdict (the library users load meshes with); None where it is not installed."""
    code = ("import json, sys, open3d as o3d\n"
            "m = o3d.io.read_triangle_mesh(sys.argv[1])\n"
            "print(json.dumps({'watertight': bool(m.is_watertight()),"
            " 'self_intersecting': bool(m.is_self_intersecting())}))\n")
    r = subprocess.run(["/usr/bin/python3", "-c", code, mesh], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"Open3D could not check {mesh}: {r.stderr.strip()[-300:]}", file=sys.stderr)
        return None
    return json.loads(r.stdout.strip().splitlines()[-1])


CONSISTENCY_LINE = re.compile(r"^(\S+)\s+([\d.]+)%\s+([\d.]+)%\s+([\d.]+)%\s+(\d+)$")


def consistency(manisweep, scene, meshes, within, log_path):
    """{mesh: (consistent share, covered share, consistent among covered)} of every pixel, or of
    those `within` covers."""
    cmd = [manisweep, "consistency", "--input", scene]
    for mesh in meshes:
        cmd += ["-m", mesh]
    if within:
        cmd += ["--within", within]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    with open(log_path, "a") as log:
        log.write("+ " + " ".join(cmd) + "\n" + out)
    shares = {}
    for line in out.splitlines():
        m = CONSISTENCY_LINE.match(line.strip())
        if m:
            shares[m.group(1)] = tuple(float(m.group(i)) / 100 for i in (2, 3, 4))
    return shares


def accuracy(manisweep, scene, ground_truth, mesh, work):
    out = os.path.join(work, os.path.basename(mesh) + ".accuracy.json")
    subprocess.run([manisweep, "evaluate", "-m", mesh, "-g", ground_truth, "-i", scene,
                    "--json", out], check=True, capture_output=True)
    total = json.load(open(out))["meshes"][0]["total"]
    return {"mae": total["mae"], "mae_all": total["mae_all"], "coverage": total["coverage"]}


def measure(args, work):
    scene = model_of(args.dataset)
    rows = []
    if args.run:
        run_dir = args.run
        summary = json.load(open(os.path.join(run_dir, "summary.json")))
        ours = {"seconds": summary.get("seconds_this_process"),
                "peak_rss_bytes": summary.get("peak_rss_bytes_this_process"),
                "command": f"an existing run ({run_dir}; the coordinator's time and memory)"}
    else:
        run_dir, ours = run_ours(args.manisweep, args.dataset, work, args.reconstruct)
    our_meshes = [("manisweep, " + name, os.path.join(run_dir, name + ".ply"))
                  for name in ("initial", "final", "refined")
                  if os.path.exists(os.path.join(run_dir, name + ".ply"))]
    peer_mesh, peer = args.peer_mesh, None
    if args.openmvs_bin:
        peer_mesh, peer = run_openmvs(args.openmvs_bin, args.dataset, work,
                                      args.openmvs_resolution_level)
    elif peer_mesh:
        peer = {"seconds": None, "peak_rss_bytes": None, "command": f"a mesh it made ({peer_mesh})"}
    extra = [tuple(spec.split("=", 1)) for spec in args.mesh]
    variant_costs = {}
    for k, options in enumerate(args.refine_variant):
        label = f"manisweep, final refined with `{options}`"
        out = os.path.join(work, f"refined_variant_{k}.ply")
        seconds, peak = timed([args.manisweep, "refine", "--input", model_of(args.dataset), "--mesh",
                               os.path.join(run_dir, "final.ply"), "--output", out]
                              + options.split(), os.path.join(work, f"refined_variant_{k}.log"))
        variant_costs[out] = {"seconds": seconds, "peak_rss_bytes": peak}
        extra.append((label, out))
    meshes = our_meshes + extra + ([("OpenMVS, refined", peer_mesh)] if peer_mesh else [])
    log = os.path.join(work, "measure.log")
    paths = [path for _, path in meshes]
    everywhere = consistency(args.manisweep, scene, paths, None, log)
    on_peer = consistency(args.manisweep, scene, paths, peer_mesh, log) if peer_mesh else {}
    ground_truth = os.path.join(args.dataset, "gt.ply")
    for label, path in meshes:
        row = {"label": label, "mesh": os.path.abspath(path),
               "check_mesh": check_mesh(args.manisweep, path)}
        if path in variant_costs:
            row["refine"] = variant_costs[path]
        row["consistency_all"], row["covered"], row["consistency_of_covered"] = everywhere[path]
        if path in on_peer:
            row["consistency_within_peer"] = on_peer[path][0]
        if args.open3d:
            row["open3d"] = open3d_check(path)
        if os.path.exists(ground_truth):
            row["accuracy"] = accuracy(args.manisweep, scene, ground_truth, path, work)
        rows.append(row)
    return {"ours": ours, "peer": peer, "meshes": rows}


def table(result):
    def seconds(x):
        return "—" if x is None else f"{x:.0f} s"

    def memory(x):
        return "—" if x is None else f"{x / 1e9:.2f} GB"

    def share(x):
        return "—" if x is None else f"{100 * x:.1f}%"

    runs = [f"manisweep: {result['ours']['command']}, {seconds(result['ours']['seconds'])}, "
            f"peak memory {memory(result['ours']['peak_rss_bytes'])}"]
    if result["peer"]:
        runs.append(f"OpenMVS: {result['peer']['command']}, {seconds(result['peer']['seconds'])}, "
                    f"peak memory {memory(result['peer']['peak_rss_bytes'])}")
    lines = [f"**{result['dataset']}** ({'; '.join(runs)})"]
    synthetic = any("accuracy" in r for r in result["meshes"])
    header = ("| mesh | vertices | photo-consistency, all pixels | covered | "
              "on the peer's pixels | closed 2-manifold (check-mesh) | boundary edges |")
    rule = "|---|---|---|---|---|---|---|"
    if synthetic:
        header += " MAE | coverage |"
        rule += "---|---|"
    lines += ["", header, rule]
    for r in result["meshes"]:
        c = r["check_mesh"]
        label = r["label"]
        if "refine" in r:
            label += (f" ({seconds(r['refine']['seconds'])}, "
                      f"{memory(r['refine']['peak_rss_bytes'])})")
        line = (f"| {label} | {c['vertices']:,} | {share(r['consistency_all'])} | "
                f"{share(r['covered'])} | {share(r.get('consistency_within_peer'))} | "
                f"{'VALID' if c['valid'] else 'no'} | {c['boundary_edges']:,} |")
        if synthetic:
            a = r.get("accuracy", {})
            line += f" {a.get('mae', float('nan')):.4f} | {share(a.get('coverage'))} |"
        lines.append(line)
    m = result["machine"]
    lines.append(f"\n{m['cpu']}, {m['cores']} cores; `{result['command']}`")
    return "\n".join(lines)


def main():
    a = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--manisweep", default=os.path.join(ROOT, "build/app/manisweep"))
    a.add_argument("--dataset", help="folder with images/ and sparse/ (or a synth dataset)")
    a.add_argument("--run", help="measure this finished manisweep run instead of running one")
    a.add_argument("--peer-mesh", help="a mesh the peer made from the same dataset")
    a.add_argument("--mesh", action="append", default=[], metavar="LABEL=PATH",
                   help="another mesh of the same dataset to measure (e.g. a refinement with other "
                        "options); repeatable")
    a.add_argument("--refine-variant", action="append", default=[], metavar="OPTIONS",
                   help="also refine the run's final.ply with these refine options (one string), "
                        "timed, as another row; repeatable")
    a.add_argument("--openmvs-bin", help="folder with the OpenMVS binaries: run the peer")
    a.add_argument("--openmvs-resolution-level", type=int, default=1)
    a.add_argument("--open3d", action="store_true",
                   help="also ask Open3D (watertight, self-intersecting; slow on large meshes)")
    a.add_argument("--work", default="bench_results/peer_compare")
    a.add_argument("--out", help="JSON to write")
    a.add_argument("--table", help="print the table of this JSON and exit")
    a.add_argument("reconstruct", nargs="*", help="after --: options for manisweep reconstruct")
    args = a.parse_args()
    if print_table_if_asked(args.table, table):
        return 0
    if not args.dataset or not args.out:
        a.error("needs --dataset and --out")
    if not os.path.exists(args.manisweep):
        a.error(f"no manisweep binary at {args.manisweep} (build first, or give --manisweep)")
    os.makedirs(args.work, exist_ok=True)
    result = {**provenance("peer_compare"),
              "dataset": os.path.basename(os.path.normpath(args.dataset))}
    result.update(measure(args, args.work))
    write_result(args.out, result, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
