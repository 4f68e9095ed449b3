#!/usr/bin/env bash
# Side-by-side eigensolver benchmark: ours (bench_eigs) vs SciPy eigsh shift-invert with
# SuperLU and with CHOLMOD. Builds the release binaries, sets up the bench venv
# (bench/setup-bench-python.sh), then runs bench/eigs_grid.py with every argument given
# here (see `bench/eigs_grid.py --help`). With no argument: the full grid, meshes of about
# 25k, 100k and 400k vertices (cached in bench/meshes/), k = 50, 200, 500, 3 runs each.
# Output: bench/results/eigs_grid.md (table) and bench/results/eigs_grid.jsonl (raw runs).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
cargo=(cargo build --release --quiet --manifest-path "$root/Cargo.toml")
"${cargo[@]}" -p spectral-mesh --example bench_eigs
"${cargo[@]}" -p spectral-mesh-cli --bin spectral-mesh
python="$("$root/bench/setup-bench-python.sh")"
EIGS_GRID_COMMAND="bench/eigs_grid.sh${*:+ $(printf '%q ' "$@")}"
export EIGS_GRID_COMMAND="${EIGS_GRID_COMMAND% }"
exec python3 "$root/bench/eigs_grid.py" \
  --bench-eigs "$CARGO_TARGET_DIR/release/examples/bench_eigs" \
  --cli "$CARGO_TARGET_DIR/release/spectral-mesh" \
  --python "$python" \
  "$@"
