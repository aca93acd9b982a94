#!/usr/bin/env python3
# Turns an STL (binary or ASCII) about the center of its bounding box and writes it as binary
# STL (float32, as any STL): the same part in another pose, to check that `ncrev` gives the
# same result whatever the pose (docs/results.md, thirty-ninth session). Standard library only.
#
#   python3 scripts/turn_stl.py IN.stl OUT.stl [ANGLE_RAD [AX AY AZ]]
#
# ANGLE_RAD defaults to 0.7 and the axis to (1, 2, 3). Turning about the box's center keeps the
# coordinates as large as they were, so float32 rounds them no coarser.
import math
import os
import struct
import sys


def read_triangles(data):
    """The triangles of an STL file's bytes, each three (x, y, z) tuples."""
    if len(data) >= 84:
        count = struct.unpack_from("<I", data, 80)[0]
        if len(data) == 84 + 50 * count:
            tris = []
            for k in range(count):
                v = struct.unpack_from("<9f", data, 84 + 50 * k + 12)
                tris.append((v[0:3], v[3:6], v[6:9]))
            return tris
    tris, corners = [], []
    for line in data.decode("ascii", errors="replace").splitlines():
        words = line.split()
        if words and words[0] == "vertex":
            corners.append(tuple(float(w) for w in words[1:4]))
            if len(corners) == 3:
                tris.append(tuple(corners))
                corners = []
    if not tris:
        sys.exit("turn_stl: no triangles read")
    return tris


def rotation(angle, axis):
    """Rodrigues' rotation matrix about the unit `axis`."""
    n = math.sqrt(sum(a * a for a in axis))
    x, y, z = (a / n for a in axis)
    c, s = math.cos(angle), math.sin(angle)
    return [
        [c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
        [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
        [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)],
    ]


def main():
    if len(sys.argv) not in (3, 4, 7):
        sys.exit("usage: turn_stl.py IN.stl OUT.stl [ANGLE_RAD [AX AY AZ]]")
    angle = float(sys.argv[3]) if len(sys.argv) > 3 else 0.7
    axis = [float(a) for a in sys.argv[4:7]] if len(sys.argv) == 7 else [1.0, 2.0, 3.0]
    with open(sys.argv[1], "rb") as f:
        tris = read_triangles(f.read())
    lo = [min(p[k] for t in tris for p in t) for k in range(3)]
    hi = [max(p[k] for t in tris for p in t) for k in range(3)]
    center = [(lo[k] + hi[k]) / 2 for k in range(3)]
    r = rotation(angle, axis)

    def turn(p):
        d = [p[k] - center[k] for k in range(3)]
        return [sum(r[i][j] * d[j] for j in range(3)) + center[i] for i in range(3)]

    write_triangles(sys.argv[2], [[turn(p) for p in t] for t in tris])


def write_triangles(path, tris):
    """Writes triangles (three (x, y, z) each) as a binary STL, float32, with their normals."""
    out = bytearray(80) + struct.pack("<I", len(tris))
    for a, b, c in tris:
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        length = math.sqrt(sum(x * x for x in n)) or 1.0
        out += struct.pack("<12f", *(x / length for x in n), *a, *b, *c) + b"\0\0"
    # Written beside the output, then renamed: a reader never sees half a file.
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(out)
    os.replace(tmp, path)


if __name__ == "__main__":
    main()
