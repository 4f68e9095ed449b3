#!/usr/bin/env python3
"""Conformance of heat kernel columns, bi-harmonic / commute-time distances and HKS.

Builds the cotangent stiffness S (positive semi-definite) and the linear FEM mass B with
NumPy/SciPy, computes k eigenpairs with eigsh (shift-invert, sigma = -0.01), computes the
same quantities independently, and compares them with the files written by our example
`crates/spectral-mesh/examples/spectral_fields.rs`. Only sign-invariant quantities are
compared (kernels, distances, HKS); choose k at a gap of the spectrum so that a repeated
eigenvalue is never cut.

Usage:
    python conformance/heat_distances.py MESH.off K T ANCHOR... [--bin CMD]
Runs `cargo run --example spectral_fields` unless --outdir DIR points at existing output.
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh


def read_off(path):
    lines = []
    with open(path) as f:
        for line in f:
            line = line.split("#")[0].strip()
            if line:
                lines.append(line)
    head = lines[0].split()
    i = 1
    if head[0].endswith("OFF"):
        head = head[1:]
    if not head:
        head = lines[1].split()
        i = 2
    nv, nf = int(head[0]), int(head[1])
    V = np.array([[float(x) for x in lines[i + j].split()[:3]] for j in range(nv)])
    F = []
    for j in range(nf):
        f = [int(x) for x in lines[i + nv + j].split()]
        m = f[0]
        for a in range(1, m - 1):
            F.append([f[1], f[1 + a], f[2 + a]])
    return V, np.array(F, dtype=np.int64)


def operators(V, F):
    n = len(V)
    I, J, W = [], [], []
    MI, MJ, MW = [], [], []
    for tri in F:
        p = V[tri]
        area = 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]))
        for k in range(3):
            a, b, c = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
            u, v = V[a] - V[c], V[b] - V[c]
            cr = np.linalg.norm(np.cross(u, v))
            cot = np.dot(u, v) / cr
            I += [a, b]
            J += [b, a]
            W += [-0.5 * cot, -0.5 * cot]
            MI += [a, a, b]
            MJ += [b, a, a]
            MW += [area / 12.0, area / 6.0, area / 12.0]
    S = sp.csr_matrix((W, (I, J)), shape=(n, n))
    S = S - sp.diags(np.asarray(S.sum(axis=1)).ravel())
    B = sp.csr_matrix((MW, (MI, MJ)), shape=(n, n))
    return S.tocsc(), B.tocsc()


def load(path):
    return np.loadtxt(path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("k", type=int)
    ap.add_argument("t", type=float)
    ap.add_argument("anchors", type=int, nargs="+")
    ap.add_argument("--outdir", default=None)
    args = ap.parse_args()

    out = args.outdir
    if out is None:
        out = tempfile.mkdtemp(prefix="heat_conf_")
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        cmd = ["cargo", "run", "-q", "-p", "spectral-mesh", "--example", "spectral_fields", "--",
               args.mesh, out, str(args.k), str(args.t)] + [str(a) for a in args.anchors]
        subprocess.run(cmd, check=True, cwd=root)

    V, F = read_off(args.mesh)
    S, B = operators(V, F)
    n = len(V)
    vals, X = eigsh(S, k=args.k, M=B, sigma=-0.01, which="LM")
    order = np.argsort(vals)
    vals, X = vals[order], X[:, order]
    # eigsh returns B-orthonormal vectors; check.
    orth = np.abs(X.T @ (B @ X) - np.eye(args.k)).max()

    ours_vals = load(os.path.join(out, "eigenvalues.txt"))
    report = {}
    report["eigenvalues (rel. to lambda_max)"] = np.abs(ours_vals - vals).max() / vals.max()

    lmax = vals.max()
    keep = vals > 1e-8 * lmax
    BX = B @ X
    for a in args.anchors:
        heat = X @ (np.exp(-vals * args.t) * BX[a, :])
        ours = load(os.path.join(out, f"heat_{a}.txt"))
        report[f"heat column {a} (rel. to max)"] = np.abs(ours - heat).max() / np.abs(heat).max()
        for name, w in (("biharmonic", 1.0 / vals[keep] ** 2), ("commute", 1.0 / vals[keep])):
            diff = X[:, keep] - X[a, keep][None, :]
            d = np.sqrt((diff ** 2 * w[None, :]).sum(axis=1))
            ours = load(os.path.join(out, f"{name}_{a}.txt"))
            report[f"{name} distances from {a} (rel. to max)"] = np.abs(ours - d).max() / d.max()

    times = np.geomspace(4 * np.log(10) / lmax, 4 * np.log(10) / vals[keep].min(), 8)
    ours_times = load(os.path.join(out, "hks_times.txt"))
    report["HKS times (rel.)"] = np.abs(ours_times - times).max() / times.max()
    hks = (X ** 2) @ np.exp(-np.outer(vals, times))
    ours = load(os.path.join(out, "hks.txt")).reshape(n, -1)
    report["HKS (rel. to max per time)"] = (np.abs(ours - hks).max(axis=0) / np.abs(hks).max(axis=0)).max()

    print(f"mesh {args.mesh}: n = {n}, k = {args.k}, t = {args.t}, "
          f"eigsh B-orthonormality error {orth:.1e}")
    worst = 0.0
    for k, v in report.items():
        print(f"  {k:45s} {v:.3e}")
        worst = max(worst, v)
    print(f"  max error {worst:.3e}")
    return 0 if worst < 1e-8 else 1


if __name__ == "__main__":
    sys.exit(main())
