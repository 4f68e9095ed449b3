#!/usr/bin/env python3
"""Side-by-side eigensolver benchmark: ours (the Rust example `bench_eigs`) against SciPy
eigsh in shift-invert mode with SuperLU and with a CHOLMOD factorization (bench/eigs_scipy.py).

Standard library only. Every run is one process; within a cell (mesh, k) the runs alternate
between routes (ours, superlu, cholmod, ours, ...) so that they see similar machine
conditions. Each run appends one JSON line to --out (timestamp, load average before and
after, exit status, every key=value the run printed); after each cell the markdown table
is rewritten to --table, so an interrupted grid still leaves a table.

Usually started through bench/eigs_grid.sh, which builds the binaries and the venv:
    bench/eigs_grid.sh                       # the full grid (hours)
    bench/eigs_grid.sh --sizes 25k --ks 50 --runs 1
    bench/eigs_grid.py --render-only --out results.jsonl --table table.md
"""
import argparse
import datetime
import json
import os
import platform
import re
import shlex
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# Built-in shapes for the three sizes (`spectral-mesh shapes`): the smooth genus-2 surface,
# sampled irregularly (coarse on -x, three levels finer on +x: triangle areas vary ~100x).
SIZE_SPECS = {
    "25k": "irregular-double-torus:res=4",  # 25 782 vertices
    "100k": "irregular-double-torus:res=5",  # 103 160 vertices
    "400k": "irregular-double-torus:res=6",  # 411 010 vertices
    # Loop subdivisions of a shared mesh (bench/loop_mesh.py, needs NumPy: --python):
    # fandisk's 6,475 vertices at levels 1-4.
    "26k": "loop:fandisk.off:1",  # 25 894 vertices
    "104k": "loop:fandisk.off:2",  # 103 570 vertices
    "416k": "loop:fandisk.off:3",  # 414 274 vertices
    "1.66m": "loop:fandisk.off:4",  # 1 657 090 vertices
}

# Where `loop:NAME:LEVEL` finds NAME: ../shared/meshes beside the clone, or this variable.
SHARED_MESHES = Path(os.environ.get("SPECTRAL_MESH_SHARED_MESHES",
                                    str(ROOT.parent / "shared" / "meshes")))

ROUTES = ("ours", "superlu", "cholmod")
ROUTE_TITLES = {"ours": "ours", "superlu": "SciPy SuperLU", "cholmod": "SciPy CHOLMOD"}
REQUIRED_KEYS = ("n", "k", "seconds", "max_residual", "lambda_k", "peak_rss_mib")
KEY_VALUE = re.compile(r"(\w+)=(\S+)")


# ---------------------------------------------------------------------------------- meshes

def mesh_file_name(spec):
    return re.sub(r"[^A-Za-z0-9_.=-]+", "_", spec) + ".off"


def resolve_mesh(entry, mesh_dir, cli, python=None):
    """Returns (label, path) for a file path, a size label (25k) or a built-in shape spec.
    Shapes are written once to mesh_dir as OFF with the CLI and reused afterwards;
    `loop:NAME:LEVEL` (a shared mesh Loop-subdivided LEVEL times) with `python`, which
    must have NumPy."""
    spec = SIZE_SPECS.get(entry, entry)
    path = Path(spec)
    if path.is_file():
        return path.name, path.resolve()
    out = mesh_dir / mesh_file_name(spec)
    if spec.startswith("loop:") and not out.is_file():
        _, name, level = spec.split(":")
        if python is None:
            raise SystemExit(f"{spec}: a Loop subdivision needs --python (with NumPy)")
        mesh_dir.mkdir(parents=True, exist_ok=True)
        print(f"building {spec} -> {out}", file=sys.stderr)
        subprocess.run([str(python), str(ROOT / "bench" / "loop_mesh.py"),
                        str(SHARED_MESHES / name), level, str(out)], check=True)
    if not out.is_file():
        if cli is None:
            raise SystemExit(f"{spec}: not a file, and no --cli to build it as a shape")
        mesh_dir.mkdir(parents=True, exist_ok=True)
        tmp = out.with_suffix(".tmp.off")
        print(f"building {spec} -> {out}", file=sys.stderr)
        r = subprocess.run([str(cli), "convert", spec, str(tmp), "--force"],
                           capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f"{spec}: neither a file nor a buildable shape:\n{r.stderr}")
        tmp.rename(out)
    return spec, out


def off_vertex_count(path):
    with open(path) as f:
        for line in f:
            toks = line.split("#", 1)[0].split()
            if not toks:
                continue
            if toks[0].upper().endswith("OFF"):
                toks = toks[1:]
                if not toks:
                    continue
            return int(toks[0])
    return None


