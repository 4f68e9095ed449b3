"""One engine, one rulebook: every number the package returns comes from the Rust library,
every default of a public signature is the library's, and each keyword means one thing.

- A Python weight function (``distance=lambda s: 1 / s``) is only evaluated in Python: which
  pairs it weighs, its checks and the distances, Green rows, spectral functions and
  embeddings made from it are the library's (equal to the bit to the text filter and to the
  command line's output).
- ``inspect.signature`` of every public function against ``_native.defaults()``.
- The package's source holds no arithmetic on arrays.
"""

from __future__ import annotations

import ast
import inspect
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import spectral_mesh as sm
from spectral_mesh import _native
from conftest import cli

PACKAGE = Path(sm.__file__).parent


@pytest.fixture(scope="module")
def torus_analysis():
    return sm.Analysis.from_shape("irregular-torus:res=3")


# ------------------------------------------------------------------ weight functions


def test_a_python_weight_function_is_the_library_filter_to_the_bit(torus_analysis):
    """``lambda s: 1 / s`` and the text filter ``commute`` give the same weights (one IEEE
    division each) to the same library functions: the results are equal bit for bit."""
    an = torus_analysis
    k, src = 40, 5
    commute = lambda s: 1 / s  # noqa: E731
    assert np.array_equal(
        an.distance(src, distance=commute, k=k), an.distance(src, distance="commute", k=k)
    )
    assert np.array_equal(
        an.distance([src, 7], distance=commute, k=k),
        an.distance([src, 7], distance="commute", k=k),
    )
    assert np.array_equal(
        an.green(src, filter=commute, k=k), an.green(src, filter="commute", k=k)
    )
    assert np.array_equal(
        an.spectral_function(commute, k=k), an.spectral_function("commute", k=k)
    )
    assert np.array_equal(an.embedding(commute, k=k), an.embedding("commute", k=k))
    for c in (0, 1, 7):
        assert np.array_equal(
            an.embedding(commute, component=c, k=k),
            an.embedding("commute", component=c, k=k),
        ), c
    # The default source is the library's (the vertex of largest x).
    assert np.array_equal(
        an.distance(distance=commute, k=k), an.distance(an.default_source, distance=commute, k=k)
    )


def test_a_weight_function_is_called_on_the_library_s_nonzero_eigenvalues(torus_analysis):
    """The function sees exactly the eigenvalues the library's filters weigh (the zero one
    left out by the library's threshold), and a scalar answer is one weight for all."""
    an = torus_analysis
    k = 30
    seen: list[np.ndarray] = []

    def w(s: np.ndarray) -> np.ndarray:
        seen.append(s.copy())
        return 1 / s

    an.spectral_function(w, k=k)
    evals = an.eigenvalues(k)
    eps = sm.DEFAULTS["zero_eigenvalue_eps"]
    want = evals[np.abs(evals) > eps * np.abs(evals).max()]
    assert np.array_equal(seen[0], want) and want.size == k - 1
    # A constant weight: the spectral function is sum over non-zero pairs of x^2.
    one = an.spectral_function(lambda s: 1.0, k=k)
    assert np.array_equal(one, an.spectral_function("poly:p=0", k=k))


def test_weight_function_errors_name_the_function_and_the_pair(torus_analysis):
    an = torus_analysis
    k = 20

    def bad(s: np.ndarray) -> np.ndarray:
        # Negative at the fourth eigenvalue it sees: pair 4 (pair 0 is the zero one).
        return np.where(np.arange(s.size) == 3, -1.0, 1.0)

    with pytest.raises(ValueError, match=r"bad \(a Python function\) is not strictly positive"):
        an.distance(0, distance=bad, k=k)
    with pytest.raises(ValueError, match=r"w\([0-9.e+-]+\) = -1 at eigenpair index 4"):
        an.green(0, filter=bad, k=k)
    with pytest.raises(ValueError, match="not strictly positive and finite"):
        an.embedding(lambda s: np.full_like(s, np.inf), k=k)
    with pytest.raises(ValueError, match="one weight per eigenvalue"):
        an.spectral_function(lambda s: np.ones(3), k=k)
    with pytest.raises(ValueError, match="out of range"):
        an.distance(an.n, distance=lambda s: 1 / s, k=k)
    with pytest.raises(ValueError, match="component"):
        an.embedding(lambda s: 1 / s, component=k, k=k)


