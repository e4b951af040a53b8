#!/usr/bin/env python3
"""Writes table.obj: a square table as one closed triangle mesh, its top 1.2 m
square and 0.05 m thick with its upper face at y = 0, on four legs 0.06 m square
reaching down to y = -0.75, every box wound so that its normals point out.

    python3 assets/meshes/make_table.py > assets/meshes/table.obj
"""

TOP_HALF, TOP_THICK = 0.6, 0.05
LEG_HALF, LEG_AT, FLOOR = 0.03, 0.52, -0.75


def box(lo, hi, verts, faces):
    base = len(verts)
    for z in (lo[2], hi[2]):
        for y in (lo[1], hi[1]):
            for x in (lo[0], hi[0]):
                verts.append((x, y, z))
    # Corner k = x + 2 y + 4 z (0 low, 1 high); quads wound outwards.
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    for a, b, c, d in quads:
        faces.append((base + a, base + b, base + c))
        faces.append((base + a, base + c, base + d))


def main():
    verts, faces = [], []
    box((-TOP_HALF, -TOP_THICK, -TOP_HALF), (TOP_HALF, 0.0, TOP_HALF), verts, faces)
    for sx in (-1, 1):
        for sz in (-1, 1):
            cx, cz = sx * LEG_AT, sz * LEG_AT
            box((cx - LEG_HALF, FLOOR, cz - LEG_HALF), (cx + LEG_HALF, -TOP_THICK, cz + LEG_HALF), verts, faces)
    print("# A table: a 1.2 m square top on four legs (make_table.py)")
    for x, y, z in verts:
        print(f"v {x:.4f} {y:.4f} {z:.4f}")
    for a, b, c in faces:
        print(f"f {a + 1} {b + 1} {c + 1}")


main()
