"""Shape collections: the eigenbasis and descriptors of every shape of a data set, one job
per shape, on a local process pool or a Dask cluster, resumable (the layout and rules of
``spectral-mesh batch``: docs/batch.md)."""

from __future__ import annotations

import json
import os
import time
from typing import Any, Callable, Iterable, Mapping, Sequence

from . import _native
from ._defaults import BATCH, POINT_CLOUD

#: How many times a shape is given to a worker process that then dies (local pool)
#: before its row says so.
ATTEMPTS = 2

#: Test hook: the process given the shape of this name aborts, as a crash would.
_TEST_ABORT = "SPECTRAL_MESH_BATCH_TEST_ABORT"


def _schedule(value: Any, key: str) -> str | None:
    """``"auto:N"``, ``N`` (auto), or a sequence of numbers, as the library's text."""
    if value is None:
        return None
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        raise ValueError(f"{key} = {value!r}: expected 'auto:N', N or a list of numbers")
    if isinstance(value, int):
        return f"auto:{value}"
    try:
        values = [float(x) for x in value]
    except (TypeError, ValueError):
        raise ValueError(f"{key} = {value!r}: expected 'auto:N', N or a list of numbers") from None
    return ",".join(repr(x) for x in values)


def worker_threads() -> int:
    """On a Dask worker, its ``nthreads`` (every task of the worker process shares one
    pool of that many threads); elsewhere 0 (the engine's default)."""
    try:
        from distributed import get_worker

        w = get_worker()
        return int(getattr(getattr(w, "state", w), "nthreads", 0) or w.nthreads)
    except (ImportError, ValueError, AttributeError):
        return 0


def _task(path: str, name: str, params: str, out: str, threads: int | None,
          retry_failed: bool) -> dict:
    """One shape (run in a pool process or as a Dask task): its record as a dict.

    On a Dask worker, ``threads=None`` holds our threads to the worker's ``nthreads``:
    every task of the worker process shares one pool of that many threads."""
    if threads is None:
        threads = worker_threads()
    if os.environ.get(_TEST_ABORT) == name:
        os.abort()  # the test hook: a crash of the process working on this shape
    return json.loads(_native.batch_one(path, name, params, out, threads, retry_failed))


def _failed(path: str, name: str, params_hash: str, message: str) -> dict:
    return json.loads(_native.batch_failed(path, name, params_hash, message))


