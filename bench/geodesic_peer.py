#!/usr/bin/env python3
"""The peer side of bench/geodesic_bench.py, written as a user of each peer would: read the
mesh with the peer's own reader, build its heat-method solver, compute the distance from
each source on its own, save them (sources x n) as .npy, print one JSON line of timings.

  geodesic_peer.py FILE OUT.npy --peer potpourri3d|libigl [--robust] --sources 0,17,...

- potpourri3d: `pp3d.read_mesh`, `MeshHeatMethodDistanceSolver(V, F, t_coef=1,
  use_robust=...)`, one `compute_distance(s)` per source.
- libigl: `igl.read_triangle_mesh`, `heat_geodesics_precompute(V, F, t, data)` with
  t = avg_edge_length(V, F)^2 (the same t = h^2 as the others; `--robust` sets
  `data.use_intrinsic_delaunay`), one `heat_geodesics_solve(data, [s])` per source.
"""
import json
import sys
import time

t_start = time.perf_counter()
import numpy as np  # noqa: E402


def main():
    path, out = sys.argv[1], sys.argv[2]
    robust = "--robust" in sys.argv
    peer = sys.argv[sys.argv.index("--peer") + 1] if "--peer" in sys.argv else "potpourri3d"
    sources = [int(s) for s in sys.argv[sys.argv.index("--sources") + 1].split(",")]
    if peer == "potpourri3d":
        import potpourri3d as pp3d

        t_import = time.perf_counter() - t_start
        t0 = time.perf_counter()
        V, F = pp3d.read_mesh(path)
        t1 = time.perf_counter()
        solver = pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1.0, use_robust=robust)
        t2 = time.perf_counter()
        D = np.stack([solver.compute_distance(s) for s in sources])
        t3 = time.perf_counter()
    elif peer == "libigl":
        import igl

        t_import = time.perf_counter() - t_start
        t0 = time.perf_counter()
        V, F = igl.read_triangle_mesh(path)
        t1 = time.perf_counter()
        data = igl.HeatGeodesicsData()
        data.use_intrinsic_delaunay = robust
        t = igl.avg_edge_length(V, F) ** 2
        igl.heat_geodesics_precompute(V, F, t, data)
        t2 = time.perf_counter()
        D = np.stack([igl.heat_geodesics_solve(data, np.array([s], dtype=np.int64)) for s in sources])
        t3 = time.perf_counter()
    else:
        sys.exit(f"unknown peer {peer}: expected potpourri3d or libigl")
    np.save(out, D if len(sources) > 1 else D[0])
    print(json.dumps({"peer": peer, "n": int(V.shape[0]), "import_s": t_import, "read_s": t1 - t0,
                      "setup_s": t2 - t1, "per_source_s": (t3 - t2) / len(sources)}))


if __name__ == "__main__":
    main()
