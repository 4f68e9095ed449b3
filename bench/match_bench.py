#!/usr/bin/env python3
"""Whole-process benchmark of the matching pipeline: ours (`spectral-mesh match`) against
the pyFM quickstart script (bench/match_pyfm.py) on one pair, alternating runs, wall time
and peak memory from `/usr/bin/time -v`, and the mean geodesic error of both maps
(potpourri3d heat-method geodesics on mesh 1, units of sqrt(area)).

The pair: MESH subdivided once (midpoints) as mesh 1 and a copy of it with shuffled
vertices as mesh 2 (the true map is the shuffle). Usage:
match_bench.py --cli CLI --python PY [--runs 3] MESH
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "conformance"))
from match_pyfm import geodesic_error, read_off, shuffled, subdivided, write_off  # noqa: E402


def timed(cmd):
    r = subprocess.run(["/usr/bin/time", "-v"] + cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: {r.stderr[-2000:]}")
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", r.stderr)
    h, m, s = wall.groups()
    secs = (int(h) if h else 0) * 3600 + int(m) * 60 + float(s)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", r.stderr).group(1))
    return secs, rss / 1024


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--python", required=True)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("mesh")
    a = ap.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    with tempfile.TemporaryDirectory() as tmp:
        V, F = read_off(a.mesh)
        V1, F1 = subdivided(V, F)
        V2, F2, gt = shuffled(V1, F1, 7)
        p1, p2 = os.path.join(tmp, "mesh1.off"), os.path.join(tmp, "mesh2.off")
        write_off(p1, V1, F1)
        write_off(p2, V2, F2)
        print(f"pair: {os.path.basename(a.mesh)} subdivided ({len(V1)} vertices) and a shuffled copy")
        ours_cmd = [a.cli, "match", p2, p1, "-k", "30", "--zoomout", "100", "--step", "5",
                    "--subsample", "2", "--w-lap", "0.1", "--w-dcomm", "1", "--w-orient", "1",
                    "-o", os.path.join(tmp, "ours.txt"), "-f"]
        theirs_cmd = [a.python, os.path.join(here, "match_pyfm.py"), p1, p2, os.path.join(tmp, "pyfm.txt")]
        res = {"ours": [], "pyFM": []}
        for i in range(a.runs):
            for name, cmd in (("ours", ours_cmd), ("pyFM", theirs_cmd)):
                t, m = timed(cmd)
                res[name].append((t, m))
                print(f"run {i + 1} {name}: {t:.2f} s, peak {m:.0f} MiB", flush=True)
        for name, f in (("ours", "ours.txt"), ("pyFM", "pyfm.txt")):
            p2p = np.loadtxt(os.path.join(tmp, f), dtype=np.int64)
            print(f"{name}: mean geodesic error {geodesic_error(V1, F1, p2p, gt):.3e} sqrt(area)")
        med = {k: statistics.median(t for t, _ in v) for k, v in res.items()}
        mem = {k: max(m for _, m in v) for k, v in res.items()}
        print(f"median wall: ours {med['ours']:.2f} s, pyFM {med['pyFM']:.2f} s, ratio {med['pyFM'] / med['ours']:.1f}x")
        print(f"peak memory: ours {mem['ours']:.0f} MiB, pyFM {mem['pyFM']:.0f} MiB")


if __name__ == "__main__":
    main()
