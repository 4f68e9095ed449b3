#!/usr/bin/env python3
"""The peer of `spectral-mesh batch` in the collection benchmark: the plain
multiprocessing.Pool script a user writes, computing the same outputs.

For every mesh (OFF files listed in a manifest, or the .off files of a folder), in a
multiprocessing.Pool of --processes: read the OFF, assemble the cotangent stiffness and
the FEM mass (bench/eigs_scipy.py's NumPy code), scale to unit area (the mass divided by
the total area, as `batch` does by default), eigsh in shift-invert mode with a CHOLMOD
factorization (scikit-sparse), the HKS at --hks automatic times (pyFM's rule, the same as
ours: geometric from 4 ln 10 / lambda_max to 4 ln 10 / lambda_1), and one .npz per mesh
with the arrays of ours (eigenvalues, eigenvectors n x k in Fortran order, the mass in
CSC form, residuals, hks n x T, hks_times), written to a temporary name and renamed. Each
mesh's errors are caught and become a row of summary.csv, as a careful user's script
does (a crash of a pool process is not survived: Pool hangs or fails the whole map).

usage: batch_scipy.py (@MANIFEST | FOLDER) --out DIR [-k 50] [--hks 16] [--processes 2]
                      [--tol 0]
Prints one `key=value` line: meshes, ok, failed, vertices, seconds.
"""
import argparse
import csv
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as sla

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eigs_scipy import operators, read_off  # noqa: E402


def job(task):
    path, out, k, n_hks, tol = task
    t0 = time.perf_counter()
    name = Path(path).name
    row = {"name": name, "status": "failed", "error": "", "n": "", "k": k, "seconds": ""}
    try:
        from sksparse.cholmod import cholesky

        v, f = read_off(path)
        row["n"] = len(v)
        S, B = operators(v, f, "fem")
        B = (B / B.sum()).tocsc()
        sn = abs(S).sum(axis=0).max()
        bn = abs(B).sum(axis=0).max()
        sigma = -max(0.01 / B.sum(), 1e-10 * sn / bn)
        fac = cholesky((S - sigma * B).tocsc())
        op = sla.LinearOperator(S.shape, matvec=fac, dtype=float)
        lam, X = sla.eigsh(S, k, M=B, sigma=sigma, which="LM", OPinv=op, tol=tol)
        order = np.argsort(lam)
        lam, X = lam[order], X[:, order]
        R = S @ X - (B @ X) * lam
        res = np.linalg.norm(R, axis=0) / ((sn + np.abs(lam) * bn) * np.linalg.norm(X, axis=0))
        lmax = np.abs(lam).max()
        l1 = lam[lam > 1e-8 * lmax].min()
        c = 4.0 * np.log(10.0)
        times = np.geomspace(c / lmax, c / l1, n_hks)
        hks = (X * X) @ np.exp(-np.outer(lam, times))
        final = Path(out) / (name + ".npz")
        tmp = Path(out) / (f".{name}.npz.tmp-{os.getpid()}")
        with open(tmp, "wb") as fh:
            np.savez(fh, eigenvalues=lam, eigenvectors=np.asfortranarray(X),
                     mass_data=B.data, mass_indices=B.indices.astype(np.int64),
                     mass_indptr=B.indptr.astype(np.int64),
                     mass_shape=np.array(B.shape, dtype=np.int64), residuals=res,
                     hks=np.asfortranarray(hks), hks_times=times)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, final)
        row["status"] = "ok"
    except Exception as e:  # a row, not a dead batch
        row["error"] = f"{type(e).__name__}: {e}"
    row["seconds"] = round(time.perf_counter() - t0, 3)
    return row


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("inputs")
    ap.add_argument("--out", required=True)
    ap.add_argument("-k", type=int, default=50)
    ap.add_argument("--hks", type=int, default=16)
    ap.add_argument("--processes", type=int, default=os.cpu_count())
    ap.add_argument("--tol", type=float, default=0.0)
    a = ap.parse_args()
    if a.inputs.startswith("@"):
        base = Path(a.inputs[1:]).parent
        paths = [str(base / line.strip()) for line in open(a.inputs[1:])
                 if line.strip() and not line.startswith("#")]
    else:
        paths = sorted(str(p) for p in Path(a.inputs).glob("*.off"))
    os.makedirs(a.out, exist_ok=True)
    t0 = time.perf_counter()
    tasks = [(p, a.out, a.k, a.hks, a.tol) for p in paths]
    rows = []
    with mp.Pool(a.processes) as pool:
        for row in pool.imap_unordered(job, tasks):
            rows.append(row)
    rows.sort(key=lambda r: r["name"])
    with open(Path(a.out) / "summary.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]) if rows else ["name"])
        w.writeheader()
        w.writerows(rows)
    secs = time.perf_counter() - t0
    ok = sum(r["status"] == "ok" for r in rows)
    verts = sum(int(r["n"]) for r in rows if r["status"] == "ok")
    print(f"meshes={len(rows)} ok={ok} failed={len(rows) - ok} vertices={verts} seconds={secs:.3f}")


if __name__ == "__main__":
    main()
