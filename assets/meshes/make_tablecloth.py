#!/usr/bin/env python3
"""Writes tablecloth.obj: a round tablecloth of radius 0.9 m lying flat in the
x-z plane at y = 0, centred on the origin, triangulated in 24 rings of 6k
vertices (ring k at radius k * 0.0375 m), with texture coordinates and faces
wound so that their normals point up (+y).

    python3 assets/meshes/make_tablecloth.py > assets/meshes/tablecloth.obj
"""
import math

RADIUS = 0.9
RINGS = 24


def main():
    rings = [[0]]  # vertex numbers (0-based) of each ring
    points = [(0.0, 0.0)]
    for k in range(1, RINGS + 1):
        n, r = 6 * k, RADIUS * k / RINGS
        ring = []
        for j in range(n):
            a = 2 * math.pi * j / n
            ring.append(len(points))
            points.append((r * math.cos(a), -r * math.sin(a)))
        rings.append(ring)
    faces = []
    for inner, outer in zip(rings, rings[1:]):
        ni, no = len(inner), len(outer)
        i = o = 0
        while o < no or (ni > 1 and i < ni):
            advance_outer = o < no and (ni == 1 or i >= ni or (o + 1) / no <= (i + 1) / ni)
            if advance_outer:
                faces.append((inner[i % ni], outer[o % no], outer[(o + 1) % no]))
                o += 1
            else:
                faces.append((inner[i % ni], outer[o % no], inner[(i + 1) % ni]))
                i += 1
    print("# A round tablecloth, radius %g m, %d rings: %d vertices, %d triangles." % (RADIUS, RINGS, len(points), len(faces)))
    print("# Made by make_tablecloth.py beside this file.")
    for x, z in points:
        print("v %.6f %.6f %.6f" % (x, 0.0, z))
    for x, z in points:
        print("vt %.6f %.6f" % (0.5 + x / (2 * RADIUS), 0.5 - z / (2 * RADIUS)))
    for a, b, c in faces:
        print("f %d/%d %d/%d %d/%d" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1))


main()
