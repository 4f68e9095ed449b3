#!/usr/bin/env python3
"""The peer side of bench/robust_bench.py: read a file, assemble robust_laplacian's operator,
write nothing, print one JSON line (read and assembly seconds, total mass, n).

  robust_peer.py FILE [--neighbors K]

FILE is a plain OFF mesh (mesh_laplacian) or an x y z text file (point_cloud_laplacian).
"""
import json
import os
import sys
import time

t_start = time.perf_counter()
import numpy as np  # noqa: E402
from off_text import read_off  # noqa: E402  (this folder, before it leaves sys.path)

_here = os.path.dirname(os.path.abspath(__file__))
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != _here]
import robust_laplacian  # noqa: E402

t_import = time.perf_counter() - t_start


def main():
    path = sys.argv[1]
    k = int(sys.argv[sys.argv.index("--neighbors") + 1]) if "--neighbors" in sys.argv else 30
    t0 = time.perf_counter()
    if path.endswith(".off"):
        V, F = read_off(path)
        t1 = time.perf_counter()
        L, M = robust_laplacian.mesh_laplacian(V, F)
    else:
        V = np.fromfile(path, sep=" ").reshape(-1, 3)
        t1 = time.perf_counter()
        L, M = robust_laplacian.point_cloud_laplacian(V, n_neighbors=k)
    t2 = time.perf_counter()
    print(json.dumps({"n": int(V.shape[0]), "import_s": t_import, "read_s": t1 - t0,
                      "assembly_s": t2 - t1, "mass": float(M.sum()), "nnz_s": int(L.nnz)}))


if __name__ == "__main__":
    main()
