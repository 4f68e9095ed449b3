#!/usr/bin/env python3
"""Conformance of our eigenbasis with SciPy's eigsh (shift-invert, ARPACK).

usage: eigs_scipy.py MESH.off BASIS.npz [--mass fem|voronoi-cot|cot]
       eigs_scipy.py MESH.off --k K [--mass ...] [--bin PATH]   (runs bench_eigs to make BASIS)

Checks, for the k pairs in BASIS.npz (written by our `save_npz`):
- eigenvalues equal SciPy's to 1e-9 relative to lambda_k (SciPy is asked for k + 16 pairs so
  that a cluster cut by k is complete on its side);
- X^T B X = I to 1e-10 with B the archive's mass matrix, which equals the one built here;
- for every cluster of eigenvalues (relative gap below 1e-6 lambda_k), the principal angles
  between our eigenvectors and SciPy's eigenspace of that cluster are below 1e-6.
Exit status 0 when everything holds.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import scipy.sparse.linalg as sla

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from eigs_scipy import operators, read_off  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from eigencheck import compare, load_basis  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("basis", nargs="?")
    ap.add_argument("--k", type=int, default=50)
    ap.add_argument("--mass", default=None)
    ap.add_argument("--bin", default=None)
    a = ap.parse_args()
    tmp = None
    if a.basis is None:
        exe = a.bin or os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "release", "examples", "bench_eigs")
        tmp = tempfile.mkdtemp()
        a.basis = os.path.join(tmp, "basis.npz")
        subprocess.run([exe, a.mesh, str(a.k), a.mass or "fem", "--out", a.basis], check=True)
    lam, X, Bf, meta = load_basis(a.basis)
    mass = a.mass or meta["laplacian"]
    k = len(lam)
    v, t = read_off(a.mesh)
    S, B = operators(v, t, mass)
    kk = min(k + 16, S.shape[0] - 2)
    sigma = -max(0.01 / B.sum(), 1e-10 * abs(S).sum(axis=0).max() / abs(B).sum(axis=0).max())
    mu, Y = sla.eigsh(S.tocsc(), kk, M=B.tocsc(), sigma=sigma, which="LM", tol=0)
    ok = compare(lam, X, Bf, B, mu, Y, "scipy")
    print("PASS" if ok else "FAIL")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
