"""Input normalization: what users pass becomes the few layouts the native module takes.

Accepted: any array-like; ``V`` of any real dtype (float32, float64, integers), ``F`` of
any integer dtype (int32, int64, unsigned), C or Fortran order, views and slices. The
result is C-contiguous float64 ``(n, 3)`` and int64 ``(m, 3)``; a copy is made only when
the input is not already in that layout. Everything wrong raises ``ValueError`` naming the
argument and the problem.
"""

from __future__ import annotations

import math
import numbers
from typing import TYPE_CHECKING, Any, Sequence, TypeAlias

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    import scipy.sparse

    #: The sparse matrices the package returns (``S``, ``B``): SciPy CSR of float64.
    CsrMatrix: TypeAlias = scipy.sparse.csr_matrix[np.float64]

#: A float64 NumPy array (per-vertex values ``(n,)``, positions ``(n, 3)``, bases ``(n, k)``).
FloatArray: TypeAlias = npt.NDArray[np.float64]
#: An int64 NumPy array (triangles ``(m, 3)``, vertex indices, labels).
IntArray: TypeAlias = npt.NDArray[np.int64]
#: A square sparse matrix as its CSC (equally, for a symmetric one, CSR) arrays.
CscParts: TypeAlias = tuple[FloatArray, IntArray, IntArray]


def vertices(V: npt.ArrayLike, name: str = "V") -> FloatArray:
    a = np.asarray(V)
    if a.dtype.kind not in "fiu":
        raise ValueError(f"{name} must hold real numbers (float32 or float64), got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {a.shape}")
    if a.shape[0] == 0:
        raise ValueError(f"{name} is empty: the mesh needs at least one vertex")
    return np.ascontiguousarray(a, dtype=np.float64)


def faces(F: npt.ArrayLike, name: str = "F") -> IntArray:
    a = np.asarray(F)
    if a.dtype.kind not in "iu":
        hint = ""
        if a.dtype.kind == "f":
            hint = f" (convert with {name}.astype(np.int64) if the values are whole numbers)"
        raise ValueError(
            f"{name} must be an integer array of vertex indices, got dtype {a.dtype}{hint}"
        )
    if a.ndim != 2 or a.shape[1] != 3:
        extra = ""
        if a.ndim == 2 and a.shape[1] == 4:
            extra = " (quads: split them into triangles first, e.g. read_mesh does)"
        raise ValueError(f"{name} must have shape (m, 3) (triangles), got {a.shape}{extra}")
    if a.shape[0] == 0:
        raise ValueError(f"{name} is empty: the mesh needs at least one triangle")
    if a.dtype.kind == "u" and a.dtype.itemsize >= 8 and a.max() > np.iinfo(np.int64).max:
        raise ValueError(f"{name} holds an index larger than any vertex count")
    return np.ascontiguousarray(a, dtype=np.int64)


def mesh(V: npt.ArrayLike, F: npt.ArrayLike) -> tuple[FloatArray, IntArray]:
    return vertices(V), faces(F)


def per_vertex(values: npt.ArrayLike, n: int | None, name: str = "values") -> FloatArray:
    a = np.asarray(values)
    if a.dtype.kind not in "fiub":
        raise ValueError(f"{name} must hold real numbers, got dtype {a.dtype}")
    if a.ndim != 1:
        raise ValueError(f"{name} must be a 1-d array of one value per vertex, got shape {a.shape}")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} has {a.shape[0]} values but the mesh has {n} vertices")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        i = int(np.flatnonzero(~np.isfinite(a))[0])
        raise ValueError(f"{name}[{i}] = {a[i]} is not finite")
    return a


def columns_t(X: npt.ArrayLike, name: str = "evecs") -> FloatArray:
    """The C-contiguous (k, n) transpose of an (n, k) matrix (free for Fortran order)."""
    a = np.asarray(X)
    if a.dtype.kind not in "fiu":
        raise ValueError(f"{name} must hold real numbers, got dtype {a.dtype}")
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise ValueError(f"{name} must have shape (n, k), got {a.shape}")
    return np.ascontiguousarray(a.T, dtype=np.float64)


def vector(values: npt.ArrayLike, name: str) -> FloatArray:
    a = np.asarray(values)
    if a.dtype.kind not in "fiu" or a.ndim != 1:
        raise ValueError(f"{name} must be a 1-d array of real numbers, got {a.dtype} {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def count(value: Any, name: str, minimum: int = 0) -> int:
    """A non-negative (or >= minimum) integer; numpy integers are accepted."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    v = int(value)
    if v < minimum:
        raise ValueError(f"{name} = {v}: must be >= {minimum}")
    return v


def real(value: Any, name: str) -> float:
    """A finite real number; numpy scalars are accepted."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} = {v}: must be a finite number")
    return v


