"""Type stubs of the private native module ``spectral_mesh._native`` (Rust, PyO3).

The public API is the pure-Python layer (``spectral_mesh``), which normalizes input to the
layouts taken here: ``V`` C-contiguous ``(n, 3)`` float64, ``F`` C-contiguous ``(m, 3)``
int64, per-vertex values ``(n,)`` float64, ``n x k`` matrices given as their C-contiguous
``(k, n)`` transpose, requests and reports as dicts (the library's serde forms), sparse matrices as CSC arrays ``(data float64, indices int64,
indptr int64)`` (for the symmetric operators these are also their CSR arrays). Returned
``(n, k)`` matrices are Fortran-ordered. Every function releases the GIL, runs on a
worker thread, raises ``KeyboardInterrupt`` on Ctrl-C and never lets a Rust panic through
(``InternalError``).
"""

from os import PathLike
from typing import Any, Callable, Final, TypedDict

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
Csc = tuple[F64, I64, I64]
# The eigensolver's keywords ``(tol, seed, dirichlet, method)`` (``_arrays.solver``).
Solver = tuple[float, int, list[int] | None, str]
# The point-cloud Laplacian's keywords ``(n_neighbors, mollify_factor)``, ``None`` for
# the library's default (``_arrays.cloud``).
Cloud = tuple[int | None, float | None]
# A point cloud: ``(P, normals or None, cloud keywords)``.
Points = tuple[F64, F64 | None, Cloud]
# One shape of a pair: ``(V, F, evals or None, evecs_t)`` (``evecs_t``: the ``(k, n)``
# transpose of the eigenvectors).
PairShape = tuple[F64, I64, F64 | None, F64]
# How the pairs are weighted: a filter's text, or a Python weight function's values at
# ``filter_eigenvalues`` and its name (for messages; checked: strictly positive, finite).
Weights = str | tuple[F64, str]
# The picture options of both ``render``s, checked by the Python layer (``_render_args``).
Figure = TypedDict(
    "Figure",
    {
        "levels": int,
        "colormap": str,
        "view": str,
        "size": int,
        "transparent": bool,
        "critical_points": bool,
        "colorbar": bool,
        "legend": bool,
        "height": int | None,
        "scale": float | None,
        "dpi": int | None,
    },
)
# What both ``render``s draw after the mesh: ``(values, marks, labels, figure, path)``.
Picture = tuple[F64, list[int], list[int] | None, Figure, str | PathLike[str] | None]

__version__: str

def read_mesh(path: str | PathLike[str]) -> tuple[F64, I64, dict]:
    """``(V (n, 3), F (m, 3), info)``; info: format, polygons triangulated, warnings."""

def write_mesh(path: str | PathLike[str], v: F64, f: I64) -> None: ...
def shape(spec: str) -> tuple[F64, I64]: ...
def shape_names() -> list[dict]:
    """The built-in shapes."""

def laplacian(v: F64, f: I64, kind: str, normalize: bool) -> tuple[Csc, Csc, float]:
    """``(S, B, A)``: S positive semi-definite, B the mass (``/ A`` when normalizing), A =
    ``1^T B 1`` as assembled."""

def read_points(path: str | PathLike[str]) -> tuple[F64, F64 | None, dict]:
    """``(P (n, 3), normals (n, 3) or None, info)``; info: format, warnings."""

def point_laplacian(points: Points, normalize: bool) -> tuple[Csc, Csc, float]:
    """``(S, B, A)`` of a point cloud (B diagonal), A = ``1^T B 1`` as assembled."""

def eigenbasis(
    v: F64,
    f: I64,
    k: int,
    kind: str,
    normalize: bool,
    solver: Solver,
    progress: Callable[[dict], object] | None = None,
    certify: bool = False,
    dtype: str | None = None,
) -> tuple[NDArray[np.floating[Any]], NDArray[np.floating[Any]], dict | None]:
    """``(evals (k,), evecs (n, k) Fortran order, certificate or None)``,
    ``evecs.T @ B @ evecs = I``; ``progress`` is called with a dict per solver event;
    ``dtype``: ``"float64"`` or ``"float32"`` (``None``: the library's default)."""

