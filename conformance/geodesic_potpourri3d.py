#!/usr/bin/env python3
"""Conformance: our heat-method geodesic distance against potpourri3d's.

For every mesh given on the command line this writes the triangulated mesh our CLI reads
(`spectral-mesh convert MESH mesh.off`), then for two source vertices (0's component:
vertex 0 and the vertex of largest x on it) and both Laplacians runs

    spectral-mesh geodesic mesh.off --source S --laplacian L --convention potpourri3d -o d.txt

and compares with `potpourri3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1,
use_robust=...)` on the very same arrays (L = voronoi-cot for use_robust=False, robust for
use_robust=True):

    max |ours - theirs| <= TOL (1e-6) * max |theirs|

on the source's connected component (potpourri3d returns a number on the others; ours is
infinite there). A mesh potpourri3d refuses or answers with non-finite values (unused
vertices, degenerate triangles without mollification) is reported and skipped.

With --exact N: also the mean relative error against exact polyhedral geodesics
(pygeodesic, MMP) from vertex 0 on the first N meshes, ours (crane convention, both
Laplacians) and potpourri3d's, as a Markdown table.

Exit status: 0 when every compared mesh passes and at least --min-meshes were compared.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

import potpourri3d as pp3d

# The OFF reader the benches and the other conformance scripts share.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from eigs_scipy import read_off  # noqa: E402

TOL = 1e-6


def components(n, F):
    rows = np.concatenate([F[:, 0], F[:, 1], F[:, 2]])
    cols = np.concatenate([F[:, 1], F[:, 2], F[:, 0]])
    A = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    return connected_components(A, directed=False)[1]


def ours(cli, off, source, laplacian, convention, workdir):
    out = os.path.join(workdir, f"d_{source}_{laplacian}_{convention}.txt")
    proc = subprocess.run(
        [cli, "geodesic", off, "--source", str(source), "--laplacian", laplacian,
         "--convention", convention, "-o", out, "--force"],
        capture_output=True, text=True,
    )
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr.strip())
    return np.loadtxt(out)


def theirs(V, F, source, robust):
    solver = pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=1.0, use_robust=robust)
    return np.asarray(solver.compute_distance(int(source)))


def compare_mesh(cli, mesh, workdir):
    name = os.path.basename(mesh)
    off = os.path.join(workdir, name + ".tri.off")
    proc = subprocess.run([cli, "convert", mesh, off, "--force"], capture_output=True, text=True)
    if proc.returncode != 0:
        return {"mesh": name, "status": "refused by spectral-mesh", "reason": proc.stderr.strip()}
    V, F = read_off(off, triangles=True)
    n = V.shape[0]
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    if not used.all():
        return {"mesh": name, "status": "skipped",
                "reason": f"{n - used.sum()} unused vertices (potpourri3d's mesh has no such vertex)"}
    comp = components(n, F)
    src0 = 0
    on = np.flatnonzero(comp == comp[src0])
    src1 = int(on[np.argmax(V[on, 0])])
    res = {"mesh": name, "n": n, "status": "ok", "cases": []}
    for robust, lap in [(False, "voronoi-cot"), (True, "robust")]:
        for s in sorted({src0, src1}):
            try:
                d_t = theirs(V, F, s, robust)
            except Exception as e:  # noqa: BLE001 - the peer refusing is a skip, not a failure
                res["cases"].append({"laplacian": lap, "source": s, "skip": f"potpourri3d: {e}"})
                continue
            mask = comp == comp[s]
            if not np.isfinite(d_t[mask]).all():
                res["cases"].append({"laplacian": lap, "source": s, "skip": "potpourri3d gives non-finite values"})
                continue
            d_o = ours(cli, off, s, lap, "potpourri3d", workdir)
            assert np.isfinite(d_o[mask]).all(), f"{name}: our distance is not finite on the source's component"
            assert np.isinf(d_o[~mask]).all(), f"{name}: our distance is finite off the source's component"
            scale = np.abs(d_t[mask]).max()
            err = float(np.abs(d_o[mask] - d_t[mask]).max() / scale)
            res["cases"].append({"laplacian": lap, "source": s, "rel": err, "pass": err <= TOL})
    return res


def exact_table(cli, meshes, workdir):
    import pygeodesic.geodesic as geodesic

    rows = []
    for mesh in meshes:
        name = os.path.basename(mesh)
        off = os.path.join(workdir, name + ".tri.off")
        subprocess.run([cli, "convert", mesh, off, "--force"], check=True, capture_output=True)
        V, F = read_off(off, triangles=True)
        algo = geodesic.PyGeodesicAlgorithmExact(V, F)
        exact, _ = algo.geodesicDistances(np.array([0]), None)
        keep = np.isfinite(exact) & (exact > 0) & (exact < 1e300)
        row = {"mesh": name, "n": V.shape[0]}

        def mre(d):
            return float(np.mean(np.abs(d[keep] - exact[keep]) / exact[keep]))

        for lap in ["voronoi-cot", "robust"]:
            row["ours " + lap] = mre(ours(cli, off, 0, lap, "crane", workdir))
        for robust in [False, True]:
            row["potpourri3d robust" if robust else "potpourri3d"] = mre(theirs(V, F, 0, robust))
        rows.append(row)
    cols = ["ours voronoi-cot", "potpourri3d", "ours robust", "potpourri3d robust"]
    print("\n| mesh | vertices | " + " | ".join(cols) + " |")
    print("| --- | ---: | " + " | ".join("---:" for _ in cols) + " |")
    for r in rows:
        print(f"| {r['mesh']} | {r['n']} | " + " | ".join(f"{100 * r[c]:.2f}%" for c in cols) + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cli", required=True)
    ap.add_argument("--min-meshes", type=int, default=1)
    ap.add_argument("--exact", type=int, default=0, help="accuracy table on the first N meshes")
    ap.add_argument("meshes", nargs="+")
    a = ap.parse_args()
    failed = 0
    compared = 0
    with tempfile.TemporaryDirectory() as workdir:
        for mesh in a.meshes:
            r = compare_mesh(a.cli, mesh, workdir)
            if r["status"] != "ok":
                print(f"{r['mesh']}: {r['status']}: {r['reason']}")
                continue
            parts = []
            any_case = False
            for c in r["cases"]:
                if "skip" in c:
                    parts.append(f"{c['laplacian']} from {c['source']}: skipped ({c['skip']})")
                    continue
                any_case = True
                ok = "ok" if c["pass"] else "FAIL"
                failed += not c["pass"]
                parts.append(f"{c['laplacian']} from {c['source']}: {c['rel']:.1e} {ok}")
            compared += any_case
            print(f"{r['mesh']} (n = {r['n']}): " + "; ".join(parts))
        if a.exact:
            exact_table(a.cli, a.meshes[: a.exact], workdir)
    print(f"{compared} meshes compared, {failed} cases above {TOL:g} of the largest distance")
    if failed or compared < a.min_meshes:
        sys.exit(1)


if __name__ == "__main__":
    main()
