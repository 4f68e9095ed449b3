#!/usr/bin/env python3
"""SciPy reference for the eigenbasis benchmark.

Builds the cotangent stiffness S (positive semi-definite) and a mass matrix B from an OFF
file with NumPy (the formulas of docs/MATH.md), then times scipy.sparse.linalg.eigsh in
shift-invert mode (SuperLU, or a CHOLMOD factorization through scikit-sparse with
--cholmod). Prints one `key=value` line like the Rust example `bench_eigs`.

--cholmod needs scikit-sparse (bench/setup-bench-python.sh installs it): without it the
script exits with status 3 rather than silently measuring SuperLU. --tol is passed to
eigsh (0, SciPy's default, means machine precision).

usage: eigs_scipy.py MESH.off K [--mass fem|voronoi-cot|cot] [--sigma S] [--cholmod]
                     [--tol T] [--save OUT.npz]
"""
import argparse
import resource
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla


def read_off(path, triangles=False):
    """Vertices and triangles of a plain OFF file; polygons are fanned into triangles, or
    refused with `triangles=True` (for files our CLI writes, which hold only triangles)."""
    toks = []
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if line:
                toks.extend(line.split())
    i = 0
    head = toks[i]
    i += 1
    if head.upper() != "OFF":
        raise SystemExit(f"{path}: only plain OFF is supported here")
    nv, nf = int(toks[i]), int(toks[i + 1])
    i += 3
    v = np.array(toks[i:i + 3 * nv], dtype=float).reshape(nv, 3)
    i += 3 * nv
    faces = []
    for _ in range(nf):
        c = int(toks[i])
        if triangles and c != 3:
            raise SystemExit(f"{path}: face {len(faces)} is not a triangle")
        idx = [int(t) for t in toks[i + 1:i + 1 + c]]
        i += 1 + c
        for j in range(1, c - 1):  # fan triangulation
            faces.append((idx[0], idx[j], idx[j + 1]))
    return v, np.array(faces, dtype=np.int64)


def operators(v, f, mass="fem"):
    n = len(v)
    p0, p1, p2 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1)
    rows, cols, vals = [], [], []
    # cot of the angle at corner c, opposite edge (a, b)
    for c, a, b in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        u = v[f[:, a]] - v[f[:, c]]
        w = v[f[:, b]] - v[f[:, c]]
        cot = np.einsum("ij,ij->i", u, w) / np.linalg.norm(np.cross(u, w), axis=1)
        h = 0.5 * cot
        rows += [f[:, a], f[:, b], f[:, a], f[:, b]]
        cols += [f[:, b], f[:, a], f[:, a], f[:, b]]
        vals += [-h, -h, h, h]
    S = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    if mass == "fem":
        r, c, x = [], [], []
        for a in range(3):
            for b in range(3):
                r.append(f[:, a]); c.append(f[:, b])
                x.append(area / 6.0 if a == b else area / 12.0)
        B = sp.csc_matrix((np.concatenate(x), (np.concatenate(r), np.concatenate(c))), shape=(n, n))
    elif mass == "voronoi-cot":
        d = np.zeros(n)
        for a in range(3):
            np.add.at(d, f[:, a], area / 3.0)
        B = sp.diags(d).tocsc()
    else:
        B = sp.identity(n, format="csc")
    S.sum_duplicates(); B.sum_duplicates()
    return S, B


def save_basis(path, lam, X, B, res, mass, generator):
    """The arrays of spectral-mesh's .npz (spectral::store): eigenvalues, eigenvectors
    (n x k, Fortran order), the mass in CSC form, residuals and a JSON meta."""
    import json
    Bc = B.tocsc()
    n, k = X.shape
    meta = json.dumps({"format_version": 1, "laplacian": mass, "n": n, "k": k,
                       "mesh_hash": "", "generator": generator}).encode()
    np.savez(path, eigenvalues=lam, eigenvectors=np.asfortranarray(X),
             mass_data=Bc.data, mass_indices=Bc.indices.astype(np.int64),
             mass_indptr=Bc.indptr.astype(np.int64),
             mass_shape=np.array(Bc.shape, dtype=np.int64), residuals=res,
             meta=np.frombuffer(meta, dtype=np.uint8))


