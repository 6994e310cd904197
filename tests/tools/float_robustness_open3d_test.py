#!/usr/bin/python3
"""Cross-check of `manisweep check-mesh`'s floating-point robustness report against Open3D.

Writes meshes of its own (binary PLY, double coordinates, as manisweep writes them): clean closed
meshes, two vertices 1e-9 (relative) apart, non-adjacent faces nearly touching, crossing, and
spheres with nearly collapsed edges or noise. For each it runs check-mesh and Open3D (Debian's
python3-open3d) and checks that
  - the face pairs check-mesh finds intersecting in double precision are exactly the pairs of
    Open3D's get_self_intersecting_triangles(), so is_self_intersecting() agrees;
  - a mesh check-mesh calls valid is watertight for Open3D (is_watertight());
  - each hand-made case gets the verdicts docs/reference/mesh-checker.md describes.
Exit 0: all agree; 1: a disagreement; 77: Open3D is not importable (CTest SKIP_RETURN_CODE).
"""
import argparse
import json
import os
import subprocess
import sys

from open3d_import import open3d_or_skip

try:
    import numpy as np
except ImportError:  # Open3D needs numpy: open3d_or_skip() reports the missing module and skips
    np = None


# A rotation with no axis along the coordinate axes: Open3D's test scales each axis of a
# pair of triangles on its own, so axis-aligned near-coincidences look large to it.
ROTATION = [[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]]


def orient_outward(v, f, centre=None):
    c = v.mean(0) if centre is None else centre
    out = []
    for t in f:
        n = np.cross(v[t[1]] - v[t[0]], v[t[2]] - v[t[0]])
        out.append(list(t) if n.dot(v[list(t)].mean(0) - c) >= 0 else [t[0], t[2], t[1]])
    return out


def corner(apex, s):
    """Tetrahedron with its right-angled corner at apex, edges s along the axes."""
    apex = np.asarray(apex, float)
    v = np.array([apex, apex + [s, 0, 0], apex + [0, s, 0], apex + [0, 0, s]])
    return v, orient_outward(v, [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)])


def append(a, b):
    return np.vstack([a[0], b[0]]), a[1] + [[i + len(a[0]) for i in t] for t in b[1]]


def icosphere(subdivisions):
    g = (1 + 5 ** 0.5) / 2
    v = [(-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0), (0, -1, g), (0, 1, g),
         (0, -1, -g), (0, 1, -g), (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1)]
    v = [np.array(p) / np.linalg.norm(p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(subdivisions):
        mid = {}

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                mid[key] = len(v) - 1
            return mid[key]
        f = [t for a, b, c in f
             for t in ((a, m(a, b), m(c, a)), (b, m(b, c), m(a, b)), (c, m(c, a), m(b, c)),
                       (m(a, b), m(b, c), m(c, a)))]
    v = np.array(v)
    return v, orient_outward(v, f, np.zeros(3))


def rotated(mesh):
    return mesh[0] @ np.array(ROTATION).T, mesh[1]


def collapsed_sphere(gap, every):
    """An icosphere with some edges shortened to `gap` (one end moved along the edge to
    the other): near-coincident adjacent vertices and needle faces around them, as in the
    builder's output, still exactly a closed 2-manifold without self-intersections."""
    v, f = icosphere(3)
    v = v.copy()
    moved = set()
    for t in f[::every]:
        a, b = int(t[0]), int(t[1])
        if a in moved or b in moved:
            continue
        d = v[a] - v[b]
        v[a] = v[b] + gap * d / np.linalg.norm(d)
        moved.update((a, b))
    return v, f


def noisy_sphere(sigma, seed):
    v, f = icosphere(2)
    rng = np.random.default_rng(seed)
    return v + rng.normal(scale=sigma, size=v.shape), f


def write_ply(workdir, name, mesh):
    """WORKDIR/NAME as manisweep writes meshes: binary PLY, double coordinates."""
    v, f = mesh
    path = os.path.join(workdir, name)
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(v)}\nproperty double x\nproperty double y\n"
              f"property double z\nelement face {len(f)}\n"
              "property list uchar int vertex_indices\nend_header\n").encode()
    faces = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"] = 3
    faces["i"] = np.asarray(f, dtype=np.int32).reshape(-1, 3)
    with open(path, "wb") as out:
        out.write(header + np.asarray(v, "<f8").tobytes() + faces.tobytes())
    return path


