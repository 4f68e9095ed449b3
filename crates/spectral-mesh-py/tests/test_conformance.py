"""Conformance with the peers users come from: libigl's operators, robust-laplacian's,
SciPy's and LaPy's eigenpairs, pyFM's HKS/WKS formulas, SciPy's eigsh on a non-mesh
pencil."""

from __future__ import annotations

import igl
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

import spectral_mesh as sm
from conftest import clusters, shared_mesh, subspace_gap

MASS_TYPES = {
    "fem": igl.MASSMATRIX_TYPE_FULL,
    "voronoi-cot": igl.MASSMATRIX_TYPE_BARYCENTRIC,
    "mixed-voronoi": igl.MASSMATRIX_TYPE_VORONOI,
}


def max_abs(A) -> float:
    A = sp.csr_matrix(A)
    return float(abs(A).max()) if A.nnz else 0.0


@pytest.mark.parametrize("kind", sorted(MASS_TYPES))
@pytest.mark.parametrize("mesh", ["sphere", "torus", "disk", "pretzel"])
def test_laplacian_equals_libigl(mesh, kind, request):
    V, F = request.getfixturevalue(mesh)
    S, B = sm.laplacian(V, F, kind)
    assert isinstance(S, sp.csr_matrix) and isinstance(B, sp.csr_matrix)
    assert S.dtype == np.float64 and S.shape == (len(V), len(V))
    L = igl.cotmatrix(V, F)
    M = igl.massmatrix(V, F, MASS_TYPES[kind])
    # Our S is positive semi-definite: libigl's cotmatrix with the sign flipped.
    assert max_abs(S + L) <= 1e-12 * max_abs(L)
    assert max_abs(B - M) <= 1e-12 * max_abs(M)
    # Exactly symmetric (so reading the CSC arrays as CSR is the same matrix), S 1 = 0.
    assert max_abs(S - S.T) == 0.0 and max_abs(B - B.T) == 0.0
    assert np.abs(S @ np.ones(len(V))).max() <= 1e-12 * max_abs(S)


def test_laplacian_on_shared_meshes():
    for name in ["bunny00.off", "mesh_with_border.off", "blobby_3cc.off"]:
        V, F = sm.read_mesh(shared_mesh(name))
        S, B = sm.laplacian(V, F)
        L = igl.cotmatrix(V, F)
        M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL)
        assert max_abs(S + L) <= 1e-12 * max_abs(L), name
        assert max_abs(B - M) <= 1e-12 * max_abs(M), name


def test_cot_and_uniform_use_the_identity_mass(sphere):
    V, F = sphere
    S, B = sm.laplacian(V, F, "cot")
    assert max_abs(B - sp.identity(len(V))) == 0.0
    assert max_abs(S + igl.cotmatrix(V, F)) <= 1e-12 * max_abs(S)
    U, I = sm.laplacian(V, F, "uniform")
    A = igl.adjacency_matrix(F).astype(float)
    D = sp.diags(np.asarray(A.sum(axis=1)).ravel())
    assert max_abs(U - (D - A)) == 0.0


def test_normalize_divides_the_mass_by_the_area(torus):
    V, F = torus
    S, B = sm.laplacian(V, F)
    S1, B1 = sm.laplacian(V, F, normalize=True)
    area = igl.doublearea(V, F).sum() / 2
    assert max_abs(S1 - S) == 0.0
    assert max_abs(B1 * area - B) <= 1e-12 * max_abs(B)
    assert abs(B1.sum() - 1.0) < 1e-12


def test_robust_laplacian_without_mollification_on_a_delaunay_mesh(sphere):
    # robust-laplacian's intrinsic Delaunay triangulation of a Delaunay mesh is the mesh
    # itself: with no mollification its (L, M) are our cotangent S and lumped mass.
    rl = pytest.importorskip("robust_laplacian")
    V, F = sphere
    L, M = rl.mesh_laplacian(V, F, mollify_factor=0.0)
    S, B = sm.laplacian(V, F, "voronoi-cot")
    assert max_abs(L - S) <= 1e-12 * max_abs(S)
    assert max_abs(M - B) <= 1e-12 * max_abs(B)


