#!/usr/bin/env python3
"""Writes the binary STL parts the placement tests lift (dimensions in mm, as a CAD export would).

Run from this directory: python3 make_meshes.py. Each part is a closed, outward-wound prism or
stack of prisms; the origin sits at a base corner, not at the part's centre, as exported parts do.
"""
import math
import struct


def write_stl(path, triangles):
    with open(path, "wb") as out:
        out.write(b"graspbed test part".ljust(80, b"\0"))
        out.write(struct.pack("<I", len(triangles)))
        for triangle in triangles:
            out.write(struct.pack("<3f", 0.0, 0.0, 0.0))
            for vertex in triangle:
                out.write(struct.pack("<3f", *vertex))
            out.write(b"\0\0")


def prism(polygon, z0, z1):
    """A prism over the counter-clockwise polygon [(x, y)] from z0 to z1."""
    triangles = []
    for i in range(1, len(polygon) - 1):
        a, b, c = polygon[0], polygon[i], polygon[i + 1]
        triangles.append([(a[0], a[1], z0), (c[0], c[1], z0), (b[0], b[1], z0)])
        triangles.append([(a[0], a[1], z1), (b[0], b[1], z1), (c[0], c[1], z1)])
    for i, a in enumerate(polygon):
        b = polygon[(i + 1) % len(polygon)]
        triangles.append([(a[0], a[1], z0), (b[0], b[1], z0), (b[0], b[1], z1)])
        triangles.append([(a[0], a[1], z0), (b[0], b[1], z1), (a[0], a[1], z1)])
    return triangles


def regular(sides, across_flats, cx, cy):
    radius = 0.5 * across_flats / math.cos(math.pi / sides)
    return [(cx + radius * math.cos(math.pi / sides + 2 * math.pi * k / sides),
             cy + radius * math.sin(math.pi / sides + 2 * math.pi * k / sides)) for k in range(sides)]


# The default scenario's box as a user's part: 50 x 50 x 80 mm.
write_stl("block_50x50x80.stl", prism([(0, 0), (50, 0), (50, 50), (0, 50)], 0, 80))
# A hexagonal bar, 45 mm across flats, 60 mm tall.
write_stl("hex_bar_45x60.stl", prism(regular(6, 45, 30, 30), 0, 60))
# A squat puck, 40 x 40 x 30 mm: pinched at the pad's lowest height.
write_stl("puck_40x40x30.stl", prism(regular(8, 40, 25, 25), 0, 30))
# A triangular prism (60 mm sides, 70 mm tall): no parallel faces, 30 degrees from square.
write_stl("wedge_60x70.stl", prism([(0, 0), (60, 0), (30, 60 * math.sin(math.pi / 3))], 0, 70))