# ------------------------------------------------------------------------------------ runs

def loadavg():
    try:
        return Path("/proc/loadavg").read_text().split()[:3]
    except OSError:
        return None


def route_command(route, mesh, k, a):
    if route == "ours":
        cmd = [str(a.bench_eigs), str(mesh), str(k), a.laplacian]
        if a.tol is not None:
            cmd += ["--tol", repr(a.tol)]
        return cmd
    cmd = [str(a.python), str(ROOT / "bench" / "eigs_scipy.py"), str(mesh), str(k),
           "--mass", a.laplacian, "--tol", repr(a.scipy_tol)]
    if route == "cholmod":
        cmd.append("--cholmod")
    return cmd


def run_once(cmd, timeout):
    """Runs cmd in its own process group. Returns (status, exit_code, stdout, stderr,
    wall_seconds, maxrss_mib) with status 'ok', 'failed' or 'timeout'. The peak RSS comes
    from wait4, the same measure for every route (the runs print their own as well)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        t0 = time.monotonic()
        try:
            proc = subprocess.Popen(cmd, stdout=out, stderr=err, start_new_session=True)
        except OSError as e:
            return "failed", None, "", str(e), 0.0, None
        status = "ok"
        try:
            while True:
                pid, wstatus, rusage = os.wait4(proc.pid, os.WNOHANG)
                if pid:
                    break
                if time.monotonic() - t0 > timeout:
                    status = "timeout"
                    os.killpg(proc.pid, signal.SIGKILL)
                    _, wstatus, rusage = os.wait4(proc.pid, 0)
                    break
                time.sleep(0.05)
        except BaseException:  # Ctrl-C or SIGTERM of the driver: leave no run behind
            os.killpg(proc.pid, signal.SIGKILL)
            os.wait4(proc.pid, 0)
            raise
        code = os.waitstatus_to_exitcode(wstatus)
        proc.returncode = code  # reaped by wait4 above
        wall = time.monotonic() - t0
        out.seek(0)
        err.seek(0)
        maxrss = rusage.ru_maxrss / 1024.0
        return status, code, out.read(), err.read(), wall, maxrss


def run_once_with_env(cmd, timeout, env):
    """As run_once, with the variables of env set in this process's environment for the
    run (the run inherits them) and restored afterwards."""
    saved = {key: os.environ.get(key) for key in env}
    os.environ.update(env)
    try:
        return run_once(cmd, timeout)
    finally:
        for key, value in saved.items():
            if value is None:
                del os.environ[key]
            else:
                os.environ[key] = value


def failure(status, code, stderr, timeout):
    """(status, reason) of a finished run: reason None for a run that succeeded, else the
    timeout or the exit code with the last line of stderr (status becomes 'failed')."""
    if status == "timeout":
        return status, f"killed after {timeout:g} s"
    if code != 0:
        last = stderr.strip().splitlines()[-1:] or [""]
        return "failed", f"exit code {code}" + (f": {last[0][:200]}" if last[0] else "")
    return status, None


def parse_line(stdout):
    """The last line with key=value pairs, numbers converted."""
    lines = [ln for ln in stdout.splitlines() if "=" in ln]
    if not lines:
        return {}
    keys = {}
    for key, value in KEY_VALUE.findall(lines[-1]):
        try:
            keys[key] = int(value)
        except ValueError:
            try:
                keys[key] = float(value)
            except ValueError:
                keys[key] = value
    return keys


def measure(route, label, mesh, vertices, k, run, a):
    cmd = route_command(route, mesh, k, a)
    before = loadavg()
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    status, code, stdout, stderr, wall, maxrss = run_once(cmd, a.timeout)
    keys = parse_line(stdout) if status == "ok" else {}
    status, reason = failure(status, code, stderr, a.timeout)
    if status == "ok":
        missing = [key for key in REQUIRED_KEYS if key not in keys]
        if missing:
            status, reason = "failed", f"missing keys {', '.join(missing)}"
    record = {
        "time": started, "mesh": label, "mesh_path": str(mesh), "vertices": vertices,
        "k": k, "route": route, "run": run, "status": status, "reason": reason,
        "exit_code": code, "timeout_seconds": a.timeout, "laplacian": a.laplacian,
        "tol": a.tol, "scipy_tol": a.scipy_tol, "keys": keys,
    }
    return save_record(a, record, (cmd, wall, maxrss, before), (stdout, stderr),
                       f"{keys.get('seconds')} s")


def save_record(a, record, run, output, shown):
    """Completes record with run = (cmd, wall seconds, peak RSS, load before), adds the
    tails of output = (stdout, stderr) when the run failed, appends it to --out and prints
    one line: shown for a run that succeeded, the status and reason otherwise."""
    cmd, wall, maxrss, before = run
    record.update({
        "wall_seconds": round(wall, 3),
        "wait4_maxrss_mib": round(maxrss, 1) if maxrss is not None else None,
        "loadavg_before": before, "loadavg_after": loadavg(), "command": shlex.join(cmd),
    })
    status = record["status"]
    if status != "ok":
        record["stdout_tail"] = output[0][-2000:]
        record["stderr_tail"] = output[1][-2000:]
    with open(a.out, "a") as f:
        f.write(json.dumps(record) + "\n")
    if status != "ok":
        shown = f"{status} ({record['reason']})"
    print(f"[{record['time']}] load {' '.join(before or [])} | {record['mesh']} "
          f"k={record['k']} {record['route']} run {record['run']}: {shown}", file=sys.stderr)
    return record


def run_cell(label, mesh, vertices, k, a, measure=None, runs=None, seconds=None):
    """All runs of one cell, alternating routes. A route stops after a timeout or a
    failure, and after its first run when that took longer than --slow-seconds.
    measure, runs and seconds (a record's time) default to this grid's; e2e_grid passes
    its own."""
    measure = measure or globals()["measure"]
    seconds = seconds or (lambda rec: rec["keys"]["seconds"])
    records = []
    active = list(a.routes)
    for run in range(1, (runs or a.runs) + 1):
        for route in list(active):
            rec = measure(route, label, mesh, vertices, k, run, a)
            records.append(rec)
            slow = rec["status"] == "ok" and seconds(rec) > a.slow_seconds
            if rec["status"] != "ok" or slow:
                active.remove(route)
        if not active:
            break
    return records


# ----------------------------------------------------------------------------------- table

def fmt_seconds(x):
    return f"{x:.2f}" if x < 10 else f"{x:.1f}" if x < 1000 else f"{x:.0f}"


class Cell:
    """The runs of one route in one (mesh, k) cell."""

    def __init__(self, records):
        self.ok = [r["keys"] for r in records if r["status"] == "ok"]
        self.timeouts = [r for r in records if r["status"] == "timeout"]
        self.failed = [r for r in records if r["status"] == "failed"]
        self.timeout_limit = max((r["timeout_seconds"] for r in self.timeouts), default=None)
        self.median = statistics.median(k["seconds"] for k in self.ok) if self.ok else None

    def time_text(self):
        if self.ok:
            secs = [k["seconds"] for k in self.ok]
            text = fmt_seconds(self.median)
            if len(secs) > 1:
                text += f" [{fmt_seconds(min(secs))}, {fmt_seconds(max(secs))}]"
            text += f" ({len(secs)})"
            if self.timeouts:
                text += " + timeout"
            elif self.failed:
                text += " + failed"
            return text
        if self.timeouts:
            return f"> {self.timeout_limit:g} s (timeout)"
        return "failed" if self.failed else "-"

    def rss_text(self):
        if not self.ok:
            return "-"
        return f"{max(k['peak_rss_mib'] for k in self.ok):.0f}"

    def residual_text(self):
        if not self.ok:
            return "-"
        return f"{max(k['max_residual'] for k in self.ok):.1e}"

    def lambda_k(self):
        return statistics.median(k["lambda_k"] for k in self.ok) if self.ok else None

    def n(self):
        return self.ok[0]["n"] if self.ok else None


def ratio_format(x):
    return f"{x:.2f}" if x < 10 else f"{x:.1f}"


def ratio_text(cells, routes):
    ours = cells.get("ours")
    scipy = [cells[r] for r in routes if r != "ours" and r in cells]
    if not ours or not scipy:
        return "-"
    done = [c.median for c in scipy if c.median is not None]
    if ours.median is not None and done:
        return f"**{ratio_format(min(done) / ours.median)}x**"
    if ours.median is not None and all(c.timeout_limit for c in scipy):
        return f"> {ratio_format(min(c.timeout_limit for c in scipy) / ours.median)}x"
    if ours.median is None and ours.timeout_limit and done:
        return f"< {ratio_format(min(done) / ours.timeout_limit)}x"
    return "-"


def lambda_text(cells):
    values = [c.lambda_k() for c in cells.values() if c.lambda_k() is not None]
    if len(values) < 2:
        return "-"
    diff = max(abs(x - y) / max(abs(x), abs(y), 1e-300) for x in values for y in values)
    return f"{diff:.1e} {'yes' if diff <= 1e-8 else 'NO'}"


def machine_text():
    model = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = ""
    try:
        kib = int(Path("/proc/meminfo").read_text().split()[1])
        mem = f", {kib / 2**20:.0f} GiB memory"
    except (OSError, ValueError, IndexError):
        pass
    return f"{os.cpu_count()} CPUs (nproc {len(os.sched_getaffinity(0))}), {model}{mem}, " \
           f"{platform.system()} {platform.release()}"


def git_text():
    try:
        rev = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain",
                                "--untracked-files=no"],
                               capture_output=True, text=True).stdout.strip()
        return rev + (" (with uncommitted changes)" if dirty else "") if rev else "unknown"
    except OSError:
        return "unknown"


def render_table(records, a, command):
    routes = [r for r in ROUTES if any(rec["route"] == r for rec in records)]
    cells = {}
    for rec in records:
        cells.setdefault((rec["mesh"], rec["k"]), {}).setdefault(rec["route"], []).append(rec)
    def values(key):  # the settings the runs were made with (--render-only: not a's)
        seen = {str(rec.get(key, getattr(a, key))) for rec in records}
        return " / ".join(sorted(seen)) if seen else str(getattr(a, key))

    lines = table_head(
        records, "# Eigensolver benchmark: ours vs SciPy eigsh (shift-invert)", command,
        f"Laplacian: {values('laplacian')}; tolerance: ours "
        f"{values('tol').replace('None', 'default (1e-10)')}, SciPy eigsh tol={values('scipy_tol')}")
    lines += [
        "- times: seconds of the eigensolve (factorization included, assembly and mesh "
        "reading excluded), median [min, max] (number of runs); peak RSS in MiB (whole "
        "process); residual = max over pairs of ||Sx - lambda Bx|| / ((||S||_1 + |lambda| "
        "||B||_1) ||x||); lambda_k agreement = largest relative difference across routes.",
        "",
    ]
    head = ["mesh", "n", "k"] + [f"{ROUTE_TITLES[r]} (s)" for r in routes]
    if "ours" in routes and len(routes) > 1:
        head.append("fastest SciPy / ours")
    head += [f"peak RSS {ROUTE_TITLES[r]}" for r in routes]
    head += [f"residual {ROUTE_TITLES[r]}" for r in routes]
    if len(routes) > 1:
        head.append("lambda_k agrees")
    lines.append("| " + " | ".join(head) + " |")
    lines.append("| " + " | ".join(["---"] + ["---:"] * (len(head) - 1)) + " |")
    for (mesh, k), by_route in cells.items():
        c = {r: Cell(by_route.get(r, [])) for r in routes}
        n = next((x.n() for x in c.values() if x.n() is not None), None)
        if n is None:  # no run finished: the vertex count of the file
            n = next(rec.get("vertices") for recs in by_route.values() for rec in recs)
        row = [f"`{mesh}`", str(n), str(k)] + [c[r].time_text() for r in routes]
        if "ours" in routes and len(routes) > 1:
            row.append(ratio_text(c, routes))
        row += [c[r].rss_text() for r in routes]
        row += [c[r].residual_text() for r in routes]
        if len(routes) > 1:
            row.append(lambda_text(c))
        lines.append("| " + " | ".join(row) + " |")
    return table_end(lines, records)


def table_head(records, title, command, settings):
    """The table's title and its lines on the command, machine, commit + settings and the
    runs' times and load."""
    loads = [float(rec["loadavg_before"][0]) for rec in records if rec.get("loadavg_before")]
    times = [rec["time"] for rec in records]
    lines = [
        title,
        "",
        f"- command: `{command}`",
        f"- machine: {machine_text()}",
        f"- commit: {git_text()}; {settings}",
    ]
    if times:
        lines.append(f"- runs: {min(times)} to {max(times)}, {len(records)} processes; "
                     f"1-min load average before a run: {min(loads):.2f} to {max(loads):.2f}")
    return lines


def table_end(lines, records):
    """The table's text: lines, then the runs that did not finish."""
    reasons = sorted({f"{rec['mesh']} k={rec['k']} {rec['route']}: {rec['status']} "
                      f"({rec['reason']})" for rec in records if rec["status"] != "ok"})
    if reasons:
        lines += ["", "Runs that did not finish (details in the JSONL):", ""]
        lines += [f"- {r}" for r in reasons]
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------------------------ main

def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="25k,100k,400k",
                    help="comma list of sizes (" + ", ".join(
                        f"{s}: {v}" for s, v in SIZE_SPECS.items())
                    + ") or shape specs; empty for none")
    ap.add_argument("--mesh", action="append", default=[],
                    help="extra mesh: an OFF file or a shape spec (repeatable)")
    ap.add_argument("--ks", default="50,200,500")
    ap.add_argument("--runs", type=int, default=3, help="runs per route and cell")
    ap.add_argument("--routes", default=",".join(ROUTES))
    ap.add_argument("--laplacian", default="fem", choices=["fem", "voronoi-cot", "cot"])
    ap.add_argument("--timeout", type=float, default=3600.0,
                    help="seconds per run; a timed-out route is not run again in its cell")
    ap.add_argument("--slow-seconds", type=float, default=300.0,
                    help="a route whose run took longer than this is run only once "
                         "in its cell (e.g. SciPy at 400k, k = 500)")
    ap.add_argument("--tol", type=float, default=None,
                    help="our residual tolerance (bench_eigs --tol); default its own")
    ap.add_argument("--scipy-tol", type=float, default=0.0,
                    help="eigsh tol (0 = machine precision, SciPy's default)")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "eigs_grid.jsonl",
                    help="JSONL of every run (appended)")
    ap.add_argument("--table", type=Path, default=ROOT / "bench" / "results" / "eigs_grid.md",
                    help="markdown table (rewritten)")
    ap.add_argument("--bench-eigs", type=Path, help="the bench_eigs binary")
    ap.add_argument("--python", type=Path, help="python of the bench venv")
    ap.add_argument("--cli", type=Path, help="the spectral-mesh binary (builds shapes)")
    ap.add_argument("--mesh-dir", type=Path, default=ROOT / "bench" / "meshes")
    ap.add_argument("--render-only", action="store_true",
                    help="rewrite --table from all records in --out, run nothing")
    a = parse_lists(ap, argv, ROUTES)
    if not a.render_only:
        if "ours" in a.routes and not (a.bench_eigs and a.bench_eigs.is_file()):
            ap.error("--bench-eigs: the bench_eigs binary is needed for route 'ours'")
        if set(a.routes) - {"ours"} and not (a.python and a.python.is_file()):
            ap.error("--python: the bench venv's python is needed for the SciPy routes")
    return a


