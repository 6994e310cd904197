#!/usr/bin/python3
"""Independent check that manisweep's PLY/OBJ files open in another library (Open3D).

Runs mesh_io_sample_writer to write meshes and point clouds (binary, ASCII, float coordinates,
OBJ) plus expected.json, reads each file with Open3D, and compares vertex and face counts,
coordinates, faces, colours and normals. Exit 0: all match; 1: a mismatch; 77: Open3D is not
importable (CTest SKIP_RETURN_CODE). Run with Debian's /usr/bin/python3 (python3-open3d).
"""
import argparse
import json
import os
import subprocess
import sys

from open3d_import import open3d_or_skip


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--writer", required=True, help="path of mesh_io_sample_writer")
    parser.add_argument("--workdir", required=True, help="folder for the written files")
    args = parser.parse_args()
    o3d = open3d_or_skip()
    import numpy as np

    subprocess.run([args.writer, args.workdir], check=True)
    with open(os.path.join(args.workdir, "expected.json")) as f:
        expected = json.load(f)
    failures = []

    def check(name, ok, detail=""):
        print(f"{'ok  ' if ok else 'FAIL'} {name} {detail}")
        if not ok:
            failures.append(name)

    em = expected["mesh"]
    ev, ef, ec = (np.array(em[k], dtype=np.float64) for k in ("vertices", "faces", "colors"))
    # (file, relative coordinate tolerance, vertex order kept). Open3D's OBJ reader (tinyobj)
    # renumbers vertices in order of first use, so OBJ is compared face by face, by position.
    cases = [("mesh_binary.ply", 0.0, True), ("mesh_ascii.ply", 0.0, True),
             ("mesh_binary_float.ply", 1e-6, True), ("mesh.obj", 1e-6, False)]
    for name, rel_tol, same_order in cases:
        path = os.path.join(args.workdir, name)
        mesh = o3d.io.read_triangle_mesh(path)
        v = np.asarray(mesh.vertices)
        t = np.asarray(mesh.triangles)
        c = np.asarray(mesh.vertex_colors)
        check(f"{name}: vertex count", v.shape == ev.shape, f"{v.shape} vs {ev.shape}")
        check(f"{name}: face count", t.shape == ef.shape, f"{t.shape} vs {ef.shape}")
        if v.shape != ev.shape or t.shape != ef.shape or c.shape != ec.shape:
            check(f"{name}: colours present", False, f"shape {c.shape} vs {ec.shape}")
            continue
        if same_order:
            got_v, want_v, got_c, want_c = v, ev, c, ec
            check(f"{name}: faces", np.array_equal(t, ef))
        else:  # corner positions and colours of every face, in face order
            got_v, want_v = v[t].reshape(-1, 3), ev[ef.astype(int)].reshape(-1, 3)
            got_c, want_c = c[t].reshape(-1, 3), ec[ef.astype(int)].reshape(-1, 3)
        err = np.max(np.abs(got_v - want_v) / (1.0 + np.abs(want_v)))
        check(f"{name}: coordinates", err <= rel_tol, f"max relative error {err:.3g}")
        err = np.max(np.abs(got_c * 255.0 - want_c))
        check(f"{name}: colours", err <= 0.51, f"max error {err:.3g} (of 255)")

    ep = expected["points"]
    pv, pn, pc = (np.array(ep[k], dtype=np.float64) for k in ("points", "normals", "colors"))
    for name in ("points_binary.ply", "points_ascii.ply"):
        cloud = o3d.io.read_point_cloud(os.path.join(args.workdir, name))
        p = np.asarray(cloud.points)
        n = np.asarray(cloud.normals)
        c = np.asarray(cloud.colors)
        check(f"{name}: point count", p.shape == pv.shape, f"{p.shape} vs {pv.shape}")
        if p.shape == pv.shape:
            check(f"{name}: coordinates", np.array_equal(p, pv))
        check(f"{name}: normals", n.shape == pn.shape and np.max(np.abs(n - pn)) < 1e-6)
        check(f"{name}: colours",
              c.shape == pc.shape and np.max(np.abs(c * 255.0 - pc)) <= 0.51)

    if failures:
        print(f"{len(failures)} checks failed")
        return 1
    print("all files read back identically in Open3D", o3d.__version__)
    return 0


if __name__ == "__main__":
    sys.exit(main())
