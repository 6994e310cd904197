#!/usr/bin/env python3
"""Regenerates tests/corpus (run from the repository root): malformed scene files, each of
which must make its reader throw InputError naming the file (tests/corpus_test.cc).

Layout: tests/corpus/<format>/<case> where <format> is a name ParseSceneFormat knows (plus
"image" for PNG/JPEG headers). A case is a file (nvm, openmvg, middlebury, image) or a
directory (colmap-text, colmap-binary, strecha, bundler: bundle.out + list.txt). NVM, Bundler
and Middlebury cases use the images in tests/data/images (a.png, b.png 64x48; c.png 80x60).
Most cases are small edits of the valid fixtures in tests/data.
"""
import os
import shutil
import struct

DATA = os.path.join('tests', 'data')
OUT = os.path.join('tests', 'corpus')


def edit(text, old, new, count=1):
    """text with `old` replaced; fails loudly if the fixture changed and `old` is gone."""
    if old not in text:
        raise SystemExit('make_corpus: %r not found in the fixture' % old)
    return text.replace(old, new, count)


def read(path, mode='r'):
    with open(path, mode) as f:
        return f.read()


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'wb' if isinstance(data, bytes) else 'w') as f:
        f.write(data)


def colmap_text():
    base = {n: read(os.path.join(DATA, 'colmap', 'text', n)) for n in ('cameras.txt', 'images.txt', 'points3D.txt')}

    def case(name, **changes):
        files = dict(base)
        for key, value in changes.items():
            files[key.replace('_txt', '.txt')] = value
        for n, text in files.items():
            if text is not None:
                write(os.path.join(OUT, 'colmap-text', name, n), text)

    cams, imgs, pts = base['cameras.txt'], base['images.txt'], base['points3D.txt']
    case('truncated_images', images_txt=imgs[:imgs.index('a.png') - 3])
    case('truncated_points', points3D_txt=pts[:len(pts) // 2 + 7])
    case('wrong_param_count', cameras_txt=edit(cams, '2 PINHOLE 64 48 52.0 51.0 31.5 24.5', '2 PINHOLE 64 48 52.0 51.0 31.5'))
    case('nan_point', points3D_txt=edit(pts, '100 0.3 -0.2', '100 nan -0.2'))
    case('inf_translation', images_txt=edit(imgs, ' 4.1231056256176615 1 a.png', ' inf 1 a.png'))
    case('negative_camera_id', cameras_txt=edit(cams, '\n1 SIMPLE_PINHOLE', '\n-1 SIMPLE_PINHOLE'))
    case('huge_point2d_index', points3D_txt=pts + '200 0 0 0 1 1 1 0.5 7 4000000000\n')
    case('unknown_image_in_track', points3D_txt=pts + '77 1 2 3 1 2 3 0.5 77 0\n')
    case('wrong_type_width', cameras_txt=edit(cams, '3 SIMPLE_RADIAL 80 60', '3 SIMPLE_RADIAL eighty 60'))
    case('huge_width', cameras_txt=edit(cams, '3 SIMPLE_RADIAL 80 60', '3 SIMPLE_RADIAL 99999999999 60'))
    case('duplicate_image_id', images_txt=edit(imgs, '\n3 0.26', '\n7 0.26'))
    case('zero_quaternion', images_txt='1 0 0 0 0 0 0 1 1 d.png\n\n')
    case('unsupported_model_used', images_txt=edit(imgs, ' 6 f.png', ' 8 f.png'))
    case('missing_points_file', points3D_txt=None)
    case('points2d_not_triples', images_txt=edit(imgs, '10.25 11.5 -1 ', '10.25 11.5 ', 1))
    case('unknown_camera', images_txt=edit(imgs, ' 1 a.png', ' 55 a.png'))
    case('not_a_rotation_scale', cameras_txt=edit(cams, '1 SIMPLE_PINHOLE 64 48 50.0 32.0 24.0', '1 SIMPLE_PINHOLE 64 48 -50.0 32.0 24.0'))
    case('binary_garbage', cameras_txt='\x00\x01\x02\xff\xfe garbage \x7f\n')


def u64(v): return struct.pack('<Q', v)
def u32(v): return struct.pack('<I', v)
def i32(v): return struct.pack('<i', v)
def f64(v): return struct.pack('<d', v)


def colmap_binary():
    base = {n: read(os.path.join(DATA, 'colmap', 'bin', n), 'rb') for n in ('cameras.bin', 'images.bin', 'points3D.bin')}

    def case(name, **changes):
        files = dict(base)
        for key, value in changes.items():
            files[key.replace('_bin', '.bin')] = value
        for n, data in files.items():
            if data is not None:
                write(os.path.join(OUT, 'colmap-binary', name, n), data)

    cams, imgs, pts = base['cameras.bin'], base['images.bin'], base['points3D.bin']
    case('truncated_cameras', cameras_bin=cams[:len(cams) // 2])
    case('truncated_points', points3D_bin=pts[:-3])
    case('empty_images', images_bin=b'')
    case('huge_image_count', images_bin=u64(1 << 62) + imgs[8:])
    case('huge_points2d_count', images_bin=u64(1) + u32(1) + f64(1) + f64(0) * 3 + f64(0) * 3 + u32(1) +
         b'a.png\x00' + u64(1 << 40))
    case('huge_track_length', points3D_bin=u64(1) + u64(1) + f64(0) * 3 + b'\x01\x02\x03' + f64(0) + u64(1 << 61))
    case('nan_qvec', images_bin=u64(1) + u32(1) + f64(float('nan')) + f64(0) * 3 + f64(0) * 3 + u32(1) +
         b'a.png\x00' + u64(0))
    case('unknown_model_id', cameras_bin=u64(1) + u32(1) + i32(99) + u64(64) + u64(48) + f64(50) * 3)
    case('negative_model_id', cameras_bin=u64(1) + u32(1) + i32(-1) + u64(64) + u64(48) + f64(50) * 3)
    case('zero_width', cameras_bin=u64(1) + u32(1) + i32(0) + u64(0) + u64(48) + f64(50) * 3)
    case('trailing_garbage', points3D_bin=pts + b'\x00\x01')
    case('unterminated_name', images_bin=u64(1) + u32(1) + f64(1) + f64(0) * 6 + u32(1) + b'a.png')
    case('inf_point', points3D_bin=u64(1) + u64(1) + f64(float('inf')) + f64(0) * 2 + b'\x01\x02\x03' + f64(0) + u64(0))


def nvm():
    good = read(os.path.join(DATA, 'nvm', 'two_models.nvm'))
    lines = good.split('\n')
    cam_a = lines[3]

    def case(name, text):
        write(os.path.join(OUT, 'nvm', name + '.nvm'), text)

    case('empty', '')
    case('bad_header', edit(good, 'NVM_V3', 'NVM_V2', 1))
    case('truncated_cameras', good[:good.index('c.png') + 8])
    case('truncated_points', '\n'.join(lines[:9]) + '\n' + lines[9][:40])
    case('wrong_camera_count', edit(good, '\n3\n', '\n5\n', 1))
    case('nan_focal', edit(good, 'a.png 50.0 ', 'a.png nan ', 1))
    case('inf_centre', edit(good, cam_a, edit(cam_a, ' 3.5 ', ' inf ')))
    case('negative_count', 'NVM_V3\n\n-3\n')
    case('huge_count', 'NVM_V3\n\n2000000000\n' + cam_a + '\n')
    case('count_beyond_int', 'NVM_V3\n\n99999999999999999999999\n')
    case('measurement_camera_out_of_range', edit(good, '\n0.3 -0.2 0.1 255 0 10 3 0 ', '\n0.3 -0.2 0.1 255 0 10 3 7 '))
    case('colour_out_of_range', edit(good, ' 255 0 10 ', ' 300 0 10 ', 1))
    case('wrong_type_focal', edit(good, 'a.png 50.0 ', 'a.png fifty ', 1))
    case('zero_quaternion', 'NVM_V3\n\n1\na.png 50 0 0 0 0 0 0 0 0 0\n0\n')
    case('zero_focal', 'NVM_V3\n\n1\na.png 0 1 0 0 0 0 0 0 0 0\n0\n')
    case('bad_fixedk', 'NVM_V3 FixedK 52 31.5\n\n1\na.png 50 1 0 0 0 0 0 0 0 0\n0\n')
    case('folding_distortion', 'NVM_V3\n\n1\na.png 50 1 0 0 0 0 0 0 -5 0\n0\n')
    case('missing_image', 'NVM_V3\n\n1\nno_such_image.png 50 1 0 0 0 0 0 0 0 0\n0\n')
    case('corrupt_image', 'NVM_V3\n\n1\ncorrupt_image.png 50 1 0 0 0 0 0 0 0 0\n0\n')
    write(os.path.join(OUT, 'nvm', 'corrupt_image.png'), b'\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR\x00\x00')
    case('name_with_control_bytes', 'NVM_V3\n\n1\n\x01\x02\x1b[31m.png nan 1 0 0 0 0 0 0 0 0\n0\n')


def bundler():
    bundle = read(os.path.join(DATA, 'bundler', 'colmap.bundle.out'))
    names = read(os.path.join(DATA, 'bundler', 'colmap.list.txt'))
    lines = bundle.split('\n')

    def case(name, text, list_text=names):
        write(os.path.join(OUT, 'bundler', name, 'bundle.out'), text)
        if list_text is not None:
            write(os.path.join(OUT, 'bundler', name, 'list.txt'), list_text)

    case('bad_version', edit(bundle, 'v0.3', 'v0.4'))
    case('truncated', bundle[:len(bundle) // 2])
    case('list_count_mismatch', bundle, 'a.png\nb.png\n')
    case('missing_list', bundle, None)
    case('negative_focal', edit(bundle, '\n50 -0.05', '\n-50 -0.05', 1))
    case('nan_rotation', '\n'.join(lines[:3] + ['nan 0 0'] + lines[4:]))
    case('not_a_rotation', '\n'.join(lines[:3] + ['2 0 0', '0 2 0', '0 0 2'] + lines[6:]))
    case('camera_out_of_range', edit(bundle, '\n3 0 5 ', '\n3 9 5 ', 1))
    case('huge_point_count', '# Bundle file v0.3\n3 2000000000\n' + '\n'.join(lines[2:17]) + '\n')
    case('trailing_data', bundle + 'extra\n')
    case('colour_out_of_range', edit(bundle, '\n250 128 64\n', '\n250 256 64\n', 1))


def openmvg():
    good = read(os.path.join(DATA, 'openmvg', 'sfm_data.json'))

    def case(name, text):
        write(os.path.join(OUT, 'openmvg', name + '.json'), text)

    case('truncated', good[:len(good) // 2])
    case('not_an_object', '[1, 2, 3]\n')
    case('views_not_array', edit(edit(good, '"views": [', '"views": {"x": ['), '"intrinsics"', '}, "intrinsics"'))
    case('missing_filename', edit(good, '"filename": "b.png",', '', 1))
    case('wrong_type_width', edit(good, '"width": 64,', '"width": "64",', 1))
    case('negative_key', edit(good, '"key": 1,', '"key": -1,', 1))
    case('rotation_two_rows', edit(good, '"rotation": [', '"rotation": [[1, 0, 0], [0, 1, 0]], "x": [', 1))
    case('infinite_number', edit(good, '"focal_length": 50.5', '"focal_length": 1e999', 1))
    case('huge_integer', edit(good, '"id_pose": 0', '"id_pose": 99999999999999999999', 1))
    case('unknown_view_in_structure', edit(good, '"key": 3,\n', '"key": 77,\n', 1))
    case('deep_nesting', '[' * 100000)
    case('unknown_polymorphic_id', edit(good, '"polymorphic_id": 1,', '"polymorphic_id": 5,', 1))
    case('dangling_shared_pointer', edit(good, '"id": 2147483650,', '"id": 9,', 1))
    case('brown_wrong_count', edit(good, '"disto_t2": [', '"disto_t2": [1, ', 1))
    case('not_a_rotation', edit(good, '"rotation": [\n                    [', '"rotation": [\n                    [2, 0, 0], [0, 2, 0], [0, 0, 2]], "old": [[', 1))


def strecha():
    good = read(os.path.join(DATA, 'strecha', 'a.png.camera'))

    def case(name, text):
        write(os.path.join(OUT, 'strecha', name, 'a.png.camera'), text)

    numbers = good.split()
    case('truncated', ' '.join(numbers[:12]) + '\n')
    case('nan', edit(good, '50.5', 'nan', 1))
    case('extra_data', good + '1 2 3\n')
    case('zero_width', ' '.join(numbers[:-2]) + ' 0 48\n')
    case('negative_height', ' '.join(numbers[:-2]) + ' 64 -48\n')
    case('skew', edit(good, '50.5 0 ', '50.5 3 ', 1))
    case('distortion', edit(good, '\n0 0 0\n', '\n0.1 0 0\n', 1))
    case('wrong_type', edit(good, '51.5', 'abc', 1))
    case('not_a_rotation', ' '.join(numbers[:12] + ['3', '0', '0', '0', '3', '0', '0', '0', '3'] + numbers[21:]) + '\n')


def middlebury():
    good = read(os.path.join(DATA, 'middlebury', 'tiny_par.txt'))

    def case(name, text):
        write(os.path.join(OUT, 'middlebury', name + '_par.txt'), text)

    case('count_too_small', edit(good, '3\n', '2\n', 1))
    case('count_too_large', edit(good, '3\n', '4\n', 1))
    case('negative_count', edit(good, '3\n', '-3\n', 1))
    case('truncated', good[:len(good) // 2])
    case('nan', edit(good, '1520.400000', 'nan', 1))
    case('lower_triangular_k', edit(good, '1520.400000 0.000000 302.320000 0.000000', '1520.400000 0.000000 302.320000 5.000000', 1))
    case('missing_image', edit(good, 'c.png', 'zzz.png'))
    case('huge_count', '4000000000\n')


def image():
    png = read(os.path.join(DATA, 'images', 'a.png'), 'rb')
    write(os.path.join(OUT, 'image', 'truncated.png'), png[:20])
    write(os.path.join(OUT, 'image', 'bad_ihdr.png'), png[:12] + b'XXXX' + png[16:])
    write(os.path.join(OUT, 'image', 'zero_width.png'), png[:16] + b'\x00\x00\x00\x00' + png[20:])
    write(os.path.join(OUT, 'image', 'huge.png'), png[:16] + b'\x7f\xff\xff\xff' + png[20:])
    write(os.path.join(OUT, 'image', 'no_frame.jpg'), b'\xff\xd8\xff\xe0\x00\x04ab\xff\xda\x00\x02')
    write(os.path.join(OUT, 'image', 'truncated_segment.jpg'), b'\xff\xd8\xff\xe1\xff\xff' + b'x' * 100)
    write(os.path.join(OUT, 'image', 'short_length.jpg'), b'\xff\xd8\xff\xe0\x00\x01')
    write(os.path.join(OUT, 'image', 'dnl_height.jpg'), b'\xff\xd8\xff\xc0\x00\x0b\x08\x00\x00\x00\x40\x01\x01\x11\x00')
    write(os.path.join(OUT, 'image', 'text.png'), b'this is not an image at all\n')


def main():
    for sub in ('colmap-text', 'colmap-binary', 'nvm', 'bundler', 'openmvg', 'strecha', 'middlebury', 'image'):
        shutil.rmtree(os.path.join(OUT, sub), ignore_errors=True)
    colmap_text()
    colmap_binary()
    nvm()
    bundler()
    openmvg()
    strecha()
    middlebury()
    image()


if __name__ == '__main__':
    main()
