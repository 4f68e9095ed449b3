#!/usr/bin/env bash
# End-to-end benchmark of the CLI's spectral commands (whole process, mesh file in,
# outputs written) against the SciPy + CHOLMOD script and the SLEPc one (bench/eigs_slepc.py)
# writing the same .npz. Builds the release CLI, sets up the bench venv
# (bench/setup-bench-python.sh) and the SLEPc peer (bench/setup-slepc.sh), then runs
# bench/e2e_grid.py with every argument given here (see `bench/e2e_grid.py --help`). With no
# argument: meshes of about 25k, 100k and 400k vertices (cached in bench/meshes/), k = 50,
# 200, 500, 3 runs per route (1 at 400k).
# Output: bench/results/e2e_grid.md (tables) and bench/results/e2e_grid.jsonl (raw runs).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
cargo build --release --quiet --manifest-path "$root/Cargo.toml" -p spectral-mesh-cli --bin spectral-mesh
python="$("$root/bench/setup-bench-python.sh")"
# The SLEPc peer (Debian's python3-slepc4py, installed with apt-get when missing).
slepc_python="$("$root/bench/setup-slepc.sh")"
E2E_GRID_COMMAND="bench/e2e_grid.sh${*:+ $(printf '%q ' "$@")}"
export E2E_GRID_COMMAND="${E2E_GRID_COMMAND% }"
exec python3 "$root/bench/e2e_grid.py" \
  --cli "$CARGO_TARGET_DIR/release/spectral-mesh" \
  --python "$python" \
  --slepc-python "$slepc_python" \
  "$@"
