#!/usr/bin/env bash
# Builds the Python package (crates/spectral-mesh-py: a release abi3 wheel, by maturin
# through pip), installs it into the conformance venv (scripts/setup-python.sh: NumPy,
# SciPy, libigl, LaPy, robust-laplacian, pytest, maturin) and runs its pytest suite.
# Arguments go to pytest instead of the default "tests" (e.g. tests/test_inputs.py -x).
#
# Real meshes: SPECTRAL_MESH_SHARED_MESHES as for scripts/test.sh (unset: those tests are
# skipped and say so).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
py="$(bash "$root/scripts/setup-python.sh")"
venv="$(dirname "$(dirname "$py")")"
t0=$SECONDS
# --no-build-isolation: the venv's maturin builds the wheel (its bin/ must be on PATH);
# cargo reuses the workspace's target/release.
PATH="$venv/bin:$PATH" "$py" -m pip install --quiet --disable-pip-version-check \
  --no-build-isolation --force-reinstall --no-deps "$root/crates/spectral-mesh-py"
echo "built and installed spectral_mesh in $((SECONDS - t0)) s"
cd "$root/crates/spectral-mesh-py"
if [ "$#" -eq 0 ]; then set -- tests; fi
exec "$py" -m pytest -q -p no:cacheprovider "$@"
