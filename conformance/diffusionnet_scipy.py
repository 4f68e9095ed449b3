"""DiffusionNet's per-shape operators (its `geometry.compute_operators`) written with the
packages it calls (potpourri3d, robust-laplacian, SciPy), without torch: the reference that
`spectral_mesh.learning.get_operators` is compared with (crates/spectral-mesh-py/tests/
test_learning.py) and timed against (BENCHMARKS.md).

The steps are DiffusionNet's, as its source does them:
- mesh: `L = potpourri3d.cotan_laplacian(V, F, denom_eps=1e-10)`, `mass =
  potpourri3d.vertex_areas(V, F) + 1e-8 * mean`; point cloud:
  `robust_laplacian.point_cloud_laplacian(V)` and its mass diagonal;
- eigenpairs: `scipy.sparse.linalg.eigsh(L + 1e-8 I, k, M=diag(mass), sigma=1e-8)`,
  eigenvalues clipped at 0;
- normals: mesh, the normalized sum of the unit triangle normals (DiffusionNet divides by
  `norm + 1e-6`); cloud, the least singular direction of the vectors to the 30 nearest
  points; frames `X` = the x axis (or the y axis when `|N.x| >= 0.9`) projected and
  normalized, `Y = N x X`;
- gradients: per vertex, `(E^T E + 1e-5 I)^-1 E^T` over the neighbours given by the
  Laplacian's pattern (mesh) or the 30 nearest points (cloud), one small solve per vertex
  in a Python loop.

Run as a script it is the benchmark's SciPy side: `python diffusionnet_scipy.py K MESH...`
computes the operators of every mesh (OFF) and prints one line per mesh and the total time.
"""

from __future__ import annotations

import os
import sys
import time

# This folder holds a script named robust_laplacian.py: import the package, not it.
_here = os.path.dirname(os.path.abspath(__file__))
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != _here]

import numpy as np  # noqa: E402
import potpourri3d as pp3d  # noqa: E402
import robust_laplacian  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as sla  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

EPS = 1e-8
EPS_REG = 1e-5
DIVIDE_EPS = 1e-6
N_NEIGHBORS = 30


def _normalize(x: np.ndarray) -> np.ndarray:
    return x / (np.linalg.norm(x, axis=-1, keepdims=True) + DIVIDE_EPS)


def _knn(V: np.ndarray, k: int) -> np.ndarray:
    _, idx = cKDTree(V).query(V, k=k + 1)
    keep = idx != np.arange(len(V))[:, None]
    # Exactly one element dropped per row (the point itself, or the last on duplicates).
    keep[keep.sum(axis=1) == keep.shape[1], -1] = False
    return idx[keep].reshape(len(V), k)


def normals(V: np.ndarray, F: np.ndarray | None) -> np.ndarray:
    if F is None:
        nb = _knn(V, N_NEIGHBORS)
        d = V[nb] - V[:, None, :]
        _, _, vh = np.linalg.svd(d, full_matrices=False)
        n = vh[:, 2, :]
        return n / np.linalg.norm(n, axis=-1, keepdims=True)
    c = V[F]
    fn = _normalize(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]))
    vn = np.zeros(V.shape)
    for i in range(3):
        np.add.at(vn, F[:, i], fn)
    return vn / np.linalg.norm(vn, axis=-1, keepdims=True)


def frames(N: np.ndarray) -> np.ndarray:
    ex = np.broadcast_to(np.array([1.0, 0.0, 0.0]), N.shape)
    ey = np.broadcast_to(np.array([0.0, 1.0, 0.0]), N.shape)
    cand = np.where((np.abs(np.sum(N * ex, axis=-1)) < 0.9)[:, None], ex, ey)
    X = _normalize(cand - N * np.sum(cand * N, axis=-1, keepdims=True))
    Y = np.cross(N, X)
    return np.stack((X, Y, N), axis=-2)


def gradients(V: np.ndarray, fr: np.ndarray, edges: np.ndarray, reg: float = EPS_REG):
    """DiffusionNet's `build_grad`: one least-squares solve per vertex, a Python loop."""
    n = len(V)
    out: list[list[int]] = [[] for _ in range(n)]
    for e in range(edges.shape[1]):
        if edges[0, e] != edges[1, e]:
            out[edges[0, e]].append(edges[1, e])
    rows, cols, vals = [], [], []
    for i in range(n):
        nb = out[i]
        d = V[nb] - V[i]
        E = np.stack((d @ fr[i, 0], d @ fr[i, 1]), axis=-1)
        rhs = np.zeros((len(nb), len(nb) + 1))
        rhs[:, 0] = -1.0
        rhs[np.arange(len(nb)), np.arange(len(nb)) + 1] = 1.0
        sol = np.linalg.inv(E.T @ E + reg * np.identity(2)) @ E.T @ rhs
        coefs = sol[0] + 1j * sol[1]
        rows.extend([i] * (len(nb) + 1))
        cols.extend([i] + nb)
        vals.extend(coefs)
    G = sp.coo_matrix((np.array(vals), (rows, cols)), shape=(n, n)).tocsc()
    return sp.csc_matrix(np.real(G)), sp.csc_matrix(np.imag(G))


def operators(V: np.ndarray, F: np.ndarray | None, k_eig: int = 128):
    """`(frames, mass, L, evals, evecs, gradX, gradY)` as DiffusionNet computes them
    (float64; F None for a point cloud)."""
    V = np.asarray(V, dtype=np.float64)
    fr = frames(normals(V, F))
    if F is None:
        L, M = robust_laplacian.point_cloud_laplacian(V)
        mass = M.diagonal()
    else:
        L = pp3d.cotan_laplacian(V, F, denom_eps=1e-10)
        mass = pp3d.vertex_areas(V, F)
        mass = mass + EPS * np.mean(mass)
    if k_eig > 0:
        Ls = (L + sp.identity(L.shape[0]) * EPS).tocsc()
        evals, evecs = sla.eigsh(Ls, k=k_eig, M=sp.diags(mass), sigma=EPS)
        evals = np.clip(evals, 0.0, np.inf)
    else:
        evals, evecs = np.zeros(0), np.zeros((len(V), 0))
    if F is None:
        nb = _knn(V, N_NEIGHBORS)
        edges = np.stack((np.repeat(np.arange(len(V)), N_NEIGHBORS), nb.ravel()))
    else:
        c = L.tocoo()
        edges = np.stack((c.row, c.col))
    gx, gy = gradients(V, fr, edges)
    return fr, mass, L, evals, evecs, gx, gy


def main(argv: list[str]) -> None:
    k = int(argv[0])
    t0 = time.perf_counter()
    for path in argv[1:]:
        t = time.perf_counter()
        V, F = pp3d.read_mesh(path)
        ops = operators(V, F, k)
        print(f"{path}: n = {len(V)}, {time.perf_counter() - t:.3f} s, lambda_1 = {ops[3][1]:.6g}")
    print(f"total {time.perf_counter() - t0:.2f} s for {len(argv) - 1} meshes")


if __name__ == "__main__":
    main(sys.argv[1:])
