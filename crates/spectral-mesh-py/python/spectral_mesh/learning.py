"""Operators for learning pipelines on surfaces.

:func:`get_operators` computes, for a mesh or a point cloud, the per-shape operators
DiffusionNet's ``get_operators`` computes, in its order, as NumPy and SciPy objects::

    frames, mass, L, evals, evecs, gradX, gradY = get_operators(verts, faces, k_eig=128,
                                                                op_cache_dir="cache/")

- ``frames``: ``(n, 3, 3)``, per vertex the rows ``X, Y, N`` (two unit tangent vectors and
  the unit normal, ``Y = N x X``);
- ``mass``: ``(n,)``, the lumped mass (for a mesh, a third of the area of the triangles
  around the vertex, raised by ``1e-8`` times its mean);
- ``L``: ``(n, n)`` ``scipy.sparse.csc_matrix``, the weak Laplacian (positive
  semi-definite: the cotangent stiffness for a mesh, the point-cloud Laplacian for a
  cloud);
- ``evals`` ``(k,)``, ``evecs`` ``(n, k)``: the ``k_eig`` smallest pairs of
  ``L x = lambda diag(mass) x``, ``evecs.T @ diag(mass) @ evecs = I``, from the library's
  eigensolver;
- ``gradX``, ``gradY``: ``(n, n)`` ``scipy.sparse.csc_matrix``, the components along ``X``
  and ``Y`` of each vertex's gradient, fitted by least squares over its neighbours.

Everything is computed in float64; ``dtype=np.float32`` rounds each value once (the
default follows ``verts``, as DiffusionNet returns its tensors in the dtype of ``verts``).
With ``op_cache_dir`` the operators are stored in that folder, keyed by the library's
content hash of the shape and the parameters, and a later call reads them back.

The conventions, and where they differ from DiffusionNet's, are in the repository's
``docs/MATH.md`` ("Learning operators"). :func:`register_geomfum` plugs the library's
Laplacian and eigensolver into geomfum.
"""

from __future__ import annotations

import inspect
import os
import sys
import types
from dataclasses import dataclass
from typing import Any, Callable, ParamSpec, TypeVar

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from . import _arrays, _native
from ._defaults import LEARNING

#: The library's defaults of the learning operators (``k_eig``, ``laplacian``,
#: ``grad_regularization``, ``n_neighbors``, ``tol``, ``mass_eps``).
DEFAULTS: dict = LEARNING


@dataclass(frozen=True)
class Operators:
    """The operators of one shape (see the module documentation), with where they came
    from: ``from_cache`` is true when they were read from ``cache_file``."""

    frames: np.ndarray
    mass: np.ndarray
    L: sp.csc_matrix
    evals: np.ndarray
    evecs: np.ndarray
    gradX: sp.csc_matrix
    gradY: sp.csc_matrix
    from_cache: bool
    cache_file: str | None

    def astuple(self) -> tuple[Any, ...]:
        """``(frames, mass, L, evals, evecs, gradX, gradY)``: DiffusionNet's order."""
        return (self.frames, self.mass, self.L, self.evals, self.evecs, self.gradX, self.gradY)


_P = ParamSpec("_P")
_R = TypeVar("_R")


def _parameters_of(f: Callable[_P, Any]) -> Callable[[Callable[..., _R]], Callable[_P, _R]]:
    """A decorator for a function that passes its arguments on to ``f``: it gets ``f``'s
    parameters, for the type checker and for ``inspect.signature`` and ``help``."""

    def decorate(g: Callable[..., _R]) -> Callable[_P, _R]:
        returns = inspect.signature(g).return_annotation
        g.__signature__ = inspect.signature(f).replace(  # type: ignore[attr-defined]
            return_annotation=returns)
        return g

    return decorate


def _dtype_name(dtype: Any, verts: np.ndarray) -> str:
    if dtype is None:
        return "float32" if verts.dtype == np.float32 else "float64"
    try:
        d = np.dtype(dtype)
    except TypeError as e:
        raise ValueError(f"dtype = {dtype!r}: expected float32 or float64") from e
    if d not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise ValueError(f"dtype = {dtype!r}: expected float32 or float64")
    return d.name


