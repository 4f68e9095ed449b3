#!/usr/bin/env python3
"""The peer side of bench/geodesic_bench.py: read an OFF mesh, build potpourri3d's heat-method
solver, compute the distance from each source on its own, save them (sources x n) as .npy,
print one JSON line of timings.

  geodesic_peer.py FILE OUT.npy --robust|--no-robust --sources 0,17,...
"""
import json
import sys
import time

t_start = time.perf_counter()
import numpy as np  # noqa: E402
import potpourri3d as pp3d  # noqa: E402

t_import = time.perf_counter() - t_start


def read_off(path):
    with open(path) as f:
        head = f.readline().split()
        assert head[0] == "OFF"
        line = f.readline()
        while line.startswith("#") or not line.strip():
            line = f.readline()
        nv, nf = (int(x) for x in line.split()[:2])
        rest = np.array(f.read().split(), dtype=np.float64)
    V = rest[: 3 * nv].reshape(nv, 3)
    F = rest[3 * nv : 3 * nv + 4 * nf].reshape(nf, 4)[:, 1:].astype(np.int64)
    return V, F


def main():
    path, out = sys.argv[1], sys.argv[2]
    robust = "--robust" in sys.argv
    sources = [int(s) for s in sys.argv[sys.argv.index("--sources") + 1].split(",")]
    t0 = time.perf_counter()
    V, F = read_off(path)
    t1 = time.perf_counter()
    solver = pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1.0, use_robust=robust)
    t2 = time.perf_counter()
    D = np.stack([solver.compute_distance(s) for s in sources])
    t3 = time.perf_counter()
    np.save(out, D if len(sources) > 1 else D[0])
    print(json.dumps({"n": int(V.shape[0]), "import_s": t_import, "read_s": t1 - t0, "setup_s": t2 - t1,
                      "per_source_s": (t3 - t2) / len(sources)}))


if __name__ == "__main__":
    main()
