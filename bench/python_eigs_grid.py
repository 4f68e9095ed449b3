#!/usr/bin/env python3
"""The Python side-by-side eigenbasis benchmark: spectral_mesh.eigenbasis against LaPy,
SciPy eigsh with SuperLU, SciPy eigsh with a CHOLMOD factor (scikit-sparse) and
robust-laplacian + eigsh, each route the whole user call from (V, F) to (evals, evecs).

Every run is one fresh Python process (bench/python_eigs.py), so that its peak memory is
its own; within a cell (mesh, k) the runs alternate between routes (ours, lapy, superlu,
..., ours, ...) so that they see similar machine conditions. Each run appends one JSON
line to --out (with the load average before and after); the markdown table (--table) is
rewritten after each cell. Usually started by bench/python_eigs.sh, which installs the
venv (the peers and this package).

    bench/python_eigs.sh                                  # 25k, 100k; k = 50, 200, 500
    bench/python_eigs.sh --sizes 400k --runs 1 --timeout 1800
    bench/python_eigs.sh --sizes 25k --ks 50 --runs 1     # a quick check
    bench/python_eigs_grid.py --render-only               # the table from --out
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SIZE_SPECS = {
    "25k": "irregular-double-torus:res=4",  # 25 782 vertices
    "100k": "irregular-double-torus:res=5",  # 103 160 vertices
    "400k": "irregular-double-torus:res=6",  # 411 010 vertices
}
ROUTES = ("ours", "lapy", "lapy-cholespy", "superlu", "cholmod", "robust")
TITLES = {
    "ours": "spectral_mesh",
    "lapy": "LaPy (SuperLU)",
    "lapy-cholespy": "LaPy (cholespy)",
    "superlu": "SciPy SuperLU",
    "cholmod": "SciPy CHOLMOD",
    "robust": "robust-laplacian + eigsh",
}
# Routes that solve the same pencil as ours (robust-laplacian's L and lumped M differ).
SAME_PENCIL = ("ours", "lapy", "lapy-cholespy", "superlu", "cholmod")


def mesh_file(spec: str, mesh_dir: Path) -> Path:
    if Path(spec).is_file() and not spec.endswith(".npz"):
        import spectral_mesh as sm
        import numpy as np

        out = mesh_dir / (Path(spec).stem + ".npz")
        if not out.exists():
            V, F = sm.read_mesh(spec)
            mesh_dir.mkdir(parents=True, exist_ok=True)
            np.savez(out, V=V, F=F)
        return out
    spec = SIZE_SPECS.get(spec, spec)
    out = mesh_dir / (spec.replace(":", "_").replace(",", "_") + ".npz")
    if not out.exists():
        import numpy as np

        import spectral_mesh as sm

        mesh_dir.mkdir(parents=True, exist_ok=True)
        V, F = sm.shape(spec)
        tmp = out.with_suffix(".tmp.npz")
        np.savez(tmp, V=V, F=F)
        tmp.rename(out)
    return out


BLAS_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def run_once(py: str, mesh: Path, k: int, route: str, timeout: float, blas_threads: int) -> dict:
    env = dict(os.environ)
    if route != "ours" and blas_threads > 0:
        env.update({v: str(blas_threads) for v in BLAS_VARS})
    rec = {
        "time": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "load_before": os.getloadavg()[0],
        "route": route,
        "k": k,
        "mesh": str(mesh),
        "blas_threads": env.get("OPENBLAS_NUM_THREADS", "default"),
    }
    t0 = time.perf_counter()
    try:
        r = subprocess.run(
            [py, str(ROOT / "bench" / "python_eigs.py"), str(mesh), str(k), route],
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
        )
        rec["status"] = r.returncode
        if r.returncode == 0:
            rec.update(json.loads(r.stdout.strip().splitlines()[-1]))
        else:
            rec["error"] = r.stderr.strip().splitlines()[-1] if r.stderr.strip() else "failed"
    except subprocess.TimeoutExpired:
        rec["status"] = "timeout"
        rec["error"] = f"> {timeout:g} s"
    rec["process_s"] = time.perf_counter() - t0
    rec["load_after"] = os.getloadavg()[0]
    return rec


def fmt_s(xs: list[float]) -> str:
    if not xs:
        return ""
    m = statistics.median(xs)
    f = (lambda x: f"{x:.3g}") if m < 100 else (lambda x: f"{x:.0f}")
    if len(xs) == 1:
        return f"{f(m)} (1)"
    return f"{f(m)} [{f(min(xs))}, {f(max(xs))}] ({len(xs)})"


def render(records: list[dict], routes: list[str], header: str) -> str:
    cells: dict = {}
    for r in records:
        key = (r.get("mesh"), r.get("k"))
        cells.setdefault(key, {}).setdefault(r["route"], []).append(r)
    lines = [header, ""]
    cols = ["mesh", "n", "k"] + [f"{TITLES[r]} (s)" for r in routes]
    cols += [
        "fastest peer / ours",
        "peak RSS MiB (" + ", ".join(routes) + ")",
        "residual ours / worst peer",
        "lambda_k agrees",
        "load (uptime 1-min)",
    ]
    lines.append("| " + " | ".join(cols) + " |")
    lines.append("| " + " | ".join(["---"] + ["---:"] * (len(cols) - 1)) + " |")
    for (mesh, k), by_route in cells.items():
        ok = {r: [x for x in by_route.get(r, []) if x.get("status") == 0] for r in routes}
        n = next((x["n"] for xs in ok.values() for x in xs), "")
        row = [f"`{Path(mesh).stem}`", str(n), str(k)]
        med = {}
        for r in routes:
            xs = [x["total_s"] for x in ok[r]]
            if xs:
                med[r] = statistics.median(xs)
                row.append(fmt_s(xs))
            else:
                bad = by_route.get(r, [])
                row.append(bad[0].get("error", "failed") if bad else "")
        peers = [med[r] for r in routes if r != "ours" and r in med]
        row.append(f"**{min(peers) / med['ours']:.2f}x**" if "ours" in med and peers else "")
        row.append(
            ", ".join(
                f"{max(x['peak_rss_mib'] for x in ok[r]):.0f}" if ok[r] else "-" for r in routes
            )
        )
        res_ours = max((x["max_residual"] for x in ok["ours"]), default=float("nan"))
        res_peer = max(
            (x["max_residual"] for r in routes if r != "ours" for x in ok[r]), default=float("nan")
        )
        row.append(f"{res_ours:.1e} / {res_peer:.1e}")
        lk = [x["lambda_k"] for r in SAME_PENCIL if r in routes for x in ok[r]]
        if len(lk) > 1:
            rel = (max(lk) - min(lk)) / max(abs(max(lk)), 1e-300)
            row.append(f"{rel:.1e} {'yes' if rel < 1e-8 else 'NO'}")
        else:
            row.append("")
        loads = [
            x[key]
            for xs in by_route.values()
            for x in xs
            for key in ("load_before", "load_after")
            if key in x
        ]
        row.append(f"{min(loads):.1f}-{max(loads):.1f}" if loads else "")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument(
        "--python", default=sys.executable, help="the venv's python (peers and spectral_mesh)"
    )
    ap.add_argument(
        "--sizes", default="25k,100k", help="25k, 100k, 400k, shape specs or mesh files"
    )
    ap.add_argument("--ks", default="50,200,500")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--routes", default=",".join(ROUTES))
    ap.add_argument("--timeout", type=float, default=3600, help="seconds per run")
    ap.add_argument(
        "--slow-seconds",
        type=float,
        default=300,
        help="a route slower than this runs once per cell",
    )
    ap.add_argument(
        "--peer-blas-threads",
        type=int,
        default=1,
        help="OPENBLAS/OMP/MKL_NUM_THREADS for the peers (0: their default). One thread is "
        "their fastest here: with two, OpenBLAS's spinning threads fight the other process "
        "for the two cores (25k, k = 50, SuperLU: 27.5 s against 4.5 s at load 11)",
    )
    ap.add_argument("--out", default=str(ROOT / "bench" / "results" / "python_eigs.jsonl"))
    ap.add_argument("--table", default=str(ROOT / "bench" / "results" / "python_eigs.md"))
    ap.add_argument("--render-only", action="store_true")
    a = ap.parse_args()
    routes = [r.strip() for r in a.routes.split(",") if r.strip()]
    for r in routes:
        if r not in ROUTES:
            raise SystemExit(f"unknown route {r!r}: expected some of {', '.join(ROUTES)}")
    out, table = Path(a.out), Path(a.table)
    out.parent.mkdir(parents=True, exist_ok=True)
    commit = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    header = (
        f"Command: `{' '.join(sys.argv)}`; machine: {platform.machine()}, {os.cpu_count()} cores; "
        f"commit {commit}; total seconds from (V, F) to (evals, evecs), median [min, max] (runs); "
        f"peers' BLAS threads: {a.peer_blas_threads or 'default'}."
    )

    def records() -> list[dict]:
        if not out.exists():
            return []
        return [json.loads(line) for line in out.read_text().splitlines() if line.strip()]

    if a.render_only:
        table.write_text(render(records(), routes, header))
        print(table.read_text())
        return
    mesh_dir = ROOT / "bench" / "meshes"
    for size in [s.strip() for s in a.sizes.split(",") if s.strip()]:
        mesh = mesh_file(size, mesh_dir)
        for k in [int(x) for x in a.ks.split(",")]:
            slow: set = set()
            dead: set = set()
            for i in range(a.runs):
                for route in routes:
                    if route in dead or (i > 0 and route in slow):
                        continue
                    rec = run_once(a.python, mesh, k, route, a.timeout, a.peer_blas_threads)
                    with out.open("a") as fh:
                        fh.write(json.dumps(rec) + "\n")
                    status = rec.get("status")
                    t = rec.get("total_s")
                    print(
                        f"{mesh.stem} k={k} {route}: "
                        + (
                            f"{t:.2f} s, {rec['peak_rss_mib']:.0f} MiB, residual {rec['max_residual']:.1e}"
                            if status == 0
                            else str(rec.get("error"))
                        )
                        + f" (load {rec['load_before']:.1f})",
                        flush=True,
                    )
                    if status != 0:
                        dead.add(route)
                    elif t is not None and t > a.slow_seconds:
                        slow.add(route)
            table.write_text(render(records(), routes, header))
    print(table.read_text())


if __name__ == "__main__":
    main()
