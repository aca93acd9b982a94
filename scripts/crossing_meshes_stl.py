#!/usr/bin/env python3
# Writes the meshes that measure healing's check of which closed components cross
# (docs/benchmarks.md, forty-fifth session) as one binary STL. Standard library only.
#
#   python3 scripts/crossing_meshes_stl.py cavity|cross|cubes N OUT.stl
#
# cavity: a ball of radius 50 mm (a latitude-longitude grid of N rows, 4 N^2 - 4 N facets) with
# a concentric cavity of radius 49.95 (its shell facing into it), every facet of one within a
# facet's size of the other's: the most work the check can have on two shells.
# cross: two such balls, the second 30 mm along x, crossing the first.
# cubes: N cubes of 1 mm, each 0.001 mm along x from the one before, their faces in common
# planes: the most pairs of components whose boxes meet.
import math
import struct
import sys


def ball(center, radius, n, inward):
    """The facets of a ball: n rows of 2n cells, one triangle at the poles, two elsewhere."""
    rows = []
    for i in range(n + 1):
        theta = math.pi * i / n
        row = []
        for j in range(2 * n):
            phi = math.pi * j / n
            row.append((center[0] + radius * math.sin(theta) * math.cos(phi),
                        center[1] + radius * math.sin(theta) * math.sin(phi),
                        center[2] + radius * math.cos(theta)))
        rows.append(row)
    for i in range(n):
        for j in range(2 * n):
            k = (j + 1) % (2 * n)
            a, b, c, d = rows[i][j], rows[i + 1][j], rows[i + 1][k], rows[i][k]
            if i > 0:
                yield (a, d, b) if inward else (a, b, d)
            if i < n - 1:
                yield (d, c, b) if inward else (d, b, c)


def cube(x, size):
    """The 12 facets of a cube of side `size` at (x, 0, 0), facing out."""
    p = [(x + size * i, size * j, size * k) for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    for a, b, c, d in ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
                       (1, 5, 7, 3)):
        yield (p[a], p[b], p[c])
        yield (p[a], p[c], p[d])


def main():
    if len(sys.argv) != 4 or sys.argv[1] not in ("cavity", "cross", "cubes"):
        sys.exit("usage: crossing_meshes_stl.py cavity|cross|cubes N OUT.stl")
    n = int(sys.argv[2])
    if sys.argv[1] == "cubes":
        facets = [t for k in range(n) for t in cube(0.001 * k, 1.0)]
    else:
        if sys.argv[1] == "cavity":
            balls = [((0, 0, 0), 50.0, False), ((0, 0, 0), 49.95, True)]
        else:
            balls = [((0, 0, 0), 50.0, False), ((30, 0, 0), 50.0, False)]
        facets = [t for center, radius, inward in balls for t in ball(center, radius, n, inward)]
    records = [struct.pack("<12fH", 0, 0, 0, *t[0], *t[1], *t[2], 0) for t in facets]
    with open(sys.argv[3], "wb") as f:
        f.write(b"\0" * 80)
        f.write(struct.pack("<I", len(records)))
        f.write(b"".join(records))


if __name__ == "__main__":
    main()