def eigsh(
    n: int,
    a: Csc,
    m: Csc | None,
    k: int,
    tol: float,
    seed: int,
    method: str,
    progress: Callable[[dict], object] | None = None,
) -> tuple[F64, F64]:
    """The ``k`` smallest pairs of ``A x = w M x`` (A PSD, M SPD or the identity)."""

def save_basis(
    path: str | PathLike[str],
    evals: F64,
    evecs_t: F64,
    mass: Csc,
    kind: str,
    v: F64 | None = None,
    f: I64 | None = None,
) -> None: ...
def load_basis(path: str | PathLike[str]) -> tuple[F64, F64, Csc, dict]:
    """``(evals, evecs (n, k), mass CSC arrays, meta)``."""

def render(v: F64, f: I64, picture: Picture) -> NDArray[np.uint8] | None:
    """Writes ``path`` (format from its extension) and returns None, or returns the
    ``(size, size, 4)`` RGBA picture."""

def defaults() -> dict[str, Any]:
    """The library's defaults: ``requests`` (every request kind's keys), ``analysis``,
    ``figure``, ``point_cloud``, ``batch`` (``spectral_mesh.batch``'s keywords),
    ``zero_eigenvalue_eps``, ``shape``, ``laplacians``, ``colormaps``."""

def learning_operators(
    v: F64,
    f: I64 | None,
    k_eig: int,
    cache_dir: str | None,
    dtype: str,
    normals: F64 | None,
    laplacian: str,
    grad_regularization: float,
    n_neighbors: int,
    tol: float,
) -> tuple[tuple[Any, Any, Csc, Any, Any, Csc, Csc], bool, str | None]:
    """``((frames (n, 3, 3), mass, L, evals, evecs (n, k) Fortran, gradX, gradY),
    from_cache, cache_file)``; a point cloud when ``f`` is None; float arrays in ``dtype``
    (``"float64"`` or ``"float32"``, rounded once), sparse ones as CSC arrays."""

def learning_defaults() -> dict:
    """The library's defaults of the learning operators."""

def num_threads() -> int: ...
def _panic_for_tests(message: str) -> None: ...
def _work_for_tests(seconds: float, checks: bool) -> float: ...

class Analysis:
    """The library's ``Analysis``: one mesh or point cloud, its operators, the factorization and a basis
    that grows with ``k``."""

    def __new__(
        cls,
        v: F64,
        f: I64,
        kind: str,
        normalize: bool,
        solver: Solver,
    ) -> Analysis: ...
    @staticmethod
    def from_points(
        points: Points,
        normalize: bool,
        solver: Solver,
    ) -> Analysis:
        """The analysis of a point cloud (its point-cloud Laplacian, kind robust); given
        normals give the tangent planes; ``None`` parameters are the library's defaults."""
    @staticmethod
    def from_file(
        path: str | PathLike[str],
        kind: str | None,
        cloud: Cloud,
        use_normals: bool,
        normalize: bool,
        solver: Solver,
    ) -> Analysis:
        """The analysis of a mesh or point-cloud file; point-cloud parameters given with a
        mesh raise ``ValueError``."""
    n: Final[int]
    is_point_cloud: Final[bool]
    point_spacing: Final[float | None]
    held_k: Final[int]
    normalized: Final[bool]
    kind: Final[str]
    input_total_mass: Final[float]
    factorizations: Final[int]
    default_source: Final[int]
    def mesh(self) -> tuple[F64, I64]: ...
    def operators(self) -> tuple[Csc, Csc]: ...
    def basis(
        self, k: int, progress: Callable[[dict], object] | None = None
    ) -> tuple[F64, F64]: ...
    def residuals(self) -> F64: ...
    def field(self, request: dict, values: F64 | None = None) -> tuple[F64, I64 | None, dict]:
        """A ``FieldRequest`` in its serde form (a dict tagged by ``kind``): ``(values
        (n,), labels (n,) or None, info)``."""
    def critical_points(self, values: F64) -> dict: ...
    def level_sets(
        self, values: F64, levels: list[float], count: int | None = None
    ) -> list[tuple[float, F64]]: ...
    def hks_many(self, times: list[float], scaled: bool, k: int) -> F64: ...
    def hks_auto_times(self, count: int, k: int) -> list[float]: ...
    def wks_many(self, energies: list[float], sigma: float, scaled: bool, k: int) -> F64: ...
    def wks_auto_energies(self, count: int, k: int) -> tuple[list[float], float]: ...
    def embedding_matrix(self, weights: Weights, k: int) -> F64: ...
    def distances_many(self, sources: list[int], weights: Weights, k: int) -> F64: ...
    def filter_eigenvalues(self, k: int) -> tuple[list[int], F64]:
        """``(pair indices, eigenvalues)`` of the first ``k`` pairs a filter weighs (the
        library's zero-eigenvalue rule); a Python weight function is evaluated at these."""
    def green_weighted(self, source: int, weights: Weights, k: int) -> F64: ...
    def spectral_function_weighted(self, weights: Weights, k: int) -> F64: ...
    def embedding_component_weighted(self, weights: Weights, component: int, k: int) -> F64: ...
    def set_basis(self, evals: F64, evecs_t: F64) -> None: ...
    def save_basis(self, path: str | PathLike[str]) -> None: ...
    def load_basis(self, path: str | PathLike[str]) -> int: ...
    def render(self, picture: Picture) -> NDArray[np.uint8] | None: ...
    def options(self) -> dict:
        """kind, normalize, tol, seed, dirichlet and point_cloud (the point-cloud
        Laplacian's parameters, or None for a mesh)."""
    def __repr__(self) -> str: ...

