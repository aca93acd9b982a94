#!/usr/bin/env python3
# Rounds an STL's coordinates otherwise and writes it as binary STL: the same part as another
# program could have written it, to check how much `ncrev` depends on the last bits of its input
# (docs/results.md, fortieth session). Standard library only.
#
#   python3 scripts/round_stl.py IN.stl OUT.stl units [SALT]   # each coordinate moved by one
#                                    # float32 unit up, down or not, by its own bits and SALT
#   python3 scripts/round_stl.py IN.stl OUT.stl digits N       # each coordinate to N significant
#                                    # digits (an ASCII STL written with "%.{N-1}e")
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from turn_stl import read_triangles, write_triangles  # noqa: E402


def float32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def nudged(x, salt):
    """x (a float32) moved by at most one float32 unit, the way chosen by its bits and salt."""
    bits = struct.unpack("<I", struct.pack("<f", x))[0]
    step = ((((bits ^ salt) * 2654435761) & 0xFFFFFFFF) >> 30) % 3 - 1
    if step == 0 or x == 0:
        return x
    bits += 1 if (x > 0) == (step > 0) else -1
    return struct.unpack("<f", struct.pack("<I", bits))[0]


def main():
    if len(sys.argv) not in (4, 5) or sys.argv[3] not in ("units", "digits"):
        sys.exit("usage: round_stl.py IN.stl OUT.stl units [SALT] | digits N")
    with open(sys.argv[1], "rb") as f:
        tris = read_triangles(f.read())
    if sys.argv[3] == "units":
        salt = int(sys.argv[4]) if len(sys.argv) == 5 else 0

        def change(x):
            return nudged(float32(x), salt)

    else:
        if len(sys.argv) != 5 or int(sys.argv[4]) < 1:
            sys.exit("round_stl.py: digits needs N >= 1")
        form = "%.{}e".format(int(sys.argv[4]) - 1)

        def change(x):
            return float32(float(form % float32(x)))

    write_triangles(sys.argv[2], [[[change(x) for x in p] for p in t] for t in tris])


if __name__ == "__main__":
    main()