def test_a_weight_function_equals_the_command_line(tmp_path):
    """The command line's commute-time distances (its text output) are the package's
    distances with a Python weight function ``1 / s`` on the same shape."""
    exe = cli()
    shape, k, src = "sphere:res=2", 24, 3
    out = tmp_path / "d.txt"
    r = subprocess.run(
        [exe, "distance", shape, "--source", str(src), "--distance", "commute", "-k", str(k),
         "-o", str(out)],
        capture_output=True, text=True, timeout=600,
    )
    assert r.returncode == 0, r.stderr
    want = np.loadtxt(out)
    got = sm.Analysis.from_shape(shape).distance(src, distance=lambda s: 1 / s, k=k)
    assert got.shape == want.shape
    assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()


def test_no_arithmetic_on_arrays_in_the_python_layer():
    """The pure-Python layer parses, checks and converts: no NumPy mathematics (a formula
    written here would drift from the library's)."""
    banned_np = {
        "sqrt", "exp", "log", "sum", "dot", "einsum", "linalg", "matmul", "outer", "cumsum",
        "mean", "prod", "power", "square", "sin", "cos", "tanh", "norm", "abs",
    }
    found = []
    for path in sorted(PACKAGE.glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id == "np"
                and node.attr in banned_np
            ):
                found.append(f"{path.name}:{node.lineno}: np.{node.attr}")
            if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.MatMult, ast.Pow)):
                found.append(f"{path.name}:{node.lineno}: {type(node.op).__name__}")
    assert not found, "mathematics in the Python layer:\n" + "\n".join(found)


def test_the_zero_eigenvalue_threshold_is_the_library_s():
    from spectral_mesh import _defaults

    assert _defaults.ZERO_EIGENVALUE_EPS == _native.defaults()["zero_eigenvalue_eps"] == 1e-8
    # No copy of it (or of the default tolerance) as a number in the code.
    for path in PACKAGE.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and not isinstance(node.value, bool):
                assert node.value not in (1e-8, 1e-10), f"{path.name}:{node.lineno}"


# ------------------------------------------------------------------ defaults


def _path(d: dict, path: str) -> Any:
    for key in path.split("/"):
        d = d[key]
    return d


