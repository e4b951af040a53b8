#!/usr/bin/env python3
"""Writes an icosphere of radius 0.5 m subdivided N times (20 * 4^N triangles;
N = 5 gives 20,480) as an OBJ on stdout, wound outwards.

    python3 benches/colliders/make_sphere_mesh.py 5 > sphere.obj
"""
import math
import sys


def main(n):
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(n):
        cache, new = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = [(x + y) / 2 for x, y in zip(verts[a], verts[b])]
                r = math.sqrt(sum(x * x for x in m))
                verts.append(tuple(x / r for x in m))
                cache[key] = len(verts) - 1
            return cache[key]

        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    for v in verts:
        print("v %.6f %.6f %.6f" % tuple(0.5 * x for x in v))
    for a, b, c in faces:
        print("f %d %d %d" % (a + 1, b + 1, c + 1))


main(int(sys.argv[1]) if len(sys.argv) > 1 else 4)
