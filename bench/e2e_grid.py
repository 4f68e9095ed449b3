#!/usr/bin/env python3
"""End-to-end benchmark: every spectral command of the `spectral-mesh` CLI, whole process
(mesh file in, outputs written), against two peers that read the same OFF file, compute
the same eigenpairs and write the same .npz: the SciPy + CHOLMOD script
(bench/eigs_scipy.py --cholmod --save) and the SLEPc one (bench/eigs_slepc.py --save:
Krylov-Schur, shift-invert, CHOLMOD, the same tolerance as ours). Also the share of each
command's process that is not its eigensolve.

Standard library only; reuses bench/eigs_grid.py's helpers. Every run is one process, in a
fresh output folder; within a cell (mesh, k) the routes alternate (scipy, eigs, heat, ...,
scipy, eigs, ...). Each run appends one JSON line to --out (timestamp, load average before
and after, wall seconds and peak RSS from wait4, the eigensolve seconds the command
printed, the solver's phase timings); the markdown tables are rewritten to --table after
each cell.

Usually started through bench/e2e_grid.sh, which builds the CLI and the venv:
    bench/e2e_grid.sh                                   # 25k, 100k, 400k x k = 50, 200, 500
    bench/e2e_grid.sh --sizes 25k --ks 500 --runs 1
    bench/e2e_grid.py --render-only --out results.jsonl --table table.md
"""
import argparse
import datetime
import re
import shutil
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import eigs_grid as eg  # noqa: E402

ROOT = eg.ROOT

# The commands and what each writes (OUT is a fresh folder per run).
COMMANDS = {
    "eigs": ["eigs", "MESH", "-k", "K", "-o", "OUT/basis.npz"],
    "heat": ["heat", "MESH", "-k", "K", "-o", "OUT/heat.txt", "-o", "OUT/heat.png"],
    "distance": ["distance", "MESH", "-k", "K", "-o", "OUT/d.txt", "-o", "OUT/d.png"],
    "signature": ["signature", "MESH", "-k", "K", "-o", "OUT/hks.txt", "-o", "OUT/hks.png"],
    "segment": ["segment", "MESH", "-k", "K", "-o", "OUT/labels.txt", "-o", "OUT/labels.png"],
    "embed": ["embed", "MESH", "-k", "K", "-o", "OUT/embedded.off", "--coords", "OUT/c.txt"],
    "experiment": ["experiment", "spectral-distance", "MESH", "-k", "K", "-o", "OUT/exp"],
}
PEERS = ("scipy", "slepc")
# Ours from Python: the user's script with this package (bench/eigs_python.py), whole
# process like the others; compared with the same peers.
ROUTES = PEERS + tuple(COMMANDS) + ("python",)
SOLVE = re.compile(r"eigenpairs in ([0-9.]+) s")
PHASES = re.compile(r"eig timings \(s\): (.*)")


def route_command(route, mesh, k, out, a):
    if route == "scipy":
        return [str(a.python), str(ROOT / "bench" / "eigs_scipy.py"), str(mesh), str(k),
                "--mass", a.laplacian, "--cholmod", "--save", str(out / "basis.npz")]
    if route == "python":
        return [str(a.python), str(ROOT / "bench" / "eigs_python.py"), str(mesh), str(k),
                "--mass", a.laplacian, "--save", str(out / "basis.npz")]
    if route == "slepc":
        return [str(a.slepc_python), str(ROOT / "bench" / "eigs_slepc.py"), str(mesh), str(k),
                "--mass", a.laplacian, "--tol", repr(a.tol), "--save", str(out / "basis.npz")]
    subst = {"MESH": str(mesh), "K": str(k)}
    args = [subst.get(x, x.replace("OUT", str(out))) for x in COMMANDS[route]]
    return [str(a.cli)] + args + ["--laplacian", a.laplacian]


