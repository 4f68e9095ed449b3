"""The eigenbasis checks the conformance scripts against SciPy (eigs_scipy.py) and SLEPc
(eigs_slepc.py) share: our archive read back, and the comparison with a peer's pairs."""
import json

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp


def load_basis(path):
    """`(eigenvalues, eigenvectors, mass as CSC, meta dict)` of one of our .npz bases."""
    f = np.load(path)
    Bf = sp.csc_matrix((f["mass_data"], f["mass_indices"], f["mass_indptr"]),
                       shape=tuple(f["mass_shape"]))
    return f["eigenvalues"], f["eigenvectors"], Bf, json.loads(bytes(f["meta"]))


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
