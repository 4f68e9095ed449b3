"""Shape correspondence on the spectral basis: functional maps, ZoomOut, point maps.

pyFM's conventions (the repository's docs/MATH.md, "Correspondence"): a functional map
``C`` is ``(k2, k1)`` and carries coefficients of functions on shape 1 to shape 2; a point
map ``p2p_21`` goes the other way: for each vertex of shape 2, a vertex of shape 1.
Bases are ``(evals, evecs)`` as :func:`spectral_mesh.eigenbasis` returns them (``evecs``
B-orthonormal for the mass of ``kind`` of the mesh as given); when omitted they are
computed. Every number comes from the Rust library; defaults from
``_native.correspondence_defaults()``.
"""

from __future__ import annotations

import json
import os
from typing import Any, Callable, Iterable, Sequence

import numpy as np
import numpy.typing as npt

from . import _arrays, _native
from ._api import eigenbasis
from ._batch import Deadline, gather, worker_threads
from ._defaults import KIND

_D: dict = _native.defaults()["correspondence"]
#: The library's defaults of the correspondence functions (``k``, ``zoomout_k``,
#: ``zoomout_step``, ``zoomout_direction``, ``descriptors``, ``weights``).
CORRESPONDENCE: dict = _D
K: int = _D["k"]
ZOOMOUT_K: int = _D["zoomout_k"]
STEP: int = _D["zoomout_step"]
DIRECTION: str = _D["zoomout_direction"]
_DESC: dict = _D["descriptors"]
_W: dict = _D["weights"]


def _basis(V: Any, F: Any, basis: Any, k: int, kind: str, which: int) -> tuple[Any, Any]:
    if basis is None:
        return eigenbasis(V, F, k=k, kind=kind)
    if len(basis) != 2:
        raise ValueError(f"basis{which} must be (evals, evecs)")
    evals = _arrays.vector(basis[0], f"evals{which}")
    evecs = np.asarray(basis[1])
    if evecs.ndim != 2 or evecs.shape[1] < k:
        raise ValueError(f"basis{which}: evecs must be (n, k) with k >= {k}, got {evecs.shape}")
    return evals, evecs


def functional_map(
    V1: npt.ArrayLike,
    F1: npt.ArrayLike,
    V2: npt.ArrayLike,
    F2: npt.ArrayLike,
    k: int = K,
    *,
    basis1: Sequence[Any] | None = None,
    basis2: Sequence[Any] | None = None,
    kind: str = KIND,
    descriptor: str = _DESC["kind"],
    n_descr: int = _DESC["count"],
    subsample_step: int = _DESC["subsample_step"],
    w_descr: float = _W["descriptors"],
    w_lap: float = _W["laplacian"],
    w_dcomm: float = _W["commutativity"],
    w_orient: float = _W["orientation"],
    orient_reversing: bool = False,
    fix_constant: bool = _W["fix_constant"],
    landmarks: npt.ArrayLike | None = None,
    return_energy: bool = False,
) -> Any:
    """The functional map ``C`` (``(k, k)``, shape 1 to shape 2) minimizing pyFM's energy
    (descriptor preservation, Laplacian and descriptor commutativity, orientation), solved
    exactly. ``landmarks`` is ``(p, 2)``: vertex of shape 1, vertex of shape 2. With
    ``return_energy``, returns ``(C, energy)``."""
    v1, f1 = _arrays.mesh(V1, F1)
    v2, f2 = _arrays.mesh(V2, F2)
    k = _arrays.count(k, "k", 2)
    e1, x1 = _basis(v1, f1, basis1, k, kind, 1)
    e2, x2 = _basis(v2, f2, basis2, k, kind, 2)
    params = {
        "k": k,
        "zoomout_k": 0,
        "descriptors": {"kind": str(descriptor).lower(), "count": int(n_descr), "subsample_step": int(subsample_step)},
        "weights": {
            "descriptors": float(w_descr),
            "laplacian": float(w_lap),
            "commutativity": float(w_dcomm),
            "orientation": float(w_orient),
            "orientation_reversing": bool(orient_reversing),
            "fix_constant": bool(fix_constant),
        },
    }
    lm: list[tuple[int, int]] = []
    if landmarks is not None:
        a = np.asarray(landmarks)
        if a.ndim != 2 or a.shape[1] != 2 or a.dtype.kind not in "iu":
            raise ValueError("landmarks must be a (p, 2) integer array")
        lm = [(int(p), int(q)) for p, q in a]
    C, energy = _native.functional_map(
        (v1, f1, e1[:k], _arrays.columns_t(x1[:, :k], "evecs1")),
        (v2, f2, e2[:k], _arrays.columns_t(x2[:, :k], "evecs2")),
        str(kind), json.dumps(params), lm,
    )
    return (C, energy) if return_energy else C