def measure(route, label, mesh, vertices, k, run, a):
    out = Path(tempfile.mkdtemp(prefix="e2e-", dir=a.work_dir))
    cmd = route_command(route, mesh, k, out, a)
    before = eg.loadavg()
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    # The runs inherit the environment: our solver's phase timings on, and SciPy's BLAS
    # threads as --scipy-blas-threads says (set for every route; our binary has no BLAS).
    env = {"SPECTRAL_MESH_EIG_TIMINGS": "1"}
    if a.scipy_blas_threads > 0:
        env["OPENBLAS_NUM_THREADS"] = str(a.scipy_blas_threads)
    status, code, stdout, stderr, wall, maxrss = eg.run_once_with_env(cmd, a.timeout, env)
    written = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
    shutil.rmtree(out, ignore_errors=True)
    status, reason = eg.failure(status, code, stderr, a.timeout)
    solve = None
    if route in PEERS + ("python",):
        keys = eg.parse_line(stdout)
        solve = keys.get("seconds")
    else:
        m = SOLVE.search(stdout)
        solve = float(m.group(1)) if m else None
    phases = {}
    m = PHASES.search(stderr)
    if m:
        for key, value in eg.KEY_VALUE.findall(m.group(1)):
            phases[key] = float(value)
    record = {
        "time": started, "mesh": label, "mesh_path": str(mesh), "vertices": vertices,
        "k": k, "route": route, "run": run, "status": status, "reason": reason,
        "exit_code": code, "laplacian": a.laplacian,
        "solve_seconds": solve, "solver_phases": phases,
        "phase_sum_seconds": round(sum(phases.values()), 3) if phases else None,
        "bytes_written": written, "scipy_blas_threads": a.scipy_blas_threads,
    }
    return eg.save_record(a, record, (cmd, wall, maxrss, before), (stdout, stderr),
                          f"{wall:.2f} s (solve {solve})")


def run_cell(label, mesh, vertices, k, a):
    runs = a.runs_large if vertices and vertices > a.large else a.runs
    return eg.run_cell(label, mesh, vertices, k, a, measure, runs,
                       lambda rec: rec["wall_seconds"])


def median_of(records, key):
    xs = [r[key] for r in records if r["status"] == "ok" and r.get(key) is not None]
    return statistics.median(xs) if xs else None


