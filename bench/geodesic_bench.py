#!/usr/bin/env python3
"""Heat-method geodesics, whole process: our CLI against potpourri3d's and libigl's solvers.

  python bench/geodesic_bench.py --cli target/release/spectral-mesh --python .venv/bin/python \
      --mesh fandisk.off [--levels 1,2,3] [--runs 3] [--sources 100]

Inputs: Loop subdivisions of MESH (levels 1, 2 and 3 of fandisk's 6,475 vertices: 25,894,
103,570 and 414,274 vertices), written once to bench/meshes/geodesic-NAME-L*.off
(git-ignored). For each input, each Laplacian pair and each task (one source; SOURCES
sources each on its own), ours and the peers run in turn RUNS times as whole processes:

- ours: `spectral-mesh geodesic FILE --laplacian L --source 0 -o d.npy` (one source) or
  `... --each --source 0 --source s1 ... -o d.npy` (many: block right-hand sides);
- peers: bench/geodesic_peer.py FILE OUT --peer potpourri3d|libigl (the peer's own mesh
  reader, its solver with t = h^2, one solve per source, np.save).

Pairs: `voronoi-cot` against potpourri3d `use_robust=False` and libigl (cotangent Laplacian);
`robust` against potpourri3d `use_robust=True` and libigl `use_intrinsic_delaunay=True`.
Wall time and the child's peak RSS (ru_maxrss) per run; medians are printed as a Markdown
table and every run is appended to bench/results/geodesic.jsonl with the load average.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_off(path):
    with open(path) as f:
        tokens = [t for line in f for t in line.split("#", 1)[0].split()]
    assert tokens[0] in ("OFF", "COFF")
    nv, nf = int(tokens[1]), int(tokens[2])
    V = np.array(tokens[4 : 4 + 3 * nv], dtype=np.float64).reshape(nv, 3)
    F = np.array(tokens[4 + 3 * nv : 4 + 3 * nv + 4 * nf], dtype=np.int64).reshape(nf, 4)
    assert (F[:, 0] == 3).all()
    return V, F[:, 1:].copy()


def write_off(path, V, F):
    with open(path, "w") as f:
        f.write(f"OFF\n{len(V)} {len(F)} 0\n")
        np.savetxt(f, V, fmt="%.17g")
        np.savetxt(f, np.hstack([np.full((len(F), 1), 3), F]), fmt="%d")


def loop_subdivide(V, F):
    """One step of Loop subdivision (boundary edges: midpoints; boundary vertices kept)."""
    n = len(V)
    he = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    opp = np.concatenate([F[:, 2], F[:, 0], F[:, 1]])
    key = np.sort(he, axis=1)
    uniq, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    ne = len(uniq)
    opp_sum = np.zeros((ne, 3))
    np.add.at(opp_sum, inv, V[opp])
    a, b = uniq[:, 0], uniq[:, 1]
    interior = counts[:, None] == 2
    E = np.where(interior, 3 / 8 * (V[a] + V[b]) + 1 / 8 * opp_sum, 0.5 * (V[a] + V[b]))
    # Vertex update.
    nbr_sum = np.zeros_like(V)
    deg = np.zeros(n)
    np.add.at(nbr_sum, a, V[b])
    np.add.at(nbr_sum, b, V[a])
    np.add.at(deg, a, 1)
    np.add.at(deg, b, 1)
    on_boundary = np.zeros(n, dtype=bool)
    on_boundary[a[counts == 1]] = True
    on_boundary[b[counts == 1]] = True
    beta = np.where(deg == 3, 3 / 16, 3 / (8 * np.maximum(deg, 1)))
    Vn = (1 - deg * beta)[:, None] * V + beta[:, None] * nbr_sum
    Vn[on_boundary] = V[on_boundary]
    Vn[deg == 0] = V[deg == 0]
    m = len(F)
    e = inv.reshape(3, m).T + n  # edges (01, 12, 20) of each triangle
    v0, v1, v2 = F[:, 0], F[:, 1], F[:, 2]
    e01, e12, e20 = e[:, 0], e[:, 1], e[:, 2]
    Fn = np.concatenate([
        np.stack([v0, e01, e20], 1),
        np.stack([v1, e12, e01], 1),
        np.stack([v2, e20, e12], 1),
        np.stack([e01, e12, e20], 1),
    ])
    return np.vstack([Vn, E]), Fn


def run(cmd):
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    out = proc.stdout.read()
    err = proc.stderr.read()
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(cmd[:3])}...: {err.strip()}")
    return wall, usage.ru_maxrss / 1024.0, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--python", required=True)
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--levels", default="1,2,3")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--sources", type=int, default=100)
    ap.add_argument("--laplacians", default="voronoi-cot,robust")
    ap.add_argument("--peers", default="potpourri3d,libigl")
    a = ap.parse_args()
    os.makedirs(os.path.join(HERE, "meshes"), exist_ok=True)
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    log = open(os.path.join(HERE, "results", "geodesic.jsonl"), "a")
    V, F = read_off(a.mesh)
    inputs = []
    for level in [int(x) for x in a.levels.split(",")]:
        path = os.path.join(HERE, "meshes", f"geodesic-{os.path.basename(a.mesh)[:-4]}-L{level}.off")
        if not os.path.exists(path):
            Vl, Fl = V, F
            for _ in range(level):
                Vl, Fl = loop_subdivide(Vl, Fl)
            write_off(path, Vl, Fl)
        with open(path) as f:
            f.readline()
            nv = int(f.readline().split()[0])
        inputs.append((path, nv))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "d.npy")
        for path, nv in inputs:
            rng = np.random.default_rng(0)
            many = [0] + [int(x) for x in rng.choice(np.arange(1, nv), a.sources - 1, replace=False)]
            for lap in a.laplacians.split(","):
                robust = lap == "robust"
                for task, srcs in [("1 source", [0]), (f"{a.sources} sources", many)]:
                    ours_cmd = [a.cli, "geodesic", path, "--laplacian", lap, "-o", out, "--force"]
                    if len(srcs) > 1:
                        ours_cmd.append("--each")
                    for s in srcs:
                        ours_cmd += ["--source", str(s)]
                    cmds = [("ours", ours_cmd)]
                    for peer in a.peers.split(","):
                        cmds.append((peer, [a.python, os.path.join(HERE, "geodesic_peer.py"), path, out,
                                            "--peer", peer] + (["--robust"] if robust else [])
                                     + ["--sources", ",".join(map(str, srcs))]))
                    res = {who: [] for who, _ in cmds}
                    for r in range(a.runs):
                        for who, cmd in cmds:
                            wall, peak, text = run(cmd)
                            res[who].append((wall, peak))
                            rec = {"input": os.path.basename(path), "n": nv, "laplacian": lap, "task": task,
                                   "who": who, "wall_s": wall, "peak_mib": peak,
                                   "load": os.getloadavg()[0], "stdout": text.strip()[-400:]}
                            log.write(json.dumps(rec) + "\n")
                            log.flush()
                            print(f"{os.path.basename(path)} {lap} {task} {who}: {wall:.2f} s, {peak:.0f} MiB", flush=True)
                    med = {w: (statistics.median(x[0] for x in v), max(x[1] for x in v)) for w, v in res.items()}
                    rows.append((nv, lap, task, med, os.getloadavg()[0]))
    print("\n| n | Laplacian | task | who | whole (median) | peak | peer / ours | load |")
    print("| ---: | --- | --- | --- | ---: | ---: | ---: | ---: |")
    for nv, lap, task, med, load in rows:
        for who, (wall, peak) in med.items():
            ratio = "" if who == "ours" else f"{wall / med['ours'][0]:.1f}x"
            print(f"| {nv:,} | {lap} | {task} | {who} | {wall:.2f} s | {peak:.0f} MiB | {ratio} | {load:.1f} |")


if __name__ == "__main__":
    sys.exit(main())
