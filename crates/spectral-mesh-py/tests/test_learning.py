"""spectral_mesh.learning: DiffusionNet's per-shape operators (exact gradients on flat
patches, the library's eigenpairs, float32 by rounding, the disk cache, conformance with
DiffusionNet's computation) and the geomfum plug-in."""

from __future__ import annotations

import importlib.util
import inspect
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import spectral_mesh as sm
from spectral_mesh import _native, learning
from conftest import clusters, subspace_gap

# Appended, not prepended: conformance/ holds a script named robust_laplacian.py.
sys.path.append(str(Path(__file__).resolve().parents[3] / "conformance"))
import diffusionnet_scipy as dn  # noqa: E402


def flat_patch(m: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """A jittered grid on a generic plane, triangulated."""
    rng = np.random.default_rng(7)
    u, v = np.meshgrid(np.linspace(0, 1, m), np.linspace(0, 1, m))
    uv = np.stack((u.ravel(), v.ravel()), axis=1)
    inner = (uv > 0).all(axis=1) & (uv < 1).all(axis=1)
    uv[inner] += 0.3 / (m - 1) * (rng.random((int(inner.sum()), 2)) - 0.5)
    s = np.array([0.6, -0.3, 0.74])
    s /= np.linalg.norm(s)
    t = np.cross([0.2, 0.9, -0.1], s)
    t /= np.linalg.norm(t)
    V = np.array([0.3, -1.2, 2.0]) + uv[:, :1] * s + uv[:, 1:] * t
    a = np.arange(m * m).reshape(m, m)[:-1, :-1].ravel()
    F = np.concatenate(
        [np.stack((a, a + 1, a + m + 1), 1), np.stack((a, a + m + 1, a + m), 1)]
    )
    return V, F


def linear_error(ops, V) -> float:
    frames, _, _, _, _, gx, gy = ops
    a = np.array([0.7, -1.3, 0.4])
    f = V @ a
    ex = np.abs(gx @ f - frames[:, 0] @ a).max()
    ey = np.abs(gy @ f - frames[:, 1] @ a).max()
    return max(ex, ey) / np.linalg.norm(a)


def test_the_order_and_types_are_diffusionnet_s(sphere):
    V, F = sphere
    ops = learning.get_operators(V, F, k_eig=20)
    frames, mass, L, evals, evecs, gx, gy = ops
    n = len(V)
    assert frames.shape == (n, 3, 3) and mass.shape == (n,)
    assert evals.shape == (20,) and evecs.shape == (n, 20)
    for M in (L, gx, gy):
        assert isinstance(M, sp.csc_matrix) and M.shape == (n, n)
    for a in (frames, mass, evals, evecs, L.data, gx.data, gy.data):
        assert a.dtype == np.float64
    # Frames: orthonormal, right-handed, normals outwards on the sphere.
    G = np.einsum("nij,nkj->nik", frames, frames)
    assert np.abs(G - np.eye(3)).max() < 1e-13
    assert np.abs(np.cross(frames[:, 0], frames[:, 1]) - frames[:, 2]).max() < 1e-13
    assert (np.einsum("ni,ni->n", frames[:, 2], V / np.linalg.norm(V, axis=1)[:, None]) > 0.99).all()
    # float32 verts give float32 operators (DiffusionNet's rule), as does dtype=.
    ops32 = learning.get_operators(V.astype(np.float32), F, k_eig=5)
    assert ops32[1].dtype == np.float32 and ops32[2].dtype == np.float32
    assert learning.get_operators(V, F, 5, dtype=np.float32)[4].dtype == np.float32


def test_signature_defaults_are_the_library_s():
    d = _native.learning_defaults()
    assert d["k_eig"] == 128 and d["grad_regularization"] == 1e-5
    for fn in (learning.get_operators, learning.operators):
        p = inspect.signature(fn).parameters
        for name in ("k_eig", "laplacian", "grad_regularization", "n_neighbors", "tol"):
            assert p[name].default == d[name], (fn.__name__, name)
    assert d["laplacian"] == "voronoi-cot"


@pytest.mark.parametrize("cloud", [False, True])
def test_gradients_are_exact_on_linear_functions_of_a_flat_patch(cloud):
    V, F = flat_patch()
    faces = None if cloud else F
    exact = learning.get_operators(V, faces, k_eig=4, grad_regularization=0.0)
    assert linear_error(exact, V) < 1e-11
    # DiffusionNet's default regularization moves the fit (by about 1e-5 / |E^T E|).
    reg = learning.get_operators(V, faces, k_eig=4)
    assert 1e-9 < linear_error(reg, V) < 1e-2


def test_the_eigenpairs_are_the_library_s(torus):
    V, F = torus
    frames, mass, L, evals, evecs, gx, gy = learning.get_operators(V, F, k_eig=30)
    # The library's solver on the returned pencil (L, diag(mass)): the same pairs.
    w, X = sm.eigsh(L, 30, sp.diags(mass), which="SM")
    assert np.array_equal(w, evals) and np.array_equal(X, evecs)
    # The library's voronoi-cot basis of the mesh (mass without the 1e-8 raise).
    S, B = sm.laplacian(V, F, "voronoi-cot")
    assert abs(S - L).max() == 0
    lib_w, lib_X = sm.eigenbasis(V, F, 30, "voronoi-cot")
    assert np.allclose(evals, lib_w, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(evecs.T @ (mass[:, None] * evecs), np.eye(30), atol=1e-9)


def test_float32_is_the_float64_result_rounded_once(sphere):
    V, F = sphere
    a = learning.get_operators(V, F, k_eig=16)
    b = learning.get_operators(V, F, k_eig=16, dtype="float32")
    for x, y in zip(a, b):
        if sp.issparse(x):
            assert np.array_equal(x.indices, y.indices) and np.array_equal(x.indptr, y.indptr)
            x, y = x.data, y.data
        assert y.dtype == np.float32
        assert np.array_equal(x.astype(np.float32), y)


def test_a_second_call_reads_the_cache(sphere, tmp_path):
    V, F = sphere
    first = learning.operators(V, F, k_eig=12, op_cache_dir=tmp_path)
    assert not first.from_cache and first.cache_file is not None
    path = Path(first.cache_file)
    assert path.parent == tmp_path and path.is_file()
    stamp = path.stat().st_mtime_ns
    second = learning.operators(V, F, k_eig=12, op_cache_dir=tmp_path)
    assert second.from_cache and second.cache_file == first.cache_file
    assert path.stat().st_mtime_ns == stamp
    for x, y in zip(first.astuple(), second.astuple()):
        if sp.issparse(x):
            assert (x != y).nnz == 0 and np.array_equal(x.indices, y.indices)
        else:
            assert np.array_equal(x, y)
    # float32 from the cache is the float64 from the cache rounded.
    c32 = learning.operators(V, F, k_eig=12, op_cache_dir=tmp_path, dtype=np.float32)
    assert c32.from_cache and np.array_equal(c32.evecs, first.evecs.astype(np.float32))
    # The file name is the library's content hash; other parameters, another file.
    other = learning.operators(V, F, k_eig=13, op_cache_dir=tmp_path)
    assert not other.from_cache and other.cache_file != first.cache_file
    # numpy can read the archive (DiffusionNet's array names).
    with np.load(path) as z:
        assert np.array_equal(z["evals"], first.evals)
        L = sp.csc_matrix((z["L_data"], z["L_indices"], z["L_indptr"]), shape=tuple(z["L_shape"]))
        assert (L != first.L).nnz == 0


def test_bad_input_is_a_value_error(sphere):
    V, F = sphere
    with pytest.raises(ValueError, match="k_eig"):
        learning.get_operators(V, F, k_eig=len(V) + 1)
    with pytest.raises(ValueError, match="lumped"):
        learning.get_operators(V, F, k_eig=4, laplacian="fem")
    with pytest.raises(ValueError, match="dtype"):
        learning.get_operators(V, F, k_eig=4, dtype=np.int32)
    with pytest.raises(ValueError, match="normals"):
        learning.get_operators(V, F, k_eig=4, normals=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="grad_regularization"):
        learning.get_operators(V, F, k_eig=4, grad_regularization=-1.0)


# ------------------------------------------------------------------ DiffusionNet


def _same_up_to_row_sign(A, B, rtol: float) -> float:
    """max |A - s B| / max |A| with a sign s per row chosen to fit (clouds: the normal's
    sign is arbitrary, so Y and the Y gradient rows may flip)."""
    A, B = sp.csr_matrix(A), sp.csr_matrix(B)
    s = np.sign(np.asarray((A.multiply(B)).sum(axis=1)).ravel())
    s[s == 0] = 1
    return abs(A - sp.diags(s) @ B).max() / abs(A).max()


def test_conformance_with_diffusionnet_on_a_mesh(torus):
    V, F = torus
    k = 40
    ours = learning.get_operators(V, F, k_eig=k)
    ref = dn.operators(V, F, k)
    frames, mass, L, evals, evecs, gx, gy = ours
    # Operators: pp3d's cotan Laplacian (whose cotangents divide by |cross| + 1e-10: about
    # 2e-7 relative on this mesh) and vertex areas (+1e-8 mean, to rounding).
    assert abs(L - ref[2]).max() <= 1e-6 * abs(ref[2]).max()
    np.testing.assert_allclose(mass, ref[1], rtol=1e-13)
    # Frames and gradients: DiffusionNet divides by norm + 1e-6 when it normalizes; that
    # is the only difference on this mesh.
    assert np.abs(frames - ref[0]).max() < 1e-4
    assert abs(gx - ref[5]).max() < 1e-3 * abs(ref[5]).max()
    assert abs(gy - ref[6]).max() < 1e-3 * abs(ref[6]).max()
    # Eigenpairs: DiffusionNet solves with L + 1e-8 I, which raises every eigenvalue by
    # about 1e-8 / mass (its zero one is 4e-6 here); eigenvectors span the same spaces.
    shift = 2e-8 / mass.min()
    assert 0 < ref[3][0] < shift
    np.testing.assert_allclose(evals, ref[3], rtol=1e-6, atol=shift)
    M = sp.diags(mass)
    for c in clusters(evals):
        if c.stop < k:
            assert subspace_gap(evecs[:, c], ref[4][:, c], M) < 1e-4


def test_conformance_with_diffusionnet_on_a_point_cloud():
    # Random points on the unit sphere: no ties among the 30 nearest neighbours (an
    # icosphere's vertices have many, which either side may break its own way).
    rng = np.random.default_rng(3)
    V = rng.normal(size=(1500, 3))
    V /= np.linalg.norm(V, axis=1)[:, None]
    ours = learning.get_operators(V, None, k_eig=10, grad_regularization=1e-5)
    ref = dn.operators(V, None, 10)
    frames = ours[0]
    # Same neighbours, same normals up to sign: X equal, Y and the gradients' Y rows up
    # to a sign per point.
    assert np.abs(np.abs(np.einsum("ni,ni->n", frames[:, 2], ref[0][:, 2])) - 1).max() < 1e-10
    assert np.abs(frames[:, 0] - ref[0][:, 0]).max() < 1e-5
    assert abs(ours[5] - ref[5]).max() < 1e-4 * abs(ref[5]).max()
    assert _same_up_to_row_sign(ours[6], ref[6], 1e-4) < 1e-4
    # The Laplacian is the library's point-cloud Laplacian, not robust_laplacian's (see
    # docs/point-clouds.md): the spectra agree to a few per cent.
    np.testing.assert_allclose(ours[3][1:], ref[3][1:], rtol=0.1)


# ------------------------------------------------------------------ geomfum

HAS_GEOMFUM = importlib.util.find_spec("geomfum") is not None


@pytest.mark.skipif(not HAS_GEOMFUM, reason="geomfum is not installed (optional: conformance/requirements-learning.txt)")
def test_geomfum_registry_finds_the_library_s_laplacian_and_basis(torus):
    from geomfum.laplacian import LaplacianFinder
    from geomfum.shape import PointCloud, TriangleMesh
    import gsops.backend as gs

    V, F = torus
    module = learning.register_geomfum()
    finder = LaplacianFinder.from_registry(mesh=True, which="spectral_mesh")
    assert isinstance(finder, module.MeshLaplacianFinder)
    mesh = TriangleMesh(V, F)
    S, B = mesh.laplacian.find(finder)
    S0, B0 = sm.laplacian(V, F, "voronoi-cot")
    assert abs(gs.sparse.to_scipy_csc(S) - S0).max() == 0
    assert abs(gs.sparse.to_scipy_csc(B) - B0).max() == 0
    # The basis through geomfum's spectrum finder is the library's.
    vals, vecs = mesh.laplacian.find_spectrum(
        laplacian_spectrum_finder=module.spectrum_finder(20), recompute=True
    )
    w, X = sm.eigenbasis(V, F, 20, "voronoi-cot")
    assert np.array_equal(gs.to_numpy(vals), w) and np.array_equal(gs.to_numpy(vecs), X)
    # geomfum's own default route (robust_laplacian's mesh Laplacian, SciPy's eigsh)
    # gives the spectrum of the library's robust Laplacian.
    ref = TriangleMesh(V, F)
    ref_vals, _ = ref.laplacian.find_spectrum(spectrum_size=20, recompute=True)
    w_robust, _ = sm.eigenbasis(V, F, 20, "robust")
    np.testing.assert_allclose(np.sort(gs.to_numpy(ref_vals)), w_robust, rtol=1e-6, atol=1e-8)
    # Point clouds.
    cf = LaplacianFinder.from_registry(mesh=False, which="spectral_mesh")
    Sc, Bc = cf(PointCloud(V))
    S1, B1 = sm.point_cloud_laplacian(V)
    assert abs(gs.sparse.to_scipy_csc(Sc) - S1).max() == 0


def test_register_geomfum_without_geomfum_says_so(monkeypatch):
    if HAS_GEOMFUM:
        monkeypatch.setitem(sys.modules, "geomfum.wrap", None)
    with pytest.raises(ImportError, match="geomfum"):
        learning.register_geomfum()