def check_same_pairs(w, X, w2, X2, B, tol=1e-9):
    """Eigenvalues equal to tol (relative to the largest), and every cluster of repeated
    eigenvalues spanning the same subspace (the cut at k may split a cluster: the last
    cluster is compared only when both sides hold all of it)."""
    scale = max(abs(w).max(), 1.0)
    assert np.abs(w - w2).max() <= tol * scale, (w, w2)
    for c in clusters(w2)[:-1]:
        idx = np.array(list(c))
        gap = subspace_gap(X[:, idx], X2[:, idx], B)
        assert gap < 1e-6, (c, gap)


@pytest.mark.parametrize("mesh", ["sphere", "torus", "disk"])
def test_eigenbasis_equals_scipy_eigsh(mesh, request):
    V, F = request.getfixturevalue(mesh)
    k = 40
    S, B = sm.laplacian(V, F)
    w, X = sm.eigenbasis(V, F, k, method="shift-invert")
    w2, X2 = sla.eigsh(S.tocsc(), k, B.tocsc(), sigma=-0.01)
    order = np.argsort(w2)
    w2, X2 = w2[order], X2[:, order]
    assert w.shape == (k,) and X.shape == (len(V), k) and X.dtype == np.float64
    assert np.all(np.diff(w) >= 0)
    assert np.abs(X.T @ B @ X - np.eye(k)).max() < 1e-10
    check_same_pairs(w, X, w2, X2, B)
    # Sign convention: the largest-magnitude entry of each vector is positive.
    idx = np.abs(X).argmax(axis=0)
    assert np.all(X[idx, np.arange(k)] > 0)


def test_eigenbasis_equals_lapy(torus):
    lapy = pytest.importorskip("lapy")
    V, F = torus
    k = 30
    w, X = sm.eigenbasis(V, F, k)
    solver = lapy.Solver(lapy.TriaMesh(V, F), lump=False)
    w2, X2 = solver.eigs(k=k)
    _, B = sm.laplacian(V, F)
    check_same_pairs(w, X, w2, X2, B)
    # LaPy's stiffness and mass are ours.
    assert max_abs(solver.stiffness - sm.laplacian(V, F)[0]) <= 1e-12 * max_abs(solver.stiffness)
    assert max_abs(solver.mass - B) <= 1e-12 * max_abs(B)


def test_eigenbasis_equals_lapy_on_a_shared_mesh():
    lapy = pytest.importorskip("lapy")
    V, F = sm.read_mesh(shared_mesh("cow.off"))
    w, X = sm.eigenbasis(V, F, 50, method="shift-invert")
    w2, X2 = lapy.Solver(lapy.TriaMesh(V, F), lump=False).eigs(k=50)
    check_same_pairs(w, X, w2, X2, sm.laplacian(V, F)[1])


def test_normalized_eigenbasis_is_the_unit_area_shape(torus):
    V, F = torus
    w, X = sm.eigenbasis(V, F, 20)
    wn, Xn = sm.eigenbasis(V, F, 20, normalize=True)
    area = igl.doublearea(V, F).sum() / 2
    assert np.abs(wn - w * area).max() <= 1e-9 * wn.max()
    # The same shape scaled to unit area gives the same pairs.
    wu, _ = sm.eigenbasis(V / np.sqrt(area), F, 20)
    assert np.abs(wu - wn).max() <= 1e-9 * wn.max()