def batch(
    paths: str | os.PathLike[str] | Iterable[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    *,
    k: int = BATCH["k"],
    laplacian: str = BATCH["laplacian"],
    tol: float = BATCH["tol"],
    normalize: bool = BATCH["normalize"],
    eigenvectors: bool = BATCH["eigenvectors"],
    hks: str | int | Sequence[float] | None = BATCH["hks"],
    wks: str | int | Sequence[float] | None = BATCH["wks"],
    wks_sigma: float | None = BATCH["wks_sigma"],
    adf: str | int | Sequence[float] | None = BATCH["adf"],
    scaled: bool = BATCH["scaled"],
    thumbnail: int | None = BATCH["thumbnail"],
    geodesic: int | None = BATCH["geodesic"],
    n_neighbors: int = POINT_CLOUD["n_neighbors"],
    mollify_factor: float = POINT_CLOUD["mollify_factor"],
    client: Any = None,
    processes: int | None = None,
    threads: int | None = None,
    retries: int = 1,
    resources: Mapping[str, float] | Callable[[str, int], Mapping[str, float] | None] | None = None,
    retry_failed: bool = False,
    force: bool = False,
    timeout: float | None = None,
    progress: Callable[[int, int, dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:
    """Compute the eigenbasis (and descriptors) of every shape and write one result per
    shape under ``out``, with ``summary.csv`` and ``summary.parquet``; returns the records
    (one dict per shape, sorted by name: the summary's columns).

    ``paths``: files, folders (scanned recursively), glob patterns and ``"@manifest"``
    files, one or a list. Per shape: ``k`` pairs of the ``laplacian`` discretization at
    relative residual ``tol``, on the shape scaled to unit area (``normalize``); the
    descriptors ``hks``, ``wks``, ``adf``: ``"auto:N"`` (or ``N``) automatic times /
    energies from each spectrum, or a list; ``thumbnail``: a PNG of that many pixels a
    side; ``geodesic``: heat-method distances (mesh units) from that many farthest-point
    samples of each mesh, arrays ``geodesic`` ``(n, N)`` (``inf`` where a sample cannot
    reach) and ``geodesic_sources``; ``eigenvectors=False`` saves the eigenvalues (and descriptors) only. Point clouds
    (point files, PLY files without faces) use their point-cloud Laplacian with
    ``n_neighbors`` and ``mollify_factor`` (as :meth:`Analysis.from_points`; the command
    line's ``--neighbors`` and ``--mollify-factor``). Results are
    ``OUT/NAME.npz`` (``numpy.load``: ``eigenvalues``, ``eigenvectors`` ``(n, k)``, the mass
    in CSC arrays, ``hks`` ``(n, T)``, ...), written to a temporary name and renamed.

    Rerun: a shape whose result holds the same input hash (BLAKE3 of the file) and
    parameter hash is skipped; one whose input or parameters changed is computed again;
    a shape that failed is reported again from its marker unless ``retry_failed``. One bad
    shape never stops the batch: its record has ``status="failed"`` and ``error``.

    Where it runs:
    - ``client=None``: a local pool of ``processes`` processes (default: the cores), each
      with ``threads`` threads (default: the cores divided among them). A process that
      dies (a crash, the out-of-memory killer) is replaced; its shape is tried once more,
      then gets a failed row.
    - ``client=dask.distributed.Client(...)``: one task per shape on that cluster (the
      output folder must be reachable from every worker, e.g. a shared file system), our
      threads held to each worker's ``nthreads`` (or ``threads`` per worker process),
      ``retries`` retries of a task that raised, a task whose worker died rescheduled by
      Dask; ``resources``: Dask resources every task asks for (a dict), or a function
      ``(path, file_size_bytes) -> dict | None`` for per-shape requests (e.g. memory for
      large meshes, matched by workers started with ``--resources``).

    ``timeout`` (seconds) raises ``TimeoutError`` when the batch is not done by then (the
    results so far stay; a rerun resumes). ``progress(done, total, record)`` is called
    after every shape.
    """
    if isinstance(paths, (str, os.PathLike)):
        specs = [os.fspath(paths)]
    else:
        specs = [os.fspath(p) for p in paths]
    out = os.fspath(out)
    raw: dict[str, Any] = {
        "k": k, "laplacian": laplacian, "tolerance": tol, "normalize": bool(normalize),
        "basis": bool(eigenvectors), "hks": _schedule(hks, "hks"), "wks": _schedule(wks, "wks"),
        "wks_sigma": wks_sigma, "adf": _schedule(adf, "adf"), "scaled": bool(scaled),
        "thumbnail": thumbnail, "geodesic": geodesic,
        "point_cloud": {
            "neighbors": n_neighbors,
            "mollify_factor": mollify_factor,
            "delaunay_tolerance": POINT_CLOUD["delaunay_tolerance"],
            "normals": POINT_CLOUD["normals"],
            "union": POINT_CLOUD["union"],
        },
    }
    params, params_hash = _native.batch_params(json.dumps(raw))
    inputs = _native.batch_inputs(specs)
    _native.batch_prepare(out, bool(force))
    deadline = Deadline(timeout, "the batch did not finish in time (a rerun resumes it)")
    if client is None:
        records = _local(inputs, params, params_hash, out, processes, threads, retry_failed,
                         deadline, progress)
    else:
        records = _dask(client, inputs, params, params_hash, out, threads, retries, resources,
                        retry_failed, deadline, progress)
    records.sort(key=lambda r: r["name"])
    _native.batch_summary(out, [json.dumps(r) for r in records])
    return records


class Deadline:
    """When a set of tasks must be done (``timeout`` seconds from now; ``None``: no limit)
    and what the ``TimeoutError`` says when they are not."""

    def __init__(self, timeout: float | None, message: str) -> None:
        self.at = None if timeout is None else time.monotonic() + timeout
        self.message = message

    def remaining(self) -> float | None:
        """The seconds left (``None``: no limit); ``TimeoutError`` when there are none."""
        if self.at is None:
            return None
        left = self.at - time.monotonic()
        if left <= 0:
            raise TimeoutError(self.message)
        return left


def gather(client: Any, futures: dict[Any, int], total: int, deadline: Deadline,
           failed: Callable[[int, str], dict], progress: Callable[..., Any] | None,
           ) -> dict[int, dict]:
    """The records of Dask ``futures`` (future -> task index) as they finish: a task that
    failed on every try (or whose workers died) gets ``failed(index, message)``. Reports
    each to ``progress(done, total, record)``; at the deadline cancels the rest and raises
    its ``TimeoutError``."""
    from distributed import as_completed

    records: dict[int, dict] = {}
    try:
        for f in as_completed(list(futures), timeout=deadline.remaining()):
            i = futures[f]
            try:
                records[i] = f.result()
            except Exception as e:  # the task failed on every try, or its workers died
                records[i] = failed(i, f"the Dask task failed: {type(e).__name__}: {e}")
            if progress is not None:
                progress(len(records), total, records[i])
    except Exception as e:
        if type(e).__name__ == "TimeoutError":
            client.cancel(list(futures))
            raise TimeoutError(deadline.message) from e
        raise
    return records


_STARTED: Any = None


def _init_pool(started: Any) -> None:
    global _STARTED
    _STARTED = started


def _pool_task(i: int, *args: Any) -> dict:
    """:func:`_task` in a local pool process, first saying which shape it starts (so that
    when the pool breaks, the shapes that were running are known)."""
    if _STARTED is not None:
        _STARTED.put(i)
    return _task(*args)


def _local(inputs, params, params_hash, out, processes, threads, retry_failed, deadline,
           progress) -> list[dict]:
    # Imported here, not with the package: they cost about 25 ms of `import spectral_mesh`.
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    cores = os.cpu_count() or 1
    processes = max(1, min(processes or cores, len(inputs) or 1))
    threads = threads or max(1, cores // processes)
    # spawn: a fork of a process whose native threads hold locks is not safe.
    context = multiprocessing.get_context("spawn")
    attempts = dict.fromkeys(range(len(inputs)), 0)
    pending = list(range(len(inputs)))
    records: dict[int, dict] = {}
    while pending:
        # The shapes that were running when a worker died are suspects: they go round
        # again first, one process at a time, so that the one that crashes takes no other
        # shape's attempt (with several processes, a shape beside a crash twice in a row
        # had failed as if it had crashed); the others follow with every process.
        suspects = [i for i in pending if attempts[i] > 0]
        if suspects:
            now, width = suspects, 1
            pending = [i for i in pending if attempts[i] == 0]
        else:
            now, width = pending, processes
            pending = []
        # A SimpleQueue writes at once: a process that crashes right after saying which
        # shape it started has said it.
        started_queue = context.SimpleQueue()
        started: set[int] = set()
        with ProcessPoolExecutor(width, mp_context=context, initializer=_init_pool,
                                 initargs=(started_queue,)) as pool:
            futures = {
                pool.submit(_pool_task, i, inputs[i][0], inputs[i][1], params, out, threads,
                            retry_failed): i
                for i in now
            }
            while futures:
                done, _ = wait(futures, timeout=deadline.remaining(), return_when=FIRST_COMPLETED)
                if not done:
                    for f in futures:
                        f.cancel()
                    deadline.remaining()
                while not started_queue.empty():
                    started.add(started_queue.get())
                for f in done:
                    i = futures.pop(f)
                    try:
                        records[i] = f.result()
                    except BrokenProcessPool as e:
                        # The pool is gone: every unfinished shape goes round again; those
                        # that were running when it broke count an attempt.
                        if i in started:
                            attempts[i] += 1
                        if attempts[i] < ATTEMPTS:
                            pending.append(i)
                            continue
                        records[i] = _failed(
                            inputs[i][0], inputs[i][1], params_hash,
                            f"the worker process died while processing this shape, "
                            f"{ATTEMPTS} times: out of memory or a crash ({e})")
                    if progress is not None:
                        progress(len(records), len(inputs), records[i])
        started_queue.close()
    return [records[i] for i in range(len(inputs))]


def _dask(client, inputs, params, params_hash, out, threads, retries, resources, retry_failed,
          deadline, progress) -> list[dict]:
    futures = {}
    for i, (path, name) in enumerate(inputs):
        res = resources
        if callable(resources):
            try:
                size = os.path.getsize(path)
            except OSError:
                size = 0
            res = resources(path, size)
        f = client.submit(_task, path, name, params, out, threads, retry_failed,
                          key=f"spectral-mesh-batch-{params_hash[:12]}-{i}-{name}",
                          pure=False, retries=retries, resources=dict(res) if res else None)
        futures[f] = i

    def failed(i: int, message: str) -> dict:
        path, name = inputs[i]
        return _failed(path, name, params_hash, message)

    records = gather(client, futures, len(inputs), deadline, failed, progress)
    return [records[i] for i in range(len(inputs))]
