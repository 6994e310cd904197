#!/usr/bin/env python3
"""Regenerates the small scene fixtures in tests/data (run from the repository root).

The fixtures are written here, independently of manisweep's writers, so every importer is
tested on files it did not write:
  images/            tiny grey PNGs whose headers give the view sizes
  colmap/text/       COLMAP text model using every supported camera model (+ an unused fisheye)
  colmap/bin/        the same model converted to binary by COLMAP (`colmap model_converter`)
  colmap/export/     a centred SIMPLE_RADIAL/RADIAL/SIMPLE_PINHOLE model, the source of ...
  bundler/           ... COLMAP's own Bundler export of it (colmap.bundle.out, colmap.list.txt)
  nvm/               NVM files as VisualSFM writes them (measurements from the image centre,
                     VisualSFM's radial model), incl. two models, NVM_V3_R9T and FixedK
  openmvg/           an openMVG sfm_data.json with cereal's polymorphic/shared-pointer ids
  strecha/           two Strecha .camera files
  middlebury/        a Middlebury *_par.txt
Needs python3 and, for colmap/bin and bundler/, Debian's `colmap`. Pure Python, no numpy.
"""
import json
import math
import os
import struct
import subprocess
import zlib

ROOT = os.path.join('tests', 'data')


def f32(x):
    return struct.unpack('<f', struct.pack('<f', x))[0]


def num(x):
    return repr(float(x))


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'w') as f:
        f.write(text)


def png(path, width, height):
    raw = b''.join(b'\x00' + bytes(((x + y) * 4) & 0xFF for x in range(width)) for y in range(height))
    def chunk(kind, data):
        return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data))
    data = (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, 8, 0, 0, 0, 0)) +
            chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'wb') as f:
        f.write(data)


# ---- small linear algebra ----------------------------------------------------------------------
def sub(a, b): return [a[i] - b[i] for i in range(3)]
def dot(a, b): return sum(a[i] * b[i] for i in range(3))
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def norm(a): return math.sqrt(dot(a, a))
def unit(a): n = norm(a); return [v / n for v in a]
def matvec(R, v): return [dot(R[i], v) for i in range(3)]
def transpose(R): return [[R[j][i] for j in range(3)] for i in range(3)]


def look_at(centre, target=(0.0, 0.0, 0.0)):
    """World->camera rotation, camera looking at target, x right, y down (world z up)."""
    z = unit(sub(target, centre))
    x = unit(cross(z, [0.0, 0.0, 1.0]))
    y = cross(z, x)
    return [x, y, z]


