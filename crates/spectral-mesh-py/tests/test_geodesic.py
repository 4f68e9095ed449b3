"""Heat-method geodesics from Python: potpourri3d's numbers, the solver object, errors."""

from __future__ import annotations

import numpy as np
import pytest

import spectral_mesh as sm

pp3d = pytest.importorskip("potpourri3d")


@pytest.mark.parametrize("kind,robust", [("voronoi-cot", False), ("robust", True)])
def test_matches_potpourri3d(torus, kind, robust):
    V, F = torus
    ours = sm.geodesic_distance(V, F, 0, kind, convention="potpourri3d")
    theirs = pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1.0, use_robust=robust).compute_distance(0)
    assert np.abs(ours - theirs).max() <= 1e-6 * np.abs(theirs).max()


def test_solver_keeps_its_factors(sphere):
    V, F = sphere
    s = sm.GeodesicSolver(V, F, "voronoi-cot")
    assert s.t == pytest.approx(s.h**2)
    D = s.distances([0, 5, 9])
    assert D.shape == (3, len(V))
    np.testing.assert_allclose(D[1], s.distance(5), rtol=0, atol=1e-12)
    # The set's distance is about the minimum of the single ones.
    d = s.distance([0, 5, 9])
    assert np.abs(d - D.min(axis=0)).mean() < 0.03 * D.max()
    # A face point at a corner is that vertex.
    f0 = int(F[0, 0])
    np.testing.assert_allclose(s.distance(face_points=[(0, (1.0, 0.0, 0.0))]), s.distance(f0), atol=1e-12)
    M = s.distance_matrix(s.farthest_point_sampling(5), symmetric=True)
    assert M.shape == (5, 5) and np.allclose(M, M.T)


def test_errors(sphere):
    V, F = sphere
    s = sm.GeodesicSolver(V, F, "voronoi-cot")
    with pytest.raises(ValueError, match="out of range"):
        s.distance(len(V))
    with pytest.raises(ValueError, match="time factor"):
        sm.GeodesicSolver(V, F, time_factor=-1.0)
    with pytest.raises(ValueError, match="convention"):
        sm.GeodesicSolver(V, F, convention="nope")


def _sphere_points(n, seed=0):
    P = np.random.default_rng(seed).normal(size=(n, 3))
    return P / np.linalg.norm(P, axis=1, keepdims=True)


def test_point_cloud_distance_on_the_sphere():
    P = _sphere_points(3000)
    exact = np.arccos(np.clip(P @ P[0], -1.0, 1.0))
    d = sm.point_cloud_geodesic_distance(P, 0)
    assert d.shape == (len(P),) and d[0] == 0.0
    err = np.abs(d - exact).mean()
    assert err < 0.05, err
    # potpourri3d's point-cloud solver (the mesh heat method on its tufted cover) on the
    # same cloud: the two agree to a few per cent of the diameter.
    theirs = pp3d.PointCloudHeatSolver(P, t_coef=1.0).compute_distance(0)
    assert np.abs(d - theirs).mean() < 0.05 * np.pi
    s = sm.GeodesicSolver.from_points(P, gradient_neighbors=8)
    assert s.n == len(P) and s.t == pytest.approx(s.h**2)
    D = s.distances([0, 7])
    assert D.shape == (2, len(P)) and D[1, 7] == 0.0
    with pytest.raises(ValueError, match="face-point"):
        s.distance(face_points=[(0, (1.0, 0.0, 0.0))])
    with pytest.raises(ValueError, match="neighbours"):
        sm.GeodesicSolver.from_points(P, gradient_neighbors=1)
