#!/usr/bin/env python3
"""Collection benchmark: `spectral-mesh batch` against a multiprocessing.Pool script calling
SciPy eigsh + CHOLMOD (bench/batch_scipy.py), same meshes, same outputs (the basis .npz and
16 automatic HKS times per mesh, k = 50, each mesh scaled to unit area).

Two steps (usually through bench/batch_bench.sh, which builds the CLI and the bench venv):

  generate: --count meshes of 5k-50k vertices (target sizes log-uniform) into --meshes:
    built-in shapes with random parameters and perturbations of the shared meshes
    (SPECTRAL_MESH_SHARED_MESHES), each resampled to its target size (`perturb
    --apply resample:F`) with a little normal noise; deterministic in --seed.
  run: every route as one whole process in a fresh output folder, routes alternating
    within each repetition: ours with --jobs 1 and 2, the Pool script with 1 and 2
    processes, and ours again over its finished folder (a rerun with nothing to do: the
    per-shape cost of the checks). --count N takes the first N meshes (a manifest).
    Prints and appends JSON lines (wall seconds, peak RSS of the largest process, the
    1-minute load average before and after); writes a markdown table; checks that the two
    sides agree (largest relative difference of the eigenvalues over all meshes).

Standard library only (the eigenvalue check runs numpy in the bench venv).
"""
import argparse
import datetime
import json
import math
import os
import random
import shlex
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))
import eigs_grid as eg  # noqa: E402

# Built-in families at a resolution below 50k vertices: (spec template, vertex count).
BUILTIN = [
    ("torus:res=3,R={R},r={r}", 6272), ("torus:res=4,R={R},r={r}", 25088),
    ("3torus:res=3", 6396), ("sphere:res=5", 10242), ("uv-sphere:res=3", 6162),
    ("double-torus:res=3", 4734), ("double-torus:res=4", 18942), ("disk:res=3", 7057),
    ("cylinder:res=3", 6384), ("irregular-torus:res=4,R={R},r={r}", None),
    ("irregular-3torus:res=4", None), ("irregular-sphere:res=5", None),
]
SHARED = ["bunny00.off", "polygon_mesh.off", "cylinder_locally_refined.off", "fandisk.off",
          "homer.off", "holes.off", "knot1.off", "cow.off", "elephant.off"]


def off_vertices(path):
    with open(path) as f:
        for line in f:
            t = line.split("#", 1)[0].split()
            if t and t[0].upper() not in ("OFF", "COFF", "NOFF"):
                return int(t[0])
            if len(t) > 1:
                return int(t[1])
    raise ValueError(f"{path}: no counts")