def parse_lists(ap, argv, routes):
    """Parses argv with ap and splits --routes (checked against routes) and --ks."""
    a = ap.parse_args(argv)
    a.routes = [r for r in a.routes.split(",") if r]
    unknown = [r for r in a.routes if r not in routes]
    if unknown:
        ap.error(f"unknown routes {unknown}; known: {', '.join(routes)}")
    a.ks = [int(k) for k in a.ks.split(",") if k]
    return a


def grid_main(argv, script, parse_args, render_table, run_cell, show_meshes=False):
    """A grid's main: parse argv, then rewrite the table from --out (--render-only) or run
    every (mesh, k) cell, rewriting the table after each. The command shown in the table is
    $<SCRIPT>_COMMAND (e.g. EIGS_GRID_COMMAND) when set, else bench/<script>.py ARGS."""
    argv = sys.argv[1:] if argv is None else argv
    a = parse_args(argv)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    command = os.environ.get(f"{script.upper()}_COMMAND") or shlex.join(
        [f"bench/{script}.py"] + argv)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.table.parent.mkdir(parents=True, exist_ok=True)
    if a.render_only:
        records = [json.loads(ln) for ln in a.out.read_text().splitlines() if ln.strip()]
        a.table.write_text(render_table(records, a, command))
        print(a.table.read_text())
        return 0

    entries = [s for s in a.sizes.split(",") if s] + a.mesh
    meshes = [resolve_mesh(e, a.mesh_dir, a.cli, a.python) for e in entries]
    meshes = [(label, path, off_vertex_count(path)) for label, path in meshes]
    if show_meshes:
        for label, path, vertices in meshes:
            print(f"mesh {label}: {path} ({vertices} vertices)", file=sys.stderr)
    records = []
    for label, path, vertices in meshes:
        for k in a.ks:
            records += run_cell(label, path, vertices, k, a)
            a.table.write_text(render_table(records, a, command))
    table = render_table(records, a, command)
    a.table.write_text(table)
    print(table)
    print(f"raw runs appended to {a.out}; table in {a.table}", file=sys.stderr)
    return 0


def main(argv=None):
    return grid_main(argv, "eigs_grid", parse_args, render_table, run_cell, show_meshes=True)


if __name__ == "__main__":
    sys.exit(main())
