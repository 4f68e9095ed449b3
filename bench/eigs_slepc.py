#!/usr/bin/env python3
"""SLEPc reference for the eigenbasis benchmarks (a second peer beside bench/eigs_scipy.py).

Reads the OFF file and assembles the same cotangent stiffness S and mass B as
bench/eigs_scipy.py (its functions), then solves S x = lambda B x with SLEPc's
Krylov-Schur (EPS type krylovschur, generalized Hermitian problem) in shift-invert mode
(ST sinvert) at the same scale-aware shift as ours, the shifted matrix factored by CHOLMOD
through PETSc (PETSc's own Cholesky when its CHOLMOD interface is missing; the route
printed says which). The convergence test is SLEPc's `EPS_CONV_NORM`,
||S x - lambda B x|| / (||S|| + |lambda| ||B||) for a unit vector: the relative residual
our `--tolerance` targets (ours divides by the 1-norms, SLEPc by its matrix norms).
Prints one `key=value` line like bench/eigs_scipy.py, with the residuals recomputed the
same way by both.

Needs Debian's python3-slepc4py (and python3-scipy) for the system python3:
bench/setup-slepc.sh installs them with apt-get when missing. Run it with /usr/bin/python3
(the bench venv's NumPy is not the one petsc4py was built against).

usage: eigs_slepc.py MESH.off K [--mass fem|voronoi-cot|cot] [--tol T] [--save OUT.npz]
       eigs_slepc.py --check   (exit status 0 when slepc4py, petsc4py and SciPy import)
"""
import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


def import_slepc():
    """(PETSc, SLEPc), initialized. Debian's .pth files find petsc4py and slepc4py through
    the /usr/lib/petsc and /usr/lib/slepc alternatives; where those links were not made,
    their versioned folders are searched."""
    import glob
    for pattern in ("/usr/lib/petscdir/*/*-real/lib/python3/dist-packages",
                    "/usr/lib/slepcdir/*/*-real/lib/python3/dist-packages"):
        for d in sorted(glob.glob(pattern))[-1:]:
            if d not in sys.path:
                sys.path.append(d)
    import petsc4py
    petsc4py.init(sys.argv[:1])
    from petsc4py import PETSc
    from slepc4py import SLEPc
    return PETSc, SLEPc


def main():
    if sys.argv[1:] == ["--check"]:
        # Used by bench/setup-slepc.sh: are slepc4py, petsc4py and SciPy importable?
        import_slepc()
        import scipy  # noqa: F401
        return
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("k", type=int)
    ap.add_argument("--mass", default="fem")
    ap.add_argument("--sigma", type=float, default=None)
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--save", default=None)
    a = ap.parse_args()
    try:
        PETSc, SLEPc = import_slepc()
    except ImportError as e:
        print(f"slepc4py is not importable ({e}); run bench/setup-slepc.sh", file=sys.stderr)
        sys.exit(3)
    out = solve(PETSc, SLEPc, a.mesh, a.k, a.mass, a.sigma, a.tol, a.save)
    if int(out["nconv"]) < a.k:
        print(f"SLEPc converged only {out['nconv']} of {a.k} pairs", file=sys.stderr)
        sys.exit(1)
    print(" ".join(f"{key}={val}" for key, val in out.items()))


def solve(PETSc, SLEPc, mesh, k, mass="fem", sigma=None, tol=1e-10, save=None):
    """The user's whole call with SLEPc: read `mesh`, assemble, solve for `k` pairs, check
    and write `save` (when given; not when fewer than `k` pairs converged). Returns the
    printed line's fields (`seconds` is the solve's)."""
    import numpy as np
    from eigs_scipy import operators, quality, read_off, save_basis, shift

    v, f = read_off(mesh)
    t0 = time.perf_counter()
    S, B = operators(v, f, mass)
    t_ops = time.perf_counter() - t0
    sigma, sn, bn = shift(S, B, sigma)
    n = len(v)

    def petsc(m):
        m = m.tocsr()
        m.sort_indices()
        it = PETSc.IntType
        return PETSc.Mat().createAIJ(
            size=m.shape, csr=(m.indptr.astype(it), m.indices.astype(it), m.data))

    t1 = time.perf_counter()
    A, M = petsc(S), petsc(B)
    for m in (A, M):
        m.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    eps = SLEPc.EPS().create()
    eps.setOperators(A, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(k)
    eps.setTolerances(tol, 10000)
    eps.setConvergenceTest(SLEPc.EPS.Conv.NORM)
    eps.setTarget(sigma)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(sigma)
    ksp = st.getKSP()
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    pc.setType(PETSc.PC.Type.CHOLESKY)
    route = "slepc-cholmod"
    try:
        pc.setFactorSolverType("cholmod")
        eps.setUp()
    except PETSc.Error:
        route = "slepc-petsc"
        pc.setFactorSolverType("petsc")
        eps.setUp()
    eps.solve()
    nconv = eps.getConverged()
    iterations = eps.getIterationNumber()
    if nconv < k:
        return {"mesh": mesh, "n": n, "k": k, "route": route, "nconv": nconv}
    lam = np.empty(nconv)
    X = np.empty((n, nconv), order="F")
    xr = A.createVecRight()
    for i in range(nconv):
        lam[i] = eps.getEigenpair(i, xr).real
        X[:, i] = xr.getArray()
    secs = time.perf_counter() - t1
    # Freed here, not at exit: the in-process benchmark (eigs_call.py) calls this again.
    eps.destroy()
    A.destroy()
    M.destroy()
    order = np.argsort(lam)[:k]
    lam, X = lam[order], np.asfortranarray(X[:, order])
    res, orth, peak = quality(S, B, lam, X, sn, bn)
    if save:
        save_basis(save, lam, X, B, res, mass, route)
    return {"mesh": mesh, "n": n, "k": k, "route": route, "tol": f"{tol:g}",
            "seconds": f"{secs:.3f}", "assembly": f"{t_ops:.3f}",
            "max_residual": f"{res.max():.2e}", "orth_error": f"{orth:.2e}",
            "lambda_k": f"{lam[-1]:.12e}", "peak_rss_mib": f"{peak:.0f}",
            "nconv": nconv, "iterations": iterations}


if __name__ == "__main__":
    main()
