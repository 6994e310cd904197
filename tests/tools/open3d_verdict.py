#!/usr/bin/python3
"""Open3D's verdict on meshes, as a user loading them would get it (Debian's python3-open3d):
for each PLY, is_watertight() and the number of get_self_intersecting_triangles() pairs.
Exit 0: every mesh watertight (or --open, for meshes with a boundary: edge- and vertex-manifold) and free of
self-intersections; 1: one is not; 77: Open3D is not importable (CTest SKIP_RETURN_CODE).
"""
import argparse
import sys

from open3d_import import open3d_or_skip


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--open", action="store_true",
                        help="meshes with a boundary: require edge- and vertex-manifold, not watertight")
    args = parser.parse_args()
    o3d = open3d_or_skip()
    ok = True
    for path in args.meshes:
        mesh = o3d.io.read_triangle_mesh(path)
        if len(mesh.triangles) == 0:
            print(f"FAIL {path}: Open3D read no triangles")
            ok = False
            continue
        pairs = len(mesh.get_self_intersecting_triangles())
        closed = (mesh.is_watertight() if not args.open else
                  mesh.is_edge_manifold(True) and mesh.is_vertex_manifold())
        good = closed and pairs == 0
        ok = ok and good
        what = "manifold" if args.open else "watertight"
        print(f"{'ok  ' if good else 'FAIL'} {path}: {len(mesh.vertices)} vertices, "
              f"{len(mesh.triangles)} faces, {what} {closed}, self-intersecting pairs {pairs}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
