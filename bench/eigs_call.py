#!/usr/bin/env python3
"""The Python call in a running interpreter (a notebook's cell), side by side: our
package against the SciPy + CHOLMOD script and the SLEPc script, each timed from the mesh
file to the written .npz, with every import already paid.

`bench/e2e_grid.py --routes python` times the same calls as whole processes, where the
interpreter's start and NumPy's import (about 0.1 s) are part of every run; a notebook pays
them once. Here each route runs in a worker process started once (its imports done, one
untimed warm-up call), and the driver sends the calls to the workers in turn, so that the
routes see similar machine conditions. The calls are the scripts' own functions:

- `python`: `bench/eigs_python.py`'s `solve` (`Analysis.from_file`, `basis`, `save_basis`);
- `scipy`: `bench/eigs_scipy.py`'s `solve` with CHOLMOD (read, assemble, eigsh, check, write);
- `slepc`: `bench/eigs_slepc.py`'s `solve` (Debian's slepc4py, under --slepc-python).

    bench/eigs_call.py --python .venv-bench/bin/python --sizes 26k,104k --ks 50,128 \\
        --runs 7 --out results/eigs_call.jsonl --table results/eigs_call.md

Each call appends one JSON line to --out (route, mesh, k, the call's wall seconds, the
load average before it); the markdown table (medians and the ratios of the peers' medians
to ours) is rewritten after each cell. Peak memory is not measured here (a worker's peak
covers all its calls): the whole-process grid has it. Standard library only in the driver.
"""
import argparse
import datetime
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import eigs_grid as eg  # noqa: E402

ROOT = eg.ROOT
ROUTES = ("scipy", "slepc", "python")
TITLES = {"scipy": "SciPy + CHOLMOD", "slepc": "SLEPc", "python": "spectral_mesh"}


# ---------------------------------------------------------------------------------- worker

def worker(route, mass, tol):
    """Reads `MESH K OUT` lines from stdin; for each, runs the route's call and prints one
    JSON line (the call's wall seconds and its printed fields, or the error)."""
    if route == "python":
        import eigs_python

        def call(mesh, k, out):
            return eigs_python.solve(mesh, k, mass, tol if tol is not None else 0.0, out)
    elif route == "scipy":
        import eigs_scipy

        def call(mesh, k, out):
            return eigs_scipy.solve(mesh, k, mass, None, True, 0.0 if tol is None else tol, out)
    else:
        import eigs_slepc
        petsc, slepc = eigs_slepc.import_slepc()

        def call(mesh, k, out):
            return eigs_slepc.solve(petsc, slepc, mesh, k, mass, None,
                                    1e-10 if tol is None else tol, out)
    print(json.dumps({"ready": route}), flush=True)
    for line in sys.stdin:
        mesh, k, out = line.split()
        t0 = time.perf_counter()
        try:
            fields = call(mesh, int(k), out)
            wall = time.perf_counter() - t0
            print(json.dumps({"wall": wall, "fields": {key: str(v) for key, v in fields.items()}}),
                  flush=True)
        except Exception as e:  # reported to the driver, which records the failure
            print(json.dumps({"error": f"{type(e).__name__}: {e}"}), flush=True)


