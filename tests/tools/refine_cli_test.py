#!/usr/bin/python3
"""End-to-end test of `manisweep refine` (docs/design/refine.md): on a small synthetic pyramid,
`reconstruct --refine` writes a refined mesh that is valid for check-mesh and for Open3D
(watertight, no self-intersecting pair), with a lower photometric energy and a lower depth error
than the swept mesh it started from, and one interrupted and resumed ends as one that was not;
the gradients computed by 1 or 2 worker processes and in one process give the same bytes, also
after an interrupted and resumed `reconstruct --refine`, and from `coordinator --refine` with two
`worker` processes; bad inputs (an open mesh, a truncated
file, a missing image) end with exit 2 and one line naming the file. Exit 0 when all hold.
"""
import os
import re
import socket
import subprocess
import sys

from small_pyramid import fresh_small_pyramid, interrupt_after, parse_test_arguments, run


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def expect_bad_input(manisweep, scene, mesh, name, out):
    r = run([manisweep, "refine", "-i", scene, "-m", mesh, "-o", out])
    lines = [l for l in r.stderr.strip().splitlines() if l.strip()]
    ok = r.returncode == 2 and lines and name in lines[-1]
    print(("ok  " if ok else "FAIL"), f"bad input {name}: exit {r.returncode}:",
          lines[-1] if lines else "(no message)")
    return ok


def check_reconstruct_refines(ms, scene, data, work, recon):
    """`reconstruct --refine`: a valid refined mesh, an energy that falls at the finest level, an
    MAE below the swept mesh's."""
    out = os.path.join(work, "run")
    r = run(recon + ["-o", out, "--workers", "2"])
    refined = os.path.join(out, "refined.ply")
    ok = r.returncode == 0 and "check-mesh: valid" in r.stdout
    print(("ok  " if ok else "FAIL"), "reconstruct --refine:",
          r.stdout.strip().splitlines()[-1:] or r.stderr[-2000:])
    # The energy at the finest level: before its first step, and of the mesh written.
    finest = [float(e) for e in
              re.findall(r"\(level 0, [0-9]+ vertices\): energy ([0-9.]+)", r.stderr)]
    final = re.findall(r"final energy ([0-9.]+)", r.stdout)
    if not finest or not final or not float(final[0]) < finest[0]:
        print("FAIL energy at the finest level does not fall:", finest, final)
        ok = False
    # Closer to the truth than the swept mesh it started from (all views, camera z).
    r = run([ms, "evaluate", "--mesh", os.path.join(out, "final.ply"), "--mesh", refined,
             "--ground-truth", os.path.join(data, "gt.ply"), "--input", scene, "--all-views"])
    mae = {m: float(v) for m, v in re.findall(r"^(final|refined)\.ply\s+([0-9.]+)", r.stdout, re.M)}
    good = r.returncode == 0 and len(mae) == 2 and mae["refined"] < mae["final"]
    print(("ok  " if good else "FAIL"), "MAE final -> refined:", mae or r.stderr[-2000:])
    return ok and good


def check_interrupted_refine_resumes(ms, scene, final_mesh, work):
    """`refine` interrupted after its third iteration, then --resume: the same bytes."""
    # The same mesh as an uninterrupted run, byte for byte, and no checkpoint left behind.
    straight = os.path.join(work, "straight.ply")
    args_refine = ["--refine.iterations", "6", "--refine.levels", "2", "--refine.max-edge-px", "20"]
    r = run([ms, "refine", "-i", scene, "-m", final_mesh, "-o", straight] + args_refine)
    ran = r.returncode == 0
    resumed = os.path.join(work, "resumed.ply")
    interrupted = interrupt_after(
        [ms, "refine", "-i", scene, "-m", final_mesh, "-o", resumed] + args_refine, "iteration 3 ")
    had_checkpoint = os.path.exists(resumed + ".checkpoint.json")
    r = run([ms, "refine", "-i", scene, "-m", final_mesh, "-o", resumed, "--resume"] + args_refine)
    same = (r.returncode == 0 and os.path.exists(resumed) and
            open(resumed, "rb").read() == open(straight, "rb").read())
    good = (interrupted == 130 and had_checkpoint and same and "resuming" in r.stderr and
            not os.path.exists(resumed + ".checkpoint.json"))
    print(("ok  " if good else "FAIL"),
          f"interrupt (exit {interrupted}, checkpoint {had_checkpoint}) and --resume: "
          f"{'the same mesh' if same else 'a different mesh'}")
    return ran and good


