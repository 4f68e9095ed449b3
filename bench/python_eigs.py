#!/usr/bin/env python3
"""One run of the Python eigenbasis benchmark: one route, one mesh, one k, in this process.

Every route starts from the same NumPy arrays (V, F) and ends with (evals, evecs), the way
a user's script does, with each package's documented defaults:

- ours           spectral_mesh.eigenbasis(V, F, k)            (FEM, tol 1e-10)
- lapy           lapy.Solver(TriaMesh(V, F)).eigs(k)          (FEM, sigma -0.01, SuperLU)
- lapy-cholespy  the same with use_cholmod=True               (cholespy's Cholesky)
- superlu        S = -igl.cotmatrix, B = igl.massmatrix(FULL),
                 scipy.sparse.linalg.eigsh(S, k, B, sigma=-0.01)     (SuperLU inside)
- cholmod        the same operators, eigsh with OPinv = a CHOLMOD factor of S + 0.01 B
                 (scikit-sparse)
- robust         L, M = robust_laplacian.mesh_laplacian(V, F),
                 eigsh(L, k, M, sigma=1e-8)          (its README; lumped M, intrinsic Delaunay)

Prints one JSON line: route, n, k, assembly_s (the operators), solve_s (the eigensolve,
factorization included), total_s (arrays in to eigenpairs out; for ours the one call),
peak_rss_mib (the process' peak resident memory right after the solve), max_residual
(||S x - l B x||_2 / ((||S||_1 + |l| ||B||_1) ||x||_2), each route on its own operators),
lambda_k, lambda_2 and the package versions.

usage: python_eigs.py MESH.npz K ROUTE        (MESH.npz holds V and F)
"""

from __future__ import annotations

import json
import resource
import sys
import time

import numpy as np


def peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def residual(S, B, lam, X) -> float:
    """The largest relative residual, by blocks of 32 columns (little memory)."""
    sn = abs(S).sum(axis=0).max()
    bn = abs(B).sum(axis=0).max()
    worst = 0.0
    for j in range(0, X.shape[1], 32):
        x = X[:, j : j + 32]
        lj = lam[j : j + 32]
        r = S @ x - (B @ x) * lj
        rel = np.linalg.norm(r, axis=0) / ((sn + np.abs(lj) * bn) * np.linalg.norm(x, axis=0))
        worst = max(worst, float(rel.max()))
    return worst


def igl_operators(V, F):
    import igl

    S = (-igl.cotmatrix(V, F)).tocsc()
    B = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL).tocsc()
    return S, B


def main() -> None:
    mesh, k, route = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    f = np.load(mesh)
    V, F = np.ascontiguousarray(f["V"]), np.ascontiguousarray(f["F"])
    versions = {"numpy": np.__version__}
    S = B = None
    t0 = time.perf_counter()
    if route == "ours":
        import spectral_mesh as sm

        versions["spectral_mesh"] = sm.__version__
        t0 = time.perf_counter()
        lam, X = sm.eigenbasis(V, F, k)
        t_total = time.perf_counter() - t0
        t_asm, t_solve = None, None
        peak = peak_mib()
        S, B = sm.laplacian(V, F)
    elif route in ("lapy", "lapy-cholespy"):
        import lapy

        versions["lapy"] = lapy.__version__
        t0 = time.perf_counter()
        solver = lapy.Solver(lapy.TriaMesh(V, F), lump=False, use_cholmod=route == "lapy-cholespy")
        t1 = time.perf_counter()
        lam, X = solver.eigs(k=k)
        t2 = time.perf_counter()
        peak = peak_mib()
        t_asm, t_solve, t_total = t1 - t0, t2 - t1, t2 - t0
        S, B = solver.stiffness, solver.mass
    elif route in ("superlu", "cholmod", "robust"):
        import scipy
        import scipy.sparse.linalg as sla

        versions["scipy"] = scipy.__version__
        if route == "cholmod":
            from sksparse.cholmod import cholesky

            versions["scikit-sparse"] = "0.4.16"
        if route == "robust":
            import robust_laplacian

            t0 = time.perf_counter()
            S, B = robust_laplacian.mesh_laplacian(V, F)
            S, B = S.tocsc(), B.tocsc()
            sigma = 1e-8
        else:
            t0 = time.perf_counter()
            S, B = igl_operators(V, F)
            sigma = -0.01
        t1 = time.perf_counter()
        if route == "cholmod":
            fac = cholesky((S - sigma * B).tocsc())
            op = sla.LinearOperator(S.shape, matvec=fac, dtype=float)
            lam, X = sla.eigsh(S, k, M=B, sigma=sigma, which="LM", OPinv=op)
        else:
            lam, X = sla.eigsh(S, k, M=B, sigma=sigma, which="LM")
        t2 = time.perf_counter()
        peak = peak_mib()
        order = np.argsort(lam)
        lam, X = lam[order], X[:, order]
        t_asm, t_solve, t_total = t1 - t0, t2 - t1, t2 - t0
    else:
        raise SystemExit(f"unknown route {route!r}")
    out = {
        "route": route,
        "mesh": mesh,
        "n": int(len(V)),
        "k": k,
        "assembly_s": t_asm,
        "solve_s": t_solve,
        "total_s": t_total,
        "peak_rss_mib": round(peak, 1),
        "max_residual": residual(S, B, lam, X),
        "lambda_2": float(lam[1]),
        "lambda_k": float(lam[-1]),
        "versions": versions,
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