# Where each public default lives in the library's defaults (`_native.defaults()`):
# {function: {parameter: path}}. A default not listed here and not None fails the test
# below: a face that states a default of its own.
_ANALYSIS = {
    "kind": "analysis/kind",
    "normalize": "analysis/normalize",
    "tol": "analysis/tol",
    "seed": "analysis/seed",
    "method": "analysis/method",
}
_FIGURE = {
    p: f"figure/{p}"
    for p in (
        "levels", "colormap", "view", "size", "transparent", "critical_points", "colorbar",
        "legend",
    )
}
WHERE: dict[str, dict[str, str]] = {
    "shape": {"spec": "shape"},
    "laplacian": {"kind": "analysis/kind"},
    "point_cloud_laplacian": {
        "n_neighbors": "point_cloud/n_neighbors",
        "mollify_factor": "point_cloud/mollify_factor",
    },
    "eigenbasis": {"k": "analysis/k", **_ANALYSIS},
    "eigsh": {"seed": "analysis/seed", "method": "analysis/method"},
    "save_basis": {"kind": "analysis/kind"},
    "geodesic_distance": {"kind": "analysis/kind"},
    "functional_map": {
        "k": "correspondence/k",
        "kind": "analysis/kind",
        "descriptor": "correspondence/descriptors/kind",
        "n_descr": "correspondence/descriptors/count",
        "subsample_step": "correspondence/descriptors/subsample_step",
        "w_descr": "correspondence/weights/descriptors",
        "w_lap": "correspondence/weights/laplacian",
        "w_dcomm": "correspondence/weights/commutativity",
        "w_orient": "correspondence/weights/orientation",
        "fix_constant": "correspondence/weights/fix_constant",
    },
    "zoomout": {
        "k_final": "correspondence/zoomout_k",
        "step": "correspondence/zoomout_step",
        "direction": "correspondence/zoomout_direction",
        "kind": "analysis/kind",
    },
    "render": _FIGURE,
    "match_pairs": {
        "pairs": "pairs/pairing",
        "k": "pairs/matching/k",
        "zoomout_k": "pairs/matching/zoomout_k",
        "step": "pairs/matching/zoomout_step",
        "direction": "pairs/matching/zoomout_direction",
        "descriptor": "pairs/matching/descriptors/kind",
        "n_descr": "pairs/matching/descriptors/count",
        "subsample_step": "pairs/matching/descriptors/subsample_step",
        "w_descr": "pairs/matching/weights/descriptors",
        "w_lap": "pairs/matching/weights/laplacian",
        "w_dcomm": "pairs/matching/weights/commutativity",
        "w_orient": "pairs/matching/weights/orientation",
        "laplacian": "pairs/laplacian",
        "normalize": "pairs/normalize",
        "tol": "pairs/tolerance",
        "geodesic_sources": "pairs/max_geodesic_sources",
    },
    "batch": {
        "k": "batch/k",
        "laplacian": "batch/laplacian",
        "tol": "batch/tol",
        "normalize": "batch/normalize",
        "eigenvectors": "batch/eigenvectors",
        "scaled": "batch/scaled",
        "n_neighbors": "point_cloud/n_neighbors",
        "mollify_factor": "point_cloud/mollify_factor",
    },
    "Analysis.__init__": _ANALYSIS,
    "Analysis.from_points": {
        **_ANALYSIS,
        "n_neighbors": "point_cloud/n_neighbors",
        "mollify_factor": "point_cloud/mollify_factor",
    },
    "Analysis.from_file": _ANALYSIS,
    "Analysis.from_shape": {"kind": "analysis/kind"},
    "Analysis.basis": {"k": "analysis/k"},
    "Analysis.eigenvalues": {"k": "analysis/k"},
    "Analysis.render": _FIGURE,
    "Analysis.level_sets": {"levels": "figure/levels"},
    "Analysis.hks_times": {"k": "requests/hks/k"},
    "Analysis.auto_hks": {"k": "requests/hks/k", "scaled": "requests/hks/scaled"},
    "Analysis.wks_energies": {"k": "requests/wks/k"},
    "Analysis.auto_wks": {"k": "requests/wks/k", "scaled": "requests/wks/scaled"},
}
# Field methods: each parameter is the request kind's key of the same name.
FIELD_METHODS = {
    "heat": "heat",
    "diffuse": "diffusion",
    "distance": "distance",
    "spectral_function": "spectral-function",
    "green": "green",
    "hks": "hks",
    "wks": "wks",
    "adf": "adf",
    "eigenfunction": "eigenfunction",
    "embedding": "embedding",
    "segmentation": "segmentation",
    "harmonic": "harmonic",
}
# Defaults that are not the library's to state, each with its reason.
NOT_LIBRARY = {
    # SciPy's signature, kept for drop-in use (tol=0 means the default, as in SciPy).
    "eigsh": {"k", "which", "tol", "return_eigenvectors", "mode"},
    # The raw operators and bases: the mesh as given, like libigl, LaPy and SciPy (and the
    # command line's `eigs` and `operators`); an analysis normalizes.
    "laplacian": {"normalize"},
    "point_cloud_laplacian": {"normalize"},
    "eigenbasis": {"normalize", "certify"},
    # How the Python face runs and reports (no effect on any number); `certify` is an
    # opt-in check that adds a third item to the result, as `eigs --certify` is a flag.
    "batch": {"retries", "retry_failed", "force"},
    "match_pairs": {"force"},
    "load_basis": {"with_mass"},
    "Analysis.field": {"return_info"},
    # Which map and which way (pyFM's keywords), and what is returned.
    "functional_map": {"orient_reversing", "return_energy"},
    "p2p": {"adjoint", "to_second"},
    "Analysis.from_file": {"use_normals"},
}


