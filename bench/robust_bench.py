#!/usr/bin/env python3
"""Robust Laplacian assembly, ours against robust_laplacian, whole process.

For each size (irregular-double-torus at res 4, 5, 6: 25 782, 103 160 and 411 010
vertices), two inputs are written once to bench/meshes/ (git-ignored): the mesh (OFF) and
its vertices alone as a point cloud (x y z text). Each run is one process that reads the
file, assembles (S, B) and writes nothing:

  ours:  target/release/examples/robust_assembly FILE      (Rust, mimalloc)
  peer:  python bench/robust_peer.py FILE                   (robust_laplacian 1.1.0)

Runs alternate (ours, peer, ours, ...). Wall time and peak resident memory (ru_maxrss of
the child, via wait4) per run; medians printed as a Markdown table with the load average
before and after each cell.

  python bench/robust_bench.py --cli target/release/spectral-mesh \
      --ours target/release/examples/robust_assembly [--sizes 25k,100k,400k] [--runs 3]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SIZES = {"25k": "irregular-double-torus:res=4", "100k": "irregular-double-torus:res=5",
         "400k": "irregular-double-torus:res=6"}


def run(cmd):
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    out = p.stdout.read().decode()
    err = p.stderr.read().decode()
    if status != 0:
        raise RuntimeError(f"{cmd}: exit {status}: {err[-500:]}")
    rec = json.loads(out.strip().splitlines()[-1])
    rec["wall_s"] = wall
    rec["rss_mib"] = usage.ru_maxrss / 1024.0
    return rec


def prepare(cli, label, spec, folder):
    mesh = os.path.join(folder, f"robust-{label}.off")
    pts = os.path.join(folder, f"robust-{label}.xyz")
    if not os.path.exists(mesh):
        subprocess.run([cli, "convert", spec, mesh, "--force"], check=True, capture_output=True)
    if not os.path.exists(pts):
        with open(mesh) as f:
            f.readline()
            nv = int(f.readline().split()[0])
            with open(pts + ".tmp", "w") as g:
                for _ in range(nv):
                    g.write(f.readline())
        os.replace(pts + ".tmp", pts)
    return mesh, pts


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=os.path.join(ROOT, "target/release/spectral-mesh"))
    ap.add_argument("--ours", default=os.path.join(ROOT, "target/release/examples/robust_assembly"))
    ap.add_argument("--python", default=sys.executable)
    ap.add_argument("--sizes", default="25k,100k,400k")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench/results/robust.jsonl"))
    a = ap.parse_args()
    folder = os.path.join(ROOT, "bench/meshes")
    os.makedirs(folder, exist_ok=True)
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    peer = [a.python, os.path.join(ROOT, "bench/robust_peer.py")]
    rows = []
    for label in a.sizes.split(","):
        mesh, pts = prepare(a.cli, label, SIZES[label], folder)
        for kind, path in (("mesh", mesh), ("points", pts)):
            load0 = os.getloadavg()[0]
            recs = {"ours": [], "peer": []}
            for _ in range(a.runs):
                recs["ours"].append(run([a.ours, path]))
                recs["peer"].append(run(peer + [path]))
            load1 = os.getloadavg()[0]
            with open(a.out, "a") as f:
                for who, rs in recs.items():
                    for r in rs:
                        f.write(json.dumps({"size": label, "input": kind, "who": who, "load": [load0, load1], **r}) + "\n")
            med = {w: {k: statistics.median(r[k] for r in rs) for k in ("wall_s", "rss_mib", "assembly_s", "read_s", "mass")} for w, rs in recs.items()}
            n = recs["ours"][0]["n"]
            rows.append((label, kind, n, med, load0, load1))
            print(f"{label} {kind} n={n}: ours {med['ours']['wall_s']:.2f} s {med['ours']['rss_mib']:.0f} MiB, "
                  f"peer {med['peer']['wall_s']:.2f} s {med['peer']['rss_mib']:.0f} MiB (load {load0:.1f}-{load1:.1f})",
                  file=sys.stderr, flush=True)
    print("| input | n | ours: whole (assembly) | ours: peak | robust_laplacian: whole (assembly) | robust_laplacian: peak | whole-time ratio | mass ours / peer | load |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
    for label, kind, n, med, l0, l1 in rows:
        o, p = med["ours"], med["peer"]
        print(f"| {kind} {label} | {n:,} | {o['wall_s']:.2f} s ({o['assembly_s']:.2f}) | {o['rss_mib']:.0f} MiB | "
              f"{p['wall_s']:.2f} s ({p['assembly_s']:.2f}) | {p['rss_mib']:.0f} MiB | {p['wall_s'] / o['wall_s']:.1f}x | "
              f"{o['mass']:.5g} / {p['mass']:.5g} | {l0:.1f}-{l1:.1f} |")


if __name__ == "__main__":
    main()