def render_table(records, a, command):
    routes = [r for r in ROUTES if any(rec["route"] == r for rec in records)]
    ours = [r for r in routes if r not in PEERS]
    cells = {}
    for rec in records:
        cells.setdefault((rec["mesh"], rec["k"]), {}).setdefault(rec["route"], []).append(rec)
    lines = eg.table_head(
        records,
        "# End-to-end: each spectral command against SciPy + CHOLMOD and SLEPc writing the same .npz",
        command, f"Laplacian: {a.laplacian}; SciPy's OpenBLAS threads: "
        + ", ".join(sorted({str(r.get("scipy_blas_threads") or "default") for r in records})))
    lines += [
        "- whole process, wall seconds (mesh file in, outputs written), median "
        "(number of runs), and in brackets each peer's median over the command's (SciPy, "
        "then SLEPc); commands: "
        + "; ".join(f"{r} = `spectral-mesh {' '.join(COMMANDS[r])}`" if r in COMMANDS
                    else f"{r} = `eigs_python.py MESH K --save OUT/basis.npz`" for r in ours)
        + "; scipy = `eigs_scipy.py MESH K --cholmod --save OUT/basis.npz`"
        + f"; slepc = `eigs_slepc.py MESH K --tol {a.tol:g} --save OUT/basis.npz`",
        "",
    ]
    head = ["mesh", "n", "k"] + [f"{r} (s)" for r in routes]
    lines.append("| " + " | ".join(head) + " |")
    lines.append("| " + " | ".join(["---"] + ["---:"] * (len(head) - 1)) + " |")
    for (mesh, k), by in cells.items():
        n = next(rec.get("vertices") for recs in by.values() for rec in recs)
        peers = [median_of(by.get(p, []), "wall_seconds") for p in PEERS]
        row = [f"`{mesh}`", str(n), str(k)]
        for r in routes:
            recs = by.get(r, [])
            med = median_of(recs, "wall_seconds")
            count = sum(1 for x in recs if x["status"] == "ok")
            if med is None:
                row.append("failed" if recs else "-")
                continue
            text = f"{eg.fmt_seconds(med)} ({count})"
            ratios = [f"{p / med:.2f}x" for p in peers if p]
            if r not in PEERS and ratios:
                text += f" **[{', '.join(ratios)}]**"
            row.append(text)
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", "Peak RSS (MiB, whole process, largest over the runs):", ""]
    lines.append("| " + " | ".join(["mesh", "k"] + routes) + " |")
    lines.append("| " + " | ".join(["---", "---:"] + ["---:"] * len(routes)) + " |")
    for (mesh, k), by in cells.items():
        row = [f"`{mesh}`", str(k)]
        for r in routes:
            xs = [x["wait4_maxrss_mib"] for x in by.get(r, []) if x["status"] == "ok"]
            row.append(f"{max(xs):.0f}" if xs else "-")
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", "Whole process over the eigensolve (the seconds the command prints as "
              "`eigenpairs in`), medians of the per-run ratios:", ""]
    lines.append("| " + " | ".join(["mesh", "k"] + ours) + " |")
    lines.append("| " + " | ".join(["---", "---:"] + ["---:"] * len(ours)) + " |")
    for (mesh, k), by in cells.items():
        row = [f"`{mesh}`", str(k)]
        for r in ours:
            xs = [x["wall_seconds"] / x["solve_seconds"] for x in by.get(r, [])
                  if x["status"] == "ok" and x.get("solve_seconds")]
            row.append(f"{statistics.median(xs):.3f}" if xs else "-")
        lines.append("| " + " | ".join(row) + " |")
    return eg.table_end(lines, records)


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="25k,100k,400k",
                    help="comma list of sizes (" + ", ".join(
                        f"{s}: {v}" for s, v in eg.SIZE_SPECS.items()) + ") or shape specs")
    ap.add_argument("--mesh", action="append", default=[], help="extra OFF file or shape")
    ap.add_argument("--ks", default="50,200,500")
    ap.add_argument("--runs", type=int, default=3, help="runs per route and cell")
    ap.add_argument("--large", type=int, default=300000,
                    help="meshes above this many vertices get --runs-large runs")
    ap.add_argument("--runs-large", type=int, default=1)
    ap.add_argument("--routes", default=",".join(r for r in ROUTES if r != "python"),
                    help="comma list of routes; `python` (not in the default) needs the "
                    "package in --python's venv (bench/python_eigs.sh installs it)")
    ap.add_argument("--laplacian", default="fem", choices=["fem", "voronoi-cot", "cot"])
    ap.add_argument("--tol", type=float, default=1e-10,
                    help="SLEPc's tolerance (the default of ours; SciPy runs with tol = 0)")
    ap.add_argument("--slepc-python", type=Path, default=Path("/usr/bin/python3"),
                    help="the python with Debian's slepc4py (bench/setup-slepc.sh)")
    ap.add_argument("--timeout", type=float, default=3600.0)
    ap.add_argument("--slow-seconds", type=float, default=300.0,
                    help="a route whose run took longer runs only once in its cell")
    ap.add_argument("--scipy-blas-threads", type=int, default=1,
                    help="OPENBLAS_NUM_THREADS of the runs (0: leave it unset). On this "
                         "shared 2-core machine under load, NumPy's OpenBLAS threads "
                         "spin-wait: eigsh at 25k, k = 50 took 17-26 s with them and 4.7 s "
                         "with one thread in the same conditions")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "e2e_grid.jsonl")
    ap.add_argument("--table", type=Path, default=ROOT / "bench" / "results" / "e2e_grid.md")
    ap.add_argument("--python", type=Path, help="python of the bench venv")
    ap.add_argument("--cli", type=Path, help="the spectral-mesh binary")
    ap.add_argument("--mesh-dir", type=Path, default=ROOT / "bench" / "meshes")
    ap.add_argument("--work-dir", type=Path, default=None,
                    help="where the per-run output folders go (default: the system's tmp)")
    ap.add_argument("--render-only", action="store_true")
    a = eg.parse_lists(ap, argv, ROUTES)
    if not a.render_only:
        if not (a.cli and a.cli.is_file()):
            ap.error("--cli: the spectral-mesh binary is needed")
        if ("scipy" in a.routes or "python" in a.routes) and not (a.python and a.python.is_file()):
            ap.error("--python: the bench venv's python is needed for the scipy and python routes")
    return a


def main(argv=None):
    return eg.grid_main(argv, "e2e_grid", parse_args, render_table, run_cell)


if __name__ == "__main__":
    sys.exit(main())
