#!/usr/bin/env bash
# The collection benchmark of BENCHMARKS.md: builds the release CLI and the bench venv,
# generates the meshes once (bench/meshes/batch/, git-ignored) and runs every route.
#   bench/batch_bench.sh                       # 200 meshes of 5k-50k vertices, k = 50, HKS x 16
#   bench/batch_bench.sh --count 40 --runs 1   # fewer meshes (run options: batch_bench.py run --help)
# env: SPECTRAL_MESH_SHARED_MESHES (the shared meshes perturbed among the generated ones).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
cargo build --release --quiet -p spectral-mesh-cli
py="$(bash bench/setup-bench-python.sh)"
python3 bench/batch_bench.py generate --count 200
python3 bench/batch_bench.py run --python "$py" "$@"
