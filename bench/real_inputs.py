#!/usr/bin/env python3
"""Every shared mesh, every shared point cloud and every generated case of issue 17 through
`eigs` and `distance` with each discretization that applies; prints a Markdown table.

    nice -n 19 python3 bench/real_inputs.py --cli target/release/spectral-mesh \
        --meshes ../shared/meshes --points ../shared/points -k 20 > table.md

Meshes take cot, voronoi-cot, fem, mixed-voronoi, uniform and robust; point clouds take
robust only (their point-cloud Laplacian). A row passes when both commands exit 0 with finite
eigenvalues and finite distances; a row whose count of zero eigenvalues differs from the
number of components (the `eigs` MISMATCH line) is flagged in its status. Standard library only; each run is bounded by --timeout.
"""

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SHARED = Path(__file__).resolve().parents[2] / "shared"  # ../shared beside the clone

MESH_LAPLACIANS = ["cot", "voronoi-cot", "fem", "mixed-voronoi", "uniform", "robust"]


def write_off(path, verts, tris):
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(verts), len(tris)))
        for v in verts:
            f.write("%.17g %.17g %.17g\n" % tuple(v))
        for t in tris:
            f.write("3 %d %d %d\n" % tuple(t))


def grid_sheet(verts, tris, edge_ids, angle, m):
    """A sheet of m x m quads hinged on the shared edge (the z axis from 0 to 1)."""
    ids = [edge_ids]
    for i in range(1, m + 1):
        r = i / m
        row = []
        for j in range(m + 1):
            verts.append((r * math.cos(angle), r * math.sin(angle), j / m))
            row.append(len(verts) - 1)
        ids.append(row)
    for i in range(m):
        for j in range(m):
            a, b, c, d = ids[i][j], ids[i + 1][j], ids[i + 1][j + 1], ids[i][j + 1]
            tris.append((a, b, c))
            tris.append((a, c, d))


def three_sheets(m=8):
    verts = [(0.0, 0.0, j / m) for j in range(m + 1)]
    edge = list(range(m + 1))
    tris = []
    for s in range(3):
        grid_sheet(verts, tris, edge, 2 * math.pi * s / 3, m)
    return verts, tris


def cone(verts, tris, apex, direction, m=24, rings=4):
    """A closed cone from the apex vertex `apex` along +-x: side rings and a base cap."""
    prev = None
    for r in range(1, rings + 1):
        ring = []
        for j in range(m):
            a = 2 * math.pi * j / m
            verts.append((direction * r / rings, 0.5 * r / rings * math.cos(a), 0.5 * r / rings * math.sin(a)))
            ring.append(len(verts) - 1)
        for j in range(m):
            k = (j + 1) % m
            if prev is None:
                tris.append((apex, ring[j], ring[k]))
            else:
                tris.append((prev[j], ring[j], ring[k]))
                tris.append((prev[j], ring[k], prev[k]))
        prev = ring
    verts.append((direction * 1.0, 0.0, 0.0))
    c = len(verts) - 1
    for j in range(m):
        tris.append((c, prev[(j + 1) % m], prev[j]))


def two_cones():
    verts = [(0.0, 0.0, 0.0)]
    tris = []
    cone(verts, tris, 0, 1.0)
    cone(verts, tris, 0, -1.0)
    return verts, tris


def uv_sphere(verts, tris, c, r, nu, nv):
    base = len(verts)
    verts.append((c[0], c[1] + r, c[2]))
    for i in range(1, nv):
        th = math.pi * i / nv
        for j in range(nu):
            ph = 2 * math.pi * j / nu
            verts.append((c[0] + r * math.sin(th) * math.cos(ph), c[1] + r * math.cos(th), c[2] + r * math.sin(th) * math.sin(ph)))
    verts.append((c[0], c[1] - r, c[2]))
    top, bottom = base, len(verts) - 1
    ring = lambda i, j: base + 1 + (i - 1) * nu + (j % nu)
    for j in range(nu):
        tris.append((top, ring(1, j + 1), ring(1, j)))
        tris.append((bottom, ring(nv - 1, j), ring(nv - 1, j + 1)))
    for i in range(1, nv - 1):
        for j in range(nu):
            a, b, cc, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
            tris.append((a, b, cc))
            tris.append((a, cc, d))


