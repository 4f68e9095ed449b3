"""The library's defaults, read once from the native module.

Every default of the Python API comes from here, and these come from the Rust library's
own types (``FieldRequest``'s serde defaults, ``AnalysisOptions``, ``EigenParams``,
``FigureOptions``, ``BatchParams``), so the Python package, the command line, the web app and experiment
files use the same numbers.
"""

from __future__ import annotations

from . import _native

DEFAULTS: dict = _native.defaults()

#: Every request kind's parameters and their defaults (``REQUESTS["heat"]["t"]`` = 0.5).
REQUESTS: dict = DEFAULTS["requests"]
#: The analysis and eigensolver defaults (discretization, normalization, k, tolerance, seed).
ANALYSIS: dict = DEFAULTS["analysis"]
#: The figure defaults (levels, colour map, view, size, ...).
FIGURE: dict = DEFAULTS["figure"]
#: The discretization names.
LAPLACIANS: list = DEFAULTS["laplacians"]
#: The colour map names.
COLORMAPS: list = DEFAULTS["colormaps"]
#: The default built-in shape (the paper's 3-torus).
SHAPE: str = DEFAULTS["shape"]

#: ``spectral_mesh.batch``'s keywords (the library's ``BatchParams`` defaults).
BATCH: dict = DEFAULTS["batch"]
#: Eigenvalues with ``|lambda| <= ZERO_EIGENVALUE_EPS * lambda_max`` count as zero (one
#: per connected component) and are skipped by the filters: the library's constant.
ZERO_EIGENVALUE_EPS: float = DEFAULTS["zero_eigenvalue_eps"]

K: int = ANALYSIS["k"]
TOL: float = ANALYSIS["tol"]
SEED: int = ANALYSIS["seed"]
KIND: str = ANALYSIS["kind"]
METHOD: str = ANALYSIS["method"]
#: The point-cloud Laplacian's defaults (``n_neighbors``, ``mollify_factor``).
POINT_CLOUD: dict = DEFAULTS["point_cloud"]
#: The learning operators' defaults (``k_eig``, ``laplacian``, ``grad_regularization``,
#: ``n_neighbors``, ``tol``, ``mass_eps``: the library's ``LearningParams``).
LEARNING: dict = _native.learning_defaults()
