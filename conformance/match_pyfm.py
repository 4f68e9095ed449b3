#!/usr/bin/env python3
"""Conformance: our functional maps and ZoomOut against pyFM's (PyPI pyfmaps).

Test pairs made here with a known correspondence (shape 1 = the TARGET of our CLI,
shape 2 = the SOURCE; the true map gt_21 gives, for each vertex of shape 2, its vertex on
shape 1): each shared mesh given with a shuffled copy of itself, the first one with its
midpoint subdivision (truth: nearest vertex), and a deformed icosphere bent
near-isometrically (shuffled).

For each pair, our side is the command line:

    spectral-mesh match S2.off S1.off -k 30 --zoomout 100 --no-normalize \
        -o ours.txt --initial-fmap C0.npy
    spectral-mesh eigs S1.off -k 100 -o b1.npz     (and S2)

pyFM runs on the very same eigenbases (`eigs -o`: eigenvalues, B-orthonormal
eigenvectors, the mass B as pyFM's `mesh.A`), the same descriptors (100 WKS energies from
the first 30 pairs, every 5th kept, L2 normalized), the same terms and weights (pyFM's
quickstart: w_descr 1, w_lap 1e-2, w_dcomm 1e-1, w_orient 1, with its "legacy" energy:
`use_resolvent_laplacian=False, normalize_weights=False`), then `zoomout_refine(nit=70,
step=1)` and `get_p2p()`.

Checks, per pair:
- energy: pyFM's own objective (the function and arguments its L-BFGS run gets) at our
  first functional map is <= its value at pyFM's solution (+ 1e-9 relative);
- mean geodesic error after ZoomOut (geodesics on shape 1 by potpourri3d's heat method,
  the same for both maps, in units of sqrt(area)): ours <= 1.05 pyFM's + 1e-3;
- shuffled pairs: ours < 0.01.

Exit status 0 when every pair passes and at least --min-pairs were compared.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

import potpourri3d as pp3d
import pyFM.functional as pyfm_functional
from pyFM.functional import FunctionalMapping
from pyFM.mesh import TriMesh

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import verdict  # noqa: E402

K = 30
K_FINAL = 100
WEIGHTS = dict(w_descr=1.0, w_lap=1e-2, w_dcomm=1e-1, w_orient=1.0)


def read_off(path):
    with open(path) as f:
        tokens = [t for line in f for t in line.split("#", 1)[0].split()]
    assert tokens[0].endswith("OFF"), f"{path}: not an OFF file"
    nv, nf = int(tokens[1]), int(tokens[2])
    pos = 4
    V = np.array(tokens[pos : pos + 3 * nv], dtype=np.float64).reshape(nv, 3)
    pos += 3 * nv
    F = np.array(tokens[pos : pos + 4 * nf], dtype=np.int64).reshape(nf, 4)
    assert (F[:, 0] == 3).all(), f"{path}: not all faces are triangles"
    return V, F[:, 1:].copy()


def write_off(path, V, F):
    with open(path, "w") as f:
        f.write(f"OFF\n{len(V)} {len(F)} 0\n")
        for v in V:
            f.write(f"{float(v[0])!r} {float(v[1])!r} {float(v[2])!r}\n")
        for t in F:
            f.write(f"3 {t[0]} {t[1]} {t[2]}\n")


def shuffled(V, F, seed):
    perm = np.random.default_rng(seed).permutation(len(V))
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(V))
    return V[perm], inv[F], perm


def subdivided(V, F):
    edges = {}
    newV = [v for v in V]
    tris = []

    def mid(a, b):
        key = (min(a, b), max(a, b))
        if key not in edges:
            edges[key] = len(newV)
            newV.append(0.5 * (V[a] + V[b]))
        return edges[key]

    for a, b, c in F:
        ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
        tris += [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
    return np.array(newV), np.array(tris, dtype=np.int64)


def load_basis(path):
    z = np.load(path)
    B = sp.csc_matrix(
        (z["mass_data"], z["mass_indices"], z["mass_indptr"]), shape=tuple(z["mass_shape"])
    )
    return z["eigenvalues"], np.asarray(z["eigenvectors"]), B.tocsr()


def pyfm_run(V1, F1, b1, V2, F2, b2, C_ours):
    meshes = []
    for V, F, (evals, evecs, B) in ((V1, F1, b1), (V2, F2, b2)):
        m = TriMesh(V, F)
        m.eigenvalues, m.eigenvectors, m.A = evals, evecs, B
        meshes.append(m)
    model = FunctionalMapping(meshes[0], meshes[1])
    model.preprocess(n_descr=100, descr_type="WKS", subsample_step=5, k_process=K_FINAL, k_descr=K)
    captured = {}
    real = pyfm_functional.fmin_l_bfgs_b

    def spy(func, x0, args=(), **kw):
        captured["func"], captured["args"] = func, args
        return real(func, x0, args=args, **kw)

    pyfm_functional.fmin_l_bfgs_b = spy
    try:
        model.fit(K=K, use_resolvent_laplacian=False, normalize_weights=False, **WEIGHTS)
    finally:
        pyfm_functional.fmin_l_bfgs_b = real
    f, args = captured["func"], captured["args"]
    e_theirs = f(model.FM_12.ravel(), *args)[0]
    e_ours = f(C_ours.ravel(), *args)[0]
    FM_zo = model.zoomout_refine(nit=K_FINAL - K, step=1)
    p2p = model.get_p2p(FM=FM_zo)
    return e_ours, e_theirs, np.asarray(p2p)


def geodesic_error(V1, F1, p2p, gt, max_sources=300):
    solver = pp3d.MeshHeatMethodDistanceSolver(V1, F1)
    n2 = len(gt)
    stride = 1
    while True:
        idx = np.arange(0, n2, stride)
        wrong = idx[p2p[idx] != gt[idx]]
        sources = np.unique(gt[wrong])
        if len(sources) <= max_sources:
            break
        stride += max(1, stride * len(sources) // max_sources - stride)
    err = np.zeros(len(idx))
    where = {v: i for i, v in enumerate(idx)}
    for s in sources:
        d = solver.compute_distance(int(s))
        for v in wrong[gt[wrong] == s]:
            err[where[v]] = d[p2p[v]]
    area = 0.5 * np.linalg.norm(np.cross(V1[F1[:, 1]] - V1[F1[:, 0]], V1[F1[:, 2]] - V1[F1[:, 0]]), axis=1).sum()
    return err.mean() / np.sqrt(area)


def run_cli(args):
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(args)}: {r.stderr.strip()}")
    return r.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cli", required=True)
    ap.add_argument("--min-pairs", type=int, default=1)
    ap.add_argument("meshes", nargs="*")
    a = ap.parse_args()
    pairs = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, m in enumerate(a.meshes):
            V, F = read_off(m)
            V2, F2, perm = shuffled(V, F, 1 + i)
            pairs.append((f"{os.path.basename(m)} <- shuffled", V, F, V2, F2, perm, True))
            if i == 0:
                Vs, Fs = subdivided(V, F)
                gt = cKDTree(V).query(Vs)[1]
                pairs.append((f"{os.path.basename(m)} <- subdivided", V, F, Vs, Fs, gt, False))
        sphere = os.path.join(tmp, "sphere.off")
        run_cli([a.cli, "convert", "sphere:res=4", sphere])
        Vb, Fb = read_off(sphere)
        x, y, z = Vb.T
        blob = np.stack([2.4 * x + 0.5 * x * x + 0.3 * y, 0.9 * y + 0.25 * z * z, 0.7 * z + 0.3 * x * y], 1)
        r = 8.0
        th = blob[:, 0] / r
        bent = np.stack([(r + blob[:, 1]) * np.sin(th), (r + blob[:, 1]) * np.cos(th) - r, blob[:, 2]], 1)
        V2, F2, perm = shuffled(bent, Fb, 99)
        pairs.append(("blob <- bent blob (shuffled)", blob, Fb, V2, F2, perm, False))

        failures = 0
        print(f"{'pair':34} {'E ours':>12} {'E pyFM':>12} {'err ours':>10} {'err pyFM':>10}  verdict")
        for name, V1, F1, V2, F2, gt, is_shuffle in pairs:
            p1, p2 = os.path.join(tmp, "s1.off"), os.path.join(tmp, "s2.off")
            write_off(p1, V1, F1)
            write_off(p2, V2, F2)
            outs = {k: os.path.join(tmp, k) for k in ("ours.txt", "C0.npy", "b1.npz", "b2.npz")}
            for o in outs.values():
                if os.path.exists(o):
                    os.remove(o)
            run_cli([a.cli, "match", p2, p1, "-k", str(K), "--zoomout", str(K_FINAL), "--no-normalize",
                     "-o", outs["ours.txt"], "--initial-fmap", outs["C0.npy"]])
            run_cli([a.cli, "eigs", p1, "-k", str(K_FINAL), "-o", outs["b1.npz"]])
            run_cli([a.cli, "eigs", p2, "-k", str(K_FINAL), "-o", outs["b2.npz"]])
            ours = np.loadtxt(outs["ours.txt"], dtype=np.int64)
            C0 = np.load(outs["C0.npy"])
            e_ours, e_theirs, p2p_theirs = pyfm_run(
                V1, F1, load_basis(outs["b1.npz"]), V2, F2, load_basis(outs["b2.npz"]), C0
            )
            err_ours = geodesic_error(V1, F1, ours, gt)
            err_theirs = geodesic_error(V1, F1, p2p_theirs, gt)
            ok = e_ours <= e_theirs + 1e-9 * abs(e_theirs)
            ok &= err_ours <= 1.05 * err_theirs + 1e-3
            if is_shuffle:
                ok &= err_ours < 0.01
            failures += not ok
            print(f"{name:34} {e_ours:12.6e} {e_theirs:12.6e} {err_ours:10.3e} {err_theirs:10.3e}  {'ok' if ok else 'FAIL'}")
    return verdict("functional maps vs pyFM", len(pairs), failures, a.min_pairs, "pairs")


if __name__ == "__main__":
    sys.exit(main())