def operators(
    verts: npt.ArrayLike,
    faces: npt.ArrayLike | None = None,
    k_eig: int = LEARNING["k_eig"],
    op_cache_dir: str | os.PathLike[str] | None = None,
    dtype: Any = None,
    *,
    normals: npt.ArrayLike | None = None,
    laplacian: str = LEARNING["laplacian"],
    grad_regularization: float = LEARNING["grad_regularization"],
    n_neighbors: int = LEARNING["n_neighbors"],
    tol: float = LEARNING["tol"],
) -> Operators:
    """The learning operators of a mesh ``(verts, faces)``, or of a point cloud when
    ``faces`` is None or empty, as an :class:`Operators` (see :func:`get_operators`)."""
    v_in = np.asarray(verts)
    name = _dtype_name(dtype, v_in)
    V = _arrays.vertices(v_in, "verts")
    F = None
    if faces is not None and np.asarray(faces).size > 0:
        F = _arrays.faces(faces, "faces")
    k = _arrays.count(k_eig, "k_eig")
    nr = None if normals is None else _arrays.vertices(normals, "normals")
    cache = None if op_cache_dir is None else os.fspath(op_cache_dir)
    ops, hit, path = _native.learning_operators(
        V,
        F,
        k,
        cache,
        name,
        nr,
        laplacian,
        _arrays.real(grad_regularization, "grad_regularization"),
        _arrays.count(n_neighbors, "n_neighbors", 2),
        _arrays.real(tol, "tol"),
    )
    frames, mass, L, evals, evecs, gx, gy = ops
    n = V.shape[0]

    def csc(parts: tuple[np.ndarray, np.ndarray, np.ndarray]) -> sp.csc_matrix:
        return sp.csc_matrix(parts, shape=(n, n))

    return Operators(frames, mass, csc(L), evals, evecs, csc(gx), csc(gy), hit, path)


@_parameters_of(operators)
def get_operators(*args: Any, **kwargs: Any) -> tuple[Any, ...]:
    """DiffusionNet's ``get_operators``: ``(frames, mass, L, evals, evecs, gradX, gradY)``
    of a mesh ``(verts (n, 3), faces (m, 3))``, or of a point cloud when ``faces`` is None
    or empty.

    Types: ``frames`` ``(n, 3, 3)``, ``mass`` ``(n,)``, ``evals`` ``(k,)`` and ``evecs``
    ``(n, k)`` NumPy arrays; ``L``, ``gradX``, ``gradY`` ``(n, n)``
    ``scipy.sparse.csc_matrix``; all of ``dtype`` (float32 or float64; default: float32
    when ``verts`` is float32, else float64), computed in float64 and rounded once.
    ``verts`` may be anything ``numpy.asarray`` takes (a CPU torch tensor among them);
    convert the results with ``torch.from_numpy`` (and DiffusionNet's
    ``utils.sparse_np_to_torch`` for the sparse ones).

    Parameters
    ----------
    k_eig : eigenpairs (default 128, as DiffusionNet; 0 for none).
    op_cache_dir : a folder for the disk cache (created when missing). The file is named
        by the shape's content hash and a hash of the parameters; a later call with the
        same shape and parameters reads it (``operators(...).from_cache`` tells which).
    normals : ``(n, 3)`` normals to build the frames from, instead of estimated ones.
    laplacian : the mesh discretization (``"voronoi-cot"``, DiffusionNet's, by default;
        any with a lumped mass: ``"robust"``, ``"mixed-voronoi"``, ...). Point clouds use
        the library's point-cloud Laplacian.
    grad_regularization : the term added to each vertex's 2 x 2 normal matrix of the
        gradient fit (DiffusionNet's ``1e-5``); ``0`` gives the plain least-squares fit,
        exact on linear functions.
    n_neighbors : point clouds: neighbours of each point for its normal, gradient and
        Laplacian (30).
    tol : target relative residual of the eigenpairs (``0``: the library's default).

    Raises ``ValueError`` for bad arrays or parameters (``k_eig > n`` among them),
    ``OSError`` when the cache folder cannot be written, :class:`SolverError` and
    :class:`NoConvergenceError` for numerical failures.
    """
    return operators(*args, **kwargs).astuple()


# ------------------------------------------------------------------------------ geomfum


