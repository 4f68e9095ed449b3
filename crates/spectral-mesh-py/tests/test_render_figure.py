"""One figure: the package's ``render`` and the command line's ``render`` take the same
options (view or camera, size, height, scale, print resolution, legend) and write the
same picture, byte for byte."""

from __future__ import annotations

import subprocess

import numpy as np

import spectral_mesh as sm
from conftest import cli

CAMERA = "camera:2.5,1.5,3.0,0.1,0.0,-0.2,0.0,1.0,0.0,40"


def _phys(png: bytes) -> tuple[int, int, int] | None:
    """The pHYs chunk of a PNG: (x, y, unit)."""
    i = png.find(b"pHYs")
    if i < 0:
        return None
    d = png[i + 4 : i + 13]
    return int.from_bytes(d[0:4], "big"), int.from_bytes(d[4:8], "big"), d[8]


def test_render_equals_the_command_line(tmp_path):
    exe = cli()
    V, F = sm.shape("sphere:res=2")
    values = V[:, 2] + 0.3 * V[:, 0]
    mesh, vals = tmp_path / "s.off", tmp_path / "v.txt"
    sm.write_mesh(mesh, V, F)
    np.savetxt(vals, values, fmt="%.17g")
    opts = dict(view=CAMERA, size=240, height=180, scale=1.5, dpi=150, colormap="diverging", levels=6)
    ours = tmp_path / "py.png"
    sm.render(V, F, values, ours, marks=[3], **opts)
    theirs = tmp_path / "cli.png"
    r = subprocess.run(
        [exe, "render", str(mesh), "--field", str(vals), "--mark", "3", "--view", CAMERA,
         "--size", "240", "--height", "180", "--scale", "1.5", "--dpi", "150",
         "--colormap", "diverging", "--levels", "6", "-o", str(theirs)],
        capture_output=True, text=True, timeout=600,
    )
    assert r.returncode == 0, r.stderr
    a, b = ours.read_bytes(), theirs.read_bytes()
    assert a == b
    assert _phys(a) == (5906, 5906, 1)  # 150 dpi in pixels per metre
    img = sm.render(V, F, values, **opts)
    assert img.shape == (180, 240, 4)
    # Without the legend the picture differs (the legend is drawn).
    assert not np.array_equal(img, sm.render(V, F, values, legend=False, **opts))
