#!/usr/bin/python3
"""The paper's baseline: screened Poisson surface reconstruction (Kazhdan), via Debian's
python3-open3d, on the same points the manifold is built from.

  poisson_baseline.py POINTS.ply OUT.ply [--depth 10]

Normals: estimated from the 30 nearest neighbours (PCA) and oriented towards the cameras that
see each point (the input PLY's normals hold the mean unit direction to those cameras).
Prints one JSON line: points, seconds (normals, poisson), peak RSS, output vertices/faces.
Run with Debian's /usr/bin/python3 (a pyenv python3 on PATH has no open3d).
"""
import argparse
import json
import resource
import sys
import time

try:
    import numpy as np
    import open3d as o3d
except ImportError as error:  # pragma: no cover - environment problem, reported clearly
    print(f"poisson_baseline: {error}; install python3-open3d (Debian)", file=sys.stderr)
    sys.exit(77)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("points")
    parser.add_argument("output")
    parser.add_argument("--depth", type=int, default=10, help="octree depth (paper: 11)")
    args = parser.parse_args()

    cloud = o3d.io.read_point_cloud(args.points)
    if not cloud.has_points():
        print(f"poisson_baseline: {args.points}: no points", file=sys.stderr)
        sys.exit(2)
    towards_cameras = np.asarray(cloud.normals).copy()
    start = time.perf_counter()
    cloud.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=30))
    normals = np.asarray(cloud.normals)
    flip = np.sum(normals * towards_cameras, axis=1) < 0
    normals[flip] *= -1
    cloud.normals = o3d.utility.Vector3dVector(normals)
    seconds_normals = time.perf_counter() - start

    start = time.perf_counter()
    mesh, _densities = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(
        cloud, depth=args.depth)
    seconds_poisson = time.perf_counter() - start
    o3d.io.write_triangle_mesh(args.output, mesh, write_ascii=False)
    print(json.dumps({
        "points": len(cloud.points),
        "depth": args.depth,
        "seconds_normals": round(seconds_normals, 3),
        "seconds_poisson": round(seconds_poisson, 3),
        "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        "vertices": len(mesh.vertices),
        "faces": len(mesh.triangles),
        "edge_manifold": bool(mesh.is_edge_manifold()),
        "vertex_manifold": bool(mesh.is_vertex_manifold()),
        "watertight": bool(mesh.is_watertight()),
    }))


if __name__ == "__main__":
    main()