def zoomout(
    V1: npt.ArrayLike,
    F1: npt.ArrayLike,
    V2: npt.ArrayLike,
    F2: npt.ArrayLike,
    C: npt.ArrayLike,
    k_final: int = ZOOMOUT_K,
    *,
    step: int = STEP,
    direction: str = DIRECTION,
    basis1: Sequence[Any] | None = None,
    basis2: Sequence[Any] | None = None,
    kind: str = KIND,
) -> tuple[Any, ...]:
    """ZoomOut: refines ``C`` (``(k2, k1)``) to ``(k_final, k_final)`` in steps.

    ``direction="forward"`` returns the refined map and its point map ``p2p_21``
    (``(n2,)``, a vertex of shape 1 for each vertex of shape 2); ``"reverse"`` refines
    ``C.T`` with the shapes swapped and returns ``(C_12, p2p_12)`` (``C_12`` carries
    functions on shape 2 to shape 1; ``p2p_12`` is ``(n1,)``, a vertex of shape 2 for each
    vertex of shape 1); ``"both"`` returns ``(C, p2p_21, C_12, p2p_12)``."""
    v1, f1 = _arrays.mesh(V1, F1)
    v2, f2 = _arrays.mesh(V2, F2)
    c = np.asarray(C, dtype=np.float64)
    if c.ndim != 2:
        raise ValueError(f"C must be a (k2, k1) matrix, got shape {c.shape}")
    kf = max(_arrays.count(k_final, "k_final", 1), c.shape[0], c.shape[1])
    _e1, x1 = _basis(v1, f1, basis1, kf, kind, 1)
    _e2, x2 = _basis(v2, f2, basis2, kf, kind, 2)
    forward, reverse = _native.zoomout_refine(
        (v1, f1, None, _arrays.columns_t(x1[:, :kf], "evecs1")),
        (v2, f2, None, _arrays.columns_t(x2[:, :kf], "evecs2")),
        str(kind), np.ascontiguousarray(c.T), kf, _arrays.count(step, "step", 1),
        str(direction),
    )
    out: list[Any] = []
    for r in (forward, reverse):
        if r is not None:
            out += [r[0], r[1].astype(np.int64)]
    return tuple(out)


def p2p(
    C: npt.ArrayLike,
    evecs1: npt.ArrayLike,
    evecs2: npt.ArrayLike,
    *,
    adjoint: bool = False,
    to_second: bool = False,
) -> Any:
    """The point map of ``C`` (``(k2, k1)``) by nearest neighbours in the spectral
    embedding (pyFM's ``FM_to_p2p``): ``p2p_21`` (``(n2,)``), or with ``to_second`` the
    other way, ``p2p_12`` (``(n1,)``, a vertex of shape 2 for each vertex of shape 1).
    ``evecs1``/``evecs2`` need at least ``k1``/``k2`` columns."""
    c = np.asarray(C, dtype=np.float64)
    if c.ndim != 2:
        raise ValueError(f"C must be a (k2, k1) matrix, got shape {c.shape}")
    k2, k1 = c.shape
    x1 = np.asarray(evecs1)
    x2 = np.asarray(evecs2)
    if x1.ndim != 2 or x1.shape[1] < k1:
        raise ValueError(f"evecs1 must be (n1, k) with k >= {k1}, got {x1.shape}")
    if x2.ndim != 2 or x2.shape[1] < k2:
        raise ValueError(f"evecs2 must be (n2, k) with k >= {k2}, got {x2.shape}")
    out = _native.point_map(
        np.ascontiguousarray(c.T),
        _arrays.columns_t(x1[:, :k1], "evecs1"),
        _arrays.columns_t(x2[:, :k2], "evecs2"),
        bool(adjoint),
        bool(to_second),
    )
    return out.astype(np.int64)


#: ``match_pairs``'s defaults (the library's ``PairParams``: ``matching``, ``laplacian``,
#: ``normalize``, ``tolerance``, ``max_geodesic_sources``; and ``pairing``).
PAIRS: dict = _native.defaults()["pairs"]
_PM: dict = PAIRS["matching"]


def _pair_task(job: str, params: str, out: str, threads: int | None) -> dict:
    """One pair (run here or as a Dask task): its record as a dict. On a Dask worker,
    ``threads=None`` holds our threads to the worker's ``nthreads``."""
    if threads is None:
        threads = worker_threads()
    return dict(json.loads(_native.match_pair(job, params, out, threads)))


def _pairing(pairs: Any) -> str:
    if isinstance(pairs, str):
        if pairs.strip().lower() in ("all", "consecutive"):
            return json.dumps(pairs.strip().lower())
        raise ValueError(f"pairs = {pairs!r}: use 'all', 'consecutive' or a list of pairs")
    listed = []
    for p in pairs:
        p = tuple(p)
        if len(p) not in (2, 3):
            raise ValueError(f"pair {p!r}: expected (source, target) or (source, target, truth)")
        entry: dict[str, Any] = {"source": os.fspath(p[0]) if not isinstance(p[0], int) else str(p[0]),
                                 "target": os.fspath(p[1]) if not isinstance(p[1], int) else str(p[1])}
        if len(p) == 3 and p[2] is not None:
            entry["truth"] = os.path.abspath(os.fspath(p[2]))
        listed.append(entry)
    return json.dumps({"list": listed})


