#!/usr/bin/env python3
# Writes two balls of radius 50 mm as one binary STL, each a latitude-longitude grid of N rows
# (4 N^2 - 4 N facets): the meshes that measure healing's check of which closed components
# cross (docs/benchmarks.md, forty-fifth session). Standard library only.
#
#   python3 scripts/two_balls_stl.py cavity|cross N OUT.stl
#
# cavity: a ball with a concentric cavity of radius 49.95 (its shell facing into it), every
# facet of one within a facet's size of the other's: the most work the check can have.
# cross: the second ball 30 mm along x, crossing the first.
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


def main():
    if len(sys.argv) != 4 or sys.argv[1] not in ("cavity", "cross"):
        sys.exit("usage: two_balls_stl.py cavity|cross N OUT.stl")
    n = int(sys.argv[2])
    if sys.argv[1] == "cavity":
        balls = [((0, 0, 0), 50.0, False), ((0, 0, 0), 49.95, True)]
    else:
        balls = [((0, 0, 0), 50.0, False), ((30, 0, 0), 50.0, False)]
    records = []
    for center, radius, inward in balls:
        for t in ball(center, radius, n, inward):
            records.append(struct.pack("<12fH", 0, 0, 0, *t[0], *t[1], *t[2], 0))
    with open(sys.argv[3], "wb") as f:
        f.write(b"\0" * 80)
        f.write(struct.pack("<I", len(records)))
        f.write(b"".join(records))


if __name__ == "__main__":
    main()