def check_distributed_refine(ms, scene, final_mesh, refined, work, recon):
    """One worker, two, a single process, an interrupted and resumed run, and a coordinator with
    worker processes: the same refined bytes."""
    # Distributed: the gradients come from the workers, summed in pair order, so one worker,
    # two workers and the single-process `refine` write the same bytes; and a reconstruct
    # interrupted while refining resumes (sweep checkpoint, then refinement checkpoint) to them.
    refined_bytes = open(refined, "rb").read()
    one = os.path.join(work, "run1")
    r = run(recon + ["-o", one, "--workers", "1"])
    same_one = r.returncode == 0 and open(os.path.join(one, "refined.ply"), "rb").read() == refined_bytes
    local = os.path.join(work, "local.ply")
    r = run([ms, "refine", "-i", scene, "-m", final_mesh, "-o", local, "--refine.iterations", "6",
             "--refine.levels", "2", "--refine.max-edge-px", "20"])
    same_local = r.returncode == 0 and open(local, "rb").read() == refined_bytes
    cut = os.path.join(work, "run_cut")
    cut_exit = interrupt_after(recon + ["-o", cut, "--workers", "2"], "iteration 3 (level")
    r = run(recon + ["-o", cut, "--workers", "2", "--resume"])
    cut_path = os.path.join(cut, "refined.ply")
    same_cut = (r.returncode == 0 and os.path.exists(cut_path) and
                open(cut_path, "rb").read() == refined_bytes)
    # --resume once more: the run is finished, refinement included; it is not redone.
    r = run(recon + ["-o", cut, "--workers", "2", "--resume"])
    not_redone = (r.returncode == 0 and "is up to date" in r.stderr and
                  open(cut_path, "rb").read() == refined_bytes)
    print(("ok  " if not_redone else "FAIL"), "--resume of a finished run does not refine again")
    # `coordinator --refine` with two `worker` processes (a cluster's shape) gives them too.
    port = free_port()
    cluster = os.path.join(work, "cluster")
    endpoint = f"tcp://127.0.0.1:{port}"
    coordinator = subprocess.Popen(
        [ms, "coordinator", "-i", scene, "-o", cluster, "--bind", endpoint, "--max-iterations",
         "4", "--refine", "--refine.iterations", "6", "--refine.levels", "2",
         "--refine.max-edge-px", "20"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = [subprocess.Popen([ms, "worker", "--connect", endpoint, "--kernel", "cpu"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
               for _ in range(2)]
    cluster_exit = coordinator.wait(timeout=300)
    worker_exits = [w.wait(timeout=60) for w in workers]
    cluster_path = os.path.join(cluster, "refined.ply")
    same_cluster = (cluster_exit == 0 and os.path.exists(cluster_path) and
                    open(cluster_path, "rb").read() == refined_bytes)
    good = (same_one and same_local and cut_exit == 130 and same_cut and same_cluster and
            worker_exits == [0, 0])
    print(("ok  " if good else "FAIL"),
          f"distributed: 1 worker {'same' if same_one else 'DIFFERENT'}, single process "
          f"{'same' if same_local else 'DIFFERENT'}, interrupted while refining (exit {cut_exit}) "
          f"and resumed {'same' if same_cut else 'DIFFERENT'}, coordinator --refine with 2 "
          f"worker processes (exit {cluster_exit}, workers {worker_exits}) "
          f"{'same' if same_cluster else 'DIFFERENT'}")
    return not_redone and good


def check_bad_inputs(ms, scene, data, initial, work):
    """An open mesh, a truncated PLY and a missing image: exit 2 naming the file."""
    ok = True
    # An open mesh: one triangle.
    open_mesh = os.path.join(work, "open.obj")
    with open(open_mesh, "w") as f:
        f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    bad_out = os.path.join(work, "bad.ply")
    ok = expect_bad_input(ms, scene, open_mesh, "open.obj", bad_out) and ok
    # A truncated PLY.
    truncated = os.path.join(work, "truncated.ply")
    with open(initial, "rb") as src, open(truncated, "wb") as dst:
        dst.write(src.read()[: os.path.getsize(initial) // 2])
    ok = expect_bad_input(ms, scene, truncated, "truncated.ply", bad_out) and ok
    # A missing image (last: the scene refers to its images by path).
    images = sorted(os.listdir(os.path.join(data, "images")))
    os.remove(os.path.join(data, "images", images[2]))
    ok = expect_bad_input(ms, scene, initial, images[2], bad_out) and ok
    return ok


def main():
    args = parse_test_arguments(__doc__)
    ms = args.manisweep
    data = fresh_small_pyramid(ms, args.workdir)
    if data is None:
        return 1
    scene = os.path.join(data, "scene.h5")
    initial = os.path.join(args.workdir, "initial.ply")
    r = run([ms, "manifold", "-i", scene, "-o", initial])
    if r.returncode != 0:
        print("FAIL manifold:", r.stderr[-2000:])
        return 1
    # `reconstruct --refine`: 4 sweep iterations, then refine final.ply into refined.ply,
    # remeshing to 20-px edges (so the distributed checks below cover remeshing too).
    recon = [ms, "reconstruct", "-i", scene, "--max-iterations", "4", "--kernel", "cpu",
             "--refine", "--refine.iterations", "6", "--refine.levels", "2",
             "--refine.max-edge-px", "20"]
    work = args.workdir
    ok = check_reconstruct_refines(ms, scene, data, work, recon)
    final_mesh = os.path.join(work, "run", "final.ply")
    refined = os.path.join(work, "run", "refined.ply")
    ok = check_interrupted_refine_resumes(ms, scene, final_mesh, work) and ok
    ok = check_distributed_refine(ms, scene, final_mesh, refined, work, recon) and ok
    check = run([ms, "check-mesh", refined])
    verdict = run([sys.executable, args.verdict, refined])
    print(("ok  " if check.returncode == 0 else "FAIL"), "check-mesh exit", check.returncode)
    print(verdict.stdout.strip())
    ok = ok and check.returncode == 0 and verdict.returncode in (0, 77)

    ok = check_bad_inputs(ms, scene, data, initial, work) and ok
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