class Worker:
    """One route's worker process (see [`worker`])."""

    def __init__(self, route, a):
        py = a.slepc_python if route == "slepc" else a.python
        cmd = [str(py), str(Path(__file__).resolve()), "--worker", route, "--mass", a.laplacian]
        if a.tol is not None:
            cmd += ["--tol", repr(a.tol)]
        env = dict(os.environ)
        if a.scipy_blas_threads > 0:
            env["OPENBLAS_NUM_THREADS"] = str(a.scipy_blas_threads)
        self.route = route
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, env=env)
        first = self.proc.stdout.readline()
        if not first:
            raise SystemExit(f"the {route} worker did not start: {shlex_join(cmd)}")

    def call(self, mesh, k, out):
        self.proc.stdin.write(f"{mesh} {k} {out}\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise SystemExit(f"the {self.route} worker ended")
        return json.loads(line)

    def close(self):
        self.proc.stdin.close()
        self.proc.wait(timeout=60)


def shlex_join(cmd):
    import shlex
    return shlex.join(cmd)


# ---------------------------------------------------------------------------------- driver

def run_cell(label, mesh, vertices, k, workers, a):
    records = []
    work = Path(tempfile.mkdtemp(prefix="eigs-call-", dir=a.work_dir))
    try:
        for w in workers:  # untimed warm-up: the first call maps the libraries' pages
            w.call(str(mesh), k, str(work / f"warm-{w.route}.npz"))
        for run in range(a.runs):
            for w in workers:
                out = work / f"{w.route}-{run}.npz"
                before = eg.loadavg()
                started = datetime.datetime.now(datetime.timezone.utc).isoformat(
                    timespec="seconds")
                reply = w.call(str(mesh), k, str(out))
                ok = "wall" in reply and out.is_file()
                rec = {"time": started, "mesh": label, "mesh_path": str(mesh),
                       "vertices": vertices, "k": k, "route": w.route, "run": run,
                       "status": "ok" if ok else "failed", "reason": reply.get("error"),
                       "wall_seconds": reply.get("wall"), "fields": reply.get("fields"),
                       "loadavg_before": before, "laplacian": a.laplacian}
                if out.is_file():
                    out.unlink()
                with a.out.open("a") as f:
                    f.write(json.dumps(rec) + "\n")
                records.append(rec)
                shown = f"{rec['wall_seconds']:.3f} s" if ok else f"failed: {rec['reason']}"
                print(f"{label} k={k} {w.route} run {run}: {shown}", file=sys.stderr)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return records


def render_table(records, a, command):
    routes = [r for r in ROUTES if any(rec["route"] == r for rec in records)]
    lines = [f"Python calls in a running interpreter (imports paid once), medians; "
             f"`{command}`", ""]
    head = "| mesh | k | " + " | ".join(TITLES[r] for r in routes) + " |"
    if "python" in routes:
        head += "".join(f" {TITLES[r]} / ours |" for r in routes if r != "python")
    lines += [head, "|" + " --- |" * (head.count("|") - 1)]
    cells = {}
    for rec in records:
        cells.setdefault((rec["mesh"], rec["vertices"], rec["k"]), []).append(rec)
    for (mesh, vertices, k), recs in cells.items():
        med = {}
        for r in routes:
            xs = [x["wall_seconds"] for x in recs if x["route"] == r and x["status"] == "ok"]
            med[r] = statistics.median(xs) if xs else None
        row = f"| {mesh} ({vertices}) | {k} | " + " | ".join(
            "failed" if med[r] is None else f"{med[r]:.3f} s" for r in routes) + " |"
        if "python" in routes:
            for r in routes:
                if r == "python":
                    continue
                ok = med[r] is not None and med["python"]
                row += f" {med[r] / med['python']:.2f}x |" if ok else " - |"
        lines.append(row)
    loads = [float(r["loadavg_before"][0]) for r in records if r.get("loadavg_before")]
    if loads:
        lines += ["", f"Load average before the calls: {min(loads):.2f}-{max(loads):.2f}."]
    return "\n".join(lines) + "\n"


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worker", choices=ROUTES, help=argparse.SUPPRESS)
    ap.add_argument("--sizes", default="26k,104k")
    ap.add_argument("--mesh", action="append", default=[], help="extra OFF file")
    ap.add_argument("--ks", default="50,128")
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--routes", default=",".join(ROUTES))
    ap.add_argument("--laplacian", "--mass", default="fem",
                    choices=["fem", "voronoi-cot", "cot"])
    ap.add_argument("--tol", type=float, default=None,
                    help="the tolerance of every route (default: each script's own: "
                         "SciPy 0, SLEPc and ours 1e-10)")
    ap.add_argument("--python", type=Path, help="python of the bench venv (scipy, python)")
    ap.add_argument("--slepc-python", type=Path, default=Path("/usr/bin/python3"))
    ap.add_argument("--scipy-blas-threads", type=int, default=1)
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "eigs_call.jsonl")
    ap.add_argument("--table", type=Path, default=ROOT / "bench" / "results" / "eigs_call.md")
    ap.add_argument("--mesh-dir", type=Path, default=ROOT / "bench" / "meshes")
    ap.add_argument("--work-dir", type=Path, default=None)
    ap.add_argument("--render-only", action="store_true")
    a = ap.parse_args(argv)
    if a.worker:
        worker(a.worker, a.laplacian, a.tol)
        return 0
    command = shlex_join(["bench/eigs_call.py"] + argv)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.table.parent.mkdir(parents=True, exist_ok=True)
    if a.render_only:
        records = [json.loads(ln) for ln in a.out.read_text().splitlines() if ln.strip()]
        a.table.write_text(render_table(records, a, command))
        print(a.table.read_text())
        return 0
    routes = [r for r in a.routes.split(",") if r]
    if any(r not in ROUTES for r in routes):
        ap.error(f"--routes: known routes are {', '.join(ROUTES)}")
    if any(r != "slepc" for r in routes) and not (a.python and a.python.is_file()):
        ap.error("--python: the bench venv's python is needed for the scipy and python routes")
    entries = [s for s in a.sizes.split(",") if s] + a.mesh
    meshes = [eg.resolve_mesh(e, a.mesh_dir, None, a.python) for e in entries]
    ks = [int(k) for k in a.ks.split(",") if k]
    workers = [Worker(r, a) for r in routes]
    records = []
    try:
        for label, path in meshes:
            vertices = eg.off_vertex_count(path)
            for k in ks:
                records += run_cell(label, path, vertices, k, workers, a)
                a.table.write_text(render_table(records, a, command))
    finally:
        for w in workers:
            w.close()
    print(a.table.read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
