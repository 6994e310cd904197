#!/usr/bin/python3
"""End-to-end test of `manisweep extend` (docs/design/extend.md) on a small synthetic pyramid:
its first three views are reconstructed, then the run is extended with all six. The extension
writes a closed mesh (check-mesh, Open3D) that sees what the new views see (depth error from a
new view far below the first run's, near the run of all six at once), leaves the first run's
folder as it was, gives the same bytes with one worker or two and after an interrupted and
resumed extension, and refuses a model whose old cameras moved (exit 2, one line naming the
camera, nothing written). Exit 0 when all hold.
"""
import hashlib
import os
import re
import signal
import socket
import subprocess
import sys

from small_pyramid import fresh_small_pyramid, interrupt_after, parse_test_arguments, run

SWEEP = ["--max-iterations", "3", "--kernel", "cpu", "--no-refine", "--no-report"]


def digest(folder):
    """Every file of a folder with its content hash."""
    out = {}
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name)
        if os.path.isfile(path):
            out[name] = hashlib.sha256(open(path, "rb").read()).hexdigest()
    return out


def report(ok, what):
    print(("ok  " if ok else "FAIL"), what)
    return ok


def mae_from(ms, data, mesh, view):
    r = run([ms, "evaluate", "--mesh", mesh, "--ground-truth", os.path.join(data, "gt.ply"),
             "--input", os.path.join(data, "scene.h5"), "--camera", str(view)])
    found = re.findall(r"^\S+\.ply\s+([0-9.]+)", r.stdout, re.M)
    return float(found[0]) if r.returncode == 0 and found else None