def batch_params(json: str) -> tuple[str, str]: ...
def batch_inputs(specs: list[str]) -> list[tuple[str, str]]: ...
def batch_prepare(out: str | PathLike[str], force: bool) -> int: ...
def batch_one(
    path: str | PathLike[str],
    name: str,
    params: str,
    out: str | PathLike[str],
    threads: int,
    retry_failed: bool = False,
) -> str: ...
def batch_failed(path: str, name: str, params_hash: str, message: str) -> str: ...
def batch_summary(out: str | PathLike[str], records: list[str]) -> tuple[str, str]: ...

class GeodesicSolver:
    def __init__(
        self, v: F64, f: I64, kind: str, time_factor: float | None = None, convention: str | None = None
    ) -> None: ...
    @staticmethod
    def from_points(
        points: Points,
        gradient_neighbors: int | None = None,
        time_factor: float | None = None,
        convention: str | None = None,
    ) -> GeodesicSolver: ...
    def distance(self, vertices: list[int], points: list[tuple[int, float, float, float]]) -> F64: ...
    def distances(self, vertices: list[int]) -> F64: ...
    def distance_matrix(self, samples: list[int], symmetric: bool) -> F64: ...
    def farthest_point_sampling(self, k: int, start: int) -> list[int]: ...
    t: Final[float]
    h: Final[float]
    n: Final[int]

def correspondence_defaults() -> str: ...
def functional_map(
    shape1: PairShape,
    shape2: PairShape,
    kind: str,
    params: str,
    landmarks: list[tuple[int, int]],
) -> tuple[F64, float]: ...
def zoomout_refine(
    shape1: PairShape,
    shape2: PairShape,
    kind: str,
    c: F64,
    k_final: int,
    step: int,
    direction: str,
) -> tuple[tuple[F64, NDArray[np.uintp]] | None, tuple[F64, NDArray[np.uintp]] | None]: ...
def point_map(
    c: F64, evecs1_t: F64, evecs2_t: F64, adjoint: bool, to_second: bool
) -> NDArray[np.uintp]: ...
def pairs_plan(specs: list[str], pairing: str, params: str) -> tuple[list[str], str]: ...
def match_pair(job: str, params: str, out: str | PathLike[str], threads: int) -> str: ...
def pair_failed(job: str, params: str, message: str) -> str: ...
def pairs_summary(out: str | PathLike[str], records: list[str]) -> str: ...
