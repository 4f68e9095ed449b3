#!/usr/bin/env python3
"""Conformance of our eigenbasis with SLEPc's (Krylov-Schur, shift-invert, CHOLMOD through
PETSc: bench/eigs_slepc.py's `solve`), the same checks as conformance/eigs_scipy.py
(`eigencheck.compare`): masses to 1e-12, eigenvalues to 1e-9 relative to lambda_k, X^T B X = I to
1e-10, every cluster's principal angles below 1e-6.

usage: eigs_slepc.py MESH.off --k K --cli PATH [--mass fem|voronoi-cot|cot]

Runs `CLI eigs MESH -k K --laplacian MASS -o BASIS.npz` and SLEPc for k + 8 pairs at a
tolerance of 1e-12 (so that a cluster cut by k is complete on its side). Run it with the
python of bench/setup-slepc.sh (Debian's /usr/bin/python3: petsc4py is built against
Debian's NumPy). Exit status 0 when everything holds.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "bench"))
import eigs_slepc  # noqa: E402  (bench/: the SLEPc script)
from eigs_scipy import operators, read_off  # noqa: E402  (bench/eigs_scipy.py)

sys.path.insert(0, here)
from eigencheck import compare, load_basis  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("--k", type=int, default=40)
    ap.add_argument("--cli", required=True)
    ap.add_argument("--mass", default="fem")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        ours = os.path.join(tmp, "ours.npz")
        theirs = os.path.join(tmp, "slepc.npz")
        subprocess.run([a.cli, "eigs", a.mesh, "-k", str(a.k), "--laplacian", a.mass,
                        "-o", ours], check=True, stdout=subprocess.DEVNULL)
        PETSc, SLEPc = eigs_slepc.import_slepc()
        line = eigs_slepc.solve(PETSc, SLEPc, a.mesh, a.k + 8, a.mass, tol=1e-12, save=theirs)
        print(f"slepc: route {line.get('route')}, {line.get('nconv')} converged of {a.k + 8}")
        if not os.path.exists(theirs):
            print("FAIL: SLEPc did not converge")
            sys.exit(1)
        lam, X, Bf, _ = load_basis(ours)
        g = np.load(theirs)
        v, t = read_off(a.mesh)
        _, B = operators(v, t, a.mass)
        ok = compare(lam, X, Bf, B, g["eigenvalues"], g["eigenvectors"], "slepc")
    print("PASS" if ok else "FAIL")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
