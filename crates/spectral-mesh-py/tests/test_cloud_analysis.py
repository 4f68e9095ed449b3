"""Point clouds in the analysis object (issue 16): ``Analysis.from_points`` and
``Analysis.from_file``, equal to the command line on the same file and parameters, every
field kind on a cloud, and bad input as ``ValueError`` with the library's message.

The command line is ``SPECTRAL_MESH_CLI`` (``scripts/test-python.sh`` builds it), else the
workspace's ``target/{release,debug}/spectral-mesh``; the shared clouds are the ``points``
folder beside ``SPECTRAL_MESH_SHARED_MESHES`` (conftest); without it a generated sphere
stands in (under CI the missing folder fails).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

import spectral_mesh as sm
from conftest import cli, shared_point_cloud



def run_cli(*args: str, cwd: Path) -> str:
    r = subprocess.run([cli(), *args], capture_output=True, text=True, cwd=cwd, timeout=600)
    assert r.returncode == 0, f"spectral-mesh {' '.join(args)}: {r.stderr}"
    return r.stdout


def sphere_points(n: int) -> np.ndarray:
    """``n`` points on the unit sphere (Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    y = 1 - 2 * i / n
    r = np.sqrt(1 - y * y)
    th = np.pi * (3 - np.sqrt(5)) * (i - 0.5)
    return np.column_stack([r * np.cos(th), y, r * np.sin(th)])


@pytest.fixture(scope="module")
def cloud_file(tmp_path_factory) -> Path:
    """A shared real cloud (a smooth closed scan), or a generated sphere when absent."""
    shared = shared_point_cloud("blobby.xyz")
    if shared is not None:
        return shared
    p = tmp_path_factory.mktemp("cloud") / "sphere.xyz"
    np.savetxt(p, sphere_points(1500), fmt="%.17g")
    return p


def close(a: np.ndarray, b: np.ndarray, rel: float = 1e-12) -> bool:
    return bool(np.abs(a - b).max() <= rel * max(1.0, float(np.abs(b).max())))


def test_eigenvalues_and_heat_equal_the_command_lines(cloud_file, tmp_path):
    k, nb = 10, 12
    run_cli(
        "eigs",
        str(cloud_file),
        "-k",
        str(k),
        "--neighbors",
        str(nb),
        "--eigenvalues-txt",
        "ev.txt",
        cwd=tmp_path,
    )
    ev_cli = np.loadtxt(tmp_path / "ev.txt")[:k]
    # eigs analyses the cloud as given (not scaled), like normalize=False.
    an = sm.Analysis.from_file(cloud_file, n_neighbors=nb, normalize=False)
    assert an.is_point_cloud and an.kind == "robust"
    assert an.point_cloud_params["neighbors"] == nb
    assert close(an.eigenvalues(k), ev_cli), (an.eigenvalues(k), ev_cli)
    # The same from the arrays (the file's normals left out, as the CLI without
    # --use-normals).
    P, _normals = sm.read_points(cloud_file)
    pts = sm.Analysis.from_points(P, n_neighbors=nb, normalize=False)
    assert close(pts.eigenvalues(k), ev_cli)
    assert np.array_equal(pts.V, P) and np.array_equal(pts.F, an.F)
    # Other neighbours, another spectrum: the parameter reaches the operator.
    other = sm.Analysis.from_file(cloud_file, normalize=False)
    assert not close(other.eigenvalues(k), ev_cli, 1e-6)

    run_cli(
        "heat",
        str(cloud_file),
        "-k",
        "20",
        "--t",
        "0.02",
        "--neighbors",
        str(nb),
        "-o",
        "heat.txt",
        cwd=tmp_path,
    )
    heat_cli = np.loadtxt(tmp_path / "heat.txt")
    heat = sm.Analysis.from_file(cloud_file, n_neighbors=nb).heat(t=0.02, k=20)
    assert heat.shape == heat_cli.shape
    assert close(heat, heat_cli)


@pytest.fixture(scope="module")
def ball() -> sm.Analysis:
    return sm.Analysis.from_points(sphere_points(900))


def test_every_field_works_on_a_cloud(ball):
    an = ball
    n = an.n
    assert n == 900 and an.is_point_cloud and an.kind == "robust"
    assert an.F.shape[1] == 3 and an.F.max() < n
    assert 0.05 < an.point_spacing < 0.2
    assert an.point_cloud_params == {
        "neighbors": sm.DEFAULTS["point_cloud"]["n_neighbors"],
        "mollify_factor": sm.DEFAULTS["point_cloud"]["mollify_factor"],
        "delaunay_tolerance": sm.DEFAULTS["point_cloud"]["delaunay_tolerance"],
        "normals": "estimate",
        "union": sm.DEFAULTS["point_cloud"]["union"],
    }
    assert "points=900" in repr(an)
    evals, evecs = an.basis(16)
    # The unit-area sphere: l (l + 1) 4 pi, multiplicity 2l + 1, within 2%.
    assert abs(evals[0]) < 1e-8
    assert np.abs(evals[1:4] / (2 * 4 * np.pi) - 1).max() < 0.02, evals
    k = 30
    fields = {
        "heat": an.heat(t=0.01, k=k),
        "diffusion": an.diffuse(0, t=0.01, k=k),
        "diffusion-ball": an.diffuse({"vertex": 0, "radius": 0.3}, t=0.01, k=k),
        "distance": an.distance(0, k=k),
        "wfem-distance": an.distance(0, distance="wfem-diffusion:t=0.1", k=k),
        "callable-distance": an.distance(0, distance=lambda s: 1 / s**3, k=k),
        "spectral-function": an.spectral_function(k=k),
        "green": an.green(0, k=k),
        "hks": an.hks(0.1, k=k),
        "wks": an.wks(2.0, k=k),
        "adf": an.adf(0.1, k=k),
        "eigenfunction": an.eigenfunction(1, k=k),
        "embedding": an.embedding(component=1, k=k),
        "harmonic": an.harmonic(2),
        "biharmonic": an.harmonic({0: 0.0, 450: 1.0}, order=2),
    }
    for name, f in fields.items():
        assert f.shape == (n,), name
        assert np.isfinite(f).all(), name
    assert fields["distance"][0] == 0 and fields["distance"].max() > 0
    assert an.hks([0.01, 0.1], k=k).shape == (n, 2)
    assert an.distance([0, 1, 2], k=k).shape == (n, 3)
    assert an.embedding(k=k).shape[0] == n
    labels = an.segmentation(k=k)
    assert labels.shape == (n,) and labels.dtype == np.int64
    # Critical points on the triangle union: an l = 1 eigenfunction of the sphere has one
    # minimum and one maximum, and the Euler check holds.
    cp = an.critical_points(fields["eigenfunction"])
    assert cp.holds and cp.chi == 2
    sets = an.level_sets(fields["harmonic"], 5)
    assert len(sets) == 5 and all(s.segments.shape[1:] == (2, 3) for s in sets)
    img = an.render(fields["distance"], size=200)
    assert img.shape == (200, 200, 4) and img.dtype == np.uint8
    assert (img[..., :3] != 255).any()


def test_bad_clouds_raise_value_error_with_the_librarys_message(tmp_path):
    P = sphere_points(200)
    with pytest.raises(ValueError, match=r"P must have shape \(n, 3\), got \(200, 2\)"):
        sm.Analysis.from_points(P[:, :2])
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        sm.Analysis.from_points(P.T)
    bad = P.copy()
    bad[7, 1] = np.nan
    with pytest.raises(ValueError, match=r"P\[7\] has a non-finite coordinate"):
        sm.Analysis.from_points(bad)
    with pytest.raises(ValueError, match="the number of neighbours must be at least 2, got 1"):
        sm.Analysis.from_points(P, n_neighbors=1)
    with pytest.raises(ValueError, match="mollify factor must be a finite number >= 0"):
        sm.Analysis.from_points(P, mollify_factor=-1.0)
    with pytest.raises(ValueError, match="normals has 10 rows but P has 200 points"):
        sm.Analysis.from_points(P, P[:10])
    # Too few points: none for a triangle, or fewer than the pairs asked for.
    with pytest.raises(ValueError, match="has no triangle in its local triangulations"):
        sm.Analysis.from_points(P[:2])
    small = sm.Analysis.from_points(P[:40])
    with pytest.raises(ValueError, match="k = 50 eigenpairs asked for, but the mesh has only 40"):
        small.basis(50)
    # A discretization that needs triangles, and cloud parameters with a mesh.
    xyz = tmp_path / "p.xyz"
    np.savetxt(xyz, P, fmt="%.17g")
    with pytest.raises(ValueError, match="the fem Laplacian needs triangles"):
        sm.Analysis.from_file(xyz, "fem")
    off = tmp_path / "m.off"
    sm.write_mesh(off, *sm.shape("sphere:res=1"))
    with pytest.raises(ValueError, match="n_neighbors applies only to point clouds"):
        sm.Analysis.from_file(off, n_neighbors=8)
    mesh = sm.Analysis.from_file(off)
    assert not mesh.is_point_cloud and mesh.point_cloud_params is None and mesh.kind == "fem"
    assert np.array_equal(mesh.eigenvalues(10), sm.Analysis(*sm.read_mesh(off)).eigenvalues(10))
    default = sm.DEFAULTS["point_cloud"]["n_neighbors"]
    assert sm.Analysis.from_file(xyz).point_cloud_params["neighbors"] == default


def test_given_normals_give_the_tangent_planes():
    P = sphere_points(1200)
    # The same normals for every point: near the equator the tangent planes are wrong, so
    # the local triangulations (and the operator) change if the normals are used.
    up = np.tile([0.0, 0.0, 1.0], (len(P), 1))
    S0, _ = sm.point_cloud_laplacian(P)
    S1, _ = sm.point_cloud_laplacian(P, normals=up)
    assert abs(S1 - S0).max() > 0
    an = sm.Analysis.from_points(P, up)
    assert an.point_cloud_params["normals"] == "from-cloud"
    S2, _ = an.operators()
    assert abs(S2 - S1).max() == 0