def register_geomfum(
    which: str = "spectral_mesh",
    *,
    as_default: bool = False,
    laplacian: str = LEARNING["laplacian"],
    n_neighbors: int = LEARNING["n_neighbors"],
) -> types.ModuleType:
    """Registers the library's Laplacians in geomfum's Laplacian-finder registry under the
    key ``which``, for meshes and for point clouds (``as_default``: also make them
    geomfum's defaults), and returns the module geomfum loads them from. Its classes:

    - ``MeshLaplacianFinder(laplacian=...)``: ``(stiffness, mass)`` of a
      ``geomfum.shape.TriangleMesh`` (a lumped mass, as geomfum's solvers expect);
    - ``PointCloudLaplacianFinder(n_neighbors=...)``: the point-cloud Laplacian of a
      ``geomfum.shape.PointCloud``;
    - ``EigSolver(spectrum_size)``: geomfum's eigensolver interface (``(A, M) -> (vals,
      vecs)``) on :func:`spectral_mesh.eigsh`;
    - ``spectrum_finder(spectrum_size, ...)``: a ``LaplacianSpectrumFinder`` with both, so
      that ``shape.laplacian.find_spectrum(laplacian_spectrum_finder=...)`` gives the
      library's basis.

    Use: ``LaplacianFinder.from_registry(mesh=True, which="spectral_mesh")``. Raises
    ``ImportError`` when geomfum is not installed.
    """
    try:
        import geomfum.wrap as gf_wrap
        import gsops.backend as gs
        from geomfum._registry import register_laplacian_finder
        from geomfum.laplacian import BaseLaplacianFinder, LaplacianSpectrumFinder
    except ImportError as e:
        raise ImportError(
            "register_geomfum needs geomfum (pip install geomfum): " + str(e)
        ) from e
    from ._api import eigsh
    from ._api import laplacian as mesh_laplacian
    from ._api import point_cloud_laplacian

    default_kind, default_neighbors = laplacian, n_neighbors

    def to_gs(m: Any) -> Any:
        return gs.sparse.from_scipy_csc(sp.csc_matrix(m))

    class MeshLaplacianFinder(BaseLaplacianFinder):
        """The library's Laplacian ``(S, B)`` of a geomfum ``TriangleMesh``."""

        def __init__(self, laplacian: str = default_kind) -> None:
            self.laplacian = laplacian

        def __call__(self, shape: Any) -> tuple[Any, Any]:
            V = gs.to_numpy(shape.vertices)
            F = gs.to_numpy(shape.faces)
            S, B = mesh_laplacian(V, F, self.laplacian)
            return to_gs(S), to_gs(B)

    class PointCloudLaplacianFinder(BaseLaplacianFinder):
        """The library's point-cloud Laplacian ``(S, B)`` of a geomfum ``PointCloud``."""

        def __init__(self, n_neighbors: int = default_neighbors) -> None:
            self.n_neighbors = n_neighbors

        def __call__(self, shape: Any) -> tuple[Any, Any]:
            S, B = point_cloud_laplacian(gs.to_numpy(shape.vertices), self.n_neighbors)
            return to_gs(S), to_gs(B)

    class EigSolver:
        """geomfum's eigensolver interface on :func:`spectral_mesh.eigsh`: the
        ``spectrum_size`` smallest pairs of ``A x = lambda M x``."""

        def __init__(self, spectrum_size: int = LEARNING["k_eig"]) -> None:
            self.spectrum_size = spectrum_size

        def __call__(self, A: Any, M: Any = None) -> tuple[Any, Any]:
            Ms = None if M is None else gs.sparse.to_scipy_csc(M)
            vals, vecs = eigsh(gs.sparse.to_scipy_csc(A), self.spectrum_size, Ms, which="SM")
            return gs.from_numpy(vals), gs.from_numpy(vecs)

    def spectrum_finder(
        spectrum_size: int = LEARNING["k_eig"],
        *,
        mesh: bool = True,
        nonzero: bool = False,
        fix_sign: bool = False,
        **finder_options: Any,
    ) -> Any:
        """A geomfum ``LaplacianSpectrumFinder`` computing the library's basis."""
        finder: Any
        if mesh:
            finder = MeshLaplacianFinder(**finder_options)
        else:
            finder = PointCloudLaplacianFinder(**finder_options)
        return LaplacianSpectrumFinder(
            nonzero=nonzero,
            fix_sign=fix_sign,
            laplacian_finder=finder,
            eig_solver=EigSolver(spectrum_size),
        )

    # geomfum imports `geomfum.wrap.<which>` and takes the class by name from it.
    name = f"geomfum.wrap.{which}"
    module = types.ModuleType(name, "spectral_mesh's Laplacians and eigensolver for geomfum")
    module.MeshLaplacianFinder = MeshLaplacianFinder  # type: ignore[attr-defined]
    module.PointCloudLaplacianFinder = PointCloudLaplacianFinder  # type: ignore[attr-defined]
    module.EigSolver = EigSolver  # type: ignore[attr-defined]
    module.spectrum_finder = spectrum_finder  # type: ignore[attr-defined]
    sys.modules[name] = module
    setattr(gf_wrap, which, module)
    register_laplacian_finder(True, which, "MeshLaplacianFinder", as_default=as_default)
    register_laplacian_finder(False, which, "PointCloudLaplacianFinder", as_default=as_default)
    return module
