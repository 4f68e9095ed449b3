#!/usr/bin/env python3
"""Conformance: our stiffness and mass matrices against libigl.

For every mesh given on the command line this runs
`spectral-mesh operators MESH --out DIR` (our CLI), reads the exported
triangulated mesh and Matrix Market files, and compares:

  S                 == -igl.cotmatrix(V, F)
  B_fem             == igl.massmatrix(V, F, MASSMATRIX_TYPE_FULL)
  B_barycentric     == igl.massmatrix(V, F, MASSMATRIX_TYPE_BARYCENTRIC)
  B_mixed_voronoi   == igl.massmatrix(V, F, MASSMATRIX_TYPE_VORONOI)

to 1e-12 of the largest entry. libigl gets the very vertex and face arrays we
used (our reader's triangulation), so the comparison is of the operators alone.
Where libigl can read the original file itself, its arrays are also compared
with ours (a check of our reader).

Exit status: 0 when every compared mesh passes, 1 otherwise.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import igl
import numpy as np
import scipy.io
import scipy.sparse as sp

# The OFF reader the benches and the other conformance scripts share.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from eigs_scipy import read_off  # noqa: E402

from common import verdict  # noqa: E402

TOL = 1e-12


def _cmp(ours, theirs, res, name):
    theirs = sp.coo_matrix(theirs).toarray()
    assert np.isfinite(ours).all(), f"{name}: our matrix has non-finite entries"
    ok = np.isfinite(theirs)
    if res is not None and (~ok).any():
        res[name + "_peer_nonfinite"] = int((~ok).sum())
    scale = max(abs(theirs[ok]).max(), 1e-300)
    return float(abs(ours[ok] - theirs[ok]).max() / scale)


def rel_err_sparse(ours, theirs, res, name):
    """Largest |ours - theirs| relative to the largest |theirs|.

    libigl writes NaN or inf for zero-area triangles (it divides by the area); we give
    such triangles no weight. Entries where libigl is not finite are left out of the
    comparison and counted in `res[name + "_peer_nonfinite"]`; ours must be finite.
    """
    ours = sp.csc_matrix(ours)
    theirs = sp.csc_matrix(theirs)
    if not np.isfinite(theirs.data).all():
        return _cmp(ours.toarray(), theirs, res, name)
    assert np.isfinite(ours.data).all(), f"{name}: our matrix has non-finite entries"
    scale = max(abs(theirs).max(), 1e-300)
    return float(abs(ours - theirs).max() / scale)


def compare(cli, mesh, workdir):
    out = os.path.join(workdir, os.path.basename(mesh) + ".ops")
    proc = subprocess.run(
        [cli, "operators", mesh, "--out", out, "--force"],
        capture_output=True,
        text=True,
    )
    if proc.returncode != 0:
        return {"mesh": mesh, "status": "refused by spectral-mesh", "reason": proc.stderr.strip()}
    V, F = read_off(os.path.join(out, "mesh.off"), triangles=True)
    res = {"mesh": os.path.basename(mesh), "n": int(V.shape[0]), "m": int(F.shape[0])}
    S = scipy.io.mmread(os.path.join(out, "S.mtx"))
    res["S"] = rel_err_sparse(S, -igl.cotmatrix(V, F), res, "S")
    kinds = {
        "B_fem": igl.MASSMATRIX_TYPE_FULL,
        "B_barycentric": igl.MASSMATRIX_TYPE_BARYCENTRIC,
        "B_mixed_voronoi": igl.MASSMATRIX_TYPE_VORONOI,
    }
    for name, kind in kinds.items():
        B = scipy.io.mmread(os.path.join(out, name + ".mtx"))
        res[name] = rel_err_sparse(B, igl.massmatrix(V, F, kind), res, name)
    # Symmetry to the last bit and S 1 = 0 (relative to the largest entry).
    S = sp.csc_matrix(S)
    res["S_asym"] = abs(S - S.T).max()
    res["S_rowsum"] = abs(S @ np.ones(S.shape[0])).max() / abs(S).max()
    try:
        Vi, Fi = igl.read_triangle_mesh(mesh)
    except Exception:  # libigl cannot read every file we can (e.g. '#' comments)
        Vi = Fi = None
    if Vi is not None and Vi.shape == V.shape:
        res["reader_vertices_max_diff"] = float(abs(Vi - V).max())
        # Faces agree only where the file holds triangles: polygons are triangulated
        # differently (libigl fans, we clip ears).
        if Fi.shape == F.shape:
            res["reader_same_faces"] = bool((Fi == F).all())
    keys = ["S", "B_fem", "B_barycentric", "B_mixed_voronoi", "S_rowsum"]
    res["status"] = "pass" if all(res[k] <= TOL for k in keys) and res["S_asym"] == 0 else "FAIL"
    if res.get("reader_vertices_max_diff", 0) > 0:
        res["status"] = "FAIL"
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cli", required=True, help="path to the spectral-mesh binary")
    ap.add_argument("--min-meshes", type=int, default=15)
    ap.add_argument("meshes", nargs="+")
    args = ap.parse_args()
    failures, compared = 0, 0
    with tempfile.TemporaryDirectory() as work:
        for m in args.meshes:
            r = compare(args.cli, m, work)
            print(json.dumps(r, default=float))
            if r["status"] == "pass":
                compared += 1
            elif r["status"] == "FAIL":
                compared += 1
                failures += 1
    return verdict("operators vs libigl", compared, failures, args.min_meshes, "meshes")


if __name__ == "__main__":
    sys.exit(main())
