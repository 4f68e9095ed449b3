# What the check_*.sh scripts share. Each sources it after `set -euo pipefail` with its own
# arguments (CLI PYTHON): sets cli, py, root (the repository) and meshes (the shared meshes;
# without SPECTRAL_MESH_SHARED_MESHES the check is skipped with exit status 0).
# shellcheck shell=bash disable=SC2034
cli="$1"
py="$2"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
meshes="${SPECTRAL_MESH_SHARED_MESHES:-}"
[ -n "$meshes" ] || { echo "skipped: SPECTRAL_MESH_SHARED_MESHES unset"; exit 0; }

# build_example NAME: builds the library's example NAME (release) and sets ex to its path.
build_example() {
  cargo build --release --quiet -p spectral-mesh --example "$1"
  ex="$root/target/release/examples/$1"
}
