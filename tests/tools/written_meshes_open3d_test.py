#!/usr/bin/python3
"""The meshes `manisweep manifold` writes, loaded the way users load them.

For the real sparse models in ../shared/data (castle-P30, fountain-P11, templeSparseRing,
dinoSparseRing) and synthetic scenes (the blob, the downward pyramid, an open street), it builds
the initial manifold with the default options and requires
  - `manisweep check-mesh` VALID: a closed 2-manifold without self-intersections in exact
    arithmetic, and float-robust (no near-coincident vertices, no face pairs within 1e-6 of the
    diagonal, no double-precision intersections);
  - Open3D (Debian's python3-open3d): is_watertight() and no get_self_intersecting_triangles().
Exit 0: all clean; 1: one is not; 77: Open3D or the shared data is missing (CTest
SKIP_RETURN_CODE; the reason is printed).
"""
import argparse
import os
import subprocess
import sys

from open3d_import import open3d_or_skip


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--manisweep", required=True)
    parser.add_argument("--data", required=True, help="the shared data folder (../shared/data)")
    parser.add_argument("--verdict", required=True, help="tests/tools/open3d_verdict.py")
    parser.add_argument("--workdir", required=True)
    args = parser.parse_args()
    open3d_or_skip()
    real = ["castle-P30", "fountain-P11", "templeSparseRing", "dinoSparseRing"]
    missing = [d for d in real if not os.path.isdir(os.path.join(args.data, d, "sparse"))]
    if missing:
        print(f"SKIP: no sparse model of {', '.join(missing)} under {args.data} "
              "(the shared data is missing): the real-data cases cannot run")
        return 77
    os.makedirs(args.workdir, exist_ok=True)

    def run(cmd):
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            print(f"FAIL {' '.join(cmd)}: exit {done.returncode}\n{done.stdout}{done.stderr}")
        return done

    inputs = [(d, os.path.join(args.data, d, "sparse")) for d in real]
    for scene, extra in [("blob", []), ("pyramid-down", []), ("city", ["--views", "60"])]:
        folder = os.path.join(args.workdir, scene)
        if run([args.manisweep, "synth", scene, "--output", folder, "--no-images"] +
               extra).returncode != 0:
            return 1
        inputs.append((scene, os.path.join(folder, "scene.h5")))

    failures = []
    for name, scene in inputs:
        mesh = os.path.join(args.workdir, f"{name}_initial.ply")
        built = run([args.manisweep, "manifold", "--input", scene, "--output", mesh])
        if built.returncode != 0:
            failures.append(name)
            continue
        cleanup = [line.strip() for line in built.stdout.splitlines() if "float cleanup" in line]
        check = run([args.manisweep, "check-mesh", mesh])
        verdict = subprocess.run([sys.executable, args.verdict, mesh], capture_output=True,
                                 text=True)
        print(verdict.stdout.strip(), "|", cleanup[0] if cleanup else "")
        if check.returncode != 0 or verdict.returncode != 0:
            failures.append(name)
    print("all clean" if not failures else f"NOT clean: {', '.join(failures)}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
