"""The package as installed: what importing it loads, what the extension links, the
public API's shape."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import spectral_mesh as sm


def test_import_loads_neither_scipy_nor_matplotlib():
    # SciPy is imported on first use of a sparse result: importing the package stays cheap.
    code = "import sys, spectral_mesh; print(sorted(m for m in sys.modules if m.split('.')[0] in ('scipy', 'matplotlib')))"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]"


def test_the_extension_needs_no_system_library():
    ext = Path(sm._native.__file__)
    assert ext.suffix == ".so" and ".abi3." in ext.name  # one wheel for every CPython >= 3.10
    if shutil.which("ldd") is None:
        pytest.skip("ldd is not available")
    out = subprocess.run(["ldd", str(ext)], capture_output=True, text=True, check=True).stdout
    libs = {line.split()[0] for line in out.splitlines() if line.strip()}
    allowed = (
        "linux-vdso",
        "libc.so",
        "libm.so",
        "libgcc_s.so",
        "libpthread.so",
        "libdl.so",
        "librt.so",
        "ld-linux",
    )
    extra = sorted(lib for lib in libs if not lib.startswith(allowed) and "ld-linux" not in lib)
    assert extra == [], out  # no libpython, BLAS, SuiteSparse, ...


def test_public_api():
    for name in sm.__all__:
        assert hasattr(sm, name), name
    assert sm.__version__ == sm._native.__version__
    assert sm.num_threads() >= 1
    import inspect

    # Keyword arguments everywhere past the data, with the paper's defaults.
    sig = inspect.signature(sm.eigenbasis)
    assert list(sig.parameters)[:4] == ["V", "F", "k", "kind"]
    assert all(
        sig.parameters[p].kind is inspect.Parameter.KEYWORD_ONLY
        for p in ["normalize", "tol", "seed", "dirichlet", "method"]
    )
    # SciPy's positional order for eigsh.
    assert list(inspect.signature(sm.eigsh).parameters)[:6] == [
        "A",
        "k",
        "M",
        "sigma",
        "which",
        "v0",
    ]
    for name in [
        "heat",
        "diffuse",
        "distance",
        "hks",
        "wks",
        "adf",
        "segmentation",
        "harmonic",
        "embedding",
    ]:
        assert getattr(sm.Analysis, name).__doc__, name


def test_the_module_docstring_example_runs():
    import doctest

    r = doctest.testmod(sm, verbose=False)
    assert r.attempted >= 7 and r.failed == 0