def cases():
    """The hand-made meshes: (file, mesh, expected exact closed manifold, check-mesh valid,
    Open3D watertight); None: not asserted, only the agreement rules."""
    n = np.ones(3) / 3 ** 0.5
    e = 3.5e-9  # 1e-9 of the two corners' bounding-box diagonal
    two_corners = append(corner((0, 0, 0), 1), corner((0, 0, 0), -1))
    apex_near_plane = (two_corners[0].copy(), two_corners[1])
    apex_near_plane[0][4] = (e, e, -e)
    apex_to_apex = (two_corners[0].copy(), two_corners[1])
    apex_to_apex[0][4] = -e * n

    return [
        ("clean_icosphere.ply", rotated(icosphere(3)), True, True, True),
        ("clean_corners.ply", rotated(append(corner((0, 0, 0), 1), corner((2, 2, 2), 1))), True,
         True, True),
        # Exactly apart; Open3D's test calls the faces at the two apexes intersecting.
        ("near_vertices_crossing.ply", apex_near_plane, True, False, False),
        ("near_vertices_crossing_rotated.ply", rotated(apex_near_plane), True, False, False),
        # Exactly apart, back to back: Open3D sees nothing, the tolerance does.
        ("near_vertices_back_to_back.ply", rotated(apex_to_apex), True, False, True),
        # A corner's apex 1e-8 above another's slanted face, pointing away; then on it (exactly
        # touching or not after rounding); then through it.
        ("near_touching_faces.ply",
         rotated(append(corner((0, 0, 0), 1), corner(n / 3 ** 0.5 + 1e-8 * n, 1))), True, False,
         False),
        ("touching_faces.ply", rotated(append(corner((0, 0, 0), 1), corner(n / 3 ** 0.5, 1))),
         None, False, False),
        ("crossing_faces.ply",
         rotated(append(corner((0, 0, 0), 1), corner(n / 3 ** 0.5 - 0.1 * n, 1))), False, False,
         False),
        # Like the builder's final.ply: exactly valid, not watertight for Open3D.
        ("collapsed_sphere_1e-9.ply", rotated(collapsed_sphere(1e-9, 7)), True, False, False),
        ("collapsed_sphere_1e-12.ply", collapsed_sphere(1e-12, 5), True, False, False),
        ("collapsed_sphere_1e-3.ply", rotated(collapsed_sphere(1e-3, 7)), True, True, True),
        ("noisy_sphere.ply", noisy_sphere(0.15, 4), False, False, False),
    ]


def check_case(manisweep, o3d, path, want_exact, want_valid, want_watertight, check):
    """check-mesh's verdicts on the mesh at PATH against Open3D's and the expected ones."""
    name = os.path.basename(path)
    json_path = os.path.join(os.path.dirname(path), "report.json")
    run = subprocess.run([manisweep, "check-mesh", path, "--json", json_path,
                          "--max-examples", "1000000"], capture_output=True, text=True)
    if run.returncode not in (0, 3):
        check(f"{name}: check-mesh runs", False, f"exit {run.returncode}: {run.stderr}")
        return
    with open(json_path) as f:
        report = json.load(f)
    fr = report["float_robustness"]
    valid = report["valid"]
    check(f"{name}: exit code", run.returncode == (0 if valid else 3))

    o3 = o3d.io.read_triangle_mesh(path)
    o3d_pairs = {tuple(p) for p in np.asarray(o3.get_self_intersecting_triangles()).tolist()}
    ours = {tuple(p) for p in fr["examples"]["float_intersections"]}
    check(f"{name}: double-precision intersections = Open3D's", ours == o3d_pairs,
          f"(ours {len(ours)}, Open3D {len(o3d_pairs)}; only ours "
          f"{sorted(ours - o3d_pairs)[:5]}, only Open3D's {sorted(o3d_pairs - ours)[:5]})")
    check(f"{name}: is_self_intersecting agrees",
          (fr["float_intersections"] > 0) == o3.is_self_intersecting())
    watertight = o3.is_watertight()
    check(f"{name}: valid implies watertight", not valid or watertight,
          f"(valid {valid}, watertight {watertight})")
    if want_exact is not None:
        check(f"{name}: exact closed manifold is {want_exact}",
              report["closed_manifold"] == want_exact)
    if want_valid is not None:
        check(f"{name}: valid is {want_valid}", valid == want_valid,
              "" if valid == want_valid else f"(problems: {report['problems']})")
    if want_watertight is not None:
        check(f"{name}: Open3D watertight is {want_watertight}", watertight == want_watertight)
    print(f"     {name}: exact closed manifold {report['closed_manifold']}, "
          f"near vertices {fr['near_vertex_pairs']}, close pairs {fr['close_face_pairs']}, "
          f"float intersections {fr['float_intersections']} (Open3D {len(o3d_pairs)}), "
          f"watertight {watertight}")


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--manisweep", required=True)
    parser.add_argument("--workdir", required=True)
    args = parser.parse_args()
    o3d = open3d_or_skip()
    os.makedirs(args.workdir, exist_ok=True)
    failures = []

    def check(name, ok, detail=""):
        print(f"{'ok  ' if ok else 'FAIL'} {name} {detail}")
        if not ok:
            failures.append(name)

    for name, mesh, want_exact, want_valid, want_watertight in cases():
        check_case(args.manisweep, o3d, write_ply(args.workdir, name, mesh), want_exact,
                   want_valid, want_watertight, check)

    # The relaxing option: the near-coincident vertices are reported but accepted.
    path = os.path.join(args.workdir, "near_vertices_back_to_back.ply")
    run = subprocess.run([args.manisweep, "check-mesh", path, "--allow-float-issues", "--json",
                          "-"], capture_output=True, text=True)
    report = json.loads(run.stdout) if run.returncode in (0, 3) else {}
    check("--allow-float-issues accepts near vertices",
          run.returncode == 0 and report.get("valid") is True
          and report.get("float_robust") is False, f"exit {run.returncode}")

    if failures:
        print(f"{len(failures)} checks failed")
        return 1
    print("check-mesh's double-precision verdicts agree with Open3D", o3d.__version__)
    return 0


if __name__ == "__main__":
    sys.exit(main())