def tetrahedra_and_sphere(count=200):
    verts, tris = [], []
    uv_sphere(verts, tris, (0.0, 0.0, 0.0), 1.0, 32, 20)
    state = 12345
    for t in range(count):
        base = len(verts)
        state = (state * 6364136223846793005 + 1442695040888963407) % 2**64
        s = 0.02 + 0.03 * (state >> 11) / 2**53
        cx, cy, cz = 3 + (t % 10) * 0.2, (t // 10 % 10) * 0.2, (t // 100) * 0.2
        verts += [(cx, cy, cz), (cx + s, cy, cz), (cx, cy + s, cz), (cx, cy, cz + s)]
        tris += [(base, base + 2, base + 1), (base, base + 1, base + 3), (base, base + 3, base + 2), (base + 1, base + 2, base + 3)]
    return verts, tris


def torus(verts, tris, c, big=1.0, small=0.35, nu=32, nv=14):
    base = len(verts)
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            v = 2 * math.pi * j / nv
            verts.append((c[0] + (big + small * math.cos(v)) * math.cos(u), c[1] + small * math.sin(v), c[2] + (big + small * math.cos(v)) * math.sin(u)))
    idx = lambda i, j: base + (i % nu) * nv + (j % nv)
    for i in range(nu):
        for j in range(nv):
            tris.append((idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)))
            tris.append((idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)))


def two_tori():
    verts, tris = [], []
    torus(verts, tris, (0.0, 0.0, 0.0))
    torus(verts, tris, (3.5, 0.0, 0.0))
    return verts, tris


def fibonacci(n, c, r):
    g = math.pi * (3 - math.sqrt(5))
    out = []
    for i in range(n):
        y = 1 - 2 * (i + 0.5) / n
        s = math.sqrt(1 - y * y)
        out.append((c[0] + r * s * math.cos(g * i), c[1] + r * y, c[2] + r * s * math.sin(g * i)))
    return out


def generated(folder):
    """(name, path, ks) of the generated cases."""
    cases = []
    for name, (v, t), ks in [
        ("gen: three sheets sharing one edge", three_sheets(), [20]),
        ("gen: two cones touching at a vertex", two_cones(), [20]),
        ("gen: 200 tetrahedra + sphere", tetrahedra_and_sphere(), [20, 250, 400]),
        ("gen: two disjoint tori", two_tori(), [20]),
    ]:
        p = os.path.join(folder, re.sub(r"[^a-z0-9]+", "_", name[5:]) + ".off")
        write_off(p, v, t)
        cases.append((name, p, ks))
    p = os.path.join(folder, "two_point_spheres.xyz")
    with open(p, "w") as f:
        for q in fibonacci(2000, (0, 0, 0), 1.0) + fibonacci(1000, (3, 0, 0), 0.5):
            f.write("%.17g %.17g %.17g\n" % q)
    cases.append(("gen: two point-cloud spheres", p, [20]))
    return cases


def run(cmd, timeout):
    t0 = time.time()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        return r.returncode, r.stdout, r.stderr, time.time() - t0
    except subprocess.TimeoutExpired:
        return -1, "", "timeout after %d s" % timeout, time.time() - t0


def is_points(path):
    ext = os.path.splitext(path)[1].lower()
    if ext in (".xyz", ".pts", ".txt", ".csv"):
        return True
    if ext == ".ply":
        with open(path, "rb") as f:
            head = f.read(4096).split(b"end_header")[0]
        m = re.search(rb"element face (\d+)", head)
        return m is None or int(m.group(1)) == 0
    return False


def count(cli, path):
    """Vertices or points of `path`, from `info --json`."""
    import json
    code, out, err, _ = run([cli, "info", path, "--json"], 600)
    if code != 0:
        return None
    j = json.loads(out)
    return j.get("vertices", j.get("points"))


