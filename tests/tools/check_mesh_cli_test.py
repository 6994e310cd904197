#!/usr/bin/python3
"""End-to-end test of `manisweep check-mesh`: exit codes and JSON on files written here by hand
(not by manisweep's writers). Exit 0 when every case behaves as documented in
docs/reference/mesh-checker.md: 0 valid, 3 readable but not valid, 2 unreadable.
"""
import argparse
import json
import os
import struct
import subprocess
import sys

TET_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def obj(vertices, faces):
    lines = [f"v {x} {y} {z}" for x, y, z in vertices]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    return "\n".join(lines) + "\n"


def shifted(vertices, d):
    return [(x + d[0], y + d[1], z + d[2]) for x, y, z in vertices]


def two_tets(offset, share_vertex=False):
    if share_vertex:  # the second tetrahedron's vertex 0 is the first one's vertex 3
        v = TET_V + shifted(TET_V, offset)[1:]
        f = TET_F + [tuple(3 if i == 0 else i + 3 for i in t) for t in TET_F]
        return v, f
    return TET_V + shifted(TET_V, offset), TET_F + [tuple(i + 4 for i in t) for t in TET_F]


def apex_to_apex(gap):
    """Two tetrahedra whose right-angled corners are `gap` apart, back to back: exactly a valid
    closed 2-manifold, but two near-coincident vertices in floating point."""
    d = gap / 3 ** 0.5
    second = [(-d, -d, -d), (-1, 0, 0), (0, -1, 0), (0, 0, -1)]
    return TET_V + second, TET_F + [(4, 5, 6), (4, 7, 5), (4, 6, 7), (5, 7, 6)]


def binary_ply(vertices, faces):
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(vertices)}\nproperty float x\nproperty float y\n"
              f"property float z\nelement face {len(faces)}\n"
              "property list uchar int vertex_indices\nend_header\n").encode()
    body = b"".join(struct.pack("<3f", *v) for v in vertices)
    body += b"".join(struct.pack("<B3i", 3, *f) for f in faces)
    return header + body


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--manisweep", required=True)
    parser.add_argument("--workdir", required=True)
    args = parser.parse_args()
    os.makedirs(args.workdir, exist_ok=True)

    def write(name, content):
        path = os.path.join(args.workdir, name)
        with open(path, "wb") as f:
            f.write(content.encode() if isinstance(content, str) else content)
        return path

    tet_ply = binary_ply(TET_V, TET_F)
    files = {
        "tet.obj": obj(TET_V, TET_F),
        "tet.ply": tet_ply,
        "triangle.obj": obj(TET_V[:3], [(0, 1, 2)]),
        "bowtie.obj": obj(*two_tets((0, 0, 1), share_vertex=True)),
        "overlap.obj": obj(*two_tets((0.2, 0.2, 0.2))),
        "apart.obj": obj(*two_tets((5, 0, 0))),
        "flipped.obj": obj(TET_V, TET_F[:3] + [(1, 3, 2)]),
        "garbage.ply": "this is not a mesh\n",
        "truncated.ply": tet_ply[:-3],
        "badindex.obj": obj(TET_V, TET_F[:3] + [(1, 2, 7)]),
        "mesh.stl": "solid x\nendsolid x\n",
        "near.obj": obj(*apex_to_apex(3.5e-9)),  # 1e-9 of the bounding-box diagonal
    }
    paths = {name: write(name, content) for name, content in files.items()}
    json_path = os.path.join(args.workdir, "report.json")
    cases = [
        # (file, extra args, expected exit code, JSON checks)
        ("tet.obj", [], 0, {"valid": True, "genus": 0, "faces": 4}),
        ("tet.ply", [], 0, {"valid": True, "euler_characteristic": 2}),
        ("triangle.obj", [], 3, {"valid": False, "boundary_edges": 3}),
        ("triangle.obj", ["--allow-boundary"], 0, {"valid": True, "closed_manifold": False}),
        ("bowtie.obj", [], 3, {"non_manifold_vertices": 1, "components": 1}),
        ("bowtie.obj", ["--allow-boundary"], 3, {"valid": False}),
        ("overlap.obj", [], 3, {"valid": False, "components": 2}),
        ("overlap.obj", ["--no-self-intersections"], 0, {"self_intersections": None}),
        ("apart.obj", [], 0, {"components": 2, "genus": 0}),
        ("flipped.obj", [], 3, {"inconsistent_edges": 3}),
        ("garbage.ply", [], 2, None),
        ("truncated.ply", [], 2, None),
        ("badindex.obj", [], 2, None),
        ("mesh.stl", [], 2, None),
        ("missing.ply", [], 2, None),
        # Floating-point robustness: exactly valid, but two vertices 1e-9 (relative) apart.
        ("near.obj", [], 3, {"valid": False, "closed_manifold": True, "float_robust": False}),
        ("near.obj", ["--allow-float-issues"], 0, {"valid": True, "float_robust": False}),
        ("near.obj", ["--float-tolerance", "1e-12"], 0, {"valid": True, "float_robust": True}),
        ("near.obj", ["--float-tolerance-abs", "1e-6"], 3, {"valid": False}),
        ("tet.obj", [], 0, {"float_robust": True, "allow_float_issues": False}),
    ]
    failures = 0
    for name, extra, code, expect in cases:
        path = paths.get(name, os.path.join(args.workdir, name))
        if os.path.exists(json_path):
            os.remove(json_path)
        cmd = [args.manisweep, "check-mesh", path, "--json", json_path] + extra
        run = subprocess.run(cmd, capture_output=True, text=True)
        ok = run.returncode == code
        detail = f"exit {run.returncode}, expected {code}"
        if ok and code == 2:
            # One clear line naming the file.
            ok = path in run.stderr and "error" in run.stderr
            detail += "; stderr names the file" if ok else f"; stderr: {run.stderr!r}"
        if ok and expect is not None:
            with open(json_path) as f:
                report = json.load(f)
            bad = {k: report.get(k) for k, v in expect.items() if report.get(k) != v}
            ok = not bad
            detail += f"; JSON {'matches' if ok else 'differs: ' + repr(bad)}"
        print(f"{'ok  ' if ok else 'FAIL'} {name} {' '.join(extra)}: {detail}")
        if not ok:
            print(run.stdout, run.stderr)
            failures += 1
    # A bad option value: exit 2, one line naming the flag the user typed.
    for flag, value in (("--float-tolerance", "-1"), ("--float-tolerance-abs", "-0.5")):
        run = subprocess.run([args.manisweep, "check-mesh", paths["tet.obj"], flag, value],
                             capture_output=True, text=True)
        expected = f"{flag} must be >= 0, got {value}"
        ok = run.returncode == 2 and expected in run.stderr
        print(f"{'ok  ' if ok else 'FAIL'} {flag} {value}: exit {run.returncode}, "
              f"stderr {run.stderr.strip()!r}")
        failures += 0 if ok else 1
    # `--json -` prints only JSON on stdout.
    run = subprocess.run([args.manisweep, "check-mesh", paths["tet.obj"], "--json", "-"],
                         capture_output=True, text=True)
    try:
        ok = json.loads(run.stdout)["valid"] is True and "VALID" in run.stderr
    except ValueError:
        ok = False
    print(f"{'ok  ' if ok else 'FAIL'} --json - gives JSON alone on stdout")
    failures += 0 if ok else 1
    print(f"{failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