def quaternion(R):
    """(w, x, y, z) with w >= 0 of a rotation matrix."""
    tr = R[0][0] + R[1][1] + R[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = [0.25 * s, (R[2][1] - R[1][2]) / s, (R[0][2] - R[2][0]) / s, (R[1][0] - R[0][1]) / s]
    else:
        i = max(range(3), key=lambda k: R[k][k])
        j, k = (i + 1) % 3, (i + 2) % 3
        s = math.sqrt(1.0 + R[i][i] - R[j][j] - R[k][k]) * 2
        q = [0.0] * 4
        q[0] = (R[k][j] - R[j][k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (R[j][i] + R[i][j]) / s
        q[1 + k] = (R[k][i] + R[i][k]) / s
    if q[0] < 0:
        q = [-v for v in q]
    return q


def rotation(q):
    w, x, y, z = q
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def opencv_distort(n, k1=0, k2=0, p1=0, p2=0, k3=0):
    x, y = n
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    return [x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
            y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y]


def visualsfm_measured(n_u, k):
    """The measured (distorted) normalised point m with m (1 + k |m|^2) = n_u (VisualSFM)."""
    r_u = math.hypot(*n_u)
    if k == 0 or r_u == 0:
        return list(n_u)
    r = r_u
    for _ in range(100):  # Newton on r (1 + k r^2) = r_u
        r -= (r * (1 + k * r * r) - r_u) / (1 + 3 * k * r * r)
    return [n_u[0] * r / r_u, n_u[1] * r / r_u]


POINTS = [[0.3, -0.2, 0.1], [-0.25, 0.15, 0.3], [0.1, 0.35, -0.2], [-0.3, -0.3, 0.0],
          [0.0, 0.05, 0.4], [0.2, 0.2, 0.25]]
COLORS = [[255, 0, 10], [12, 200, 30], [7, 8, 9], [100, 110, 120], [0, 0, 0], [250, 128, 64]]


def camera_centre(angle_deg, radius=4.0, height=1.0):
    a = math.radians(angle_deg)
    return [radius * math.cos(a), radius * math.sin(a), height]


# ---- COLMAP text model with every supported model ------------------------------------------
def colmap_main():
    cameras = [  # id, model, w, h, params, distortion kwargs, (fx, fy, cx, cy)
        (1, 'SIMPLE_PINHOLE', 64, 48, [50, 32, 24]),
        (2, 'PINHOLE', 64, 48, [52, 51, 31.5, 24.5]),
        (3, 'SIMPLE_RADIAL', 80, 60, [55, 40, 30, -0.1]),
        (4, 'RADIAL', 64, 48, [50, 32, 24, -0.1, 0.02]),
        (5, 'OPENCV', 64, 48, [50, 51, 32, 24, -0.1, 0.01, 0.001, -0.002]),
        (6, 'FULL_OPENCV', 64, 48, [50, 51, 32, 24, -0.1, 0.01, 0.001, -0.002, 0.003, 0, 0, 0]),
        (8, 'OPENCV_FISHEYE', 64, 48, [50, 50, 32, 24, 0.1, 0, 0, 0]),  # unused by any image
    ]

    def project(cam, R, t, X):
        _, model, w, h, p = cam
        c = [a + b for a, b in zip(matvec(R, X), t)]
        n = [c[0] / c[2], c[1] / c[2]]
        if model == 'SIMPLE_PINHOLE': fx = fy = p[0]; cx, cy = p[1], p[2]; d = {}
        elif model == 'PINHOLE': fx, fy, cx, cy = p; d = {}
        elif model == 'SIMPLE_RADIAL': fx = fy = p[0]; cx, cy = p[1], p[2]; d = dict(k1=p[3])
        elif model == 'RADIAL': fx = fy = p[0]; cx, cy = p[1], p[2]; d = dict(k1=p[3], k2=p[4])
        else:
            fx, fy, cx, cy = p[:4]
            d = dict(k1=p[4], k2=p[5], p1=p[6], p2=p[7])
            if model == 'FULL_OPENCV': d['k3'] = p[8]
        m = opencv_distort(n, **d)
        return [f32(fx * m[0] + cx), f32(fy * m[1] + cy)]

    # (image id, camera id, name, angle); listed in this (unsorted) order.
    images = [(7, 1, 'a.png', 0), (3, 2, 'b.png', 40), (5, 3, 'c.png', 80), (1, 4, 'd.png', 120),
              (2, 5, 'e.png', 160), (9, 6, 'f.png', 200)]
    point_ids = [100, 42, 7, 13, 55, 8]
    cam_by_id = {c[0]: c for c in cameras}
    poses = {}
    points2d = {img[0]: [] for img in images}
    tracks = {pid: [] for pid in point_ids}
    for image_id, cam_id, name, angle in images:
        C = camera_centre(angle)
        R = look_at(C)
        q = quaternion(R)
        R = rotation(q)  # what a reader reconstructs from the written quaternion
        t = [-v for v in matvec(R, C)]
        poses[image_id] = (q, t)
        if image_id == 9:
            continue  # an image without any POINTS2D
        points2d[image_id].append((10.25, 11.5, -1))  # an unmatched feature
        for pid, X in zip(point_ids, POINTS):
            xy = project(cam_by_id[cam_id], R, t, X)
            tracks[pid].append((image_id, len(points2d[image_id])))
            points2d[image_id].append((xy[0], xy[1], pid))
    # Point 42 seen twice in image 3: a second feature 1.5 px away, listed after the first.
    first = [e for e in points2d[3] if e[2] == 42][0]
    tracks[42].append((3, len(points2d[3])))
    points2d[3].append((f32(first[0] + 1.5), first[1], 42))

    out = ['# Camera list with one line of data per camera:',
           '#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]', '# Number of cameras: 7']
    for cid, model, w, h, p in cameras:
        out.append(' '.join([str(cid), model, str(w), str(h)] + [num(v) for v in p]))
    write(os.path.join(ROOT, 'colmap', 'text', 'cameras.txt'), '\n'.join(out) + '\n')

    out = ['# Image list with two lines of data per image:',
           '#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME',
           '#   POINTS2D[] as (X, Y, POINT3D_ID)', '# Number of images: 6']
    for image_id, cam_id, name, _ in images:
        q, t = poses[image_id]
        out.append(' '.join([str(image_id)] + [num(v) for v in q + t] + [str(cam_id), name]))
        out.append(' '.join('%s %s %d' % (num(x), num(y), pid) for x, y, pid in points2d[image_id]))
    write(os.path.join(ROOT, 'colmap', 'text', 'images.txt'), '\n'.join(out) + '\n')

    out = ['# 3D point list with one line of data per point:',
           '#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)',
           '# Number of points: 6']
    for pid, X, rgb in zip(point_ids, POINTS, COLORS):
        track = ' '.join('%d %d' % e for e in tracks[pid])
        out.append(' '.join([str(pid)] + [num(v) for v in X] + [str(c) for c in rgb] + ['0.5', track]))
    write(os.path.join(ROOT, 'colmap', 'text', 'points3D.txt'), '\n'.join(out) + '\n')


# ---- a centred model for COLMAP's Bundler export --------------------------------------------
def colmap_export_source():
    cameras = [(1, 'SIMPLE_RADIAL', 64, 48, [50, 32, 24, -0.05]),
               (2, 'RADIAL', 64, 48, [52, 32, 24, 0.03, -0.01]),
               (3, 'SIMPLE_PINHOLE', 80, 60, [55, 40, 30])]
    images = [(1, 1, 'a.png', 10), (2, 2, 'b.png', 50), (3, 3, 'c.png', 95)]
    out_c = ['# cameras'] + [' '.join([str(c[0]), c[1], str(c[2]), str(c[3])] + [num(v) for v in c[4]]) for c in cameras]
    out_i, out_p = ['# images'], ['# points']
    obs = {1: [], 2: [], 3: []}
    tracks = {i: [] for i in range(len(POINTS))}
    for image_id, cam_id, name, angle in images:
        cam = cameras[cam_id - 1]
        C = camera_centre(angle)
        q = quaternion(look_at(C))
        R = rotation(q)
        t = [-v for v in matvec(R, C)]
        out_i.append(' '.join([str(image_id)] + [num(v) for v in q + t] + [str(cam_id), name]))
        for pi, X in enumerate(POINTS):
            if image_id == 3 and pi == 4:
                continue  # not every point in every image
            c = [a + b for a, b in zip(matvec(R, X), t)]
            n = [c[0] / c[2], c[1] / c[2]]
            p = cam[4]
            d = dict(k1=p[3]) if cam[1] == 'SIMPLE_RADIAL' else dict(k1=p[3], k2=p[4]) if cam[1] == 'RADIAL' else {}
            m = opencv_distort(n, **d)
            tracks[pi].append((image_id, len(obs[image_id])))
            obs[image_id].append((f32(p[0] * m[0] + p[1]), f32(p[0] * m[1] + p[2]), pi + 1))
        out_i.append(' '.join('%s %s %d' % (num(x), num(y), pid) for x, y, pid in obs[image_id]))
    for pi, (X, rgb) in enumerate(zip(POINTS, COLORS)):
        out_p.append(' '.join([str(pi + 1)] + [num(v) for v in X] + [str(c) for c in rgb] + ['0.25'] +
                              ['%d %d' % e for e in tracks[pi]]))
    base = os.path.join(ROOT, 'colmap', 'export')
    write(os.path.join(base, 'cameras.txt'), '\n'.join(out_c) + '\n')
    write(os.path.join(base, 'images.txt'), '\n'.join(out_i) + '\n')
    write(os.path.join(base, 'points3D.txt'), '\n'.join(out_p) + '\n')


# ---- NVM as VisualSFM writes it ---------------------------------------------------------------
SIZES = {'a.png': (64, 48), 'b.png': (64, 48), 'c.png': (80, 60), 'd.png': (64, 48)}


def nvm_model(views, points, r9t=False, fixed=None):
    """views: (name, f, angle, k); points: indices into POINTS. Returns the model's text."""
    lines = [str(len(views))]
    cams = []
    for name, f, angle, k in views:
        C = camera_centre(angle, radius=3.5, height=0.5)
        q = quaternion(look_at(C))
        R = rotation(q)
        t = [-v for v in matvec(R, C)]
        cams.append((name, f, R, t, k))
        if r9t:
            vals = [v for row in R for v in row] + t
        else:
            vals = q + C
        lines.append(' '.join([name, num(f)] + [num(v) for v in vals] + [num(k), '0']))
    lines.append('')
    lines.append(str(len(points)))
    for pi in points:
        X = POINTS[pi]
        meas = []
        for ci, (name, f, R, t, k) in enumerate(cams):
            c = [a + b for a, b in zip(matvec(R, X), t)]
            n = [c[0] / c[2], c[1] / c[2]]
            if fixed:
                fx, cx, fy, cy = fixed
                meas.append('%d %d %s %s' % (ci, pi, num(fx * n[0] + cx - cx), num(fy * n[1] + cy - cy)))
            else:
                m = visualsfm_measured(n, k)
                meas.append('%d %d %s %s' % (ci, pi, num(f * m[0]), num(f * m[1])))
        lines.append(' '.join([num(v) for v in X] + [str(c) for c in COLORS[pi]] +
                              [str(len(meas))] + meas))
    return '\n'.join(lines) + '\n'


def nvm_files():
    trailer = ('\n0\n\n#the last part of NVM file points to the PLY files\n'
               '#the first number is the number of associated PLY files\n'
               '#each following number gives a model-index that has PLY\n0\n')
    model0 = nvm_model([('a.png', 50.0, 0, 0.0), ('b.png', 52.0, 45, 0.0), ('c.png', 55.0, 90, -0.07)],
                       [0, 1, 2, 3, 4])
    model1 = nvm_model([('b.png', 60.0, 200, 0.0), ('a.png', 61.0, 240, 0.0)], [5, 0])
    write(os.path.join(ROOT, 'nvm', 'two_models.nvm'), 'NVM_V3\n\n' + model0 + '\n' + model1 + trailer)
    write(os.path.join(ROOT, 'nvm', 'r9t.nvm'),
          'NVM_V3_R9T\n\n' + nvm_model([('a.png', 50.0, 10, 0.0), ('d.png', 53.0, 70, 0.0)], [0, 1], r9t=True))
    write(os.path.join(ROOT, 'nvm', 'fixedk.nvm'),
          'NVM_V3 FixedK 52 31.5 51 24.5 0\n\n' +
          nvm_model([('a.png', 52.0, 10, 0.0), ('b.png', 52.0, 70, 0.0)], [0, 1, 2], fixed=(52, 31.5, 51, 24.5)))


# ---- openMVG ------------------------------------------------------------------------------------
def openmvg():
    ptr = [0]

    def pointer(data):
        ptr[0] += 1
        return {'id': 2147483648 + ptr[0], 'data': data}

    views = []
    for key, (name, intrinsic, pose) in enumerate([('a.png', 0, 0), ('b.png', 1, 1), ('c.png', 2, 2),
                                                   ('d.png', 0, 4294967295)]):
        w, h = SIZES[name]
        views.append({'key': key, 'value': {'polymorphic_id': 1073741824, 'ptr_wrapper': pointer({
            'local_path': '', 'filename': name, 'width': w, 'height': h, 'id_view': key,
            'id_intrinsic': intrinsic, 'id_pose': pose})}})
    intrinsics = [
        {'key': 0, 'value': {'polymorphic_id': 2147483649, 'polymorphic_name': 'pinhole_radial_k3',
                             'ptr_wrapper': pointer({'width': 64, 'height': 48, 'focal_length': 50.5,
                                                     'principal_point': [32.25, 23.75],
                                                     'disto_k3': [-0.1, 0.02, -0.003]})}},
        {'key': 1, 'value': {'polymorphic_id': 1,  # the type registered above
                             'ptr_wrapper': pointer({'width': 64, 'height': 48, 'focal_length': 52.0,
                                                     'principal_point': [32.0, 24.0],
                                                     'disto_k3': [0.0, 0.0, 0.0]})}},
        {'key': 2, 'value': {'polymorphic_id': 2147483650, 'polymorphic_name': 'pinhole_brown_t2',
                             'ptr_wrapper': pointer({'width': 80, 'height': 60, 'focal_length': 55.0,
                                                     'principal_point': [40.0, 30.0],
                                                     'disto_t2': [-0.05, 0.01, 0.0, 0.001, -0.002]})}},
    ]
    extrinsics = []
    for key, angle in enumerate([0, 60, 120]):
        C = camera_centre(angle)
        extrinsics.append({'key': key, 'value': {'rotation': look_at(C), 'center': C}})
    structure = []
    for key, X in enumerate(POINTS[:3]):
        obs = [{'key': v, 'value': {'id_feat': 10 * key + v, 'x': [10.0 + key + v, 20.5 - v]}} for v in (2, 0, 3)]
        structure.append({'key': key, 'value': {'X': X, 'observations': obs}})
    doc = {'sfm_data_version': '0.3', 'root_path': '/nonexistent/images', 'views': views,
           'intrinsics': intrinsics, 'extrinsics': extrinsics, 'structure': structure,
           'control_points': []}
    write(os.path.join(ROOT, 'openmvg', 'sfm_data.json'), json.dumps(doc, indent=4) + '\n')


def strecha_and_middlebury():
    for name, angle, K in [('a.png', 0, (50.5, 51.5, 31.75, 24.25)), ('b.png', 70, (50.0, 50.0, 32.0, 24.0))]:
        fx, fy, cx, cy = K
        C = camera_centre(angle, radius=5.0, height=2.0)
        Rcw = transpose(look_at(C))  # camera -> world
        text = '%s 0 %s \n0 %s %s \n0 0 1 \n0 0 0\n' % (num(fx), num(cx), num(fy), num(cy))
        text += ''.join(' '.join(num(v) for v in row) + ' \n' for row in Rcw)
        text += ' '.join(num(v) for v in C) + ' \n%d %d\n' % SIZES[name]
        write(os.path.join(ROOT, 'strecha', name + '.camera'), text)
    lines = ['3']
    for name, angle in [('a.png', 20), ('b.png', 140), ('c.png', 260)]:
        C = camera_centre(angle, radius=0.6, height=0.1)
        R = look_at(C)
        t = [-v for v in matvec(R, C)]
        w, h = SIZES[name]
        K = [1520.4, 0, 302.32, 0, 1525.9, 246.87, 0, 0, 1] if name != 'c.png' else [1600, 0, w / 2, 0, 1600, h / 2, 0, 0, 1]
        lines.append(' '.join([name] + ['%.6f' % v for v in K] + ['%.20f' % v for row in R for v in row] +
                              ['%.12g' % v for v in t]))
    write(os.path.join(ROOT, 'middlebury', 'tiny_par.txt'), '\n'.join(lines) + '\n')


def main():
    for name, (w, h) in SIZES.items():
        png(os.path.join(ROOT, 'images', name), w, h)
    colmap_main()
    colmap_export_source()
    nvm_files()
    openmvg()
    strecha_and_middlebury()
    os.makedirs(os.path.join(ROOT, 'colmap', 'bin'), exist_ok=True)
    subprocess.run(['colmap', 'model_converter', '--input_path', os.path.join(ROOT, 'colmap', 'text'),
                    '--output_path', os.path.join(ROOT, 'colmap', 'bin'), '--output_type', 'BIN'],
                   check=True, stdout=subprocess.DEVNULL)
    os.makedirs(os.path.join(ROOT, 'bundler'), exist_ok=True)
    subprocess.run(['colmap', 'model_converter', '--input_path', os.path.join(ROOT, 'colmap', 'export'),
                    '--output_path', os.path.join(ROOT, 'bundler', 'colmap'), '--output_type', 'Bundler'],
                   check=True, stdout=subprocess.DEVNULL)


if __name__ == '__main__':
    main()
