#!/usr/bin/env bash
# The Python eigenbasis benchmark (BENCHMARKS.md, "From Python"): installs its venv and
# runs bench/python_eigs_grid.py with the arguments given.
#
# The venv is the eigensolver benchmark's (.venv-bench from bench/setup-bench-python.sh:
# NumPy, SciPy, scikit-sparse 0.4.16 on Debian's SuiteSparse) plus the Python peers
# pinned below and this repository's package, built from crates/spectral-mesh-py (release,
# abi3 wheel) by pip. Re-running reinstalls the package only (the peers when their pins
# change).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
py="$(bash "$root/bench/setup-bench-python.sh")"
venv="$(dirname "$(dirname "$py")")"
peers=(
  "lapy==1.7.0"
  "cholespy==2.2.0"
  "robust-laplacian==1.1.0"
  "libigl==2.6.3"
  "maturin==1.16.0"
)
stamp="$venv/.python-peers.sha"
want="$(printf '%s\n' "${peers[@]}" | sha256sum | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  "$py" -m pip install --quiet --disable-pip-version-check "${peers[@]}" >&2
  echo "$want" > "$stamp"
fi
# --no-build-isolation: the venv's maturin builds it (its bin/ must be on PATH).
PATH="$venv/bin:$PATH" "$py" -m pip install --quiet --disable-pip-version-check --no-build-isolation \
  --force-reinstall --no-deps "$root/crates/spectral-mesh-py" >&2
exec "$py" "$root/bench/python_eigs_grid.py" --python "$py" "$@"
