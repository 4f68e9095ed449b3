#!/usr/bin/env bash
# Heat-method geodesic distance against potpourri3d's MeshHeatMethodDistanceSolver
# (t_coef = 1) on the shared meshes, both Laplacians (use_robust False / True against our
# voronoi-cot / robust, --convention potpourri3d): max |ours - theirs| <= 1e-6 of the
# largest distance on the source's component.
# Arguments: CLI PYTHON.
set -euo pipefail
cli="$1"
py="$2"
root="$(cd "$(dirname "$0")/.." && pwd)"
meshes="${SPECTRAL_MESH_SHARED_MESHES:-}"
[ -n "$meshes" ] || { echo "skipped: SPECTRAL_MESH_SHARED_MESHES unset"; exit 0; }
"$py" "$root/conformance/geodesic_potpourri3d.py" --cli "$cli" --min-meshes 10 "$meshes"/*.off
