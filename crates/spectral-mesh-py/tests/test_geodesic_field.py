"""Geodesic distance as a field request: ``Analysis.field("geodesic", ...)`` is the library's
kind (the same numbers as the solver object), and unreachable components are said."""

from __future__ import annotations

import numpy as np
import pytest

import spectral_mesh as sm


def test_analysis_field_geodesic_is_the_solvers_distance(pretzel):
    """``an.field("geodesic")``: the library's request kind, the same numbers as the
    solver object, in mesh units whatever the normalisation, no eigenbasis."""
    V, F = pretzel
    an = sm.Analysis(V, F)
    d, info = an.field("geodesic", source=7, return_info=True)
    assert d.shape == (len(V),) and d[7] == 0.0
    s = sm.GeodesicSolver(V, F, "fem")
    np.testing.assert_allclose(d, s.distance(7), rtol=0, atol=1e-12)
    assert info["request"] == {"kind": "geodesic", "source": 7, "time_factor": 1.0, "convention": "crane"}
    assert info["k"] is None and info["normalized"] is False and info["unreachable"] == []
    # The default source is the vertex of largest x; a set is the nearest of its vertices.
    d0 = an.field("geodesic")
    assert d0[int(np.argmax(V[:, 0]))] == 0.0
    both = an.field("geodesic", sources=[7, 100], time_factor=2.0, convention="potpourri3d")
    np.testing.assert_allclose(
        both, sm.GeodesicSolver(V, F, "fem", time_factor=2.0, convention="potpourri3d").distance([7, 100]),
        rtol=0, atol=1e-12,
    )


def test_analysis_field_geodesic_says_what_it_cannot_reach(sphere):
    V, F = sphere
    n = len(V)
    V2 = np.vstack([V, V + [10.0, 0.0, 0.0]])
    F2 = np.vstack([F, F + n])
    an = sm.Analysis(V2, F2)
    with pytest.warns(RuntimeWarning, match=f"{n} of {2 * n} vertices cannot be reached"):
        d, info = an.field("geodesic", source=0, return_info=True)
    assert np.isfinite(d[:n]).all() and np.isposinf(d[n:]).all()
    assert info["unreachable_vertices"] == n and len(info["unreachable"]) == 1
    with pytest.raises(ValueError, match=f"source {2 * n} is out of range"):
        an.field("geodesic", source=2 * n)


def test_batch_saves_geodesic_distances_from_farthest_samples(tmp_path):
    """``batch(..., geodesic=N)``: the library's farthest-point samples and the distance
    from each, as arrays of the result (processes=1: no pool start-up cost matters)."""
    V, F = sm.shape("torus:res=2")
    sm.write_mesh(tmp_path / "t.off", V, F)
    out = tmp_path / "out"
    (rec,) = sm.batch([str(tmp_path / "t.off")], out, k=6, geodesic=3, processes=1)
    assert rec["status"] == "ok", rec
    with np.load(out / "t.off.npz") as z:
        D, S = z["geodesic"], z["geodesic_sources"].astype(int)
    assert D.shape == (len(V), 3) and S.shape == (3,)
    s = sm.GeodesicSolver(V, F, "fem")
    assert S[0] == int(np.argmax(V[:, 0]))
    np.testing.assert_array_equal(S, s.farthest_point_sampling(3, start=int(S[0])))
    for j in range(3):
        np.testing.assert_allclose(D[:, j], s.distance(int(S[j])), rtol=0, atol=1e-12)
        assert D[S[j], j] == 0.0