def row(cli, name, path, lap, k, tmp, timeout):
    ev = os.path.join(tmp, "ev.txt")
    d = os.path.join(tmp, "d.txt")
    code, out, err, te = run([cli, "eigs", path, "-k", str(k), "--laplacian", lap, "--eigenvalues-txt", ev, "-f"], timeout)
    n = re.search(r"n = (\d+)", out)
    zero = re.search(r"near-zero eigenvalues \([^)]*\): (\d+); expected (\d+)", out)
    problems = []
    notes = []
    if code != 0:
        problems.append("eigs: " + (err.strip().splitlines() or ["exit %d" % code])[-1][:120])
    elif zero is None or zero.group(1) != zero.group(2):
        notes.append("zero eigenvalues != components")
    lam = ""
    if code == 0 and os.path.exists(ev):
        vals = [float(x) for x in open(ev).read().split()]
        if not all(math.isfinite(v) for v in vals):
            problems.append("eigs: non-finite eigenvalue")
        lam = "%.4g" % vals[-1] if vals else ""
    code2, out2, err2, td = run([cli, "distance", path, "-k", str(k), "--laplacian", lap, "-o", d, "-f"], timeout)
    finite = ""
    all_zero = zero is not None and int(zero.group(1)) == k and int(zero.group(2)) >= k
    if code2 != 0 and all_zero and "no non-zero eigenvalue" in err2:
        # k <= components: every pair is a zero one and no filter applies; the refusal
        # (which says so) is the expected result.
        notes.append("distance refused as expected: all %d pairs are zero ones, k <= components" % k)
    elif code2 != 0:
        problems.append("distance: " + (err2.strip().splitlines() or ["exit %d" % code2])[-1][:120])
    else:
        vals = [float(x) for x in open(d).read().split()]
        ok = all(math.isfinite(v) for v in vals)
        finite = "yes" if ok else "NO"
        if not ok:
            problems.append("distance: non-finite values")
    return {
        "name": name,
        "n": n.group(1) if n else "?",
        "lap": lap,
        "k": k,
        "zeros": "%s/%s" % zero.groups() if zero else "-",
        "lam": lam,
        "te": te,
        "td": td,
        "finite": finite,
        "status": ("ok" if not problems else "FAIL: " + "; ".join(problems)) + "".join(" (%s)" % x for x in notes),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", required=True)
    ap.add_argument("--meshes", default=str(SHARED / "meshes"))
    ap.add_argument("--points", default=str(SHARED / "points"))
    ap.add_argument("-k", type=int, default=20)
    ap.add_argument("--timeout", type=int, default=900)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="real_inputs_")
    inputs = []
    for f in sorted(os.listdir(a.meshes)):
        if os.path.splitext(f)[1].lower() in (".off", ".obj", ".ply", ".stl"):
            inputs.append((f, os.path.join(a.meshes, f), [a.k]))
    for f in sorted(os.listdir(a.points)):
        if os.path.splitext(f)[1].lower() in (".xyz", ".pts", ".txt", ".csv", ".ply"):
            inputs.append((f, os.path.join(a.points, f), [a.k]))
    inputs += generated(tmp)
    rows = []
    for name, path, ks in inputs:
        laps = ["robust"] if is_points(path) else MESH_LAPLACIANS
        n = count(a.cli, path)
        # k as asked, or every pair of a mesh with fewer vertices.
        for k in sorted({min(k, n) if n else k for k in ks}):
            for lap in laps:
                r = row(a.cli, name, path, lap, k, tmp, a.timeout)
                r["kind"] = "points" if is_points(path) else "mesh"
                rows.append(r)
                print("%-40s %-14s k=%-4d %s" % (name, lap, k, r["status"]), file=sys.stderr, flush=True)
    fails = [r for r in rows if r["status"].startswith("FAIL")]
    odd = [r for r in rows if "zero eigenvalues != components" in r["status"]]
    refused = [r for r in rows if "refused as expected" in r["status"]]
    print("| input | kind | n | discretization | k | zero eigenvalues (found/expected: min(components, k)) | lambda_k | eigs s | distance s | distances finite | status |")
    print("| --- | --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | --- | --- |")
    for r in rows:
        print("| %s | %s | %s | %s | %d | %s | %s | %.2f | %.2f | %s | %s |" % (
            r["name"], r["kind"], r["n"], r["lap"], r["k"], r["zeros"], r["lam"], r["te"], r["td"], r["finite"], r["status"]))
    print()
    print("%d runs of eigs + distance, %d failed, %d with a zero-eigenvalue count that differs from the components, %d distances refused as expected (k <= components); load average at the end %s" % (len(rows), len(fails), len(odd), len(refused), " ".join(open("/proc/loadavg").read().split()[:3])))
    for p in os.listdir(tmp):
        os.remove(os.path.join(tmp, p))
    os.rmdir(tmp)
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
