#!/usr/bin/env python3
"""Writes LEVEL Loop subdivisions of an OFF mesh to OUT (the large benchmark inputs).

    python bench/loop_mesh.py ../shared/meshes/fandisk.off 4 bench/meshes/fandisk-L4.off

fandisk's 6,475 vertices become 25,894, 103,570, 414,274 and 1,657,090 at levels 1 to 4.
Needs NumPy (the bench venv's python); the subdivision is geodesic_bench.loop_subdivide.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from geodesic_bench import loop_subdivide, read_off, write_off  # noqa: E402


def main():
    if len(sys.argv) != 4:
        raise SystemExit(__doc__)
    src, level, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    V, F = read_off(src)
    for _ in range(level):
        V, F = loop_subdivide(V, F)
    tmp = out + ".tmp"
    write_off(tmp, V, F)
    os.replace(tmp, out)
    print(f"{out}: {len(V)} vertices, {len(F)} triangles")


if __name__ == "__main__":
    main()
