#!/usr/bin/env bash
# The robust Laplacian (tufted cover, mollification, intrinsic Delaunay) against the
# robust-laplacian pip package: S_robust and B_robust equal robust_laplacian.mesh_laplacian
# to 1e-10 of the largest entry on every shared mesh (same mollify factor), and our
# point-cloud operators on every shared cloud are finite, symmetric, S 1 = 0, positive mass
# (the peer's point-cloud operator differs by design: docs/point-clouds.md).
# Arguments: CLI PYTHON.
set -euo pipefail
# shellcheck source=conformance/common.sh
source "$(dirname "$0")/common.sh"
points="$meshes/../points"
clouds=()
if [ -d "$points" ]; then
  clouds=("$points"/*.xyz "$points"/*.ply)
fi
"$py" "$root/conformance/robust_laplacian.py" --cli "$cli" --min-meshes 15 \
  "$meshes"/*.off --points "${clouds[@]}"
