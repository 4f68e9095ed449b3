#!/usr/bin/env python3
"""Compare spectral-mesh's harmonic and bi-harmonic fields with libigl's igl.harmonic.

Usage:
    harmonic_libigl.py MESH.off CONSTRAINTS.txt [--harmonic F1.txt] [--biharmonic F2.txt]
                       [--tol 1e-8]

CONSTRAINTS.txt: one "VERTEX VALUE" pair per line, '#' comments (the format printed by
`cargo run -p spectral-mesh --example harmonic_field`). F1.txt / F2.txt: one value per
vertex, as written by that example with ORDER 1 / 2.

What is compared:
  * order 1: igl.harmonic(V, F, b, bc, 1) solves -L f = 0 with cot weights (libigl's L is
    negative semi-definite; ours is S = -L). Any of our cotangent discretizations gives the
    same field.
  * order 2: igl.harmonic(V, F, b, bc, 2) uses L M^-1 L with M = massmatrix(VORONOI), i.e.
    Meyer's mixed Voronoi areas: our field must be made with LAPLACIAN = mixed-voronoi.
Vertices no face uses are left out of the comparison (we write 0 there; libigl's system is
singular there).

The mesh is read here with a plain OFF parser that fan-triangulates polygons exactly as
the Rust example does. Exit status 0 when every requested comparison is within --tol (max
absolute difference), 1 otherwise. Requires numpy, scipy and libigl (pip install libigl).
"""

import argparse
import os
import sys

import igl
import numpy as np
import scipy.sparse  # noqa: F401  (libigl returns scipy sparse matrices)


# The OFF reader the benches and the other conformance scripts share.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from eigs_scipy import read_off  # noqa: E402


def read_constraints(path):
    b, bc = [], []
    with open(path) as fh:
        for line in fh:
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            vtx, val = line.replace(",", " ").split()
            b.append(int(vtx))
            bc.append(float(val))
    return np.array(b, dtype=np.int64), np.array(bc, dtype=float)


def compare(v, f, b, bc, k, ours_path, tol):
    ours = np.loadtxt(ours_path, dtype=float)
    w = igl.harmonic(v, f, b, bc.reshape(-1, 1), k)
    w = np.asarray(w).reshape(-1)
    used = np.zeros(len(v), dtype=bool)
    used[f.reshape(-1)] = True
    if ours.shape[0] != len(v):
        print(f"order {k}: {ours_path} has {ours.shape[0]} values, mesh has {len(v)} vertices")
        return False
    diff = np.abs(ours[used] - w[used])
    err = float(np.max(diff)) if diff.size else 0.0
    scale = float(np.ptp(w[used])) if diff.size else 0.0
    ok = bool(np.isfinite(err) and err <= tol)
    print(f"order {k}: max |ours - libigl| = {err:.3e} (field range {scale:.3e}, "
          f"{int(used.sum())} vertices) -> {'OK' if ok else 'FAIL'}")
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mesh")
    ap.add_argument("constraints")
    ap.add_argument("--harmonic")
    ap.add_argument("--biharmonic")
    ap.add_argument("--tol", type=float, default=1e-8)
    a = ap.parse_args()
    v, f = read_off(a.mesh)
    b, bc = read_constraints(a.constraints)
    ok = True
    if a.harmonic:
        ok &= compare(v, f, b, bc, 1, a.harmonic, a.tol)
    if a.biharmonic:
        ok &= compare(v, f, b, bc, 2, a.biharmonic, a.tol)
    if not (a.harmonic or a.biharmonic):
        print("nothing to compare: give --harmonic and/or --biharmonic")
        return 2
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
