#!/usr/bin/env python3
"""The Python user's script with this package, for the end-to-end grid (route `python`):
read a mesh file, assemble, solve and write the same .npz as `spectral-mesh eigs -o` and
the SciPy script (`eigs_scipy.py --save`), in one fresh process, the package's shortest
way (no SciPy imported):

    an = spectral_mesh.Analysis.from_file(MESH, "fem", normalize=False)
    an.basis(K)
    an.save_basis(OUT)

`normalize=False`: the mesh as given, as the command line and SciPy's script do.

usage: eigs_python.py MESH K [--mass fem] [--tol T] [--save OUT.npz]

Prints one line of key=value pairs (the grid reads `seconds`, the solve's).
"""

import argparse
import time

import spectral_mesh as sm


def solve(mesh: str, k: int, mass: str = "fem", tol: float = 0.0, save=None) -> dict:
    """The user's whole call: read `mesh`, assemble, solve for `k` pairs and write `save`
    (when given). Returns the printed line's fields (`seconds` is the solve's)."""
    t0 = time.perf_counter()
    an = sm.Analysis.from_file(mesh, mass, normalize=False, tol=tol)
    t_ops = time.perf_counter() - t0
    t1 = time.perf_counter()
    lam, _ = an.basis(k)
    secs = time.perf_counter() - t1
    if save:
        an.save_basis(save)
    return {"mesh": mesh, "n": an.n, "k": k, "route": "python", "tol": f"{tol:g}",
            "seconds": f"{secs:.3f}", "read_and_assembly": f"{t_ops:.3f}",
            "lambda_k": f"{lam[-1]:.12e}"}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("k", type=int)
    ap.add_argument("--mass", default="fem")
    ap.add_argument("--tol", type=float, default=0.0)
    ap.add_argument("--save", default=None)
    a = ap.parse_args()
    out = solve(a.mesh, a.k, a.mass, a.tol, a.save)
    print(" ".join(f"{key}={val}" for key, val in out.items()))


if __name__ == "__main__":
    main()
