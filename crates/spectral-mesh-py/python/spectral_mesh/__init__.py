"""spectral_mesh: Laplace-Beltrami eigenbases, heat diffusion, filtered spectral distances
and harmonic maps on triangle meshes, from a Rust engine with no system library.

NumPy arrays in, NumPy arrays and ``scipy.sparse.csr_matrix`` out:

>>> import spectral_mesh as sm
>>> V, F = sm.shape("sphere:res=4")                   # or sm.read_mesh("bunny.off")
>>> S, B = sm.laplacian(V, F)                         # S = -igl.cotmatrix, B = FEM mass
>>> evals, evecs = sm.eigenbasis(V, F, k=50)          # S x = lambda B x, X^T B X = I
>>> an = sm.Analysis(V, F)                            # keeps the factor, grows k
>>> d = an.distance(0, distance="biharmonic", k=100)  # (n,) distances from vertex 0
>>> h = an.hks([0.01, 0.1, 1.0])                      # (n, 3) heat kernel signatures
>>> img = an.render(d)                                # (800, 800, 4) uint8 picture

Point clouds (scans: ``.xyz``, ``.pts``, PLY without faces) go wherever a mesh does:
``Analysis.from_points(P, n_neighbors=30)`` or ``Analysis.from_file("scan.ply")`` analyse
them with their point-cloud Laplacian (as robust-laplacian's), with every field above.

Conventions (the repository's docs/MATH.md): ``S`` is positive semi-definite (libigl's
``cotmatrix`` is ``-S``), ``B`` symmetric positive definite, eigenvalues ascending and
``>= 0``, eigenvectors B-orthonormal with their largest-magnitude entry positive, filters
given as weights ``w = 1/phi``. :func:`eigenbasis` and :func:`laplacian` use the mesh as
given (``normalize=False``, like LaPy and SciPy); :class:`Analysis` analyses the shape
scaled to unit area by default (``normalize=True``), so its times are comparable across
meshes.

Computations release the GIL, use every core (``RAYON_NUM_THREADS`` limits them) and stop
on Ctrl-C with ``KeyboardInterrupt``. Errors: ``ValueError`` for bad arrays and
parameters, ``OSError`` subclasses for files (:class:`MeshFileError` for invalid
content), :class:`NoConvergenceError` and :class:`SolverError` for numerical failures.
"""

from __future__ import annotations

# The native module's allocator is mimalloc v2 (the workspace's Cargo.toml): it returns
# the memory a computation frees to the system 10 ms later (MIMALLOC_PURGE_DELAY, read
# from the environment when the module loads; v3's default of 1 s kept every buffer a
# 26k-vertex solve had freed in the process' peak).
from . import _native
from ._analysis import Analysis, CriticalPoints, LevelSet
from ._batch import batch
from ._correspondence import functional_map, match_pairs, p2p, zoomout
from ._geodesic import GeodesicSolver, geodesic_distance, point_cloud_geodesic_distance
from ._api import (
    eigenbasis,
    eigsh,
    laplacian,
    load_basis,
    num_threads,
    point_cloud_laplacian,
    read_mesh,
    read_points,
    render,
    save_basis,
    shape,
    shape_names,
    write_mesh,
)
from ._defaults import DEFAULTS
from ._errors import (
    InternalError,
    MeshFileError,
    NoConvergenceError,
    SolverError,
    SpectralMeshError,
)

__version__: str = _native.__version__

__all__ = [
    "Analysis",
    "CriticalPoints",
    "DEFAULTS",
    "GeodesicSolver",
    "InternalError",
    "LevelSet",
    "MeshFileError",
    "NoConvergenceError",
    "SolverError",
    "SpectralMeshError",
    "__version__",
    "batch",
    "eigenbasis",
    "eigsh",
    "functional_map",
    "geodesic_distance",
    "laplacian",
    "load_basis",
    "match_pairs",
    "num_threads",
    "p2p",
    "point_cloud_geodesic_distance",
    "point_cloud_laplacian",
    "read_mesh",
    "read_points",
    "render",
    "save_basis",
    "shape",
    "shape_names",
    "write_mesh",
    "zoomout",
]
