#!/usr/bin/env python3
"""The Dask routes of the collection benchmark (bench/batch_bench.py gives the others):
`spectral_mesh.batch` on a local Dask cluster (a scheduler and W worker processes of one
thread on 127.0.0.1, no dashboard) against the same function with its local process pool,
over the meshes of a manifest, same outputs as the CLI route (k, HKS at automatic times);
then the per-task overhead of Dask:

- a rerun over the finished folder, every shape up to date, through Dask and through the
  local pool: the per-shape work is a check (hash the file, read the result's meta), so
  (wall / shapes) is the per-task cost of each route, and their difference Dask's
  overhead per task over a local pool;
- empty tasks (`client.submit` of a function returning None, one per shape, as batch
  submits them): the scheduler's round trip per task on this machine.

Prints one JSON line per measurement (with the 1-minute load average before and after)
and a markdown table.

usage: batch_dask.py --manifest M [--workers 2] [-k 50] [--hks 16]
                     [--work-dir DIR]
"""
import argparse
import json
import os
import shutil
import time
from pathlib import Path


def loadavg():
    return open("/proc/loadavg").read().split()[:3]


def noop(i):
    return None


def timed(label, fn, records, meshes):
    before = loadavg()
    t0 = time.perf_counter()
    out = fn()
    wall = time.perf_counter() - t0
    rec = {"route": label, "meshes": meshes, "wall_seconds": round(wall, 3),
           "per_shape_ms": round(wall / meshes * 1000, 2),
           "meshes_per_minute": round(meshes / wall * 60, 2),
           "loadavg_before": before, "loadavg_after": loadavg()}
    records.append(rec)
    print(json.dumps(rec), flush=True)
    return out, rec


def main():
    import spectral_mesh as sm
    from distributed import Client, LocalCluster

    ap = argparse.ArgumentParser()
    ap.add_argument("--manifest", required=True)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("-k", type=int, default=50)
    ap.add_argument("--hks", type=int, default=16)
    ap.add_argument("--work-dir", default="bench/results/batch-dask")
    ap.add_argument("--table", default="bench/results/batch-dask.md")
    ap.add_argument("--skip-compute", action="store_true",
                    help="only the overhead measurements (reruns and empty tasks)")
    a = ap.parse_args()
    paths = [line.strip() for line in open(a.manifest) if line.strip()]
    n = len(paths)
    vertices = 0
    for p in paths:
        with open(p) as f:
            for line in f:
                t = line.split("#", 1)[0].split()
                if t and t[0].upper() != "OFF":
                    vertices += int(t[0])
                    break
    work = Path(a.work_dir)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    params = dict(k=a.k, hks=f"auto:{a.hks}")
    records = []
    cores = os.cpu_count() or 1
    threads = max(1, cores // a.workers)
    with LocalCluster(host="127.0.0.1", n_workers=a.workers, threads_per_worker=threads,
                      processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        if not a.skip_compute:
            timed(f"dask, {a.workers} workers x {threads} threads",
                  lambda: sm.batch(paths, work / "dask", client=client, **params), records, n)
            timed(f"local pool, {a.workers} processes x {threads} threads",
                  lambda: sm.batch(paths, work / "local", processes=a.workers, **params),
                  records, n)
            same = all((work / "dask" / p.name).read_bytes() == p.read_bytes()
                       for p in (work / "local").glob("*.npz"))
            print(json.dumps({"dask_results_equal_local_bit_for_bit": same}))
        else:
            sm.batch(paths, work / "local", processes=a.workers, **params)
            shutil.copytree(work / "local", work / "dask")
        timed("rerun (all up to date), dask",
              lambda: sm.batch(paths, work / "dask", client=client, **params), records, n)
        timed("rerun (all up to date), local pool",
              lambda: sm.batch(paths, work / "local", processes=a.workers, **params), records, n)

        def empty():
            futures = [client.submit(noop, i, pure=False) for i in range(n)]
            client.gather(futures)
        timed("empty tasks, dask", empty, records, n)
    lines = ["| route | meshes | wall s | per shape (ms) | meshes/min | load before -> after |",
             "| --- | ---: | ---: | ---: | ---: | --- |"]
    for r in records:
        lines.append(f"| {r['route']} | {r['meshes']} | {r['wall_seconds']:.2f} | {r['per_shape_ms']:.1f} "
                     f"| {r['meshes_per_minute']:.1f} | {r['loadavg_before'][0]} -> {r['loadavg_after'][0]} |")
    lines.append(f"\n{n} meshes, {vertices} vertices in all.")
    Path(a.table).write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
