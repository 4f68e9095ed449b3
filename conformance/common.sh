# What the check_*.sh scripts share. Each sources it after `set -euo pipefail` with its own
# arguments (CLI PYTHON): sets cli, py, root (the repository) and meshes (the shared meshes;
# without SPECTRAL_MESH_SHARED_MESHES the check is skipped with exit status 0).
# shellcheck shell=bash disable=SC2034
cli="$1"
py="$2"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
meshes="${SPECTRAL_MESH_SHARED_MESHES:-}"
if [ -z "$meshes" ]; then
  # Under CI a missing folder fails: a CI that forgot the variable must not look green.
  if [ "${CI:-}" = true ]; then echo "SPECTRAL_MESH_SHARED_MESHES is not set under CI"; exit 1; fi
  echo "skipped: SPECTRAL_MESH_SHARED_MESHES unset"; exit 0
fi

# build_example NAME: builds the library's example NAME (release) and sets ex to its path.
# --workspace: the features of `cargo test --release --workspace`, whose build this reuses
# (with -p spectral-mesh cargo would resolve them otherwise and rebuild the library).
build_example() {
  cargo build --release --quiet --workspace --example "$1"
  ex="$root/target/release/examples/$1"
}