def match_pairs(
    paths: str | os.PathLike[str] | Iterable[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    *,
    pairs: str | Sequence[Sequence[Any]] = PAIRS["pairing"],
    k: int = _PM["k"],
    zoomout_k: int = _PM["zoomout_k"],
    step: int = _PM["zoomout_step"],
    direction: str = _PM["zoomout_direction"],
    descriptor: str = _PM["descriptors"]["kind"],
    n_descr: int = _PM["descriptors"]["count"],
    subsample_step: int = _PM["descriptors"]["subsample_step"],
    w_descr: float = _PM["weights"]["descriptors"],
    w_lap: float = _PM["weights"]["laplacian"],
    w_dcomm: float = _PM["weights"]["commutativity"],
    w_orient: float = _PM["weights"]["orientation"],
    laplacian: str = PAIRS["laplacian"],
    normalize: bool = PAIRS["normalize"],
    tol: float = PAIRS["tolerance"],
    geodesic_sources: int | None = PAIRS["max_geodesic_sources"],
    client: Any = None,
    threads: int | None = None,
    force: bool = False,
    timeout: float | None = None,
    progress: Callable[[int, int, dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:
    """Match pairs of a collection with the library's pipeline (:func:`functional_map`,
    :func:`zoomout`, the point map) and write, under ``out``, one map per pair
    (``maps/SOURCE--TARGET.txt``: for each source vertex a target vertex, 0-based, one per
    line; ``maps/SOURCE--TARGET.reverse.txt`` with ``direction`` ``"reverse"`` or
    ``"both"``) and ``pairs.csv`` (one row per pair, written by the library); returns the
    records (dicts: the CSV's columns) in the order of the pairs.

    ``paths``: files, folders, glob patterns and ``"@manifest"`` files, as for
    :func:`batch`. ``pairs``: ``"all"`` (every unordered pair, the earlier input the
    source), ``"consecutive"``, or a list of ``(source, target)`` or
    ``(source, target, truth)``, each shape an input's name, path or position, ``truth`` a
    file holding the true map (then the record has ``mean_geodesic_error`` in units of
    ``sqrt(area)`` of the target, at most ``geodesic_sources`` geodesic solves, and
    ``exact_share``). A bad mesh gives a record with ``status="failed"`` and an ``error``
    naming the file; the other pairs go on.

    ``client=None`` runs the pairs here, one after the other (each on ``threads`` threads,
    default all); with a ``dask.distributed.Client`` one task per pair on that cluster
    (the files must be reachable from every worker). ``timeout`` (seconds) raises
    ``TimeoutError``; ``progress(done, total, record)`` is called after every pair.
    """
    specs = [os.fspath(paths)] if isinstance(paths, (str, os.PathLike)) else [os.fspath(p) for p in paths]
    out = os.fspath(out)
    raw = {
        "matching": {
            "k": k, "zoomout_k": zoomout_k, "zoomout_step": step,
            "zoomout_direction": str(direction).lower(),
            "descriptors": {"kind": str(descriptor).lower(), "count": n_descr,
                            "subsample_step": subsample_step},
            "weights": {**_PM["weights"], "descriptors": float(w_descr), "laplacian": float(w_lap),
                        "commutativity": float(w_dcomm), "orientation": float(w_orient)},
        },
        "laplacian": laplacian, "normalize": bool(normalize), "tolerance": float(tol),
        "max_geodesic_sources": geodesic_sources,
    }
    jobs, params = _native.pairs_plan(specs, _pairing(pairs), json.dumps(raw))
    _native.batch_prepare(out, bool(force))
    deadline = Deadline(timeout, "the pairs did not finish in time")
    records: dict[int, dict] = {}
    if client is None:
        for i, job in enumerate(jobs):
            deadline.remaining()
            records[i] = _pair_task(job, params, out, threads or 0)
            if progress is not None:
                progress(len(records), len(jobs), records[i])
    else:
        futures = {
            client.submit(_pair_task, job, params, out, threads,
                          key=f"spectral-mesh-pair-{i}-{json.loads(job)['name']}", pure=False): i
            for i, job in enumerate(jobs)
        }

        def failed(i: int, message: str) -> dict:
            return json.loads(_native.pair_failed(jobs[i], params, message))

        records = gather(client, futures, len(jobs), deadline, failed, progress)
    ordered = [records[i] for i in range(len(jobs))]
    _native.pairs_summary(out, [json.dumps(r) for r in ordered])
    return ordered
