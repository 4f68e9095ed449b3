#!/usr/bin/env python3
"""Heat-method geodesics on point clouds: ours against great-circle distance and against
potpourri3d's PointCloudHeatSolver.

  python conformance/geodesic_cloud.py --cli target/release/spectral-mesh \
      [--densities 2000,8000,32000] [--cloud sphere_20k.xyz] [--source 0] [--time-factor 1]

1. Uniform random samples of the unit sphere (NumPy, seed 0) at each density, written as
   .xyz: `spectral-mesh geodesic cloud.xyz --source 0 -o d.npy` (point-cloud Laplacian,
   gradient in each point's tangent plane) and `pp3d.PointCloudHeatSolver(P, t_coef=1)`;
   mean and max error of each against the great-circle distance from the source, and the
   order of ours in the mean spacing h (from the CLI's report).
2. With --cloud FILE (points on the unit sphere, x y z per line): the same on that file,
   and the mean and max difference between ours and potpourri3d's.

Prints Markdown tables. Exit status 0 when our mean error falls with density.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

import numpy as np
import potpourri3d as pp3d


def ours(cli, path, source, out, m):
    text = subprocess.run([cli, "geodesic", path, "--source", str(source), "--time-factor", str(m), "-o", out, "--force"],
                          check=True, capture_output=True, text=True).stdout
    h = float(re.search(r"h = ([0-9.e+-]+)", text).group(1))
    return np.load(out), h


def errors(d, exact):
    e = np.abs(d - exact)
    return e.mean(), e.max()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--densities", default="2000,8000,32000")
    ap.add_argument("--cloud")
    ap.add_argument("--source", type=int, default=0)
    ap.add_argument("--time-factor", type=float, default=1.0, help="m in t = m h^2 (both tools)")
    a = ap.parse_args()
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "d.npy")
        print("| points | h | ours: mean error | ours: max error | order (mean) | potpourri3d: mean error | potpourri3d: max error |")
        print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        prev = None
        for n in [int(x) for x in a.densities.split(",")]:
            P = np.random.default_rng(0).normal(size=(n, 3))
            P /= np.linalg.norm(P, axis=1, keepdims=True)
            path = os.path.join(tmp, f"sphere{n}.xyz")
            np.savetxt(path, P, fmt="%.17g")
            exact = np.arccos(np.clip(P @ P[0], -1.0, 1.0))
            d, h = ours(a.cli, path, 0, out, a.time_factor)
            theirs = pp3d.PointCloudHeatSolver(P, t_coef=a.time_factor).compute_distance(0)
            m, x = errors(d, exact)
            pm, px = errors(theirs, exact)
            order = "" if prev is None else f"{np.log(prev[1] / m) / np.log(prev[0] / h):.2f}"
            if prev is not None and not m < prev[1]:
                ok = False
            prev = (h, m)
            print(f"| {n:,} | {h:.4f} | {m:.2e} | {x:.2e} | {order} | {pm:.2e} | {px:.2e} |")
        if a.cloud:
            P = np.loadtxt(a.cloud, usecols=(0, 1, 2))
            d, h = ours(a.cli, a.cloud, a.source, out, a.time_factor)
            theirs = pp3d.PointCloudHeatSolver(P, t_coef=a.time_factor).compute_distance(a.source)
            u = P / np.linalg.norm(P, axis=1, keepdims=True)
            exact = np.arccos(np.clip(u @ u[a.source], -1.0, 1.0))
            m, x = errors(d, exact)
            pm, px = errors(theirs, exact)
            dm, dx = errors(d, theirs)
            print(f"\n{os.path.basename(a.cloud)} ({len(P):,} points, source {a.source}): ours mean/max error "
                  f"{m:.2e}/{x:.2e}, potpourri3d {pm:.2e}/{px:.2e}; |ours - potpourri3d| mean {dm:.2e}, "
                  f"max {dx:.2e} (largest distance {theirs.max():.3f})")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
