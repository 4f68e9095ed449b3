"""The package's own exceptions (everything else is a built-in: ``ValueError`` for bad
arrays and parameters, ``OSError`` and its subclasses for files that cannot be opened or
written, ``KeyboardInterrupt`` when Ctrl-C stops a computation)."""

from __future__ import annotations


class SpectralMeshError(Exception):
    """Base class of the exceptions defined by spectral_mesh."""


class MeshFileError(SpectralMeshError, OSError):
    """A mesh or basis file was read but its content is invalid.

    An ``OSError`` (like every file problem); ``filename`` is the file and ``lineno`` the
    1-based line of the problem when the format has lines (else ``None``). ``str(e)`` is
    the library's ``path:line: problem`` message.
    """

    def __init__(self, message: str, filename: str | None = None, lineno: int | None = None):
        OSError.__init__(self, message)
        self.filename = filename
        self.lineno = lineno

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class NoConvergenceError(SpectralMeshError, RuntimeError):
    """The eigensolver stopped before every wanted pair reached the tolerance (SciPy raises
    ``ArpackNoConvergence``, also a ``RuntimeError``, in the same situation)."""


class SolverError(SpectralMeshError, RuntimeError):
    """A numerical failure other than non-convergence, e.g. ``S - sigma B`` could not be
    factored (a singular mass matrix: vertices that no triangle uses?)."""


class InternalError(SpectralMeshError, RuntimeError):
    """A bug in spectral-mesh (a Rust panic, caught before it reached Python). Please
    report it with the message."""
