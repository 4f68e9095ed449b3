"""Shared meshes and helpers of the Python package's test suite.

Run by ``bash scripts/test-python.sh`` (which builds and installs the package into the
conformance venv first). Tests that use the shared real meshes read their folder from
``SPECTRAL_MESH_SHARED_MESHES`` (the shared point clouds are in ``points`` beside it);
unset, they are skipped and say so, except under CI (``CI`` set), where they fail: a CI
that forgot the variable must not look green.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import spectral_mesh as sm

SHARED = os.environ.get("SPECTRAL_MESH_SHARED_MESHES")


def _shape_fixture(name, spec, doc):
    """A session fixture `name` giving the built-in shape `spec`."""

    def build():
        return sm.shape(spec)

    build.__doc__ = doc
    return pytest.fixture(scope="session", name=name)(build)


sphere = _shape_fixture("sphere", "sphere:res=3", "An icosphere (642 vertices, closed, Delaunay).")
torus = _shape_fixture(
    "torus",
    "irregular-torus:res=3",
    "An irregularly sampled torus (closed, genus 1, triangle areas vary a lot).",
)
disk = _shape_fixture("disk", "disk:res=1", "A disk (bordered).")
pretzel = _shape_fixture("pretzel", "3torus", "The paper's 3-torus (genus 3).")


ROOT = Path(__file__).resolve().parents[3]


def cli() -> str:
    """The command line the tests compare with: ``SPECTRAL_MESH_CLI`` (scripts/test-python.sh
    sets it), else the newest of the workspace's release and debug builds."""
    exe = os.environ.get("SPECTRAL_MESH_CLI")
    if exe:
        return exe
    found = [
        p
        for p in (ROOT / "target/release/spectral-mesh", ROOT / "target/debug/spectral-mesh")
        if p.exists()
    ]
    if not found:
        pytest.skip("no spectral-mesh binary: set SPECTRAL_MESH_CLI (scripts/test-python.sh does)")
    return str(max(found, key=lambda p: p.stat().st_mtime))


def under_ci() -> bool:
    """Whether this run is CI's (``CI`` set, and not ``false`` or ``0``)."""
    return os.environ.get("CI", "") not in ("", "false", "0")


def shared_dir() -> Path | None:
    """The folder of shared meshes; ``None`` when the variable is unset outside CI (the
    caller skips or uses generated data); a failure under CI or when it is no folder."""
    if not SHARED:
        if under_ci():
            pytest.fail("SPECTRAL_MESH_SHARED_MESHES is not set under CI")
        return None
    d = Path(SHARED)
    if not d.is_dir():
        pytest.fail(f"SPECTRAL_MESH_SHARED_MESHES={SHARED} is not a folder")
    return d


def shared_mesh(name: str) -> Path:
    d = shared_dir()
    if d is None:
        pytest.skip("SPECTRAL_MESH_SHARED_MESHES is not set: test on shared meshes skipped")
    p = d / name
    if not p.exists():
        pytest.fail(f"{p} is missing from SPECTRAL_MESH_SHARED_MESHES")
    return p


def shared_point_cloud(name: str) -> Path | None:
    """A shared point cloud (``points`` beside the meshes' folder), or ``None`` when the
    variable is unset outside CI."""
    d = shared_dir()
    if d is None:
        return None
    p = d.parent / "points" / name
    if not p.exists():
        pytest.fail(f"{p} is missing (the points folder beside SPECTRAL_MESH_SHARED_MESHES)")
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
