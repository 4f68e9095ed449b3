"""Input handling: every dtype and order is accepted, everything wrong is a clear
exception (never a crash), files fail with OSError subclasses."""

from __future__ import annotations

import errno
import os

import numpy as np
import pytest
import scipy.sparse as sp

import spectral_mesh as sm


@pytest.fixture(scope="module")
def mesh():
    return sm.shape("sphere:res=2")  # 162 vertices


@pytest.fixture(scope="module")
def reference(mesh):
    V, F = mesh
    S, B = sm.laplacian(V, F)
    return S, B, sm.eigenbasis(V, F, 12)


VDTYPES = [np.float64, np.float32, np.int64]
FDTYPES = [np.int64, np.int32, np.uint32, np.uint64, np.int16]


@pytest.mark.parametrize("vdtype", VDTYPES)
@pytest.mark.parametrize("fdtype", FDTYPES)
@pytest.mark.parametrize("order", ["C", "F"])
def test_every_dtype_and_order(mesh, reference, vdtype, fdtype, order):
    V, F = mesh
    scale = 1000 if vdtype == np.int64 else 1  # integer coordinates: scale, then round
    V2 = np.asarray(np.round(V * scale) if scale > 1 else V, dtype=vdtype, order=order)
    F2 = np.asarray(F, dtype=fdtype, order=order)
    S, B = sm.laplacian(V2, F2)
    w, X = sm.eigenbasis(V2, F2, 12)
    if vdtype == np.float64:
        S0, B0, (w0, X0) = reference
        assert abs(S - S0).max() == 0 and abs(B - B0).max() == 0
        assert np.array_equal(w, w0) and np.array_equal(X, X0)
    else:
        ref = sm.eigenbasis(np.asarray(V2, dtype=np.float64), F, 12)[0]
        assert np.array_equal(w, ref)


def test_views_slices_and_lists(mesh, reference):
    V, F = mesh
    _, _, (w0, _) = reference
    big = np.zeros((len(V), 6))
    big[:, ::2] = V  # a strided view
    assert np.array_equal(sm.eigenbasis(big[:, ::2], F, 12)[0], w0)
    assert np.array_equal(sm.eigenbasis(V.tolist(), F.tolist(), 12)[0], w0)
    assert np.array_equal(sm.eigenbasis(V, F[::-1].copy()[::-1], 12)[0], w0)


BAD = [
    (lambda V, F: (V[:, :2], F), "V must have shape (n, 3), got (162, 2)"),
    (lambda V, F: (V.ravel(), F), "V must have shape (n, 3)"),
    (lambda V, F: (V[:0], F), "V is empty"),
    (lambda V, F: (V, F[:, :2]), "F must have shape (m, 3)"),
    (lambda V, F: (V, np.c_[F, F[:, :1]]), "quads"),
    (lambda V, F: (V, F[:0]), "F is empty"),
    (lambda V, F: (V, F.astype(float)), "F must be an integer array"),
    (lambda V, F: (V.astype(complex), F), "V must hold real numbers"),
    (lambda V, F: (V.astype(str), F), "V must hold real numbers"),
    (lambda V, F: (V.astype(object), F), "V must hold real numbers"),
    (
        lambda V, F: (np.where(np.arange(len(V))[:, None] == 7, np.nan, V), F),
        "V[7] has a non-finite coordinate",
    ),
    (
        lambda V, F: (np.where(np.arange(len(V))[:, None] == 3, np.inf, V), F),
        "V[3] has a non-finite coordinate",
    ),
    (
        lambda V, F: (V, np.where(np.arange(len(F))[:, None] == 5, 10_000, F)),
        "F[5] refers to vertex 10000, but V has 162 vertices",
    ),
    (
        lambda V, F: (V, np.where(np.arange(len(F))[:, None] == 9, -1, F)),
        "F[9] refers to vertex -1",
    ),
    (lambda V, F: (V, np.where(np.arange(len(F))[:, None] == 2, F[2, 0], F)), "F[2] uses vertex"),
]