def test_analysis_basis_equals_eigenbasis_and_grows(torus):
    V, F = torus
    an = sm.Analysis(V, F, normalize=False)
    w10, X10 = an.basis(10)
    assert an.held_k == 10 and an.factorizations == 1
    w30, X30 = an.basis(30)
    assert an.held_k == 30
    w5, X5 = an.basis(5)
    assert an.held_k == 30  # smaller k: the held basis serves
    assert np.array_equal(w5, w30[:5]) and np.array_equal(X5, X30[:, :5])
    w, X = sm.eigenbasis(V, F, 30)
    # The pairs for a given k do not depend on what was asked before.
    assert np.array_equal(w30, w) and np.array_equal(X30, X)
    assert np.abs(w10 - w[:10]).max() <= 1e-9 * w.max()


# ------------------------------------------------------------------------ HKS / WKS


def _scaled(natural, coefs, scaled):
    """pyFM's optional scaling of a signature: each column by the sum of its coefficients."""
    if scaled:
        return natural / coefs.sum(axis=1)[None, :]
    return natural


def pyfm_hks(evals, evects, times, scaled):
    """pyFM's signatures.HKS, re-derived: sum_k exp(-lambda_k t) phi_k(x)^2 (all pairs),
    scaled by the heat trace sum_k exp(-lambda_k t)."""
    coefs = np.exp(-np.outer(times, evals))  # (T, K)
    natural = np.einsum("tk,nk->nt", coefs, np.square(evects))
    return _scaled(natural, coefs, scaled)


def pyfm_auto_times(evals, num_t):
    abs_ev = sorted(np.abs(evals))
    t_min = 4 * np.log(10) / abs_ev[-1]
    t_max = 4 * np.log(10) / abs_ev[1]
    return np.geomspace(t_min, t_max, num_t)


def pyfm_wks(evals, evects, energy_list, sigma, scaled):
    """pyFM's signatures.WKS, re-derived: pairs with lambda <= 1e-8 lambda_max dropped,
    coefs exp(-(e - log lambda)^2 / (2 sigma^2)), optionally divided by their sum."""
    keep = evals > 1e-8 * evals.max()  # pyFM: evals > 1e-8 * max (after abs)
    ev, X = evals[keep], evects[:, keep]
    coefs = np.exp(-np.square(energy_list[:, None] - np.log(np.abs(ev))[None, :]) / (2 * sigma**2))
    natural = np.einsum("tk,nk->nt", coefs, np.square(X))
    return _scaled(natural, coefs, scaled)


def pyfm_auto_energies(evals, num_e):
    abs_ev = sorted(np.abs(evals))
    e_min, e_max = np.log(abs_ev[1]), np.log(abs_ev[-1])
    sigma = 7 * (e_max - e_min) / num_e
    e_min += 2 * sigma
    e_max -= 2 * sigma
    return np.linspace(e_min, e_max, num_e), sigma


@pytest.mark.parametrize("scaled", [False, True])
def test_hks_and_wks_equal_pyfm(pretzel, scaled):
    V, F = pretzel
    an = sm.Analysis(V, F)
    k = 60
    w, X = an.basis(k)
    times = np.array([0.001, 0.01, 0.1])
    got = an.hks(times, scaled=scaled, k=k)
    want = pyfm_hks(w, X, times, scaled)
    assert got.shape == (len(V), 3)
    assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
    one = an.hks(0.01, scaled=scaled, k=k)
    assert np.abs(one - want[:, 1]).max() <= 1e-12 * np.abs(want).max()
    # Automatic times and energies.
    assert np.allclose(an.hks_times(8, k=k), pyfm_auto_times(w, 8), rtol=1e-12)
    auto = an.auto_hks(8, scaled=scaled, k=k)
    assert (
        np.abs(auto - pyfm_hks(w, X, pyfm_auto_times(w, 8), scaled)).max()
        <= 1e-12 * np.abs(auto).max()
    )
    energies, sigma = pyfm_auto_energies(w, 10)
    e, s = an.wks_energies(10, k=k)
    assert np.allclose(e, energies, rtol=1e-12) and abs(s - sigma) <= 1e-12 * sigma
    got = an.wks(energies, sigma=sigma, scaled=scaled, k=k)
    want = pyfm_wks(w, X, energies, sigma, scaled)
    assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
    auto = an.auto_wks(10, scaled=scaled, k=k)
    assert np.abs(auto - want).max() <= 1e-12 * np.abs(want).max()
    single = an.wks(float(energies[3]), sigma=sigma, scaled=scaled, k=k)
    assert np.abs(single - want[:, 3]).max() <= 1e-12 * np.abs(want).max()


