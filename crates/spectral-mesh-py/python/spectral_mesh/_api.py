"""Meshes, operators, eigenbases, the generic eigensolver, basis files and pictures."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Callable, Literal, Sequence, overload

import numpy as np
import numpy.typing as npt

from . import _arrays, _native
from ._arrays import FloatArray, IntArray

if TYPE_CHECKING:
    from ._arrays import CsrMatrix
from ._defaults import FIGURE, K, KIND, METHOD, POINT_CLOUD, SEED, SHAPE, TOL


# ----------------------------------------------------------------------------- meshes


def read_mesh(path: str | os.PathLike[str]) -> tuple[FloatArray, IntArray]:
    """Read a triangle mesh file: OFF, OBJ, PLY (ASCII or binary) or STL.

    Returns ``(V, F)``: ``V`` is ``(n, 3)`` float64 vertex positions, ``F`` is ``(m, 3)``
    int64 vertex indices (0-based). Polygons are triangulated (fans of convex polygons,
    ear clipping otherwise).

    Raises ``FileNotFoundError`` / ``PermissionError`` / ``OSError`` when the file cannot
    be read and :class:`MeshFileError` (an ``OSError``) when its content is invalid; the
    message names the file and the line.
    """
    V, F, _info = _native.read_mesh(os.fspath(path))
    return V, F


def write_mesh(path: str | os.PathLike[str], V: npt.ArrayLike, F: npt.ArrayLike) -> None:
    """Write ``(V, F)`` to a mesh file; the format comes from the extension (``.off``,
    ``.obj``, ``.ply``, ``.stl``). The file is written to a temporary name and renamed,
    so a failed write never leaves half a file."""
    V, F = _arrays.mesh(V, F)
    _native.write_mesh(os.fspath(path), V, F)


def shape(spec: str = SHAPE) -> tuple[FloatArray, IntArray]:
    """A built-in shape ``(V, F)`` from its spec, e.g. ``"3torus"`` (the paper's default
    shape), ``"sphere:res=5"`` (an icosphere, 10 * 4^res + 2 vertices), ``"torus:res=4,R=1,r=0.3"``,
    ``"irregular-double-torus:res=5"``. :func:`shape_names` lists every name and
    parameter. Deterministic: the same spec gives the same arrays."""
    if not isinstance(spec, str):
        raise ValueError(f"spec must be a string such as 'sphere:res=4', got {spec!r}")
    return _native.shape(spec)


def shape_names() -> list[dict[str, Any]]:
    """The built-in shapes: a list of ``{"name", "description", "params",
    "default_vertices", "vertex_formula"}``."""
    return _native.shape_names()


# -------------------------------------------------------------------------- operators


def laplacian(
    V: npt.ArrayLike, F: npt.ArrayLike, kind: str = KIND, *, normalize: bool = False
) -> tuple[CsrMatrix, CsrMatrix]:
    """The discrete Laplace-Beltrami operator as the pair ``(S, B)``.

    Both are ``n x n`` ``scipy.sparse.csr_matrix`` of float64 and exactly symmetric.

    - ``S`` (stiffness) is the cotangent Laplacian, **positive semi-definite**:
      ``S[i, j] = -(cot a_ij + cot b_ij) / 2`` on an edge, ``S[i, i] = -sum_j S[i, j]``,
      so ``S @ ones = 0``. This is ``-igl.cotmatrix(V, F)`` (libigl's is negative
      semi-definite) and the sign of robust-laplacian's ``L``, LaPy's stiffness and
      pyFM's ``W``. (``kind="uniform"``: the graph Laplacian ``D - A`` instead.)
    - ``B`` (mass), by ``kind``:

      ============== ========================================== ==========================
      kind           B                                          libigl / robust-laplacian
      ============== ========================================== ==========================
      fem (default)  linear FEM: ``|t|/12`` per edge of t,       ``massmatrix(FULL)``
                     ``|t|/6`` on the diagonal (not diagonal)
      voronoi-cot    diagonal, ``sum |t| / 3`` at each vertex   ``massmatrix(BARYCENTRIC)``
      mixed-voronoi  diagonal, Meyer's mixed Voronoi areas      ``massmatrix(VORONOI)``
      cot, uniform   the identity
      robust         diagonal, on the intrinsic Delaunay        ``mesh_laplacian(V, F)``
                     tufted cover (Sharp and Crane 2020)
      ============== ========================================== ==========================

      robust-laplacian's ``M`` is lumped (diagonal) like ``voronoi-cot`` but on its
      intrinsic Delaunay (tufted) triangulation, so its numbers differ on poor meshes;
      ``kind="robust"`` computes that pair (``S`` included: the intrinsic Delaunay
      cotangent weights), and works on any triangle soup (non-manifold edges, duplicate
      or degenerate triangles).

    The generalized eigenproblem is ``S x = lambda B x`` with ``lambda >= 0`` (one zero
    per connected component).

    ``normalize=True`` returns ``(S, B / A)`` with ``A = 1^T B 1`` (the area for the
    area-based masses): the operators of the shape scaled to unit area, whose eigenvalues
    are ``A`` times the raw ones. Default ``False``: the mesh as given, like libigl and
    robust-laplacian.
    """
    V, F = _arrays.mesh(V, F)
    s, b, _total = _native.laplacian(V, F, str(kind), bool(normalize))
    n = V.shape[0]
    return _arrays.csr_from_parts(s, n), _arrays.csr_from_parts(b, n)


# ------------------------------------------------------------------------ point clouds


def read_points(path: str | os.PathLike[str]) -> tuple[FloatArray, FloatArray | None]:
    """Read a point-cloud file: text points (``.xyz``, ``.pts``, ``.txt``: ``x y z`` or
    ``x y z nx ny nz`` per line) or a PLY file's vertices (its faces, if any, are ignored).

    Returns ``(P, normals)``: ``P`` is ``(n, 3)`` float64; ``normals`` is ``(n, 3)``
    float64 when the file has them (a zero row means unknown), else ``None``.

    Raises ``FileNotFoundError`` / ``OSError`` when the file cannot be read and
    :class:`MeshFileError` when its content is invalid (the message names the line).
    """
    P, normals, _info = _native.read_points(os.fspath(path))
    return P, normals


def point_cloud_laplacian(
    P: npt.ArrayLike,
    n_neighbors: int = POINT_CLOUD["n_neighbors"],
    *,
    normals: npt.ArrayLike | None = None,
    mollify_factor: float = POINT_CLOUD["mollify_factor"],
    normalize: bool = False,
) -> tuple[CsrMatrix, CsrMatrix]:
    """The Laplacian ``(S, B)`` of a point cloud ``P`` (``(n, 3)``, any real dtype).

    Both are ``n x n`` ``scipy.sparse.csr_matrix`` of float64: ``S`` positive
    semi-definite with ``S @ ones = 0`` (the sign of :func:`laplacian` and of
    robust-laplacian's ``L``), ``B`` diagonal and positive (lumped areas). Built the way
    ``robust_laplacian.point_cloud_laplacian(P, n_neighbors=30)`` builds it (each point's
    ``n_neighbors`` nearest neighbours triangulated in its tangent plane, the local
    triangles combined, then the robust pipeline: mollification, intrinsic Delaunay),
    except how the local triangles are combined: triangles the neighbourhoods agree on
    first, holes filled, so the operator is not biased by the union rule.

    ``normals``: optional ``(n, 3)`` normals giving the tangent planes (zero rows:
    estimated from the neighbours, as without normals). ``normalize=True`` returns
    ``(S, B / A)`` with ``A = 1^T B 1`` (the cloud scaled to unit area).

    For the eigenpairs use :func:`eigsh`: ``evals, evecs = sm.eigsh(S, k, B, sigma=-0.01)``.

    Raises ``ValueError`` for a bad array (wrong shape, NaN) or ``n_neighbors < 2``.
    """
    P = _arrays.vertices(P, "P")
    nr = None if normals is None else _arrays.vertices(normals, "normals")
    if nr is not None and nr.shape[0] != P.shape[0]:
        raise ValueError(f"normals has {nr.shape[0]} rows but P has {P.shape[0]} points")
    cloud = (_arrays.count(n_neighbors, "n_neighbors", 2), _arrays.real(mollify_factor, "mollify_factor"))
    s, b, _total = _native.point_laplacian((P, nr, cloud), bool(normalize))
    n = P.shape[0]
    return _arrays.csr_from_parts(s, n), _arrays.csr_from_parts(b, n)


# -------------------------------------------------------------------------- eigenbasis


@overload
def eigenbasis(
    V: npt.ArrayLike,
    F: npt.ArrayLike,
    k: int = ...,
    kind: str = ...,
    *,
    normalize: bool = ...,
    tol: float = ...,
    seed: int = ...,
    dirichlet: Sequence[int] | None = ...,
    method: str = ...,
    progress: Callable[[dict[str, Any]], Any] | None = ...,
    certify: Literal[False] = ...,
    dtype: str | None = ...,
) -> tuple[npt.NDArray[np.floating[Any]], npt.NDArray[np.floating[Any]]]: ...


@overload
def eigenbasis(
    V: npt.ArrayLike,
    F: npt.ArrayLike,
    k: int = ...,
    kind: str = ...,
    *,
    normalize: bool = ...,
    tol: float = ...,
    seed: int = ...,
    dirichlet: Sequence[int] | None = ...,
    method: str = ...,
    progress: Callable[[dict[str, Any]], Any] | None = ...,
    certify: Literal[True],
    dtype: str | None = ...,
) -> tuple[npt.NDArray[np.floating[Any]], npt.NDArray[np.floating[Any]], dict[str, Any]]: ...


def eigenbasis(
    V: npt.ArrayLike,
    F: npt.ArrayLike,
    k: int = K,
    kind: str = KIND,
    *,
    normalize: bool = False,
    tol: float = TOL,
    seed: int = SEED,
    dirichlet: Sequence[int] | None = None,
    method: str = METHOD,
    progress: Callable[[dict[str, Any]], Any] | None = None,
    certify: bool = False,
    dtype: str | None = None,
) -> (
    tuple[npt.NDArray[np.floating[Any]], npt.NDArray[np.floating[Any]]]
    | tuple[npt.NDArray[np.floating[Any]], npt.NDArray[np.floating[Any]], dict[str, Any]]
):
    """The ``k`` smallest eigenpairs of ``S x = lambda B x`` for the mesh ``(V, F)``.

    Returns ``(evals, evecs)``: ``evals`` is ``(k,)`` float64 (or ``dtype``), ascending, ``>= 0`` up to
    round-off (one zero per connected component); ``evecs`` is ``(n, k)`` float64
    (Fortran order), **B-orthonormal**: ``evecs.T @ B @ evecs = I`` (not ``evecs.T @ evecs``,
    as with LaPy, pyFM and SciPy's ``eigsh(S, k, M=B, ...)``). Sign convention: each
    eigenvector's entry of largest magnitude is positive (lowest vertex index on ties).
    Repeated eigenvalues are resolved completely before ``k`` pairs are returned.

    This is what ``scipy.sparse.linalg.eigsh(S, k, M=B, sigma=-0.01)`` and
    ``lapy.Solver(TriaMesh(V, F)).eigs(k)`` compute, several times faster and with no
    system library: a block Krylov-Schur iteration on a sparse Cholesky factor, on all
    cores, with the GIL released (Ctrl-C stops it with ``KeyboardInterrupt``).

    Parameters
    ----------
    k : the number of pairs (default 100, the paper's), ``1 <= k <= n``.
    kind : the discretization (see :func:`laplacian`); default ``"fem"``.
    normalize : ``False`` (default here, as LaPy, SciPy and libigl): the mesh as given.
        ``True``: the shape scaled to unit total area (eigenvalues multiplied by the area
        ``A``, eigenvectors by ``sqrt(A)``), the :class:`Analysis` default.
    tol : target relative residual ``||S x - lambda B x|| / ((||S||_1 + |lambda| ||B||_1) ||x||)``
        of every pair (default 1e-10); ``0`` means the default, as in :func:`eigsh` and
        SciPy's ``eigsh`` (one meaning of ``tol`` in every function of the package).
    seed : seed of the start block (results are deterministic for a given seed).
    dirichlet : vertex indices held at zero (Dirichlet boundary conditions); the vectors
        are zero there. Default: natural (Neumann) boundary conditions.
    method : ``"auto"`` (dense for small meshes, else the sparse solver), ``"dense"`` or
        ``"shift-invert"``.
    progress : called with a dict per solver event, on the solver's thread:
        ``{"stage": "factorization", "n", "shift"}``, ``{"stage": "iteration",
        "iteration", "converged", "wanted", "basis"}`` (``wanted`` is ``k`` minus the
        connected components, whose constant vectors are deflated exactly and returned
        first with eigenvalue 0), ``{"stage": "finished",
        "iterations", "solves", "max_residual", "orthogonality_error"}`` or
        ``{"stage": "dense", "n"}``. An exception it raises stops the solve and is raised
        by this call.
    certify : ``True``: prove that no eigenvalue was skipped, multiplicities included
        (the command line's ``eigs --certify``): the eigenvalues below a shift just above
        ``lambda_k`` are counted from the negative pivots of an ``L D L^T`` factorization
        of ``S - sigma B`` (Sylvester's law of inertia) and compared with the computed
        ones; when they disagree the missing pairs are searched for and the completed
        basis is returned. The call then returns a third item, the certificate:
        ``{"certified": True, "k", "first": {"shift", "below", "found"}, "last": {...},
        "added", "searches", "values_changed", "lines"}`` (``first`` is the count of the
        pairs as solved, ``last`` after any completion, ``lines`` the report the command
        line prints). A count that still disagrees raises :class:`SolverError`. Cost:
        about one more factorization.
    dtype : ``"float64"`` (default) or ``"float32"`` (as learning pipelines store
        bases): the pairs are computed in double precision either way and rounded once.

    Raises ``ValueError`` for bad arrays or parameters (``k > n`` among them),
    :class:`NoConvergenceError` and :class:`SolverError` for numerical failures.

    For several ``k`` on one mesh, or fields computed from the basis, use
    :class:`Analysis`, which keeps the operators and the basis.
    """
    V, F = _arrays.mesh(V, F)
    k = _arrays.count(k, "k", 1)
    if k > V.shape[0]:
        raise ValueError(
            f"k = {k} eigenpairs asked for, but the mesh has only {V.shape[0]} vertices"
        )
    evals, evecs, certificate = _native.eigenbasis(
        V,
        F,
        k,
        str(kind),
        bool(normalize),
        _arrays.solver(tol, seed, dirichlet, method),
        progress,
        bool(certify),
        None if dtype is None else str(dtype),
    )
    if certify:
        assert certificate is not None
        return evals, evecs, certificate
    return evals, evecs


#: A matrix :func:`eigsh` takes: a SciPy sparse matrix or array (any format) or a dense 2-d
#: array.
Matrix = Any  # scipy.sparse.sparray | scipy.sparse.spmatrix | npt.ArrayLike


@overload
def eigsh(
    A: Matrix,
    k: int = ...,
    M: Matrix | None = ...,
    sigma: float | None = ...,
    which: str = ...,
    v0: npt.ArrayLike | None = ...,
    ncv: int | None = ...,
    maxiter: int | None = ...,
    tol: float = ...,
    return_eigenvectors: Literal[True] = ...,
    Minv: object = ...,
    OPinv: object = ...,
    mode: str = ...,
    *,
    seed: int = ...,
    method: str = ...,
    progress: Callable[[dict[str, Any]], Any] | None = ...,
) -> tuple[FloatArray, FloatArray]: ...


@overload
def eigsh(
    A: Matrix,
    k: int = ...,
    M: Matrix | None = ...,
    sigma: float | None = ...,
    which: str = ...,
    v0: npt.ArrayLike | None = ...,
    ncv: int | None = ...,
    maxiter: int | None = ...,
    tol: float = ...,
    *,
    return_eigenvectors: Literal[False],
    Minv: object = ...,
    OPinv: object = ...,
    mode: str = ...,
    seed: int = ...,
    method: str = ...,
    progress: Callable[[dict[str, Any]], Any] | None = ...,
) -> FloatArray: ...


def eigsh(
    A: Matrix,
    k: int = 6,
    M: Matrix | None = None,
    sigma: float | None = None,
    which: str = "LM",
    v0: npt.ArrayLike | None = None,
    ncv: int | None = None,
    maxiter: int | None = None,
    tol: float = 0,
    return_eigenvectors: bool = True,
    Minv: object = None,
    OPinv: object = None,
    mode: str = "normal",
    *,
    seed: int = SEED,
    method: str = METHOD,
    progress: Callable[[dict[str, Any]], Any] | None = None,
) -> tuple[FloatArray, FloatArray] | FloatArray:
    """The ``k`` smallest eigenpairs of ``A x = lambda M x``, a drop-in for
    ``scipy.sparse.linalg.eigsh`` in the case it is most used for.

    ``A`` must be symmetric positive **semi**-definite and ``M`` (default: the identity)
    symmetric positive definite, both ``n x n`` SciPy sparse matrices (any format) or
    dense arrays. Code that calls ``scipy.sparse.linalg.eigsh(A, k, M, sigma=-eps)`` (or
    ``sigma=0`` with a definite ``A``, or ``which="SM"``/``"SA"``) for the smallest
    eigenvalues can swap the import.

    Returns ``(w, v)`` like SciPy: ``w`` is ``(k,)`` ascending, ``v`` is ``(n, k)``,
    M-orthonormal (``v.T @ M @ v = I``), each column with its largest-magnitude entry
    positive; only ``w`` when ``return_eigenvectors=False``. ``k`` may go up to ``n``.

    Differences from SciPy, by design:

    - Only the smallest eigenvalues: ``sigma`` must be ``None`` (then ``which`` must be
      ``"SM"`` or ``"SA"``) or a number ``<= 0`` with ``which="LM"`` (shift-invert: the
      eigenvalues nearest ``sigma`` are the smallest). The shift used inside is chosen
      by the solver (from ``k = 24`` on an interior ``s`` with about ``0.6 k``
      eigenvalues below it, ``A - s M`` factored as ``L D L^T``; otherwise a small
      ``s < 0`` and sparse Cholesky); ``sigma`` only selects the mode.
    - ``tol``: the target relative residual ``||A x - w M x|| / ((||A||_1 + |w| ||M||_1) ||x||)``
      of every pair; ``0`` (SciPy's "machine precision") means 1e-10.
    - ``v0``, ``ncv`` and ``maxiter`` are accepted and ignored (the start block comes
      from ``seed``); ``Minv``, ``OPinv`` and ``mode`` other than ``"normal"`` are refused.
    - ``method`` (``"auto"``, ``"dense"``, ``"shift-invert"``) and ``progress`` (see
      :func:`eigenbasis`) are keyword-only additions.

    Raises ``ValueError`` for non-square, mismatched, non-symmetric or non-finite input,
    a negative diagonal in ``A`` or a non-positive one in ``M`` (they cannot be
    semi-definite / definite), ``k`` outside ``1..n`` and a mode other than the smallest
    eigenvalues; :class:`SolverError` when ``A - s M`` cannot be factored (``M`` singular,
    or ``A`` indefinite); :class:`NoConvergenceError`. Definiteness is not checked beyond
    the diagonal: an indefinite ``A`` with a non-negative diagonal gives one of these
    errors or eigenvalues below zero.
    """
    if Minv is not None or OPinv is not None:
        raise ValueError("Minv and OPinv are not supported: the solver factors A - s M itself")
    if mode != "normal":
        raise ValueError(f"mode = {mode!r}: only 'normal' is supported")
    if sigma is None:
        if which not in ("SM", "SA"):
            raise ValueError(
                f"which = {which!r} without sigma asks for the largest eigenvalues; "
                "spectral_mesh.eigsh computes the smallest: pass sigma <= 0 (shift-invert, as "
                "with SciPy) or which='SM'"
            )
    else:
        s = _arrays.real(sigma, "sigma")
        if s > 0:
            raise ValueError(
                f"sigma = {s} > 0: spectral_mesh.eigsh computes the smallest eigenvalues of a "
                "positive semi-definite A; pass sigma <= 0 (e.g. -0.01) or use SciPy for "
                "interior eigenvalues"
            )
        if which != "LM":
            raise ValueError(
                f"which = {which!r} with sigma: only 'LM' (the eigenvalues nearest sigma) is "
                "supported"
            )
    A, a_parts = _arrays.sparse_csc(A, "A", "nonnegative")
    n = A.shape[0]
    m_parts = None
    if M is not None:
        M, m_parts = _arrays.sparse_csc(M, "M", "positive")
        if M.shape != A.shape:
            raise ValueError(f"M has shape {M.shape} but A has shape {A.shape}")
    k = _arrays.count(k, "k", 1)
    if k > n:
        raise ValueError(f"k = {k}: must be between 1 and n = {n}")
    w, v = _native.eigsh(
        n,
        a_parts,
        m_parts,
        k,
        _arrays.real(tol, "tol"),
        _arrays.count(seed, "seed"),
        str(method),
        progress,
    )
    return (w, v) if return_eigenvectors else w


# ----------------------------------------------------------------------- basis files


def save_basis(
    path: str | os.PathLike[str],
    evals: npt.ArrayLike,
    evecs: npt.ArrayLike,
    B: Any,
    kind: str = KIND,
    V: npt.ArrayLike | None = None,
    F: npt.ArrayLike | None = None,
) -> None:
    """Save an eigenbasis as the project's ``.npz`` archive (the CLI's ``eigs -o``
    format, readable by plain ``numpy.load``): ``eigenvalues`` ``(k,)``, ``eigenvectors``
    ``(n, k)``, the mass ``B`` as CSC arrays (``mass_data``, ``mass_indices``,
    ``mass_indptr``, ``mass_shape``), ``residuals`` and a JSON ``meta``. With ``V`` and
    ``F`` the archive records the mesh's hash, so :meth:`Analysis.load_basis` can refuse
    a basis of another mesh. The file is written atomically."""
    evals = _arrays.vector(evals, "evals")
    evecs_t = _arrays.columns_t(evecs, "evecs")
    _B, b_parts = _arrays.sparse_csc(B, "B")
    if _B.shape[0] != evecs_t.shape[1]:
        raise ValueError(
            f"B is {_B.shape[0]} x {_B.shape[1]} but evecs has {evecs_t.shape[1]} rows"
        )
    v = f = None
    if V is not None or F is not None:
        if V is None or F is None:
            raise ValueError("give both V and F, or neither")
        v, f = _arrays.mesh(V, F)
    _native.save_basis(os.fspath(path), evals, evecs_t, b_parts, str(kind), v, f)


@overload
def load_basis(
    path: str | os.PathLike[str], *, with_mass: Literal[False] = False
) -> tuple[FloatArray, FloatArray]: ...


@overload
def load_basis(
    path: str | os.PathLike[str], *, with_mass: Literal[True]
) -> tuple[FloatArray, FloatArray, CsrMatrix, dict[str, Any]]: ...


def load_basis(
    path: str | os.PathLike[str], *, with_mass: bool = False
) -> (
    tuple[FloatArray, FloatArray]
    | tuple[FloatArray, FloatArray, CsrMatrix, dict[str, Any]]
):
    """Load a ``.npz`` eigenbasis archive (written by :func:`save_basis`,
    :meth:`Analysis.save_basis` or ``spectral-mesh eigs -o``).

    Returns ``(evals, evecs)`` (``(k,)`` and ``(n, k)`` float64), or with
    ``with_mass=True`` ``(evals, evecs, B, meta)`` with ``B`` the mass matrix the vectors
    are orthonormal in (``scipy.sparse.csr_matrix``) and ``meta`` a dict (discretization,
    ``n``, ``k``, mesh hash, solver parameters, generator).

    Raises ``FileNotFoundError`` / ``OSError`` and :class:`MeshFileError` for an archive
    that is not a valid eigenbasis.
    """
    evals, evecs, mass, meta = _native.load_basis(os.fspath(path))
    if not with_mass:
        return evals, evecs
    return evals, evecs, _arrays.csr_from_parts(mass, evecs.shape[0]), meta


# -------------------------------------------------------------------------- pictures


def _view_text(view: Any) -> str:
    if isinstance(view, str):
        return view
    try:
        az, el = view
    except (TypeError, ValueError):
        raise ValueError(
            f"view must be 'front', 'side', 'top', 'iso' or (azimuth, elevation) in degrees, got {view!r}"
        ) from None
    return f"{_arrays.real(az, 'azimuth')!r},{_arrays.real(el, 'elevation')!r}"


def _labels(labels: npt.ArrayLike | None, n: int) -> list[int] | None:
    if labels is None:
        return None
    a = np.asarray(labels)
    if a.dtype.kind not in "iu" or a.ndim != 1 or a.shape[0] != n:
        raise ValueError(f"labels must be {n} non-negative integers, got {a.dtype} {a.shape}")
    if a.size and a.min() < 0:
        raise ValueError("labels must be non-negative")
    return a.astype(np.int64).tolist()


def _marks(marks: int | Sequence[int] | None) -> list[int]:
    if marks is None:
        return []
    if isinstance(marks, (int, np.integer)):
        marks = [marks]
    return [_arrays.count(m, "mark") for m in marks]


def _render_args(values: Any, n: int, marks: Any, labels: Any, levels: Any, colormap: Any,
                 view: Any, size: Any, transparent: Any, critical_points: Any,
                 colorbar: Any, path: Any, *, legend: Any = True, height: Any = None,
                 scale: Any = None, dpi: Any = None) -> _native.Picture:
    """The native render's argument after the mesh (values, marks, labels, the picture
    options as one dict, path), checked and converted: the one way of :func:`render` and
    :meth:`Analysis.render` (``n`` vertices)."""
    vals = _arrays.per_vertex(values, n)
    marks, labels = _marks(marks), _labels(labels, n)
    figure: _native.Figure = {
        "levels": _arrays.count(levels, "levels"),
        "colormap": str(colormap),
        "view": _view_text(view),
        "size": _arrays.count(size, "size", 1),
        "transparent": bool(transparent),
        "critical_points": bool(critical_points),
        "colorbar": bool(colorbar),
        "legend": bool(legend),
        "height": None if height is None else _arrays.count(height, "height", 1),
        "scale": None if scale is None else _arrays.real(scale, "scale"),
        "dpi": None if dpi is None else _arrays.count(dpi, "dpi", 1),
    }
    return vals, marks, labels, figure, None if path is None else os.fspath(path)


def render(
    V: npt.ArrayLike,
    F: npt.ArrayLike,
    values: Any,
    path: str | os.PathLike[str] | None = None,
    *,
    marks: Any = None,
    labels: Any = None,
    levels: int = FIGURE["levels"],
    colormap: str = FIGURE["colormap"],
    view: str | tuple[float, float] = FIGURE["view"],
    size: int = FIGURE["size"],
    transparent: bool = FIGURE["transparent"],
    critical_points: bool = FIGURE["critical_points"],
    colorbar: bool = FIGURE["colorbar"],
    legend: bool = FIGURE["legend"],
    height: int | None = None,
    scale: float | None = None,
    dpi: int | None = None,
):
    """Draw a per-vertex field on the mesh, the way the CLI and the web app draw it.

    With ``path`` the picture is written there (``.png``; also ``.wrl`` for a VRML 2.0
    scene, ``.ply`` for a coloured mesh, ``.txt`` for the values) and ``None`` is
    returned; without it the picture is returned as a ``(size, size, 4)`` uint8 RGBA
    array (``matplotlib.pyplot.imshow`` shows it).

    ``values``: ``(n,)`` real. ``marks``: vertices drawn as stars (a source, an
    anchor). ``labels``: ``(n,)`` non-negative integers (a segmentation):
    one colour per label instead of the colour map, no level sets. ``levels``: number of
    evenly spaced level sets drawn (0 = none). ``colormap``: ``"hue"`` (the paper's, red
    through magenta), ``"viridis"``, ``"turbo"``, ``"diverging"``, ``"grey"``. ``view``:
    ``"front"``, ``"side"``, ``"top"``, ``"iso"``, ``(azimuth, elevation)`` in degrees, or
    a camera ``"camera:EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV"`` (eye, target, up, vertical field of
    view in degrees; the web page's download sends its camera so). ``size`` is the width,
    ``height`` the height (default ``size``); ``scale``: picture pixels per screen pixel of
    the markers, lines and text (default the smaller side / 800); ``dpi``: print
    resolution written into the PNG. ``critical_points``: mark minima (blue triangles
    down), maxima (red triangles up) and saddles (green diamonds). ``legend``: draw the
    legend (top right; the colour bar is at the bottom left). The same options as the
    command line's ``render`` give the same picture.
    """
    V, F = _arrays.mesh(V, F)
    args = _render_args(values, V.shape[0], marks, labels, levels, colormap, view, size,
                        transparent, critical_points, colorbar, path,
                        legend=legend, height=height, scale=scale, dpi=dpi)
    return _native.render(V, F, args)


def num_threads() -> int:
    """The number of threads computations use (all cores unless the environment variable
    ``RAYON_NUM_THREADS`` is set before the first computation)."""
    return _native.num_threads()
