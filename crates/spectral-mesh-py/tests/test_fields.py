"""Fields of the analysis object checked against their definitions (docs/MATH.md), basis
files, pictures and the example script."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

import spectral_mesh as sm

HERE = Path(__file__).resolve().parent


@pytest.fixture(scope="module")
def small():
    """A small bordered mesh whose full spectrum is cheap (dense reference), bumped at
    random so that no symmetry makes eigenvalues repeat (a truncation that cuts a cluster
    of repeated eigenvalues depends on the basis chosen inside it)."""
    V, F = sm.shape("disk:res=1")
    V = V.copy()
    V[:, 2] += 0.05 * np.random.default_rng(7).standard_normal(len(V))
    return V, F


@pytest.fixture(scope="module")
def full(small):
    """The analysis of the small mesh and its full generalized spectrum (dense)."""
    V, F = small
    an = sm.Analysis(V, F)
    S, B = an.operators()
    w, X = sla.eigh(S.toarray(), B.toarray())
    return an, S, B, w, X


def test_heat_kernel_definitions(full):
    an, S, B, w, X = full
    n = an.n
    a, t = 5, 0.01
    Kt = X @ np.diag(np.exp(-w * t)) @ X.T
    h = an.heat(a, t=t, k=n)
    assert np.abs(h - Kt @ B @ np.eye(n)[a]).max() <= 1e-9 * np.abs(h).max()
    std = an.heat(a, t=t, kernel="standard", k=n)
    assert np.abs(std - Kt[:, a]).max() <= 1e-9 * np.abs(std).max()
    D = np.asarray(B.sum(axis=1)).ravel()
    vc = an.heat(a, t=t, kernel="voronoi-cot", k=n)
    assert np.abs(vc - Kt[:, a] * D[a]).max() <= 1e-9 * np.abs(vc).max()
    # Diffusion conserves the B-mass and K_s K_t = K_{s+t} (full spectrum).
    rng = np.random.default_rng(0)
    f = rng.standard_normal(n)
    g = an.diffuse(f, t=t, k=n)
    assert abs(np.sum(B @ g) - np.sum(B @ f)) <= 1e-9 * np.abs(B @ f).sum()
    gg = an.diffuse(an.diffuse(f, t=0.004, k=n), t=0.006, k=n)
    assert np.abs(gg - g).max() <= 1e-9 * np.abs(g).max()
    # An impulse diffuses to the heat basis function; a ball is its indicator diffused.
    assert np.allclose(an.diffuse(a, t=t, k=n), h, rtol=0, atol=1e-12 * np.abs(h).max())
    assert an.last_info["marks"] == [a]
    ball = np.linalg.norm(an.V - an.V[a], axis=1) <= 0.3
    assert np.allclose(
        an.diffuse({"vertex": a, "radius": 0.3}, t=t, k=n), an.diffuse(ball.astype(float), t=t, k=n)
    )


def test_distances(full):
    an, S, B, w, X = full
    n, k = an.n, 30
    src = 4
    pos = w[:k] > 1e-8 * w[:k].max()
    E = X[:, :k][:, pos] / w[:k][pos]  # bi-harmonic embedding: w = 1/s^2, sqrt(w) = 1/s
    want = np.linalg.norm(E - E[src], axis=1)
    d = an.distance(src, k=k)
    assert d[src] == 0 and np.abs(d - want).max() <= 1e-9 * want.max()
    assert (
        np.abs(np.linalg.norm(an.embedding(k=k) - an.embedding(k=k)[src], axis=1) - d).max()
        <= 1e-9 * d.max()
    )
    # Several sources: one column each, and every filter of the text syntax.
    many = an.distance([src, 7], k=k)
    assert many.shape == (n, 2) and np.array_equal(many[:, 0], d)
    for text, weight in [
        ("commute", lambda s: 1 / s),
        ("diffusion:t=0.05", lambda s: np.exp(-0.05 * s)),
        ("mix:a=0.3,t=0.1", lambda s: 0.7 * np.exp(-0.1 * s) + 0.3 / s**2),
        ("poly:p=3", lambda s: s**-3.0),
        ("custom-w:exp(-s*t)/s;t=0.1", lambda s: np.exp(-0.1 * s) / s),
        ("custom-phi:s^2+s", lambda s: 1 / (s**2 + s)),
    ]:
        Wt = weight(w[:k][pos])
        Et = X[:, :k][:, pos] * np.sqrt(Wt)
        want = np.linalg.norm(Et - Et[src], axis=1)
        got = an.distance(src, distance=text, k=k)
        assert np.abs(got - want).max() <= 1e-9 * want.max(), text
        assert (
            np.abs(an.spectral_function(text, k=k) - np.sum(Et**2, axis=1)).max()
            <= 1e-9 * np.sum(Et**2, axis=1).max()
        ), text
        assert (
            np.abs(an.green(src, filter=text, k=k) - Et @ Et[src]).max()
            <= 1e-9 * np.abs(Et @ Et[src]).max()
        ), text
    # A Python weight function is the same filter as its text form.
    assert (
        np.abs(
            an.distance(src, distance=lambda s: np.exp(-0.1 * s) / s, k=k)
            - an.distance(src, distance="custom-w:exp(-s*t)/s;t=0.1", k=k)
        ).max()
        <= 1e-12
    )
    assert (
        np.abs(an.distance([src, 7], distance=lambda s: s**-2.0, k=k) - many).max()
        <= 1e-12 * many.max()
    )
    assert (
        np.abs(
            an.spectral_function(lambda s: 1 / s, k=k) - an.spectral_function("commute", k=k)
        ).max()
        <= 1e-12
    )
    assert (
        np.abs(
            an.green(src, filter=lambda s: 1 / s, k=k) - an.green(src, filter="commute", k=k)
        ).max()
        <= 1e-12
    )
    assert np.abs(an.embedding(lambda s: 1 / s, k=k) - an.embedding("commute", k=k)).max() <= 1e-12
    with pytest.raises(ValueError, match="not strictly positive and finite on the spectrum"):
        an.distance(src, distance=lambda s: s - s[3], k=k)
    # wFEM diffusion distance (eq. 15) over the full spectrum.
    t = 0.02
    St = B @ X @ np.diag(np.exp(-w * t)) @ X.T @ B
    e = np.eye(n)
    want = np.sqrt([max(0.0, (e[src] - e[j]) @ St @ (e[src] - e[j])) for j in range(n)])
    got = an.distance(src, distance=f"wfem-diffusion:t={t}", k=n)
    assert np.abs(got - want).max() <= 1e-7 * want.max()
    assert np.array_equal(an.distance([src], distance=f"wfem-diffusion:t={t}", k=n)[:, 0], got)


def test_signatures_eigenfunctions_embedding(full):
    an, S, B, w, X = full
    k = 25
    sign = np.sign(X[np.abs(X[:, :k]).argmax(axis=0), np.arange(k)])
    Xs = X[:, :k] * sign  # the documented sign convention
    assert np.abs(an.eigenfunction(3, k=k) - Xs[:, 3]).max() <= 1e-8
    pos = w[:k] > 1e-8 * w[:k].max()
    adf = np.sum(np.exp(-0.1 * w[:k][pos]) * Xs[:, pos] ** 2, axis=1)
    assert np.abs(an.adf(0.1, k=k) - adf).max() <= 1e-9 * adf.max()
    emb = an.embedding("commute", k=k)
    assert emb.shape == (an.n, pos.sum())
    assert (
        np.abs(an.embedding("commute", component=2, k=k) - Xs[:, 2] / np.sqrt(w[2])).max() <= 1e-8
    )


def test_harmonic_maps_and_critical_points(full):
    an, S, B, w, X = full
    f = an.harmonic()
    c = an.last_info["request"]["constraints"]
    assert c == 2
    xmin, xmax = an.V[:, 0].argmin(), an.V[:, 0].argmax()
    assert f[xmin] == 0 and f[xmax] == 1 and sorted(an.last_info["marks"]) == sorted([xmin, xmax])
    free = np.setdiff1d(np.arange(an.n), [xmin, xmax])
    assert np.abs((S @ f)[free]).max() <= 1e-10
    # Explicit constraints in every form give the same map.
    g = an.harmonic({3: 1.0, 10: -1.0, 20: 0.5})
    assert np.array_equal(g, an.harmonic([(3, 1.0), (10, -1.0), (20, 0.5)]))
    assert np.array_equal(g, an.harmonic((np.array([3, 10, 20]), np.array([1.0, -1.0, 0.5]))))
    assert g[3] == 1 and g[10] == -1 and g[20] == 0.5
    # Bi-harmonic: S D^-1 S f = 0 at the free vertices (D lumped).
    bi = an.harmonic({3: 1.0, 10: -1.0, 20: 0.5}, order=2)
    D = np.asarray(B.sum(axis=1)).ravel()
    r = S @ ((S @ bi) / D)
    free = np.setdiff1d(np.arange(an.n), [3, 10, 20])
    assert np.abs(r[free]).max() <= 1e-8 * np.abs(S @ ((S @ bi) / D)).max() + 1e-8
    cp = an.critical_points(an.harmonic(4))
    assert cp.holds and cp.lhs == cp.rhs
    assert cp.minima.dtype == np.int64 and len(cp.saddles) == len(cp.multiplicities)


def test_segmentation_and_level_sets(pretzel):
    V, F = pretzel
    an = sm.Analysis(V, F)
    labels = an.segmentation(k=50)
    assert labels.dtype == np.int64 and labels.shape == (an.n,)
    assert labels.min() == 0 and len(np.unique(labels)) == labels.max() + 1
    assert labels.max() >= 1
    # The same from the given values of the signature.
    hks = an.hks(0.1, k=50)
    assert np.array_equal(an.segmentation(hks, k=50), labels)
    f = an.harmonic()
    sets = an.level_sets(f, 4)
    assert [s.value for s in sets] == [0.125, 0.375, 0.625, 0.875]
    for s in sets:
        assert s.segments.shape[1:] == (2, 3) and len(s.segments) > 0
        # The end points lie on the surface where f = value: check against the linear
        # interpolation along x through the nearest vertices is too loose; instead every
        # end point lies within the mesh's bounding box.
        assert np.all(s.segments >= V.min(axis=0) - 1e-12) and np.all(
            s.segments <= V.max(axis=0) + 1e-12
        )
    assert [s.value for s in an.level_sets(f, [0.5])] == [0.5]


def test_normalization_changes_times_only(torus):
    V, F = torus
    raw = sm.Analysis(V, F, normalize=False)
    unit = sm.Analysis(V, F)
    A = unit.area
    assert unit.normalized and not raw.normalized and abs(raw.area - A) < 1e-12 * A
    w_raw = raw.eigenvalues(20)
    w_unit = unit.eigenvalues(20)
    assert np.abs(w_unit - A * w_raw).max() <= 1e-9 * w_unit.max()
    # The wFEM heat basis function at unit-area time t is the raw one at time A t:
    # X' = sqrt(A) X, lambda' = A lambda, B' = B / A.
    h_unit = unit.heat(3, t=0.05, k=20)
    h_raw = raw.heat(3, t=0.05 * A, k=20)
    assert np.abs(h_unit - h_raw).max() <= 1e-8 * np.abs(h_unit).max()


def test_basis_files(tmp_path, torus):
    V, F = torus
    an = sm.Analysis(V, F, normalize=False)
    w, X = an.basis(20)
    p = tmp_path / "basis.npz"
    an.save_basis(p)
    f = np.load(p)
    assert np.array_equal(f["eigenvalues"], w) and np.array_equal(f["eigenvectors"], X)
    meta = json.loads(bytes(f["meta"]))
    assert meta["k"] == 20 and meta["laplacian"] == "fem" and meta["mesh_hash"]
    w2, X2 = sm.load_basis(p)
    assert np.array_equal(w2, w) and np.array_equal(X2, X)
    w3, X3, B3, meta3 = sm.load_basis(p, with_mass=True)
    assert abs(B3 - an.operators()[1]).max() == 0 and meta3 == meta
    # A fresh analysis picks it up without solving.
    an2 = sm.Analysis(V, F, normalize=False)
    assert an2.load_basis(p) == 20 and an2.held_k == 20
    assert np.array_equal(an2.distance(3, k=20), an.distance(3, k=20)) and an2.factorizations == 0
    # Refused: another normalization, another discretization, another mesh.
    with pytest.raises(ValueError, match="another mass matrix"):
        sm.Analysis(V, F).load_basis(p)
    with pytest.raises(ValueError, match="'fem' discretization"):
        sm.Analysis(V, F, "voronoi-cot", normalize=False).load_basis(p)
    with pytest.raises(ValueError, match="another mesh"):
        sm.Analysis(V * 1.01, F, normalize=False).load_basis(p)
    # Module-level save from plain arrays (e.g. LaPy's), loaded back.
    S, B = sm.laplacian(V, F)
    q = tmp_path / "plain.npz"
    sm.save_basis(q, w, np.ascontiguousarray(X), B, V=V, F=F)
    an3 = sm.Analysis(V, F, normalize=False)
    assert an3.load_basis(q) == 20 and np.array_equal(an3.basis(20)[1], X)
    # set_basis with arrays: fields use it.
    an4 = sm.Analysis(V, F, normalize=False)
    an4.set_basis(w, X)
    assert np.array_equal(an4.distance(3, k=20), an.distance(3, k=20)) and an4.factorizations == 0
    assert an4.residuals().max() < 1e-8


def test_pictures(tmp_path, sphere):
    V, F = sphere
    an = sm.Analysis(V, F)
    d = an.distance(0, k=30)
    img = an.render(d, size=120)
    assert img.shape == (120, 120, 4) and img.dtype == np.uint8
    assert len(np.unique(img.reshape(-1, 4), axis=0)) > 50  # a coloured surface
    assert np.array_equal(img, sm.render(V, F, d, size=120, marks=[0]))
    p = tmp_path / "d.png"
    assert an.render(d, p, size=120) is None
    assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    seg = an.segmentation(k=30)
    lab = an.render(seg.astype(float), size=80, labels=seg)
    assert lab.shape == (80, 80, 4)
    for ext in ["wrl", "ply", "txt"]:
        q = tmp_path / f"d.{ext}"
        an.render(d, q, size=64)
        assert q.stat().st_size > 0
    assert np.array_equal(np.loadtxt(tmp_path / "d.txt"), d)
    tr = sm.render(V, F, d, size=64, transparent=True, view=(30, 20), colormap="viridis", levels=0)
    assert tr[0, 0, 3] == 0


def test_defaults_come_from_the_library(sphere):
    d = sm.DEFAULTS
    assert d["requests"]["heat"] == {"t": 0.5, "kernel": "wfem", "k": 100}
    assert d["requests"]["distance"] == {"distance": "biharmonic", "k": 100}
    assert d["requests"]["harmonic"] == {"constraints": 2, "order": 1}
    assert d["analysis"]["normalize"] is True and d["analysis"]["kind"] == "fem"
    import inspect

    sig = inspect.signature(sm.Analysis.heat)
    assert sig.parameters["t"].default == d["requests"]["heat"]["t"]
    assert inspect.signature(sm.eigenbasis).parameters["k"].default == d["analysis"]["k"]
    # The default source is the vertex of largest x.
    V, F = sphere
    an = sm.Analysis(V, F)
    an.distance(k=20)
    assert an.last_info["request"]["source"] == int(V[:, 0].argmax()) == an.default_source


def test_stubs_match_the_native_module():
    """Every function, method and read-only attribute the stub declares exists, and every
    public native one is declared."""
    import ast

    stub = Path(sm.__file__).with_name("_native.pyi")
    tree = ast.parse(stub.read_text())
    declared = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Analysis")
    methods = {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}
    methods |= {
        n.target.id
        for n in cls.body
        if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)
    }
    native = {
        x for x in dir(sm._native) if not x.startswith("__") and callable(getattr(sm._native, x))
    }
    assert declared == native
    have = {x for x in dir(sm._native.Analysis) if not x.startswith("__")}
    assert methods - {"__new__", "__repr__"} == have


def test_example_script(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "fig.png"
    env = dict(os.environ, MPLBACKEND="Agg")
    r = subprocess.run(
        [
            sys.executable,
            str(HERE.parent / "examples" / "biharmonic_distance.py"),
            "--shape",
            "3torus",
            "--k",
            "40",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:4] == b"\x89PNG"
