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
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as sla

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from eigs_scipy import operators, read_off  # noqa: E402


def b_orthonormal(X, B):
    G = X.T @ (B @ X)
    L = np.linalg.cholesky((G + G.T) / 2)
    return la.solve_triangular(L, X.T, lower=True).T


def compare(lam, X, Bf, B, mu, Y, peer):
    """Prints and checks our basis (`lam`, `X`, its archive's mass `Bf`) against a peer's
    pairs (`mu`, `Y`, any order, ideally more than k so that a cluster cut by k is complete
    on its side), with `B` the mass built here: the masses equal to 1e-12, eigenvalues to
    1e-9 relative to lambda_k, X^T B X = I to 1e-10, and every cluster's principal angles
    below 1e-6. Returns whether everything holds."""
    k = len(lam)
    ok = True
    dB = abs(Bf - B).max() / abs(B).max()
    print(f"mass matrix: max relative difference to ours {dB:.2e}")
    ok &= dB < 1e-12
    o = np.argsort(mu)
    mu, Y = mu[o], Y[:, o]
    scale = abs(lam[-1])
    dl = abs(lam - mu[:k]).max() / scale
    print(f"eigenvalues: max |ours - {peer}| / lambda_k = {dl:.2e} (k = {k}, lambda_k = {lam[-1]:.6e})")
    ok &= dl < 1e-9
    orth = abs(X.T @ (B @ X) - np.eye(k)).max()
    print(f"B-orthonormality: max |X^T B X - I| = {orth:.2e}")
    ok &= orth < 1e-10
    # Clusters of our eigenvalues; the peer's cluster includes its pairs beyond k.
    gap = 1e-6 * scale
    worst = 0.0
    j = 0
    nclusters = 0
    while j < k:
        e = j + 1
        while e < k and lam[e] - lam[e - 1] < gap:
            e += 1
        lo, hi = lam[j] - gap, lam[e - 1] + gap
        idx = np.where((mu >= lo) & (mu <= hi))[0]
        Xs = b_orthonormal(X[:, j:e], B)
        Ys = b_orthonormal(Y[:, idx], B)
        s = np.linalg.svd(Xs.T @ (B @ Ys), compute_uv=False)
        if len(idx) < e - j:
            ang = np.pi / 2
        else:
            ang = float(np.arccos(np.clip(s.min(), -1, 1))) if len(s) else np.pi / 2
            # arccos is inaccurate near 1: use the sine form as well.
            resid = Xs - Ys @ (Ys.T @ (B @ Xs))
            ang = max(min(ang, 1.0), float(np.sqrt(max(0.0, np.linalg.norm(resid.T @ (B @ resid), 2)))))
        worst = max(worst, ang)
        nclusters += 1
        j = e
    print(f"eigenspaces: {nclusters} clusters, largest principal angle {worst:.2e} rad")
    ok &= worst < 1e-6
    return ok


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
    f = np.load(a.basis)
    meta = json.loads(bytes(f["meta"]))
    mass = a.mass or meta["laplacian"]
    lam, X = f["eigenvalues"], f["eigenvectors"]
    k = len(lam)
    Bf = sp.csc_matrix((f["mass_data"], f["mass_indices"], f["mass_indptr"]), shape=tuple(f["mass_shape"]))
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