def _public_functions():
    for name in sm.__all__:
        obj = getattr(sm, name)
        if inspect.isfunction(obj):
            yield name, obj
    for name, obj in vars(sm.Analysis).items():
        if isinstance(obj, classmethod):
            obj = obj.__func__
        if inspect.isfunction(obj) and (not name.startswith("_") or name == "__init__"):
            yield f"Analysis.{name}", obj


def test_every_signature_default_is_the_library_s():
    d = _native.defaults()
    checked = 0
    for qual, fn in _public_functions():
        method = qual.split(".")[-1]
        for p in inspect.signature(fn).parameters.values():
            if p.default is inspect.Parameter.empty or p.default is None:
                continue
            if p.name in NOT_LIBRARY.get(qual, set()):
                continue
            if qual.startswith("Analysis.") and method in FIELD_METHODS:
                want = d["requests"][FIELD_METHODS[method]][p.name]
            else:
                where = WHERE.get(qual, {})
                assert p.name in where, (
                    f"{qual}({p.name}={p.default!r}): a default of the Python layer's own; "
                    "read it from the library (_native.defaults())"
                )
                want = _path(d, where[p.name])
            assert p.default == want and type(p.default) is type(want), (qual, p.name)
            checked += 1
    assert checked > 60
    # A default written as None means "the library's" and is resolved there: the use of
    # the normals is the library's choice.
    assert d["point_cloud"]["normals"] == "estimate"



def test_the_defaults_are_the_ones_every_face_reads():
    # One object for every face: the web page's GET /api/defaults answers the same
    # (spectral_mesh_render::defaults::to_json); the figure options read the library's
    # picture defaults, and a point cloud's default discretization is the robust one.
    d = _native.defaults()
    assert d["figure"]["levels"] == d["pictures"]["levels"]
    assert d["figure"]["size"] == d["pictures"]["size"]
    assert d["pictures"]["min_size"] <= d["figure"]["size"] <= d["pictures"]["max_size"]
    assert d["default_laplacian"] == {"mesh": d["analysis"]["kind"], "point cloud": "robust"}
    assert d["batch"]["normalize"] == d["analysis"]["normalize"]
    assert d["server"]["max_k"] >= d["analysis"]["k"]

# ------------------------------------------------------------------ keyword rules


def test_tol_means_one_thing_everywhere(sphere):
    V, F = sphere
    zero = sm.eigenbasis(V, F, 6, tol=0)
    default = sm.eigenbasis(V, F, 6)
    assert np.array_equal(zero[0], default[0]) and np.array_equal(zero[1], default[1])
    S, B = sm.laplacian(V, F)
    w0 = sm.eigsh(S, 6, B, sigma=-0.01, tol=0)[0]
    assert np.array_equal(w0, sm.eigsh(S, 6, B, sigma=-0.01, tol=sm.DEFAULTS["analysis"]["tol"])[0])
    a0 = sm.Analysis(V, F, tol=0)
    assert a0._native.options()["tol"] == sm.DEFAULTS["analysis"]["tol"]
    for call in (
        lambda: sm.eigenbasis(V, F, 6, tol=-1.0),
        lambda: sm.eigsh(S, 6, B, sigma=-0.01, tol=-1.0),
        lambda: sm.Analysis(V, F, tol=-1.0),
        lambda: sm.batch([], "/nonexistent-out", tol=-1.0),
    ):
        with pytest.raises(ValueError, match=r"tol = -1: must be a finite number > 0, or 0"):
            call()


def test_messages_use_python_ranges():
    V = np.zeros((3, 3))
    V[1, 0] = V[2, 1] = 1.0
    with pytest.raises(ValueError, match=r"valid: 0 to 2\)") as e:
        sm.laplacian(V, [[0, 1, 3]])
    assert ".." not in str(e.value)
    an = sm.Analysis.from_shape("sphere:res=1")
    with pytest.raises(ValueError, match=rf"out of range|valid: 0 to {an.n - 1}\)") as e:
        an.harmonic({0: 0.0, an.n: 1.0})
    assert ".." not in str(e.value)
