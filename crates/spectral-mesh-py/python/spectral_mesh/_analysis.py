"""The analysis object: one mesh, its operators, the factorization and a basis that grows
with ``k``, answering every field of the paper."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Literal, Sequence, overload

import numpy as np
import numpy.typing as npt

from . import _arrays, _native
from ._arrays import FloatArray, IntArray
from ._errors import InternalError
from ._forward import NativeAttribute
from ._api import _render_args
if TYPE_CHECKING:
    from ._arrays import CsrMatrix

from ._defaults import ANALYSIS, FIGURE, K, POINT_CLOUD, REQUESTS, SEED, TOL

_R = REQUESTS


@dataclass(frozen=True)
class CriticalPoints:
    """The critical points of a piecewise-linear field (Banchoff's rule, ties broken by
    vertex index), with the Euler characteristic check.

    ``minima``, ``maxima``, ``saddles``: int64 vertex indices, ascending;
    ``multiplicities``: the multiplicity of each saddle (1 for a simple saddle, ``m`` for a
    monkey saddle of ``2m + 2`` sign changes); ``on_boundary``: the critical points on the
    boundary; ``non_manifold``: non-manifold vertices met. The check: ``lhs == rhs``
    (``minima - saddles + maxima = chi`` on a closed surface, ``formula`` states the
    bordered form). The points are those every face shows: simplified by persistence
    (pairs below ``persistence_threshold`` hidden; ``hidden`` raw points, saddles with
    multiplicity, are not listed).
    """

    minima: IntArray
    maxima: IntArray
    saddles: IntArray
    multiplicities: IntArray
    on_boundary: IntArray
    non_manifold: IntArray
    chi: int
    lhs: int
    rhs: int
    holds: bool
    formula: str
    hidden: int = 0
    persistence_threshold: float = 0.0

    @property
    def saddle_count(self) -> int:
        """Saddles counted with multiplicity."""
        return int(self.multiplicities.sum())


@dataclass(frozen=True)
class LevelSet:
    """The level set ``{f = value}``: ``segments`` is ``(s, 2, 3)`` float64, the end points
    of its ``s`` straight pieces (one per triangle it crosses)."""

    value: float
    segments: FloatArray = field(repr=False)


def _signal(signal: Any, n: int) -> tuple[dict[str, Any], FloatArray | None]:
    """A diffusion signal as (its serde form, per-vertex values or None)."""
    if isinstance(signal, (int, np.integer)) and not isinstance(signal, bool):
        return {"impulse": _arrays.count(signal, "signal vertex")}, None
    if isinstance(signal, dict):
        if set(signal) != {"vertex", "radius"}:
            raise ValueError(
                "a ball signal is {'vertex': v, 'radius': r} (the indicator of the Euclidean "
                f"ball of radius r around vertex v), got keys {sorted(signal)}"
            )
        return {
            "ball": {
                "vertex": _arrays.count(signal["vertex"], "signal vertex"),
                "radius": _arrays.real(signal["radius"], "radius"),
            }
        }, None
    return {"values": []}, _arrays.per_vertex(signal, n, "signal")


def _constraints(c: Any) -> Any:
    """Harmonic constraints as their serde form: a preset count or a list of tables."""
    if isinstance(c, (int, np.integer)) and not isinstance(c, bool):
        return int(c)
    if isinstance(c, dict):
        items = list(c.items())
    else:
        try:
            items = list(c)
        except TypeError:
            raise ValueError(
                "constraints: 2, 4 or 6 (the paper's presets), {vertex: value, ...}, "
                f"[(vertex, value), ...] or (vertices, values), got {c!r}"
            ) from None
        if len(items) == 2 and all(np.ndim(x) == 1 for x in items):
            verts, vals = (np.asarray(x) for x in items)
            if verts.shape != vals.shape:
                raise ValueError(
                    f"constraints: {verts.shape[0]} vertices but {vals.shape[0]} values"
                )
            items = list(zip(verts.tolist(), vals.tolist(), strict=True))
    out = []
    for item in items:
        try:
            v, x = item
        except (TypeError, ValueError):
            raise ValueError(f"constraint {item!r}: expected (vertex, value)") from None
        out.append(
            {
                "vertex": _arrays.count(v, "constraint vertex"),
                "value": _arrays.real(x, "constraint value"),
            }
        )
    return out


#: A weight function of the eigenvalues given as a Python function (``lambda s: 1 / s**3``):
#: called with the NumPy array of the eigenvalues a filter weighs, it returns their weights.
WeightFunction = Callable[[FloatArray], npt.ArrayLike]


def _function_name(w: Callable[..., Any]) -> str:
    """How an error message names a Python weight function."""
    name = getattr(w, "__qualname__", None) or getattr(w, "__name__", None) or repr(w)
    return f"{name} (a Python function)"


class Analysis:
    """One mesh or point cloud analysed: its operators ``(S, B)``, the factorization, an eigenbasis that
    grows with ``k``, and every field of the paper computed from them.

    ``Analysis(V, F)`` assembles the operators (cheap); the first spectral request computes
    the basis, later requests with the same or a smaller ``k`` reuse it, a larger ``k``
    computes a larger basis (the pairs for a given ``k`` never depend on what was asked
    before). Fields come back as NumPy arrays of one value per vertex, ``(n,)`` float64.

    **Point clouds.** :meth:`from_points` analyses points ``P`` with their point-cloud
    Laplacian and :meth:`from_file` opens any mesh or point file; everything below then
    works on the points as on a mesh's vertices (see :meth:`from_points`).

    **Scale.** ``normalize=True`` (the default, the paper's and the library's) analyses
    the shape as if scaled to unit total area: ``B`` is divided by the area ``A``, so the
    eigenvalues are ``A`` times those of the mesh as given and every time ``t`` (heat,
    diffusion, HKS) is a time on the unit-area shape, comparable across meshes of any
    size (pyFM and DiffusionNet rescale to unit area too). ``normalize=False`` uses the
    mesh as given (LaPy's and libigl's times).

    Defaults of every field (``k = 100`` pairs, ``t = 0.5``, the bi-harmonic filter, the
    source at the vertex of largest x, 2 harmonic constraints) come from the library's
    request type, the same as the command line's, the web app's and experiment files'.

    Thread-safe: several Python threads may query one analysis at once (the GIL is
    released during computations). Ctrl-C stops a computation with ``KeyboardInterrupt``.

    Parameters
    ----------
    V : ``(n, 3)`` real array of vertex positions (float32 or float64, any order).
    F : ``(m, 3)`` integer array of 0-based vertex indices (int32 or int64, any order).
    kind : the discretization, see :func:`spectral_mesh.laplacian` (default ``"fem"``).
    normalize : analyse the unit-area shape (default ``True``, see above).
    tol, seed, dirichlet, method : the eigensolver's, see :func:`spectral_mesh.eigenbasis`.
    """

    def __init__(
        self,
        V: npt.ArrayLike,
        F: npt.ArrayLike,
        kind: str = ANALYSIS["kind"],
        *,
        normalize: bool = ANALYSIS["normalize"],
        tol: float = TOL,
        seed: int = SEED,
        dirichlet: Sequence[int] | None = None,
        method: str = ANALYSIS["method"],
    ):
        V, F = _arrays.mesh(V, F)
        native = _native.Analysis(
            V,
            F,
            str(kind),
            bool(normalize),
            _arrays.solver(tol, seed, dirichlet, method),
        )
        # Own read-only copies: the analysis does not change when the caller's arrays do.
        self._setup(native, V.copy(), F.copy())

    def _setup(self, native: _native.Analysis, V: FloatArray, F: IntArray) -> None:
        self._native = native
        self._V = V
        self._F = F
        self._V.setflags(write=False)
        self._F.setflags(write=False)
        self._info: dict[str, Any] = {}
        self._last: Any = None

    @classmethod
    def _of_native(cls, native: _native.Analysis, V: FloatArray | None = None) -> Analysis:
        """An analysis around a native one; ``V`` defaults to its vertices (or points)."""
        an = cls.__new__(cls)
        v, f = native.mesh()
        an._setup(native, v if V is None else V, f)
        return an

    @classmethod
    def from_points(
        cls,
        P: npt.ArrayLike,
        normals: npt.ArrayLike | None = None,
        *,
        n_neighbors: int = POINT_CLOUD["n_neighbors"],
        mollify_factor: float = POINT_CLOUD["mollify_factor"],
        normalize: bool = ANALYSIS["normalize"],
        tol: float = TOL,
        seed: int = SEED,
        dirichlet: Sequence[int] | None = None,
        method: str = ANALYSIS["method"],
    ) -> Analysis:
        """The analysis of a point cloud ``P`` (``(n, 3)``, any real dtype and order) with
        its point-cloud Laplacian (``kind="robust"``, the only discretization that applies
        to points; see :func:`spectral_mesh.point_cloud_laplacian`): every field, picture
        and check of a mesh analysis works on it.

        A separate constructor rather than ``Analysis(P)`` with ``F=None``: as
        robust-laplacian's ``point_cloud_laplacian(P, n_neighbors=30)`` beside its
        ``mesh_laplacian(V, F)``, points are asked for by name, so a forgotten ``F`` is an
        error and never silently another operator.

        ``normals``: optional ``(n, 3)`` normals giving the tangent planes where they are
        non-zero (else estimated from the neighbours; robust-laplacian always estimates).
        ``n_neighbors`` (as robust-laplacian's, at least 2) and ``mollify_factor`` default
        to the library's values (:data:`spectral_mesh.DEFAULTS` ``["point_cloud"]``), the
        command line's ``--neighbors`` and ``--mollify-factor``. The other keywords are
        those of :class:`Analysis`.

        The connectivity that critical points, level sets, segmentations and harmonic
        maps use is the triangle union the Laplacian was built on: :attr:`F` (the points
        are :attr:`V`, in the given order). Raises ``ValueError`` with the library's
        message for a bad array (wrong shape, NaN), bad parameters or points that give no
        triangle (collinear or coincident).
        """
        P = _arrays.vertices(P, "P")
        nr = None if normals is None else _arrays.vertices(normals, "normals")
        native = _native.Analysis.from_points(
            (P, nr, _arrays.cloud(n_neighbors, mollify_factor)),
            bool(normalize),
            _arrays.solver(tol, seed, dirichlet, method),
        )
        return cls._of_native(native, P.copy())

    @classmethod
    def from_file(
        cls,
        path: str | os.PathLike[str],
        kind: str | None = None,
        *,
        n_neighbors: int | None = None,
        mollify_factor: float | None = None,
        use_normals: bool = False,
        normalize: bool = ANALYSIS["normalize"],
        tol: float = TOL,
        seed: int = SEED,
        dirichlet: Sequence[int] | None = None,
        method: str = ANALYSIS["method"],
    ) -> Analysis:
        """The analysis of a mesh or point-cloud file, as the command line reads it: OFF,
        OBJ, PLY and STL meshes (see :func:`spectral_mesh.read_mesh`); ``.xyz``, ``.pts``,
        ``.txt`` and ``.csv`` points and PLY files without faces are point clouds (see
        :meth:`from_points`).

        ``kind``: ``None`` for the input's default (``"fem"`` for a mesh, ``"robust"`` for
        a point cloud, the only one that applies to it). The point-cloud keywords, as the
        command line's ``--neighbors``, ``--mollify-factor`` and ``--use-normals``
        (``use_normals``: the file's normals give the tangent planes where non-zero), take
        the library's defaults when ``None``; given with a mesh they raise ``ValueError``.
        """
        native = _native.Analysis.from_file(
            os.fspath(path),
            None if kind is None else str(kind),
            _arrays.cloud(n_neighbors, mollify_factor),
            bool(use_normals),
            bool(normalize),
            _arrays.solver(tol, seed, dirichlet, method),
        )
        return cls._of_native(native)

    @classmethod
    def from_shape(cls, spec: str, kind: str = ANALYSIS["kind"], **options: Any) -> Analysis:
        """The analysis of a built-in shape (see :func:`spectral_mesh.shape`)."""
        from ._api import shape

        return cls(*shape(spec), kind, **options)

    # ------------------------------------------------------------------ properties

    @property
    def V(self) -> FloatArray:
        """``(n, 3)`` float64 vertex positions (the points of a point cloud) as given (not
        scaled; a read-only copy)."""
        return self._V

    @property
    def F(self) -> IntArray:
        """``(m, 3)`` int64 triangles (a read-only copy); for a point cloud the triangle
        union its Laplacian was built on (the connectivity of critical points, level sets,
        segmentations and harmonic maps)."""
        return self._F

    n: NativeAttribute[int] = NativeAttribute("Number of vertices (or points).")

    is_point_cloud: NativeAttribute[bool] = NativeAttribute(
        """True for the analysis of a point cloud (:meth:`from_points`, :meth:`from_file`)."""
    )

    @property
    def point_cloud_params(self) -> dict[str, Any] | None:
        """The point-cloud Laplacian's parameters (``neighbors``, ``mollify_factor``,
        ``delaunay_tolerance``, ``normals``, ``union``: the library's names, as in
        experiment files' ``[point_cloud]``), ``None`` for a mesh."""
        params: dict[str, Any] | None = self._native.options()["point_cloud"]
        return params

    point_spacing: NativeAttribute[float | None] = NativeAttribute(
        """The mean spacing of a point cloud's points (the mean edge length of
        :attr:`F`; pictures draw discs of a size from it), ``None`` for a mesh."""
    )

    kind: NativeAttribute[str] = NativeAttribute("The discretization.")

    normalized: NativeAttribute[bool] = NativeAttribute("True when the shape is analysed at unit total area.")

    area: NativeAttribute[float] = NativeAttribute(
        """``A = 1^T B 1`` of the mass as assembled: the surface area for the area-based
        masses (``n`` for ``cot`` and ``uniform``). Normalization divides ``B`` by it.""", name="input_total_mass"
    )

    held_k: NativeAttribute[int] = NativeAttribute(
        """The number of eigenpairs held (0 before the first spectral request)."""
    )

    factorizations: NativeAttribute[int] = NativeAttribute(
        """How many times ``S - sigma B`` was factored for eigenbases (a counter)."""
    )

    default_source: NativeAttribute[int] = NativeAttribute(
        """The default source and anchor: the vertex of largest x (lowest index on ties)."""
    )

    @property
    def last_info(self) -> dict[str, Any]:
        """What the last field request resolved: the request with every default filled in
        (source, anchor, constraints), the marked vertices, ``k`` used and held."""
        return self._info

    def __repr__(self) -> str:
        return self._native.__repr__()

    # ------------------------------------------------------------------ operators, basis

    def operators(self) -> tuple[CsrMatrix, CsrMatrix]:
        """``(S, B)`` in use, ``scipy.sparse.csr_matrix`` (``B / area`` when normalized);
        conventions as :func:`spectral_mesh.laplacian`."""
        s, b = self._native.operators()
        return _arrays.csr_from_parts(s, self.n), _arrays.csr_from_parts(b, self.n)

    def basis(
        self, k: int = K, *, progress: Callable[[dict], Any] | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """The first ``k`` eigenpairs ``(evals (k,), evecs (n, k))`` of the operators in
        use (copies): ascending, B-orthonormal, signs as :func:`spectral_mesh.eigenbasis`.
        Computed, or grown, when fewer than ``k`` are held; ``progress`` as in
        :func:`spectral_mesh.eigenbasis`."""
        return self._native.basis(self._k(k), progress)

    def eigenvalues(self, k: int = K) -> FloatArray:
        """The first ``k`` eigenvalues ``(k,)``."""
        return self.basis(k)[0]

    def residuals(self) -> FloatArray:
        """Relative residuals of the held pairs (``(held_k,)``)."""
        return self._native.residuals()

    def set_basis(self, evals: npt.ArrayLike, evecs: npt.ArrayLike) -> None:
        """Hold a basis computed elsewhere (LaPy, SciPy, a file): ``evals`` ``(k,)``
        ascending and ``evecs`` ``(n, k)`` orthonormal for this analysis' mass (remember
        ``normalize``: eigenvalues of the raw mesh times the area, vectors times
        ``sqrt(area)``). Fields then use it."""
        self._native.set_basis(_arrays.vector(evals, "evals"), _arrays.columns_t(evecs, "evecs"))

    def save_basis(self, path: str | os.PathLike[str]) -> None:
        """Save the held basis as a ``.npz`` archive (see :func:`spectral_mesh.save_basis`)
        with the mesh's hash and the solver parameters."""
        self._native.save_basis(os.fspath(path))

    def load_basis(self, path: str | os.PathLike[str]) -> int:
        """Hold the basis of an archive saved for this mesh, discretization and
        normalization (refused with ``ValueError`` otherwise). Returns its ``k``."""
        return self._native.load_basis(os.fspath(path))

    # ------------------------------------------------------------------ fields

    def _k(self, k: Any) -> int:
        k = _arrays.count(k, "k", 1)
        if k > self.n:
            raise ValueError(
                f"k = {k} eigenpairs asked for, but the mesh has only {self.n} vertices"
            )
        return k

    @overload
    def field(
        self, kind: str, *, return_info: Literal[False] = False, **params: Any
    ) -> FloatArray | IntArray: ...

    @overload
    def field(
        self, kind: str, *, return_info: Literal[True], **params: Any
    ) -> tuple[FloatArray | IntArray, dict[str, Any]]: ...

    def field(
        self, kind: str, *, return_info: bool = False, **params: Any
    ) -> FloatArray | IntArray | tuple[FloatArray | IntArray, dict[str, Any]]:
        """Any field by its request kind and parameters, exactly as in experiment files
        and the web app (``kind`` is one of ``harmonic``, ``heat``, ``diffusion``,
        ``distance``, ``spectral-function``, ``hks``, ``wks``, ``adf``, ``segmentation``,
        ``embedding``, ``eigenfunction``, ``green``, ``geodesic``; unknown parameters are
        refused by name). ``geodesic`` (``source``, ``sources``, ``time_factor``,
        ``convention``) is the heat method's distance in the mesh's units, from the
        solver the analysis keeps; vertices its sources cannot reach are ``inf``, with a
        ``RuntimeWarning`` and ``info["unreachable"]``. Returns the ``(n,)`` values, or
        ``(values, info)`` with ``return_info=True`` (``info``: see :attr:`last_info`). A
        segmentation returns its int64 labels."""
        values, labels = self._request(kind, params.pop("_values", None), params)
        out = labels if labels is not None else values
        return (out, self._info) if return_info else out

    def _request(
        self, kind: str, values: FloatArray | None, params: dict[str, Any]
    ) -> tuple[FloatArray, IntArray | None]:
        """The library's field of a request (its values, and a segmentation's labels)."""
        req: dict[str, Any] = {"kind": str(kind)}
        for key, v in params.items():
            if v is not None:
                req[key] = _arrays.plain(v, key)
        vals, labels, info = self._native.field(req, values)
        info.pop("values", None)
        info.pop("labels", None)
        self._info = info
        self._last = labels if labels is not None else vals
        if info.get("unreachable_message"):
            # A geodesic distance's unreachable components: inf, said aloud.
            warnings.warn(info["unreachable_message"], RuntimeWarning, stacklevel=3)
        return vals, labels

    def _values(self, kind: str, values: FloatArray | None = None, **params: Any) -> FloatArray:
        """The values of a request's field."""
        return self._request(kind, values, params)[0]

    def _function_weights(self, w: WeightFunction, k: int) -> tuple[FloatArray, str]:
        """A Python weight function's values at the eigenvalues the library's filters
        weigh (the zero ones left out by the library's rule), and its name. Which pairs,
        the checks (strictly positive, finite) and every use of the weights are the
        library's: only the function itself runs in Python."""
        _used, s = self._native.filter_eigenvalues(k)
        values = np.asarray(w(s.copy()), dtype=np.float64)
        if values.shape != s.shape:
            try:
                values = np.broadcast_to(values, s.shape)
            except ValueError:
                raise ValueError(
                    f"the weight function {_function_name(w)} returned shape {values.shape} "
                    f"for {s.shape[0]} eigenvalues: it must return one weight per eigenvalue"
                ) from None
        return np.ascontiguousarray(values, dtype=np.float64), _function_name(w)

    def heat(
        self,
        anchor: int | None = None,
        *,
        t: float = _R["heat"]["t"],
        kernel: str = _R["heat"]["kernel"],
        k: int = _R["heat"]["k"],
    ) -> FloatArray:
        """The heat kernel basis function ``K_t e_anchor`` (the paper's diffusion basis,
        eq. 8): ``(n,)``. ``kernel``: ``"wfem"`` (default, ``X D_t X^T B``, conserves the
        B-mass), ``"voronoi-cot"`` (``X D_t X^T D``, D lumped) or ``"standard"``
        (``X D_t X^T``, LaPy's and pyFM's ``heat kernel`` columns). ``D_t =
        diag(exp(-lambda t))`` over the first ``k`` pairs. ``anchor`` defaults to the
        vertex of largest x."""
        return self._values("heat", anchor=anchor, t=t, kernel=kernel, k=self._k(k))

    def diffuse(
        self,
        signal: npt.ArrayLike | int | dict[str, float],
        *,
        t: float = _R["diffusion"]["t"],
        kernel: str = _R["diffusion"]["kernel"],
        k: int = _R["diffusion"]["k"],
    ) -> FloatArray:
        """The diffusion ``K_t f`` of a signal (the solution at time ``t`` of
        ``B F' + S F = 0``, ``F(0) = f``, truncated to ``k`` pairs): ``(n,)``.
        ``signal``: ``(n,)`` values, a vertex index (the unit impulse there), or
        ``{"vertex": v, "radius": r}`` (the indicator of the Euclidean ball of radius
        ``r``, in mesh units, around ``v``). ``kernel`` as in :meth:`heat`."""
        sig, values = _signal(signal, self.n)
        return self._values("diffusion", values, signal=sig, t=t, kernel=kernel, k=self._k(k))

    def distance(
        self,
        source: int | Sequence[int] | None = None,
        *,
        distance: str | WeightFunction = _R["distance"]["distance"],
        k: int = _R["distance"]["k"],
    ) -> FloatArray:
        """Filtered spectral distances from ``source`` (eq. 13), ``(n,)``; from several
        sources ``(n, len(source))``.

        ``d(p, q)^2 = sum_{lambda_j > 0} w(lambda_j) (x_j(p) - x_j(q))^2`` over the first
        ``k`` pairs, zero eigenvalues skipped, with the weight ``w = 1/phi``:

        - ``"biharmonic"`` (default) ``w = 1/s^2``; ``"commute"`` ``w = 1/s``;
          ``"diffusion:t=0.5"`` ``w = exp(-t s)``; ``"mix:a=0.5,t=0.5"``
          ``w = (1-a) exp(-t s) + a/s^2``; ``"poly:p=2"`` ``w = s^-p``; ``"band:1,4"``
          band suppression of those pairs;
        - custom filters: ``"custom-w:EXPR;name=value,..."`` gives the weight ``w(s)``,
          ``"custom-phi:EXPR;..."`` the filter map ``phi(s) = 1/w(s)``; EXPR uses ``s``,
          ``pi``, the named parameters, ``+ - * / ^``, ``exp log sqrt abs sin cos tanh
          pow min max``, e.g. ``"custom-w:exp(-s*t)/s;t=0.1"``;
        - ``"wfem-diffusion:t=0.5"``: the wFEM diffusion distance of eq. 15,
          ``d_t(i, j)^2 = (e_i - e_j)^T B X D_t X^T B (e_i - e_j)``.

        ``source`` defaults to the vertex of largest x. A Python function of the
        eigenvalues (``distance=lambda s: 1 / s**3``, vectorized over a NumPy array) is a
        custom weight ``w(s)`` too, evaluated here with NumPy on the basis.
        """
        k = self._k(k)
        if callable(distance):
            one = source is None or isinstance(source, (int, np.integer))
            if source is None:
                srcs = [self.default_source]
            elif isinstance(source, (int, np.integer)):
                srcs = [_arrays.count(source, "source")]
            else:
                srcs = [_arrays.count(x, "source") for x in source]
            d = self._native.distances_many(srcs, self._function_weights(distance, k), k)
            return d[:, 0] if one else d
        if source is not None and not isinstance(source, (int, np.integer)):
            sources = [_arrays.count(s, "source") for s in source]
            if str(distance).strip().startswith("wfem-diffusion"):
                return (
                    np.column_stack(
                        [self._values("distance", source=s, distance=distance, k=k) for s in sources]
                    )
                    if sources
                    else np.zeros((self.n, 0))
                )
            return self._native.distances_many(sources, str(distance), k)
        return self._values("distance", source=source, distance=distance, k=k)

    def spectral_function(
        self,
        filter: str | WeightFunction = _R["spectral-function"]["filter"],
        *,
        k: int = _R["spectral-function"]["k"],
    ) -> FloatArray:
        """The generalized spectral function ``G(p, p) = sum_{lambda > 0} w(lambda) x(p)^2``
        of a filter (see :meth:`distance` for filters, text or a Python function): ``(n,)``."""
        k = self._k(k)
        if callable(filter):
            return self._native.spectral_function_weighted(self._function_weights(filter, k), k)
        return self._values("spectral-function", filter=filter, k=k)

    def green(
        self,
        source: int | None = None,
        *,
        filter: str | WeightFunction = _R["green"]["filter"],
        k: int = _R["green"]["k"],
    ) -> FloatArray:
        """A row ``G(source, .)`` of the generalized Green kernel ``X diag(w) X^T``
        (zero eigenvalues skipped): ``(n,)``. ``filter``: text or a Python function
        (see :meth:`distance`)."""
        k = self._k(k)
        if callable(filter):
            s = self.default_source if source is None else _arrays.count(source, "source")
            return self._native.green_weighted(s, self._function_weights(filter, k), k)
        return self._values("green", source=source, filter=filter, k=k)

    def hks(
        self,
        t: float | Sequence[float] = _R["hks"]["t"],
        *,
        scaled: bool = _R["hks"]["scaled"],
        k: int = _R["hks"]["k"],
    ) -> FloatArray:
        """The heat kernel signature ``hks_t(p) = sum_j exp(-lambda_j t) x_j(p)^2`` over
        all ``k`` pairs (the zero eigenvalue included, pyFM's ``HKS``); ``scaled`` divides
        by the heat trace ``sum_j exp(-lambda_j t)``. A number ``t`` gives ``(n,)``, a
        sequence of times ``(n, len(t))``."""
        k = self._k(k)
        if np.ndim(t) == 0:
            return self._values("hks", t=t, scaled=bool(scaled), k=k)
        times = [_arrays.real(x, "t") for x in np.asarray(t).ravel()]
        return self._native.hks_many(times, bool(scaled), k)

    def hks_times(self, n_times: int, *, k: int = _R["hks"]["k"]) -> FloatArray:
        """pyFM's automatic HKS times: ``n_times`` values geometrically spaced from
        ``4 ln 10 / lambda_max`` to ``4 ln 10 / lambda_1`` (the first non-zero)."""
        return np.asarray(self._native.hks_auto_times(_arrays.count(n_times, "n_times", 1), self._k(k)))

    def auto_hks(
        self, n_times: int, *, scaled: bool = _R["hks"]["scaled"], k: int = _R["hks"]["k"]
    ) -> FloatArray:
        """pyFM's ``auto_HKS``: the HKS at :meth:`hks_times`, ``(n, n_times)``.
        ``scaled`` has one default in every function (the library's, ``False``, as
        :meth:`hks` and the command line); pyFM's ``auto_HKS`` scales by default: pass
        ``scaled=True`` for its numbers."""
        times = self.hks_times(n_times, k=k)
        return self._native.hks_many([float(x) for x in times], bool(scaled), self._k(k))

    def wks(
        self,
        energy: float | Sequence[float],
        *,
        sigma: float = _R["wks"]["sigma"],
        scaled: bool = _R["wks"]["scaled"],
        k: int = _R["wks"]["k"],
    ) -> FloatArray:
        """The wave kernel signature at energy ``e`` (a log-eigenvalue):
        ``wks_e(p) = sum_j c_j(e) x_j(p)^2``, ``c_j(e) = exp(-(e - ln lambda_j)^2 / (2 sigma^2))``,
        pairs with ``lambda <= 1e-8 lambda_max`` dropped (pyFM's ``WKS``); ``scaled``
        divides by ``sum_j c_j(e)``. A number gives ``(n,)``, a sequence ``(n, len)``."""
        k = self._k(k)
        if np.ndim(energy) == 0:
            return self._values("wks", energy=energy, sigma=sigma, scaled=bool(scaled), k=k)
        es = [_arrays.real(x, "energy") for x in np.asarray(energy).ravel()]
        return self._native.wks_many(es, _arrays.real(sigma, "sigma"), bool(scaled), k)

    def wks_energies(self, n_energies: int, *, k: int = _R["wks"]["k"]) -> tuple[FloatArray, float]:
        """pyFM's automatic WKS energies and bandwidth: ``sigma = 7 (e_max - e_min) / n``,
        ``n`` energies evenly spaced from ``ln lambda_1 + 2 sigma`` to
        ``ln lambda_max - 2 sigma``. Returns ``(energies, sigma)``."""
        e, s = self._native.wks_auto_energies(_arrays.count(n_energies, "n_energies", 1), self._k(k))
        return np.asarray(e), s

    def auto_wks(
        self, n_energies: int, *, scaled: bool = _R["wks"]["scaled"], k: int = _R["wks"]["k"]
    ) -> FloatArray:
        """pyFM's ``auto_WKS``: the WKS at :meth:`wks_energies`, ``(n, n_energies)``.
        ``scaled`` defaults to the library's ``False`` as in :meth:`wks`; pass
        ``scaled=True`` for pyFM's default."""
        e, s = self.wks_energies(n_energies, k=k)
        return self._native.wks_many([float(x) for x in e], float(s), bool(scaled), self._k(k))

    def adf(self, t: float = _R["adf"]["t"], *, k: int = _R["adf"]["k"]) -> FloatArray:
        """The auto-diffusion function ``G(p, p)`` with the weight ``exp(-t s)``, zero
        eigenvalues skipped: ``(n,)``."""
        return self._values("adf", t=t, k=self._k(k))

    def eigenfunction(
        self, index: int = _R["eigenfunction"]["index"], *, k: int = _R["eigenfunction"]["k"]
    ) -> FloatArray:
        """Eigenfunction ``x_index`` (0-based; default 1, the first after the constant):
        ``(n,)``."""
        return self._values("eigenfunction", index=index, k=self._k(k))

    def embedding(
        self,
        filter: str | WeightFunction = _R["embedding"]["filter"],
        *,
        component: int | None = None,
        k: int = _R["embedding"]["k"],
    ) -> FloatArray:
        """The filtered spectral embedding ``p -> (sqrt(w(lambda_j)) x_j(p))_j``, whose
        Euclidean distances are the filtered distances of :meth:`distance`: ``(n, d)``
        with one column per pair of non-zero weight (zero eigenvalues skipped). With
        ``component=j``, only the coordinate of pair ``j`` (0-based, in basis order):
        ``(n,)``. ``filter``: text or a Python function (see :meth:`distance`)."""
        k = self._k(k)
        if callable(filter):
            weights = self._function_weights(filter, k)
            if component is None:
                return self._native.embedding_matrix(weights, k)
            c = _arrays.count(component, "component")
            return self._native.embedding_component_weighted(weights, c, k)
        if component is None:
            return self._native.embedding_matrix(str(filter), k)
        return self._values("embedding", filter=filter, component=component, k=k)

    def segmentation(
        self,
        signature: str | npt.ArrayLike = _R["segmentation"]["signature"],
        *,
        persistence: float = _R["segmentation"]["persistence"],
        k: int = _R["segmentation"]["k"],
    ) -> IntArray:
        """Segmentation into the watershed basins of a signature's maxima, merged by
        persistence (relative to the field's range): ``(n,)`` int64 patch labels.
        ``signature``: ``"hks:t=0.1"`` (default), ``"adf:t=0.1"``,
        ``"wks:e=E,sigma=0.5"``, ``"biharmonic-function"``, ``"commute-function"``,
        ``"spectral-function:FILTER"``, or ``(n,)`` values of any field."""
        if isinstance(signature, str):
            req = {"signature": signature, "persistence": persistence, "k": self._k(k)}
            _, labels = self._request("segmentation", None, req)
        else:
            values = _arrays.per_vertex(signature, self.n, "signature")
            req = {"signature": [], "persistence": persistence, "k": self._k(k)}
            _, labels = self._request("segmentation", values, req)
        if labels is None:
            raise InternalError("a segmentation came back without labels")
        return labels

    def harmonic(
        self,
        constraints: int | dict[int, float] | Sequence[Any] = _R["harmonic"]["constraints"],
        *,
        order: int = _R["harmonic"]["order"],
    ) -> FloatArray:
        """The harmonic (``order=1``: ``S f = 0``) or bi-harmonic (``order=2``:
        ``S B^-1 S f = 0``, lumped B) map with Dirichlet constraints: ``(n,)``. No
        eigenbasis is needed; the factorization is kept for the same constrained vertices.

        ``constraints``: ``2`` (default, the paper's: the vertex of min x -> 0, of max
        x -> 1), ``4`` (adds min/max y), ``6`` (adds z); or explicit ``{vertex: value}``,
        ``[(vertex, value), ...]`` or ``(vertices, values)``. Every connected component
        needs a constraint."""
        return self._values("harmonic", constraints=_constraints(constraints), order=order)

    def critical_points(self, values: npt.ArrayLike) -> CriticalPoints:
        """The minima, maxima and saddles of a field ``(n,)``, with the Euler check."""
        r = self._native.critical_points(_arrays.per_vertex(values, self.n))
        p = r["points"]
        sad = np.asarray(p["saddles"], dtype=np.int64).reshape(-1, 2)
        ints = lambda x: np.asarray(x, dtype=np.int64)  # noqa: E731
        return CriticalPoints(
            minima=ints(p["minima"]),
            maxima=ints(p["maxima"]),
            saddles=sad[:, 0].copy(),
            multiplicities=sad[:, 1].copy(),
            on_boundary=ints(p["on_boundary"]),
            non_manifold=ints(p["non_manifold"]),
            chi=r["chi"],
            lhs=r["lhs"],
            rhs=r["rhs"],
            holds=r["holds"],
            formula=r["formula"],
            hidden=sum(r["hidden"].values()),
            persistence_threshold=r["persistence_threshold"],
        )

    def level_sets(
        self, values: npt.ArrayLike, levels: int | Sequence[float] = FIGURE["levels"]
    ) -> list[LevelSet]:
        """Level sets of a field ``(n,)``: at ``levels`` evenly spaced values inside its
        range (the centres of ``levels`` equal bins, as the figures draw them), or at the
        given values. Each
        :class:`LevelSet` holds its segments ``(s, 2, 3)``."""
        vals = _arrays.per_vertex(values, self.n)
        if np.ndim(levels) == 0:
            sets = self._native.level_sets(vals, [], _arrays.count(levels, "levels"))
        else:
            sets = self._native.level_sets(
                vals, [_arrays.real(x, "level") for x in np.asarray(levels).ravel()]
            )
        return [LevelSet(v, seg.reshape(-1, 2, 3)) for v, seg in sets]

    # ------------------------------------------------------------------ pictures

    def render(
        self,
        values: npt.ArrayLike,
        path: str | os.PathLike[str] | None = None,
        *,
        marks: int | Sequence[int] | None = None,
        labels: npt.ArrayLike | None = None,
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
    ) -> npt.NDArray[np.uint8] | None:
        """Draw a field on this mesh; see :func:`spectral_mesh.render`. ``marks=None``
        marks the vertices of the last field request (its source, anchor or constraints)
        when ``values`` is the array that request returned."""
        if marks is None:
            marks = self._info.get("marks", []) if values is self._last else []
        args = _render_args(values, self.n, marks, labels, levels, colormap, view, size,
                            transparent, critical_points, colorbar, path,
                            legend=legend, height=height, scale=scale, dpi=dpi)
        return self._native.render(args)