# ------------------------------------------------------------------ generic eigsh


def poisson_2d(m: int) -> sp.csr_matrix:
    """The 5-point Dirichlet Laplacian on an m x m grid (SPD, clustered eigenvalues)."""
    T = sp.diags([-np.ones(m - 1), 2 * np.ones(m), -np.ones(m - 1)], [-1, 0, 1])
    I = sp.identity(m)
    return (sp.kron(T, I) + sp.kron(I, T)).tocsr()


def test_eigsh_equals_scipy_on_a_poisson_matrix():
    A = poisson_2d(40)  # n = 1600
    n, k = A.shape[0], 30
    w, X = sm.eigsh(A, k, sigma=-1e-3)
    w2, X2 = sla.eigsh(A.tocsc(), k, sigma=-1e-3)
    order = np.argsort(w2)
    w2, X2 = w2[order], X2[:, order]
    check_same_pairs(w, X, w2, X2, sp.identity(n))
    # Analytic: 4 (sin^2(i pi / 2(m+1)) + sin^2(j pi / 2(m+1))).
    s = np.sin(np.arange(1, 41) * np.pi / (2 * 41)) ** 2
    exact = np.sort((4 * (s[:, None] + s[None, :])).ravel())[:k]
    assert np.abs(w - exact).max() <= 1e-10 * exact.max()


def test_eigsh_generalized_pencil_and_formats():
    A = poisson_2d(25)
    n = A.shape[0]
    rng = np.random.default_rng(1)
    d = rng.uniform(0.5, 2.0, n)
    M = (
        sp.diags(d)
        + 0.1 * sp.diags(np.sqrt(d[:-1] * d[1:]), 1)
        + 0.1 * sp.diags(np.sqrt(d[:-1] * d[1:]), -1)
    ).tocsr()
    w, X = sm.eigsh(A, 12, M, sigma=-0.01)
    w2, X2 = sla.eigsh(A.tocsc(), 12, M.tocsc(), sigma=-0.01)
    order = np.argsort(w2)
    check_same_pairs(w, X, w2[order], X2[:, order], M)
    assert np.abs(X.T @ M @ X - np.eye(12)).max() < 1e-10
    # Any SciPy format, dense arrays, sparse arrays, float32, which='SM' without sigma:
    # the same pairs.
    for A2, M2 in [
        (A.tocoo(), M.tocsc()),
        (sp.csr_array(A), sp.csr_array(M)),
        (A.toarray(), M.toarray()),
        (A.astype(np.float32), M),
    ]:
        wa = sm.eigsh(A2, 12, M2, sigma=-0.01, return_eigenvectors=False)
        assert np.abs(wa - w).max() <= 1e-9 * w.max()
    assert np.abs(sm.eigsh(A, 12, M, which="SM")[0] - w).max() <= 1e-9 * w.max()


def test_eigsh_on_a_singular_psd_matrix():
    # A graph Laplacian of a path: semi-definite, one zero eigenvalue.
    n = 400
    Lp = sp.diags(
        [-np.ones(n - 1), np.r_[1, 2 * np.ones(n - 2), 1], -np.ones(n - 1)], [-1, 0, 1]
    ).tocsr()
    w, X = sm.eigsh(Lp, 8, sigma=-1e-6)
    exact = 2 - 2 * np.cos(np.pi * np.arange(8) / n)
    assert abs(w[0]) < 1e-10
    assert np.abs(w - exact).max() <= 1e-10 * exact.max()