def shift(S, B, given=None):
    """(sigma, ||S||_1, ||B||_1): the shift `given`, or by default the same scale-aware
    shift as ours, -max(0.01 / total mass, 1e-10 ||S||_1 / ||B||_1)."""
    sn = abs(S).sum(axis=0).max()
    bn = abs(B).sum(axis=0).max()
    sigma = given if given is not None else -max(0.01 / B.sum(), 1e-10 * sn / bn)
    return sigma, sn, bn


def quality(S, B, lam, X, sn, bn):
    """(residuals, orthogonality error, peak RSS in MiB) of the pairs `(lam, X)`: the
    relative residuals ||S x - lambda B x|| / ((||S||_1 + |lambda| ||B||_1) ||x||) as ours,
    max |X^T B X - I|, and this process' peak resident memory."""
    R = S @ X - (B @ X) * lam
    res = np.linalg.norm(R, axis=0) / ((sn + np.abs(lam) * bn) * np.linalg.norm(X, axis=0))
    orth = abs(X.T @ (B @ X) - np.eye(X.shape[1])).max()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return res, orth, peak


def solve(mesh, k, mass="fem", sigma=None, cholmod=False, tol=0.0, save=None):
    """The user's whole call: read `mesh`, assemble, solve for `k` pairs, check and write
    `save` (when given). Returns the printed line's fields (`seconds` is the solve's)."""
    v, f = read_off(mesh)
    t0 = time.perf_counter()
    S, B = operators(v, f, mass)
    t_ops = time.perf_counter() - t0
    sigma, sn, bn = shift(S, B, sigma)
    t1 = time.perf_counter()
    if cholmod:
        from sksparse.cholmod import cholesky
        route = "cholmod"
        fac = cholesky((S - sigma * B).tocsc())
        op = sla.LinearOperator(S.shape, matvec=fac, dtype=float)
        lam, X = sla.eigsh(S, k, M=B, sigma=sigma, which="LM", OPinv=op, tol=tol)
    else:
        route = "superlu"
        lam, X = sla.eigsh(S, k, M=B, sigma=sigma, which="LM", tol=tol)
    secs = time.perf_counter() - t1
    order = np.argsort(lam)
    lam, X = lam[order], X[:, order]
    res, orth, peak = quality(S, B, lam, X, sn, bn)
    if save:
        save_basis(save, lam, X, B, res, mass, f"scipy {route}")
    return {"mesh": mesh, "n": len(v), "k": k, "route": f"scipy-{route}", "tol": f"{tol:g}",
            "seconds": f"{secs:.3f}", "assembly": f"{t_ops:.3f}",
            "max_residual": f"{res.max():.2e}", "orth_error": f"{orth:.2e}",
            "lambda_k": f"{lam[-1]:.12e}", "peak_rss_mib": f"{peak:.0f}"}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("k", type=int)
    ap.add_argument("--mass", default="fem")
    ap.add_argument("--sigma", type=float, default=None)
    ap.add_argument("--cholmod", action="store_true")
    ap.add_argument("--tol", type=float, default=0.0)
    ap.add_argument("--save", default=None)
    a = ap.parse_args()
    if a.cholmod:
        try:
            import sksparse.cholmod  # noqa: F401
        except ImportError as e:
            print(f"--cholmod: scikit-sparse is not importable ({e}); "
                  "run bench/setup-bench-python.sh", file=sys.stderr)
            sys.exit(3)
    out = solve(a.mesh, a.k, a.mass, a.sigma, a.cholmod, a.tol, a.save)
    print(" ".join(f"{key}={val}" for key, val in out.items()))


if __name__ == "__main__":
    main()