@pytest.mark.parametrize("make,message", BAD, ids=[b[1][:30] for b in BAD])
def test_bad_meshes_raise_value_error(mesh, make, message):
    V, F = make(*mesh)
    for call in (
        lambda: sm.laplacian(V, F),
        lambda: sm.eigenbasis(V, F, 5),
        lambda: sm.Analysis(V, F),
        lambda: sm.render(V, F, np.zeros(len(V))),
    ):
        with pytest.raises(ValueError) as e:
            call()
        assert message in str(e.value)


def test_bad_parameters(mesh):
    V, F = mesh
    n = len(V)
    cases = [
        (
            lambda: sm.eigenbasis(V, F, n + 1),
            f"k = {n + 1} eigenpairs asked for, but the mesh has only {n} vertices",
        ),
        (lambda: sm.eigenbasis(V, F, 0), "k = 0: must be >= 1"),
        (lambda: sm.eigenbasis(V, F, 2.5), "k must be an integer"),
        (lambda: sm.eigenbasis(V, F, 5, "cotan-ish"), "unknown Laplacian 'cotan-ish'"),
        (lambda: sm.eigenbasis(V, F, 5, tol=-1), "tol = -1: must be a finite number > 0"),
        (lambda: sm.eigenbasis(V, F, 5, tol=float("nan")), "tol = nan: must be a finite number"),
        (lambda: sm.eigenbasis(V, F, 5, method="lobpcg"), "method = 'lobpcg'"),
        (lambda: sm.eigenbasis(V, F, 5, dirichlet=[n]), f"Dirichlet vertex {n} does not exist"),
        (lambda: sm.laplacian(V, F, "nope"), "unknown Laplacian 'nope'"),
        (lambda: sm.shape("klein-bottle"), "unknown shape `klein-bottle`"),
        (lambda: sm.shape("sphere:res=x"), "bad value `x` for parameter `res`"),
        (
            lambda: sm.render(V, F, np.zeros(n - 1)),
            f"values has {n - 1} values but the mesh has {n} vertices",
        ),
        (lambda: sm.render(V, F, np.zeros(n), colormap="jet"), "unknown colour map 'jet'"),
        (lambda: sm.render(V, F, np.zeros(n), view="diagonal"), "unknown view 'diagonal'"),
        (lambda: sm.render(V, F, np.zeros(n), size=0), "size = 0: must be >= 1"),
        (lambda: sm.render(V, F, np.zeros(n), size=100_000), "invalid image size"),
        (lambda: sm.render(V, F, np.zeros(n), marks=[n]), f"marked vertex {n} is out of range"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError) as e:
            call()
        assert message in str(e.value), (message, str(e.value))


def test_bad_field_requests(mesh):
    V, F = mesh
    an = sm.Analysis(V, F)
    n = len(V)
    cases = [
        (lambda: an.heat(n), f"anchor {n} is out of range: the mesh has {n} vertices"),
        (lambda: an.heat(-1), "anchor = -1: must be >= 0"),
        (lambda: an.heat(t=-1.0), "t: -1: the time must be a finite number >= 0"),
        (lambda: an.heat(t=float("inf")), "t = inf: must be a finite number"),
        (lambda: an.heat(k=n + 1), f"k = {n + 1} eigenpairs asked for"),
        (lambda: an.heat(kernel="gauss"), "unknown variant `gauss`"),
        (lambda: an.distance(distance="biharmonik"), "biharmonik"),
        (
            lambda: an.distance(distance="custom-w:exp(-s*t;t=1"),
            "expression error at character 8 of 'exp(-s*t': expected ')'",
        ),
        (lambda: an.distance(distance="diffusion:t=-1"), "diffusion"),
        (
            lambda: an.distance(3, distance="band:200", k=20),
            "band-suppression index 200 is out of range",
        ),
        (
            lambda: an.diffuse(np.ones(n - 1)),
            f"signal has {n - 1} values but the mesh has {n} vertices",
        ),
        (lambda: an.diffuse(np.r_[np.nan, np.ones(n - 1)]), "signal[0] = nan is not finite"),
        (lambda: an.diffuse({"vertex": 0}), "a ball signal is"),
        (lambda: an.harmonic(3), "3: the presets are 2, 4 or 6"),
        (
            lambda: an.harmonic({0: 1.0}, order=3),
            "order: 3: must be 1 (harmonic) or 2 (bi-harmonic)",
        ),
        (lambda: an.harmonic({n: 1.0}), f"constraint on vertex {n}, but the mesh has {n} vertices"),
        (lambda: an.harmonic([(0, np.nan)]), "constraint value = nan"),
        (lambda: an.eigenfunction(20, k=20), "index: 20: out of range for k = 20 pairs"),
        (lambda: an.wks(1.0, sigma=0.0), "sigma: 0: must be a finite number > 0"),
        (lambda: an.segmentation("nonsense"), "unknown signature 'nonsense'"),
        (
            lambda: an.segmentation(persistence=-1.0),
            "persistence: -1: must be a finite number >= 0",
        ),
        (lambda: an.field("geodesics"), "unknown variant `geodesics`"),
        (lambda: an.field("geodesic", source=n), f"source {n} is out of range"),
        (lambda: an.field("geodesic", time_factor=0.0), "time_factor: 0"),
        (lambda: an.field("distance", filter="biharmonic"), "unknown field `filter`"),
        (
            lambda: an.critical_points(np.zeros(3)),
            f"values has 3 values but the mesh has {n} vertices",
        ),
        (lambda: an.level_sets(np.zeros(n), [np.inf]), "level = inf: must be a finite number"),
        (
            lambda: an.set_basis(np.ones(3), np.ones((n, 2))),
            "evecs has 2 columns but evals has 3 values",
        ),
        (
            lambda: an.set_basis(np.ones(3), np.ones((n + 1, 3))),
            f"basis has {n + 1} values but the mesh has {n} vertices",
        ),
    ]
    for call, message in cases:
        with pytest.raises(ValueError) as e:
            call()
        assert message in str(e.value), (message, str(e.value))


def test_files(tmp_path, mesh):
    V, F = mesh
    with pytest.raises(FileNotFoundError) as e:
        sm.read_mesh(tmp_path / "missing.off")
    assert e.value.errno == errno.ENOENT and e.value.filename == str(tmp_path / "missing.off")
    assert "cannot read" in str(e.value)
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
    with pytest.raises(sm.MeshFileError) as e:
        sm.read_mesh(bad)
    assert isinstance(e.value, OSError)
    assert str(e.value).startswith(f"{bad}:") and "7" in str(e.value)
    assert e.value.filename == str(bad) and e.value.lineno == 6
    unknown = tmp_path / "mesh.xyz"
    unknown.write_text("hello")
    with pytest.raises(sm.MeshFileError):
        sm.read_mesh(unknown)
    with pytest.raises(IsADirectoryError):
        sm.read_mesh(tmp_path)
    with pytest.raises(FileNotFoundError):
        sm.load_basis(tmp_path / "nothing.npz")
    with pytest.raises(sm.MeshFileError) as e:
        sm.load_basis(bad)
    assert "not a valid eigenbasis archive" in str(e.value)
    # Writing into a folder that does not exist: OSError, nothing left behind.
    with pytest.raises(FileNotFoundError):
        sm.write_mesh(tmp_path / "no" / "such" / "dir.off", V, F)
    with pytest.raises(FileNotFoundError):
        sm.render(V, F, V[:, 0], tmp_path / "no" / "pic.png")
    # A round trip through every format.
    for ext in ["off", "obj", "ply", "stl"]:
        p = tmp_path / f"m.{ext}"
        sm.write_mesh(p, V, F)
        V2, F2 = sm.read_mesh(p)
        if ext != "stl":  # STL stores float32 triangles and merges vertices
            assert np.array_equal(F2, F) and np.abs(V2 - V).max() < 1e-12, ext
    assert sorted(os.listdir(tmp_path)) == sorted(
        ["bad.off", "m.obj", "m.off", "m.ply", "m.stl", "mesh.xyz"]
    )


def test_eigsh_input_errors():
    A = sp.diags([1.0, 2.0, 3.0, 4.0]).tocsr()
    cases = [
        (lambda: sm.eigsh(A, 2), "which = 'LM' without sigma asks for the largest"),
        (lambda: sm.eigsh(A, 2, sigma=1.0), "sigma = 1.0 > 0"),
        (lambda: sm.eigsh(A, 2, sigma=-1, which="SA"), "only 'LM'"),
        (lambda: sm.eigsh(A, 5, sigma=-1), "k = 5: must be between 1 and n = 4"),
        (
            lambda: sm.eigsh(sp.random(4, 4, density=0.8, random_state=1) + sp.eye(4), 2, sigma=-1),
            "A is not symmetric",
        ),
        (lambda: sm.eigsh(sp.random(4, 3, density=1.0), 2, sigma=-1), "A must be square"),
        (lambda: sm.eigsh(A, 2, sp.eye(5), sigma=-1), "M has shape (5, 5) but A has shape (4, 4)"),
        (lambda: sm.eigsh(A, 2, sigma=-1, mode="cayley"), "only 'normal'"),
        (lambda: sm.eigsh(A, 2, sigma=-1, OPinv=object()), "OPinv"),
        (lambda: sm.eigsh(sp.linalg.aslinearoperator(A), 2, sigma=-1), "LinearOperator"),
        (lambda: sm.eigsh(A.multiply(np.nan), 2, sigma=-1), "A has non-finite entries"),
        (
            lambda: sm.eigsh(A, 2, sigma=-1, tol=-1.0),
            "tol = -1: must be a finite number > 0, or 0 for the default (1e-10)",
        ),
    ]
    for call, message in cases:
        with pytest.raises(ValueError) as e:
            call()
        assert message in str(e.value), (message, str(e.value))
    with pytest.raises(ValueError, match=r"A is not positive semi-definite: A\[0, 0\] = -5"):
        sm.eigsh(sp.diags([-5.0, 1.0, 2.0, 3.0]).tocsr(), 2, sigma=-1)
    with pytest.raises(ValueError, match=r"M is not positive definite: M\[1, 1\] = 0"):
        sm.eigsh(A, 2, sp.diags([1.0, 0.0, 1.0, 1.0]), sigma=-1)
    # An indefinite M with a positive diagonal: a SolverError rather than a crash.
    n = 200
    Mind = sp.identity(n, format="lil")
    Mind[0, 1] = Mind[1, 0] = 2.0
    with pytest.raises(sm.SolverError, match="not positive definite"):
        sm.eigsh(sp.diags(np.arange(1.0, n + 1)).tocsr(), 3, Mind.tocsr(), sigma=-1e-3)


def test_native_module_checks_its_own_input():
    # The private module validates too: no crash when called directly with bad arrays.
    V, F = sm.shape("sphere:res=1")
    nat = sm._native
    with pytest.raises(ValueError, match="C-contiguous"):
        nat.laplacian(np.asfortranarray(V), F, "fem", False)
    with pytest.raises(ValueError, match="shape"):
        nat.laplacian(V[:, :2].copy(), F, "fem", False)
    with pytest.raises(TypeError):
        nat.laplacian(V.astype(np.float32), F, "fem", False)
    with pytest.raises(ValueError, match="inconsistent"):
        nat.eigsh(
            3, (np.ones(2), np.array([0, 0]), np.array([0, 2, 2, 2])), None, 1, 1e-10, 1, "auto"
        )
