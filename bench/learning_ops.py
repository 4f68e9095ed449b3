"""The learning operators (DiffusionNet's `get_operators`) of a collection of meshes: ours
(`spectral_mesh.learning.get_operators`) or DiffusionNet's steps in SciPy
(`conformance/diffusionnet_scipy.py`), one process for the whole collection, so that
`/usr/bin/time -v` gives the whole run and its peak memory.

    python bench/learning_ops.py make DIR            # writes the 100 benchmark meshes
    python bench/learning_ops.py ours K DIR/*.off
    python conformance/diffusionnet_scipy.py K DIR/*.off

The collection: 100 built-in shapes (spheres, tori, irregular tori, double tori, disks,
3-tori at several resolutions and radii), 2k to 10k vertices, written as OFF.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import spectral_mesh as sm
from spectral_mesh import learning

SPECS = (
    [f"sphere:res={r}" for r in (4, 5)]
    + [f"torus:res={r},R=1,r={t}" for r in (4, 5) for t in (0.2, 0.3, 0.4, 0.5)]
    + [f"irregular-torus:res={r}" for r in (4, 5)]
    + [f"disk:res={r}" for r in (3, 4)]
    + ["3torus", "double-torus"]
)


def make(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    count = 0
    i = 0
    while count < 100:
        spec = SPECS[i % len(SPECS)]
        # Each pass over the list scales the shape a little: distinct meshes (and hashes).
        V, F = sm.shape(spec)
        V = V * (1.0 + 0.01 * (i // len(SPECS)))
        if 1500 <= len(V) <= 12000:
            sm.write_mesh(out / f"{count:03d}.off", V, F)
            count += 1
        i += 1
        if i > 2000:
            raise SystemExit("not enough shapes in the size range")


def ours(k: int, paths: list[str]) -> None:
    t0 = time.perf_counter()
    for path in paths:
        t = time.perf_counter()
        V, F = sm.read_mesh(path)
        ops = learning.get_operators(V, F, k_eig=k)
        print(f"{path}: n = {len(V)}, {time.perf_counter() - t:.3f} s, lambda_1 = {ops[3][1]:.6g}")
    print(f"total {time.perf_counter() - t0:.2f} s for {len(paths)} meshes")


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(Path(sys.argv[2]))
    else:
        ours(int(sys.argv[2]), sys.argv[3:])
