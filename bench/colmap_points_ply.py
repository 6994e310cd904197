#!/usr/bin/python3
"""The sparse points of a COLMAP text model as a PLY for bench/poisson_baseline.py: each point
with, as its normal, the mean unit direction to the cameras that see it.

  manisweep convert --input SCENE --output MODEL_DIR --to colmap-text
  colmap_points_ply.py MODEL_DIR POINTS.ply
  poisson_baseline.py POINTS.ply POISSON.ply
"""
import sys

import numpy as np


def camera_centres(path):
    centres = {}
    with open(path) as lines:
        for line in lines:
            parts = line.split()
            # Image lines have 10 fields; their 2D-point lines come in threes.
            if line.startswith("#") or len(parts) != 10:
                continue
            qw, qx, qy, qz, tx, ty, tz = map(float, parts[1:8])
            rotation = np.array([
                [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
                [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
                [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]])
            centres[int(parts[0])] = -rotation.T @ np.array([tx, ty, tz])
    return centres


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    model, output = sys.argv[1], sys.argv[2]
    centres = camera_centres(model + "/images.txt")
    points, normals = [], []
    with open(model + "/points3D.txt") as lines:
        for line in lines:
            parts = line.split()
            if line.startswith("#") or not parts:
                continue
            x = np.array(list(map(float, parts[1:4])))
            seen_from = [centres[int(i)] for i in parts[8::2] if int(i) in centres]
            if not seen_from:
                continue
            mean = np.mean([(c - x) / np.linalg.norm(c - x) for c in seen_from], axis=0)
            points.append(x)
            normals.append(mean / np.linalg.norm(mean))
    with open(output, "w") as out:
        out.write("ply\nformat ascii 1.0\nelement vertex %d\n" % len(points))
        out.write("".join("property float %s\n" % a for a in ("x", "y", "z", "nx", "ny", "nz")))
        out.write("end_header\n")
        for x, n in zip(points, normals):
            out.write("%.9g %.9g %.9g %.6g %.6g %.6g\n" % (*x, *n))
    print(f"{len(points)} points, {len(centres)} cameras -> {output}")


if __name__ == "__main__":
    main()
