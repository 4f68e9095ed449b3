#!/usr/bin/env python3
"""Conformance: our robust Laplacian against the `robust-laplacian` pip package.

Meshes: for every mesh given on the command line this runs
`spectral-mesh operators MESH --robust --out DIR` (our CLI), reads the exported
triangulated mesh (mesh.off) and S_robust.mtx / B_robust.mtx, and compares them with
`robust_laplacian.mesh_laplacian(V, F, mollify_factor)` on the very same arrays:

  S_robust == L   and   B_robust == M     to TOL (1e-10) of the largest |entry| of L, M.

Both sides are positive semi-definite with a lumped (diagonal) mass. A vertex that no
triangle uses is left out of the comparison: robust_laplacian puts 1 on L's diagonal and
a small mass there, we keep a zero row (checked: our row is zero).

Point clouds (--points FILE ...): ours (`spectral-mesh operators FILE`) against
`robust_laplacian.point_cloud_laplacian` at the same neighbour count. The two differ by
design (see docs/point-clouds.md: the peer's PCA centroid is biased), so this only reports
the relative difference of the total masses and of the matrices; it fails only when our
operator is not finite, not symmetric, has S 1 != 0 or a non-positive mass.

Exit status: 0 when every mesh passes, 1 otherwise.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import scipy.io
import scipy.sparse as sp

# This file shares its name with the package it checks: import the package, not itself.
_here = os.path.dirname(os.path.abspath(__file__))
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != _here]
import robust_laplacian  # noqa: E402

# The OFF reader the benches and the other conformance scripts share.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from eigs_scipy import read_off  # noqa: E402

sys.path.insert(0, _here)  # the package is imported: this folder's modules are safe now
from common import verdict  # noqa: E402

TOL = 1e-10


def rel_diff(ours, theirs, keep):
    ours = sp.csc_matrix(ours)[keep][:, keep]
    theirs = sp.csc_matrix(theirs)[keep][:, keep]
    scale = max(abs(theirs).max(), 1e-300)
    return float(abs(ours - theirs).max() / scale)


def compare_mesh(cli, mesh, workdir, mollify):
    out = os.path.join(workdir, os.path.basename(mesh) + ".ops")
    proc = subprocess.run(
        [cli, "operators", mesh, "--robust", "--mollify-factor", repr(mollify), "--out", out, "--force"],
        capture_output=True,
        text=True,
    )
    if proc.returncode != 0:
        return {"mesh": mesh, "status": "refused by spectral-mesh", "reason": proc.stderr.strip()}
    V, F = read_off(os.path.join(out, "mesh.off"), triangles=True)
    S = sp.csc_matrix(scipy.io.mmread(os.path.join(out, "S_robust.mtx")))
    B = sp.csc_matrix(scipy.io.mmread(os.path.join(out, "B_robust.mtx")))
    L, M = robust_laplacian.mesh_laplacian(V, F, mollify_factor=mollify)
    used = np.zeros(V.shape[0], dtype=bool)
    used[F.ravel()] = True
    keep = np.flatnonzero(used)
    res = {"mesh": os.path.basename(mesh), "n": int(V.shape[0]), "m": int(F.shape[0])}
    res["S"] = rel_diff(S, L, keep)
    res["B"] = rel_diff(B, M, keep)
    res["unreferenced"] = int((~used).sum())
    if res["unreferenced"]:
        drop = np.flatnonzero(~used)
        res["unreferenced_rows_zero"] = bool(abs(S[drop]).max() == 0 and abs(B[drop]).max() == 0)
    res["S_asym"] = float(abs(S - S.T).max())
    res["S_rowsum"] = float(abs(S @ np.ones(S.shape[0])).max() / abs(S).max())
    res["mass_total_ours"] = float(B.sum())
    res["mass_total_peer"] = float(M[keep][:, keep].sum())
    ok = res["S"] <= TOL and res["B"] <= TOL and res["S_asym"] == 0 and res["S_rowsum"] <= 1e-12
    ok = ok and res.get("unreferenced_rows_zero", True)
    res["status"] = "pass" if ok else "FAIL"
    return res


def compare_points(cli, path, workdir, neighbors):
    out = os.path.join(workdir, os.path.basename(path) + ".pc")
    proc = subprocess.run(
        [cli, "operators", path, "--neighbors", str(neighbors), "--out", out, "--force"],
        capture_output=True,
        text=True,
    )
    if proc.returncode != 0:
        return {"points": path, "status": "FAIL", "reason": proc.stderr.strip()}
    S = sp.csc_matrix(scipy.io.mmread(os.path.join(out, "S_robust.mtx")))
    B = sp.csc_matrix(scipy.io.mmread(os.path.join(out, "B_robust.mtx")))
    P = read_points(path)
    L, M = robust_laplacian.point_cloud_laplacian(P, n_neighbors=neighbors)
    res = {"points": os.path.basename(path), "n": int(P.shape[0])}
    res["mass_ours"] = float(B.sum())
    res["mass_peer"] = float(M.sum())
    res["S_rel_diff"] = float(abs(S - L).max() / abs(L).max())
    res["B_rel_diff"] = float(abs(B - M).max() / abs(M).max())
    finite = np.isfinite(S.data).all() and np.isfinite(B.data).all()
    res["S_asym"] = float(abs(S - S.T).max())
    res["S_rowsum"] = float(abs(S @ np.ones(S.shape[0])).max() / abs(S).max())
    res["min_mass"] = float(B.diagonal().min())
    ok = finite and res["S_asym"] == 0 and res["S_rowsum"] <= 1e-12 and res["min_mass"] > 0
    res["status"] = "pass" if ok else "FAIL"
    return res


def read_points(path):
    """x y z [nx ny nz] text, or a PLY without faces (ASCII or binary little-endian)."""
    if path.endswith(".ply"):
        with open(path, "rb") as f:
            data = f.read()
        end = data.index(b"end_header") + len(b"end_header")
        end = data.index(b"\n", end) + 1
        header = data[:end].decode("ascii").splitlines()
        props, count, fmt = [], 0, "ascii"
        types = {"double": "<f8", "float": "<f4", "float32": "<f4", "float64": "<f8", "int": "<i4", "uchar": "u1"}
        in_vertex = False
        for line in header:
            w = line.split()
            if not w:
                continue
            if w[0] == "format":
                fmt = w[1]
            elif w[0] == "element":
                in_vertex = w[1] == "vertex"
                if in_vertex:
                    count = int(w[2])
            elif w[0] == "property" and in_vertex:
                props.append((w[2], types[w[1]]))
        if fmt == "ascii":
            arr = np.loadtxt(data[end:].decode().splitlines()[:count], ndmin=2)
            return arr[:, :3].astype(np.float64)
        rec = np.frombuffer(data[end:], dtype=np.dtype(props), count=count)
        return np.stack([rec["x"], rec["y"], rec["z"]], axis=1).astype(np.float64)
    rows = []
    with open(path) as f:
        for line in f:
            t = line.split("#", 1)[0].replace(",", " ").split()
            if len(t) >= 3:
                rows.append([float(x) for x in t[:3]])
    return np.array(rows, dtype=np.float64)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", required=True, help="path to the spectral-mesh binary")
    ap.add_argument("--mollify-factor", type=float, default=1e-5)
    ap.add_argument("--min-meshes", type=int, default=1)
    ap.add_argument("--neighbors", type=int, default=30)
    ap.add_argument("--points", nargs="*", default=[], help="point-cloud files")
    ap.add_argument("meshes", nargs="*")
    args = ap.parse_args()
    failures, compared = 0, 0
    with tempfile.TemporaryDirectory() as work:
        for m in args.meshes:
            r = compare_mesh(args.cli, m, work, args.mollify_factor)
            print(json.dumps(r, default=float))
            if r["status"] in ("pass", "FAIL"):
                compared += 1
                failures += r["status"] == "FAIL"
        for p in args.points:
            r = compare_points(args.cli, p, work, args.neighbors)
            print(json.dumps(r, default=float))
            compared += 1
            failures += r["status"] == "FAIL"
    return verdict("robust Laplacian vs robust_laplacian", compared, failures, args.min_meshes,
                   "inputs")


if __name__ == "__main__":
    sys.exit(main())
