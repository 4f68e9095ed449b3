"""Shared meshes and helpers of the Python package's test suite.

Run by ``bash scripts/test-python.sh`` (which builds and installs the package into the
conformance venv first). Tests that use the shared real meshes read their folder from
``SPECTRAL_MESH_SHARED_MESHES``; unset, they are skipped and say so.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import spectral_mesh as sm

SHARED = os.environ.get("SPECTRAL_MESH_SHARED_MESHES")


@pytest.fixture(scope="session")
def sphere():
    """An icosphere (642 vertices, closed, Delaunay)."""
    return sm.shape("sphere:res=3")


@pytest.fixture(scope="session")
def torus():
    """An irregularly sampled torus (closed, genus 1, triangle areas vary a lot)."""
    return sm.shape("irregular-torus:res=3")


@pytest.fixture(scope="session")
def disk():
    """A disk (bordered)."""
    return sm.shape("disk:res=1")


@pytest.fixture(scope="session")
def pretzel():
    """The paper's 3-torus (genus 3)."""
    return sm.shape("3torus")


def shared_mesh(name: str) -> Path:
    if not SHARED:
        pytest.skip("SPECTRAL_MESH_SHARED_MESHES is not set: test on shared meshes skipped")
    p = Path(SHARED) / name
    if not p.exists():
        pytest.fail(f"{p} is missing from SPECTRAL_MESH_SHARED_MESHES")
    return p


def subspace_gap(X: np.ndarray, Y: np.ndarray, B) -> float:
    """The largest principal-angle sine between span(X) and span(Y), both B-orthonormal:
    sqrt(1 - sigma_min(X^T B Y)^2)."""
    s = np.linalg.svd(X.T @ (B @ Y), compute_uv=False)
    return float(np.sqrt(max(0.0, 1.0 - s.min() ** 2)))


def clusters(evals: np.ndarray, rel: float = 1e-6) -> list[range]:
    """Index ranges of (numerically) repeated eigenvalues."""
    out, start = [], 0
    scale = max(abs(evals).max(), 1e-300)
    for i in range(1, len(evals) + 1):
        if i == len(evals) or evals[i] - evals[i - 1] > rel * scale:
            out.append(range(start, i))
            start = i
    return out
