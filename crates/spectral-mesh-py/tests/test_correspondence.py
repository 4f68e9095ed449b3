"""Shape correspondence from Python: ZoomOut in both directions on a shuffled copy (the
maps are the known permutation and its inverse, and agree with each other)."""

from __future__ import annotations

import numpy as np
import pytest

import spectral_mesh as sm


def blob(res: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """An icosphere deformed without any symmetry."""
    V, F = sm.shape(f"sphere:res={res}")
    x, y, z = V[:, 0], V[:, 1], V[:, 2]
    W = np.column_stack([
        1.6 * x + 0.35 * x * x + 0.2 * y,
        0.9 * y + 0.25 * z * z,
        0.7 * z + 0.3 * x * y + 0.15 * z ** 3,
    ])
    return W, F


def shuffled(V: np.ndarray, F: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mesh with its vertices renumbered: vertex ``i`` of the copy is vertex
    ``perm[i]`` of the original (``perm`` is the true ``p2p_21``)."""
    perm = np.random.default_rng(seed).permutation(len(V))
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(V))
    return V[perm], inv[F], perm


def test_zoomout_both_directions_on_a_shuffled_pair():
    V1, F1 = blob()
    V2, F2, perm = shuffled(V1, F1, 3)
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(perm))
    C = sm.functional_map(V1, F1, V2, F2, k=20)
    assert C.shape == (20, 20)
    both = sm.zoomout(V1, F1, V2, F2, C, 50, direction="both")
    assert len(both) == 4
    C21, p21, C12, p12 = both
    assert C21.shape == C12.shape == (50, 50)
    assert p21.shape == (len(V2),) and p12.shape == (len(V1),)
    assert np.mean(p21 == perm) > 0.99
    assert np.mean(p12 == inv) > 0.99
    # Consistent: inverse point maps, transposed functional maps.
    assert np.mean(p21[p12] == np.arange(len(V1))) > 0.99
    assert np.linalg.norm(C12 - C21.T) < 0.05 * np.linalg.norm(C21)
    # One direction at a time gives the same as both.
    fwd = sm.zoomout(V1, F1, V2, F2, C, 50, direction="forward")
    rev = sm.zoomout(V1, F1, V2, F2, C, 50, direction="reverse")
    assert len(fwd) == len(rev) == 2
    np.testing.assert_array_equal(fwd[1], p21)
    np.testing.assert_array_equal(rev[1], p12)
    np.testing.assert_array_equal(rev[0], C12)
    # The default is the library's (forward).
    assert sm.zoomout(V1, F1, V2, F2, C, 30)[1].shape == (len(V2),)
    with pytest.raises(ValueError, match="forward, reverse or both"):
        sm.zoomout(V1, F1, V2, F2, C, 30, direction="sideways")
