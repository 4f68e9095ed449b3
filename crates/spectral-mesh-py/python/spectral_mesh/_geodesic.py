"""Geodesic distance by the heat method (Crane, Weischedel and Wardetzky 2013), on meshes
and point clouds."""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from . import _arrays, _native
from ._defaults import KIND
from ._forward import NativeAttribute


def _sources(sources: Any) -> list[int]:
    a = np.atleast_1d(np.asarray(sources))
    if a.dtype.kind not in "iu" or a.ndim != 1:
        raise ValueError(f"sources must be a vertex index or a 1-d array of them, got {a.dtype} {a.shape}")
    if a.size == 0:
        raise ValueError("sources is empty: name at least one vertex")
    if (a < 0).any():
        raise ValueError(f"sources holds a negative vertex index ({int(a.min())})")
    return [int(x) for x in a]


def _points(face_points: Any) -> list[tuple[int, float, float, float]]:
    if face_points is None:
        return []
    out = []
    for p in face_points:
        if len(p) != 2:
            raise ValueError("face_points: each entry is (face, (b0, b1, b2))")
        face, bary = p
        b = [_arrays.real(x, "barycentric coordinate") for x in bary]
        if len(b) != 3:
            raise ValueError("face_points: three barycentric coordinates per point")
        out.append((_arrays.count(face, "face"), b[0], b[1], b[2]))
    return out


class GeodesicSolver:
    """The heat method on one mesh, factored once, for any number of sources.

    ``t = time_factor * h^2`` with ``h`` the mean edge length (``time_factor`` is
    potpourri3d's ``t_coef``; default 1). ``kind`` is the discretization (the operators
    of :func:`laplacian`, unscaled: distances are in the mesh's units).
    ``convention="crane"`` (default) averages the Neumann and Dirichlet heat solutions on
    a mesh with boundary and solves the Poisson problem exactly;
    ``convention="potpourri3d"`` reproduces potpourri3d's ``MeshHeatMethodDistanceSolver``
    (with ``kind="voronoi-cot"`` for ``use_robust=False``, ``kind="robust"`` for its
    default ``use_robust=True``). Vertices on a component without a source get ``inf``.
    """

    def __init__(
        self,
        V: Any,
        F: Any,
        kind: str = KIND,
        *,
        time_factor: float | None = None,
        convention: str | None = None,
    ) -> None:
        V, F = _arrays.mesh(V, F)
        tf = None if time_factor is None else _arrays.real(time_factor, "time_factor")
        self._native = _native.GeodesicSolver(V, F, kind, tf, convention)

    @classmethod
    def from_points(
        cls,
        P: Any,
        *,
        normals: Any = None,
        n_neighbors: int | None = None,
        mollify_factor: float | None = None,
        gradient_neighbors: int | None = None,
        time_factor: float | None = None,
        convention: str | None = None,
    ) -> "GeodesicSolver":
        """The heat method on a point cloud ``P`` (``(n, 3)``): the heat and Poisson solves
        on its point-cloud Laplacian (:func:`point_cloud_laplacian`, ``n_neighbors`` and
        ``mollify_factor`` as there), the gradient by least squares over each point's
        ``gradient_neighbors`` nearest neighbours in its tangent plane (PCA, or
        ``normals`` where non-zero). ``h`` is the mean edge length of the Laplacian's
        triangles. Sources are point indices (no face points). ``None``: the library's
        default."""
        P = _arrays.vertices(P, "P")
        nr = None if normals is None else _arrays.vertices(normals, "normals")
        tf = None if time_factor is None else _arrays.real(time_factor, "time_factor")
        gn = None if gradient_neighbors is None else _arrays.count(gradient_neighbors, "gradient_neighbors")
        self = cls.__new__(cls)
        points = (P, nr, _arrays.cloud(n_neighbors, mollify_factor))
        self._native = _native.GeodesicSolver.from_points(points, gn, tf, convention)
        return self

    n: NativeAttribute[int] = NativeAttribute("The number of vertices (or points).")

    t: NativeAttribute[float] = NativeAttribute("The time step ``t = m h^2``.")

    h: NativeAttribute[float] = NativeAttribute("The mean edge length.")

    def distance(self, sources: Any = (), face_points: Sequence | None = None) -> np.ndarray:
        """``(n,)`` distance to the nearest of the source vertices and face points
        (``[(face, (b0, b1, b2)), ...]``)."""
        vs = _sources(sources) if np.size(sources) else []
        pts = _points(face_points)
        if not vs and not pts:
            raise ValueError("no source given: pass vertices and/or face_points")
        return self._native.distance(vs, pts)

    def distances(self, sources: Any) -> np.ndarray:
        """``(k, n)``: row ``i`` is the distance from ``sources[i]`` alone (solved as blocks
        of right-hand sides)."""
        return self._native.distances(_sources(sources))

    def distance_matrix(self, samples: Any, symmetric: bool = True) -> np.ndarray:
        """``(k, k)`` distances between the sample vertices (``(D + D^T) / 2`` when
        ``symmetric``)."""
        return self._native.distance_matrix(_sources(samples), bool(symmetric))

    def farthest_point_sampling(self, k: int, start: int = 0) -> np.ndarray:
        """``k`` vertices spread by farthest-point sampling from ``start``."""
        got = self._native.farthest_point_sampling(_arrays.count(k, "k"), _arrays.count(start, "start"))
        return np.asarray(got, dtype=np.int64)


def geodesic_distance(
    V: Any,
    F: Any,
    sources: Any,
    kind: str = KIND,
    *,
    time_factor: float | None = None,
    convention: str | None = None,
) -> np.ndarray:
    """``(n,)`` heat-method geodesic distance from the vertex or vertices ``sources`` (the
    distance to the nearest). See :class:`GeodesicSolver`, which keeps its factors for
    more sources."""
    return GeodesicSolver(V, F, kind, time_factor=time_factor, convention=convention).distance(sources)


def point_cloud_geodesic_distance(
    P: Any,
    sources: Any,
    *,
    normals: Any = None,
    n_neighbors: int | None = None,
    gradient_neighbors: int | None = None,
    time_factor: float | None = None,
) -> np.ndarray:
    """``(n,)`` heat-method geodesic distance on the point cloud ``P`` from the point or
    points ``sources`` (the distance to the nearest). See
    :meth:`GeodesicSolver.from_points`, which keeps its factors for more sources."""
    return GeodesicSolver.from_points(
        P,
        normals=normals,
        n_neighbors=n_neighbors,
        gradient_neighbors=gradient_neighbors,
        time_factor=time_factor,
    ).distance(sources)
