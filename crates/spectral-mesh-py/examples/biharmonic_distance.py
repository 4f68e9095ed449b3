#!/usr/bin/env python3
"""The paper's bi-harmonic distance figure (Patane, Fig. 9 and the default
Spectral_distances experiment), drawn with matplotlib.

The bi-harmonic distance from a source point (the vertex of largest x) on the 3-torus,
with the paper's hue colour map and level sets, for several discretizations of the
Laplace-Beltrami operator (columns) and numbers k of eigenpairs (rows). The default
experiment of the executable paper is the top-left panel: linear FEM, k = 100.

    python biharmonic_distance.py                          # writes biharmonic-distance.png
    python biharmonic_distance.py --shape irregular-3torus --k 20 100 --out fig.png
    python biharmonic_distance.py --mesh bunny.off --kinds fem voronoi-cot

Needs numpy, matplotlib and spectral_mesh.
"""

from __future__ import annotations

import argparse
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import hsv_to_rgb  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402

import spectral_mesh as sm  # noqa: E402


def hue(t: np.ndarray) -> np.ndarray:
    """The paper's colour map: HSV hue from red (t = 0) through yellow, green, cyan and
    blue to magenta (t = 1), full saturation and value."""
    hsv = np.stack([np.clip(t, 0, 1) * 300 / 360, np.ones_like(t), np.ones_like(t)], axis=-1)
    return hsv_to_rgb(hsv)


def draw(ax, V, F, d, sets, source, title):
    t = (d - d.min()) / max(d.max() - d.min(), 1e-300)
    colors = hue(t[F].mean(axis=1))  # one colour per triangle: the mean of its corners
    # Simple two-sided Lambert shading from the viewer's side.
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-300
    light = np.array([0.4, 0.3, 1.0]) / np.linalg.norm([0.4, 0.3, 1.0])
    shade = 0.45 + 0.55 * np.abs(n @ light)
    ax.add_collection3d(
        Poly3DCollection(V[F], facecolors=colors * shade[:, None], edgecolors="none")
    )
    segs = np.concatenate([s.segments for s in sets]) if sets else np.zeros((0, 2, 3))
    ax.add_collection3d(Line3DCollection(segs, colors="black", linewidths=0.6))
    ax.scatter(*V[source], color="black", s=30, depthshade=False)
    lo, hi = V.min(axis=0), V.max(axis=0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=35, azim=-60)
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)


def main() -> None:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument(
        "--shape", default="3torus", help="built-in shape spec (default: the paper's 3-torus)"
    )
    p.add_argument("--mesh", help="a mesh file instead of a built-in shape")
    p.add_argument(
        "--kinds",
        nargs="+",
        default=["fem", "voronoi-cot", "cot"],
        help="discretizations (columns)",
    )
    p.add_argument(
        "--k", nargs="+", type=int, default=[100, 20], help="numbers of eigenpairs (rows)"
    )
    p.add_argument("--levels", type=int, default=20, help="level sets drawn")
    p.add_argument("--out", default="biharmonic-distance.png")
    a = p.parse_args()

    V, F = sm.read_mesh(a.mesh) if a.mesh else sm.shape(a.shape)
    rows, cols = len(a.k), len(a.kinds)
    fig = plt.figure(figsize=(3.2 * cols, 3.2 * rows))
    for j, kind in enumerate(a.kinds):
        t0 = time.perf_counter()
        an = sm.Analysis(V, F, kind)  # one analysis per discretization: k grows, one factor
        for i, k in enumerate(a.k):
            d = an.distance(distance="biharmonic", k=k)
            source = an.last_info["request"]["source"]
            sets = an.level_sets(d, a.levels)
            ax = fig.add_subplot(rows, cols, i * cols + j + 1, projection="3d")
            draw(ax, V, F, d, sets, source, f"{kind}, k = {k}")
        print(f"{kind}: {time.perf_counter() - t0:.2f} s for k = {a.k}")
    fig.suptitle(
        f"Bi-harmonic distance from the vertex of largest x ({len(V)} vertices)", fontsize=11
    )
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