def plain(value: Any, name: str) -> Any:
    """A request parameter as a JSON-ready value (numpy scalars unwrapped, floats finite)."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{name} = {value}: must be a finite number")
    if (
        isinstance(value, int)
        and not isinstance(value, bool)
        and value < 0
        and name
        in (
            "k",
            "source",
            "anchor",
            "index",
            "component",
            "vertex",
        )
    ):
        raise ValueError(f"{name} = {value}: must be >= 0")
    if isinstance(value, (list, tuple)):
        return [plain(v, name) for v in value]
    if isinstance(value, dict):
        return {str(k): plain(v, f"{name}.{k}") for k, v in value.items()}
    return value


def sparse_csc(
    A: Any, name: str, diagonal: str | None = None
) -> tuple[scipy.sparse.csc_matrix, CscParts]:
    """A square float64 SciPy CSC matrix in canonical form (sorted, no duplicates) and its
    arrays with int64 indices. ``diagonal="nonnegative"`` or ``"positive"`` checks the
    diagonal (a necessary condition of semi-definiteness or definiteness)."""
    import scipy.sparse as sp

    if isinstance(A, np.ndarray) or (not sp.issparse(A) and hasattr(A, "__array__")):
        a = np.asarray(A)
        if a.ndim != 2:
            raise ValueError(f"{name} must be a 2-d matrix, got shape {a.shape}")
        A = sp.csc_matrix(a)
    if not sp.issparse(A):
        raise ValueError(
            f"{name} must be a SciPy sparse matrix or a 2-d array, got {type(A).__name__} "
            "(a LinearOperator cannot be used: the solver factors the matrices)"
        )
    given: Any = A  # any SciPy sparse matrix or array
    if given.dtype.kind not in "fiub":
        raise ValueError(f"{name} must hold real numbers, got dtype {given.dtype}")
    if given.ndim != 2 or given.shape[0] != given.shape[1]:
        raise ValueError(f"{name} must be square, got shape {given.shape}")
    A = sp.csc_matrix(given, dtype=np.float64)
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
    if A.nnz and not np.all(np.isfinite(A.data)):
        raise ValueError(f"{name} has non-finite entries")
    D = A - A.T
    scale = abs(A).max() if A.nnz else 0.0
    if D.nnz and abs(D).max() > 1e-12 * scale:
        raise ValueError(
            f"{name} is not symmetric (max |{name} - {name}.T| = {abs(D).max():.3g}, "
            f"max |{name}| = {scale:.3g}); use ({name} + {name}.T) / 2 if that is what you mean"
        )
    if diagonal is not None and A.shape[0]:
        d = A.diagonal()
        bad = np.flatnonzero(d < 0 if diagonal == "nonnegative" else d <= 0)
        if bad.size:
            i = int(bad[0])
            what = "semi-definite" if diagonal == "nonnegative" else "definite"
            raise ValueError(f"{name} is not positive {what}: {name}[{i}, {i}] = {d[i]:.6g}")
    parts = (
        np.ascontiguousarray(A.data, dtype=np.float64),
        np.ascontiguousarray(A.indices, dtype=np.int64),
        np.ascontiguousarray(A.indptr, dtype=np.int64),
    )
    return A, parts


def csr_from_parts(parts: CscParts, n: int) -> CsrMatrix:
    """A symmetric matrix's CSC arrays read as CSR (the same matrix)."""
    import scipy.sparse as sp

    data, indices, indptr = parts
    return sp.csr_matrix((data, indices, indptr), shape=(n, n))


def solver(
    tol: Any, seed: Any, dirichlet: Sequence[int] | None, method: Any
) -> tuple[float, int, list[int] | None, str]:
    """The eigensolver keywords as the native functions take them: one tuple
    ``(tol, seed, dirichlet, method)``, each checked."""
    d = None if dirichlet is None else [count(i, "dirichlet vertex") for i in dirichlet]
    return real(tol, "tol"), count(seed, "seed"), d, str(method)


def cloud(n_neighbors: Any, mollify_factor: Any) -> tuple[int | None, float | None]:
    """The point-cloud Laplacian's keywords as the native functions take them: one tuple
    ``(n_neighbors, mollify_factor)``, each checked (``None``: the library's default)."""
    return (
        None if n_neighbors is None else count(n_neighbors, "n_neighbors"),
        None if mollify_factor is None else real(mollify_factor, "mollify_factor"),
    )
