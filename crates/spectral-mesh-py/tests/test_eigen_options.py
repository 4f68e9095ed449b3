"""``eigenbasis(certify=True)`` and ``eigenbasis(dtype="float32")``: the library's inertia
certificate and float32 bases, through the Python call (the command line's
``eigs --certify`` and ``--dtype float32``)."""

from __future__ import annotations

import numpy as np
import pytest

import spectral_mesh as sm


def test_certify_counts_the_sphere_clusters(sphere):
    """The icosphere's spectrum comes in clusters 1, 3, 5, 7, 9: k = 16 ends a cluster and
    k = 12 cuts the l = 3 one; both are certified without completion, and the pairs are
    those of the plain call."""
    V, F = sphere
    for k in (16, 12):
        w, X = sm.eigenbasis(V, F, k, method="shift-invert")
        wc, Xc, cert = sm.eigenbasis(V, F, k, method="shift-invert", certify=True)
        assert cert["certified"] is True
        assert cert["k"] == k
        first = cert["first"]
        # Every eigenvalue below the shift was computed (multiplicities included).
        assert first["below"] == first["found"] >= k
        assert first["shift"] > wc[-1]
        assert cert["added"] == 0 and cert["values_changed"] == 0
        assert cert["last"] == first
        assert any(line.startswith("certified") for line in cert["lines"])
        assert np.array_equal(w, wc) and np.array_equal(X, Xc)


def test_certify_on_several_components():
    """Three disjoint spheres: three zero eigenvalues, every eigenvalue of multiplicity 3
    or more; the count agrees."""
    V, F = sm.shape("sphere:res=2")
    n = len(V)
    V3 = np.vstack([V, V + [3.0, 0, 0], V + [6.0, 0, 0]])
    F3 = np.vstack([F, F + n, F + 2 * n])
    w, X, cert = sm.eigenbasis(V3, F3, 30, method="shift-invert", certify=True)
    assert cert["certified"]
    assert np.count_nonzero(w == 0.0) == 3
    assert cert["first"]["below"] == cert["first"]["found"]


def test_certify_is_only_a_third_item_when_asked(torus):
    V, F = torus
    out = sm.eigenbasis(V, F, 10, certify=False)
    assert len(out) == 2


def test_float32_is_the_float64_basis_rounded_once(torus):
    V, F = torus
    k = 20
    w, X = sm.eigenbasis(V, F, k)
    w32, X32 = sm.eigenbasis(V, F, k, dtype="float32")
    assert w32.dtype == np.float32 and X32.dtype == np.float32
    assert X32.shape == X.shape and X32.flags.f_contiguous
    # Computed in double precision, rounded once: bit for bit the float64 result cast.
    assert np.array_equal(w32, w.astype(np.float32))
    assert np.array_equal(X32, X.astype(np.float32))
    # The names the command line takes are accepted, and float64 is the default.
    w64, X64 = sm.eigenbasis(V, F, k, dtype="float64")
    assert w64.dtype == np.float64 and np.array_equal(X64, X)


def test_float32_with_certify(sphere):
    V, F = sphere
    w, X, cert = sm.eigenbasis(V, F, 9, method="shift-invert", certify=True, dtype="float32")
    assert cert["certified"] and w.dtype == np.float32 and X.dtype == np.float32
    # l = 0, 1, 2: 1 + 3 + 5 pairs.
    assert np.all(np.diff(w[1:4]) <= 1e-5 * w[3])


def test_a_bad_dtype_is_a_value_error(torus):
    V, F = torus
    with pytest.raises(ValueError, match="dtype"):
        sm.eigenbasis(V, F, 5, dtype="float16")