def cli_run(cli, args):
    r = subprocess.run([str(cli)] + args, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{shlex.join([str(cli)] + args)}: {r.stderr.strip()}")
    return r.stdout


def generate(a):
    rng = random.Random(a.seed)
    out = Path(a.meshes)
    out.mkdir(parents=True, exist_ok=True)
    shared = Path(os.environ.get("SPECTRAL_MESH_SHARED_MESHES", str(Path(__file__).resolve().parents[2] / "shared" / "meshes")))
    bases = []
    for spec, n in BUILTIN:
        bases.append(("shape", spec, n))
    for name in SHARED:
        p = shared / name
        if p.is_file():
            bases.append(("file", str(p), off_vertices(p)))
    # The vertex counts of the irregular families (data-dependent): built once.
    sizes = {}
    for i in range(a.count):
        target = int(round(math.exp(rng.uniform(math.log(a.min_vertices), math.log(a.max_vertices)))))
        R, r = round(rng.uniform(1.0, 2.0), 3), round(rng.uniform(0.2, 0.6), 3)
        seed = rng.randrange(1 << 30)
        choices = []
        for kind, spec, n in bases:
            src = spec.format(R=R, r=r) if kind == "shape" else spec
            if n is None:
                if spec not in sizes:
                    tmp = out / ".probe.off"
                    cli_run(a.cli, ["convert", spec.format(R=1.5, r=0.4), str(tmp), "--force"])
                    sizes[spec] = off_vertices(tmp)
                    tmp.unlink()
                n = sizes[spec]
            if target / 8 <= n <= target:
                choices.append((src, n))
        if not choices:
            continue
        src, n = rng.choice(choices)
        factor = max(1.0, target / n)
        dest = out / f"m{i:03d}.off"
        if dest.exists() and not a.force:
            continue
        cli_run(a.cli, ["perturb", src, "--apply", f"resample:{factor:.6f},seed={seed}",
                        "--apply", f"noise:0.05,seed={seed}", "-o", str(dest), "--force"])
        print(f"{dest.name}: {src} x {factor:.3f} -> {off_vertices(dest)} vertices", file=sys.stderr)


def loadavg():
    try:
        return open("/proc/loadavg").read().split()[:3]
    except OSError:
        return None


def run_process(cmd, env, timeout):
    """Wall seconds, exit code, stdout, stderr and the peak RSS (MiB) from wait4: the
    largest of the process and its waited-for descendants (workers, pool processes)."""
    status, code, stdout, stderr, wall, maxrss = eg.run_once_with_env(cmd, timeout, env)
    if status == "timeout":
        code = -9
    return wall, code, stdout, stderr, maxrss


def eigen_check(python, ours, theirs):
    code = r"""
import sys, numpy as np
from pathlib import Path
a, b = Path(sys.argv[1]), Path(sys.argv[2])
worst, count = 0.0, 0
for p in sorted(a.glob('*.npz')):
    q = b / p.name
    if not q.exists():
        continue
    x = np.load(p)['eigenvalues']; y = np.load(q)['eigenvalues']
    scale = np.abs(y).max()
    worst = max(worst, float(np.abs(x - y).max() / scale)); count += 1
print(f"compared={count} max_rel_eig_diff={worst:.2e}")
"""
    r = subprocess.run([str(python), "-c", code, str(ours), str(theirs)], capture_output=True, text=True)
    return r.stdout.strip() or r.stderr.strip()[-300:]


def run(a):
    meshes = sorted(Path(a.meshes).glob("*.off"))[: a.count]
    if not meshes:
        raise SystemExit(f"{a.meshes}: no .off files (run the generate step)")
    work = Path(a.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    manifest = work / "manifest.txt"
    manifest.write_text("".join(f"{p.resolve()}\n" for p in meshes))
    vertices = sum(off_vertices(p) for p in meshes)
    cores = os.cpu_count() or 1
    print(f"{len(meshes)} meshes, {vertices} vertices in all, k = {a.k}, HKS x {a.hks}", file=sys.stderr)
    records = []
    finished = {}
    for rep in range(1, a.runs + 1):
        for route in a.routes.split(","):
            kind, _, workers = route.partition(":")
            workers = int(workers or 1)
            threads = max(1, cores // workers)
            out = work / f"{kind}-{workers}-run{rep}"
            env = {}
            if kind == "ours":
                shutil.rmtree(out, ignore_errors=True)
                cmd = [str(a.cli), "batch", f"@{manifest}", "--out", str(out), "-k", str(a.k),
                       "--hks", f"auto:{a.hks}", "--jobs", str(workers), "--threads", str(threads)]
            elif kind == "rerun":
                out = finished.get("ours")
                if out is None:
                    continue
                cmd = [str(a.cli), "batch", f"@{manifest}", "--out", str(out), "-k", str(a.k),
                       "--hks", f"auto:{a.hks}", "--jobs", str(workers), "--threads", str(threads)]
            else:
                shutil.rmtree(out, ignore_errors=True)
                cmd = [str(a.python), str(ROOT / "bench" / "batch_scipy.py"), f"@{manifest}",
                       "--out", str(out), "-k", str(a.k), "--hks", str(a.hks),
                       "--processes", str(workers)]
                env = {"OPENBLAS_NUM_THREADS": str(threads), "OMP_NUM_THREADS": str(threads)}
            before = loadavg()
            started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
            wall, code, stdout, stderr, rss = run_process(cmd, env, a.timeout)
            rec = {
                "time": started, "route": kind, "workers": workers, "threads": threads,
                "run": rep, "meshes": len(meshes), "vertices": vertices, "k": a.k,
                "hks": a.hks, "exit_code": code, "wall_seconds": round(wall, 3),
                "meshes_per_minute": round(len(meshes) / wall * 60, 2),
                "vertices_per_second": round(vertices / wall),
                "peak_rss_mib": round(rss, 1) if rss is not None else None,
                "loadavg_before": before, "loadavg_after": loadavg(),
                "command": shlex.join(cmd), "stdout_tail": stdout[-400:],
                "stderr_tail": stderr[-400:] if code != 0 else "",
            }
            if kind in ("ours", "scipy") and code == 0:
                finished[kind] = out
            if kind == "scipy" and "ours" in finished:
                rec["eigen_check"] = eigen_check(a.python, finished["ours"], out)
            records.append(rec)
            with open(a.out, "a") as f:
                f.write(json.dumps(rec) + "\n")
            print(f"[{started}] load {' '.join(before or [])} | {kind} x{workers}: {wall:.1f} s, "
                  f"{rec['meshes_per_minute']} meshes/min, exit {code} {rec.get('eigen_check', '')}",
                  file=sys.stderr)
    render(records, a)
    if not a.keep:
        shutil.rmtree(work, ignore_errors=True)


def render(records, a):
    by = {}
    for r in records:
        by.setdefault((r["route"], r["workers"]), []).append(r)
    name = {"ours": "spectral-mesh batch", "rerun": "spectral-mesh batch, rerun (all up to date)",
            "scipy": "Pool + SciPy eigsh + CHOLMOD"}
    lines = ["| route | workers x threads | runs | wall s (median) | meshes/min | vertices/s "
             "| peak RSS MiB (largest process) | load before -> after |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
    for (route, workers), rs in by.items():
        ok = [r for r in rs if r["exit_code"] == 0]
        if not ok:
            lines.append(f"| {name[route]} | {workers} | {len(rs)} | failed | | | | |")
            continue
        wall = statistics.median(r["wall_seconds"] for r in ok)
        m, v = ok[0]["meshes"], ok[0]["vertices"]
        loads = ", ".join(f"{r['loadavg_before'][0]} -> {r['loadavg_after'][0]}" for r in ok)
        rss = max(r["peak_rss_mib"] or 0 for r in ok)
        lines.append(f"| {name[route]} | {workers} x {ok[0]['threads']} | {len(ok)} | {wall:.1f} "
                     f"| {m / wall * 60:.1f} | {v / wall:,.0f} | {rss:.0f} | {loads} |")
    checks = [r["eigen_check"] for r in records if r.get("eigen_check")]
    if checks:
        lines.append("")
        lines.append("Eigenvalues, ours against SciPy's: " + "; ".join(sorted(set(checks))))
    text = "\n".join(lines) + "\n"
    Path(a.table).write_text(text)
    print(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="step", required=True)
    both = argparse.ArgumentParser(add_help=False)  # the options of both steps
    both.add_argument("--cli", default=str(ROOT / "target/release/spectral-mesh"))
    both.add_argument("--meshes", default=str(ROOT / "bench/meshes/batch"))
    both.add_argument("--count", type=int, default=200)
    g = sub.add_parser("generate", parents=[both])
    g.add_argument("--min-vertices", type=int, default=5000)
    g.add_argument("--max-vertices", type=int, default=50000)
    g.add_argument("--seed", type=int, default=1)
    g.add_argument("--force", action="store_true")
    r = sub.add_parser("run", parents=[both])
    r.add_argument("--python", required=True, help="the bench venv's python")
    r.add_argument("-k", type=int, default=50)
    r.add_argument("--hks", type=int, default=16)
    r.add_argument("--runs", type=int, default=1)
    r.add_argument("--routes", default="ours:1,scipy:1,ours:2,scipy:2,rerun:2")
    r.add_argument("--work-dir", default=str(ROOT / "bench/results/batch-work"))
    r.add_argument("--keep", action="store_true", help="keep the output folders")
    r.add_argument("--timeout", type=float, default=7200, help="seconds per run")
    r.add_argument("--out", default=str(ROOT / "bench/results/batch.jsonl"))
    r.add_argument("--table", default=str(ROOT / "bench/results/batch.md"))
    a = ap.parse_args()
    (generate if a.step == "generate" else run)(a)


if __name__ == "__main__":
    main()