def main():
    args = parse_test_arguments(__doc__)
    ms, work = args.manisweep, args.workdir
    data = fresh_small_pyramid(ms, work)
    if data is None:
        return 1
    scene = os.path.join(data, "scene.h5")
    first_model = os.path.join(data, "first.h5")
    r = run([ms, "convert", "-i", scene, "-o", first_model, "--keep-views", "0-2"])
    if not report(r.returncode == 0, "convert --keep-views 0-2: " + r.stderr[-500:].strip()):
        return 1
    first, full = os.path.join(work, "first"), os.path.join(work, "full")
    for model, out in ((first_model, first), (scene, full)):
        r = run([ms, "reconstruct", "-i", model, "-o", out, "--workers", "2"] + SWEEP)
        if not report(r.returncode == 0, f"reconstruct {os.path.basename(model)}"):
            print(r.stderr[-3000:])
            return 1
    before = digest(first)

    ext2 = os.path.join(work, "extended2")
    r = run([ms, "extend", "--run", first, "-i", scene, "-o", ext2, "--workers", "2"] + SWEEP)
    ok = report(r.returncode == 0 and "extension (iteration 4)" in r.stderr,
                "extend with 2 workers: " + (r.stderr.strip().splitlines() or [""])[-1])
    if r.returncode != 0:
        print(r.stderr[-3000:])
        return 1
    final = os.path.join(ext2, "final.ply")
    check = run([ms, "check-mesh", final])
    ok = report(check.returncode == 0, "check-mesh of the extended final.ply") and ok
    verdict = run([sys.executable, args.verdict, final])
    print(verdict.stdout.strip())
    ok = ok and verdict.returncode in (0, 77)

    # Views 3-5 are the new ones: the first run never saw what only they see. The extension
    # must see it better than the first run, and come near the run of all six at once (one
    # trajectory each on a tiny scene: the bounds leave room for another draw).
    good = True
    for view in (3, 4, 5):
        mae = {name: mae_from(ms, data, os.path.join(d, "final.ply"), view)
               for name, d in (("first", first), ("extended", ext2), ("full", full))}
        good = good and None not in mae.values() and mae["extended"] < mae["first"] and \
            mae["extended"] < 2 * mae["full"]
        print(f"     MAE from new view {view}: first run {mae['first']}, extended "
              f"{mae['extended']}, all six at once {mae['full']}")
    ok = report(good, "the extension sees the new views: MAE below the first run's, within 2x "
                      "of the run of all six") and ok

    ext1 = os.path.join(work, "extended1")
    r = run([ms, "extend", "--run", first, "-i", scene, "-o", ext1, "--workers", "1"] + SWEEP)
    same = r.returncode == 0 and digest(ext1).get("final.ply") == digest(ext2)["final.ply"]
    ok = report(same, "1 worker and 2 workers: the same final.ply") and ok

    cut = os.path.join(work, "extended_cut")
    cmd = [ms, "extend", "--run", first, "-i", scene, "-o", cut, "--workers", "2"] + SWEEP
    code = interrupt_after(cmd, "iteration 5 done")
    r = run(cmd + ["--resume"])
    same = r.returncode == 0 and digest(cut).get("final.ply") == digest(ext2)["final.ply"]
    ok = report(code == 130 and same,
                f"interrupted after iteration 5 (exit {code}), resumed: "
                f"{'the same' if same else 'another'} final.ply") and ok

    # kill -9 as the extension's points are inserted (its checkpoint being written or not):
    # --resume starts it again or goes on, to the same bytes.
    killed = os.path.join(work, "extended_killed")
    cmd = [ms, "extend", "--run", first, "-i", scene, "-o", killed, "--workers", "2"] + SWEEP
    p = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True,
                         start_new_session=True)
    for line in p.stderr:
        if "extension (iteration 4)" in line:
            os.killpg(p.pid, signal.SIGKILL)  # the workers too, as a lost node would
            break
    p.wait(timeout=60)
    r = run(cmd + ["--resume"])
    same = r.returncode == 0 and digest(killed).get("final.ply") == digest(ext2)["final.ply"]
    ok = report(same, f"kill -9 at the extension's insertion, --resume: "
                      f"{'the same' if same else 'another'} final.ply") and ok

    # A coordinator with --extend-run and two `worker` processes (a cluster's shape).
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        endpoint = f"tcp://127.0.0.1:{probe.getsockname()[1]}"
    cluster = os.path.join(work, "extended_cluster")
    coordinator = subprocess.Popen(
        [ms, "coordinator", "--extend-run", first, "-i", scene, "-o", cluster, "--bind",
         endpoint, "--max-iterations", "3", "--no-report"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = [subprocess.Popen([ms, "worker", "--connect", endpoint, "--kernel", "cpu"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
               for _ in range(2)]
    code = coordinator.wait(timeout=300)
    worker_codes = [w.wait(timeout=60) for w in workers]
    same = code == 0 and digest(cluster).get("final.ply") == digest(ext2)["final.ply"]
    ok = report(same and worker_codes == [0, 0],
                f"coordinator --extend-run with 2 worker processes (exit {code}, workers "
                f"{worker_codes}): {'the same' if same else 'another'} final.ply") and ok

    # The model as COLMAP text with camera 1 moved (its translation changed by 0.5 along x).
    moved_model = os.path.join(work, "moved")
    os.makedirs(os.path.join(moved_model, "sparse"))
    os.symlink(os.path.join(data, "images"), os.path.join(moved_model, "images"))
    r = run([ms, "convert", "-i", scene, "-o", os.path.join(moved_model, "sparse"), "--to",
             "colmap-text"])
    images_txt = os.path.join(moved_model, "sparse", "images.txt")
    lines = open(images_txt).read().split("\n")
    heads = [i for i, line in enumerate(lines) if line and not line.startswith("#")][::2]
    fields = lines[heads[1]].split()
    fields[5] = repr(float(fields[5]) + 0.5)
    lines[heads[1]] = " ".join(fields)
    open(images_txt, "w").write("\n".join(lines))
    moved_out = os.path.join(work, "moved_out")
    r = run([ms, "extend", "--run", first, "-i", moved_model, "-o", moved_out] + SWEEP)
    lines = [line for line in r.stderr.strip().splitlines() if line.strip()]
    refused = (r.returncode == 2 and lines and "camera 1 (0001.png) moved by 0.5" in lines[-1] and
               not os.path.exists(os.path.join(moved_out, "run.h5")))
    ok = report(refused, f"a moved camera: exit {r.returncode}: {lines[-1] if lines else ''}") and ok
    ok = report(digest(first) == before, "the first run's folder is unchanged") and ok
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
