"""Point clouds and the robust Laplacian: read_points, point_cloud_laplacian and
laplacian(kind="robust"), against analytic sphere spectra and robust-laplacian."""

from __future__ import annotations

import numpy as np
import pytest

import spectral_mesh as sm

from conftest import shared_mesh


def max_abs(A) -> float:
    A = A.tocoo() if hasattr(A, "tocoo") else np.asarray(A)
    return float(np.abs(A.data).max()) if hasattr(A, "data") and A.nnz else 0.0


def sphere_points(n: int, seed: int = 1) -> np.ndarray:
    x = np.random.default_rng(seed).normal(size=(n, 3))
    return x / np.linalg.norm(x, axis=1, keepdims=True)


@pytest.fixture(scope="module")
def cloud():
    return sphere_points(4000)


@pytest.fixture(scope="module")
def cloud_ops(cloud):
    return sm.point_cloud_laplacian(cloud)


def test_point_cloud_laplacian_is_a_laplacian(cloud, cloud_ops):
    S, B = cloud_ops
    n = len(cloud)
    assert S.shape == B.shape == (n, n)
    assert S.dtype == B.dtype == np.float64
    assert max_abs(S - S.T) == 0.0
    assert np.abs(S @ np.ones(n)).max() <= 1e-12 * max_abs(S)
    assert (S.diagonal() > 0).all()
    # B is diagonal and positive; its total is the sphere's area.
    Bd = B.tocoo()
    assert (Bd.row == Bd.col).all() and (Bd.data > 0).all()
    assert abs(B.sum() - 4 * np.pi) < 0.01 * 4 * np.pi


def test_point_cloud_spectrum_is_the_spheres(cloud_ops):
    # Laplace-Beltrami on the unit sphere: l (l + 1) with multiplicity 2 l + 1.
    S, B = cloud_ops
    w, X = sm.eigsh(S, 16, B, sigma=-0.01)
    assert abs(w[0]) < 1e-8
    exact = np.repeat([2.0, 6.0, 12.0], [3, 5, 7])
    assert np.abs(w[1:] / exact - 1).max() < 0.02, w
    assert np.abs(X.T @ (B @ X) - np.eye(16)).max() < 1e-9


def test_point_cloud_laplacian_against_robust_laplacian(cloud, cloud_ops):
    # Same pipeline, different union of the local triangulations (docs/point-clouds.md):
    # the same sparsity scale and total mass; the peer's eigenvalues are about 5% low.
    rl = pytest.importorskip("robust_laplacian")
    L, M = rl.point_cloud_laplacian(cloud, n_neighbors=30)
    S, B = cloud_ops
    assert abs(B.sum() - M.sum()) < 0.01 * M.sum()
    w = sm.eigsh(S, 4, B, sigma=-0.01, return_eigenvectors=False)
    w_rl = sm.eigsh(L.tocsc(), 4, M.tocsc(), sigma=-0.01, return_eigenvectors=False)
    assert np.abs(w[1:] - 2).max() < np.abs(w_rl[1:] - 2).max()


def test_point_cloud_inputs(cloud, cloud_ops):
    S, B = cloud_ops
    S2, B2 = sm.point_cloud_laplacian(np.asfortranarray(cloud))
    assert max_abs(S2 - S) == 0.0 and max_abs(B2 - B) == 0.0
    P32 = cloud.astype(np.float32)
    S2, _ = sm.point_cloud_laplacian(P32)
    S3, _ = sm.point_cloud_laplacian(P32.astype(np.float64))
    assert max_abs(S2 - S3) == 0.0
    S3, B3 = sm.point_cloud_laplacian(cloud.tolist(), normalize=True)
    assert max_abs(S3 - S) == 0.0
    assert abs(B3.sum() - 1.0) < 1e-12
    # Given normals (the sphere's exact ones) give a Laplacian too.
    S4, B4 = sm.point_cloud_laplacian(cloud, normals=cloud)
    assert abs(B4.sum() - 4 * np.pi) < 0.01 * 4 * np.pi
    bad = cloud.copy()
    bad[7, 1] = np.nan
    with pytest.raises(ValueError, match=r"P\[7\]"):
        sm.point_cloud_laplacian(bad)
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        sm.point_cloud_laplacian(cloud[:, :2])
    with pytest.raises(ValueError, match="n_neighbors"):
        sm.point_cloud_laplacian(cloud, n_neighbors=1)
    with pytest.raises(ValueError, match="normals"):
        sm.point_cloud_laplacian(cloud, normals=cloud[:10])
    with pytest.raises(ValueError):
        sm.point_cloud_laplacian(cloud, mollify_factor=-1.0)


def test_read_points(tmp_path, cloud):
    p = tmp_path / "pts.xyz"
    np.savetxt(p, cloud[:500], fmt="%.17g")
    P, N = sm.read_points(p)
    assert P.shape == (500, 3) and P.dtype == np.float64 and N is None
    assert np.array_equal(P, cloud[:500])
    q = tmp_path / "with_normals.xyz"
    np.savetxt(q, np.hstack([cloud[:50], 2 * cloud[:50]]), fmt="%.17g")
    P, N = sm.read_points(q)
    assert np.array_equal(N, 2 * cloud[:50])
    with pytest.raises(FileNotFoundError):
        sm.read_points(tmp_path / "missing.xyz")
    r = tmp_path / "bad.xyz"
    r.write_text("0 0 0\n1 2 oops\n")
    with pytest.raises(sm.MeshFileError, match="2"):
        sm.read_points(r)


def test_read_points_shared_clouds():
    P, N = sm.read_points(shared_mesh("../points/kitten.xyz"))
    assert P.shape == (5210, 3) and N is not None and N.shape == (5210, 3)
    P, N = sm.read_points(shared_mesh("../points/hippo1.ply"))
    assert P.shape == (6104, 3)
    S, B = sm.point_cloud_laplacian(P, normals=N)
    assert np.abs(S @ np.ones(len(P))).max() <= 1e-12 * max_abs(S)
    assert (B.diagonal() > 0).sum() > 0.99 * len(P)


def test_robust_laplacian_of_a_mesh_equals_robust_laplacian(torus):
    rl = pytest.importorskip("robust_laplacian")
    V, F = torus
    S, B = sm.laplacian(V, F, "robust")
    L, M = rl.mesh_laplacian(V, F)
    assert max_abs(S - L) <= 1e-10 * max_abs(L)
    assert max_abs(B - M) <= 1e-10 * max_abs(M)


def test_robust_laplacian_of_a_nonmanifold_soup():
    # Three triangles on one edge (non-manifold) plus a duplicate triangle.
    rl = pytest.importorskip("robust_laplacian")
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0], [0.5, 0, 1]], float)
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4], [0, 1, 4]])
    S, B = sm.laplacian(V, F, "robust")
    L, M = rl.mesh_laplacian(V, F)
    assert max_abs(S - L) <= 1e-10 * max_abs(L)
    assert max_abs(B - M) <= 1e-10 * max_abs(M)
    assert np.abs(S @ np.ones(5)).max() <= 1e-12 * max_abs(S)
