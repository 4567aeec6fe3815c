#!/usr/bin/env python3
"""Measures the copies a portal leaves in a mesh (docs/modulus-portals.md, bunny-ear-portals).

For each portal ball (centre, radius) it takes the mesh vertices inside the ball and above the
plane y = centre_y - below (the copy sits above the ear tip), and prints their extent and its
ratio to the whole mesh's extent. Reads binary little-endian PLY with float vertices and uchar-int
faces, as `quijibo portal` writes them.

  /usr/bin/python3 scripts/portal_copies.py RESULTS/portal/julia.ply \
      --portal -0.327 0.486 -0.298 --portal 0.001 0.518 -0.128 --radius 0.17 --below 0.07
"""
import argparse
import math
import struct


def read_ply_vertices(path):
    data = open(path, 'rb').read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    header = data[:end].decode().split('\n')
    if 'format binary_little_endian 1.0' not in header:
        raise SystemExit(path + ': expected a binary little-endian PLY')
    nv = int([l for l in header if l.startswith('element vertex')][0].split()[2])
    flat = struct.unpack_from('<%df' % (3 * nv), data, end)
    return [flat[3 * i:3 * i + 3] for i in range(nv)]


def extent(points):
    return [max(p[k] for p in points) - min(p[k] for p in points) for k in range(3)]


def fmt(values, digits):
    return '[' + ', '.join('%.*f' % (digits, x) for x in values) + ']'


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('ply')
    ap.add_argument('--portal', nargs=3, type=float, action='append', required=True, metavar=('X', 'Y', 'Z'))
    ap.add_argument('--radius', type=float, required=True)
    ap.add_argument('--below', type=float, default=0.0, help='keep vertices above centre_y - below')
    a = ap.parse_args()
    v = read_ply_vertices(a.ply)
    whole = extent(v)
    print('whole mesh extent', fmt(whole, 4))
    for c in a.portal:
        sel = [p for p in v if math.dist(p, c) < a.radius and p[1] > c[1] - a.below]
        if not sel:
            print('portal', c, ': no vertex')
            continue
        ext = extent(sel)
        print('portal', c, ':', len(sel), 'vertices, extent', fmt(ext, 4),
              'ratio to the whole', fmt([e / w for e, w in zip(ext, whole)], 3))


if __name__ == '__main__':
    main()
