#!/usr/bin/env bash
# Builds the Python package (crates/spectral-mesh-py: a release abi3 wheel, by maturin
# through pip), installs it into the conformance venv (scripts/setup-python.sh: NumPy,
# SciPy, libigl, LaPy, robust-laplacian, pytest, maturin, mypy), type-checks its Python
# layer with mypy and runs its pytest suite. Arguments go to pytest instead of the default
# "tests" (e.g. tests/test_inputs.py -x).
#
# Real meshes: SPECTRAL_MESH_SHARED_MESHES as for scripts/test.sh (unset: those tests are
# skipped and say so). The tests that compare with the command line run
# SPECTRAL_MESH_CLI; unset, the CLI is built here (debug, incremental after `cargo test`).
#
# Cost in CI: the release build of the library and the bindings took 315 s after a merge of
# main (spectral-mesh, its renderer and the extension recompiled; load rising to 11 on the
# 2-core machine), pytest 43 s; with the venv's extra pip packages (maturin, pytest, lapy,
# matplotlib) about 6-8 minutes on top of the rest of scripts/test.sh.
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
if [ -z "${SPECTRAL_MESH_CLI:-}" ]; then
  t0=$SECONDS
  (cd "$root" && cargo build --quiet -p spectral-mesh-cli)
  export SPECTRAL_MESH_CLI="$root/target/debug/spectral-mesh"
  echo "built the command line (for the tests that compare with it) in $((SECONDS - t0)) s"
fi
cd "$root/crates/spectral-mesh-py"
# The type hints of the Python layer against the native module's stubs (_native.pyi);
# configuration in pyproject.toml ([tool.mypy]), cache in the venv.
t0=$SECONDS
"$py" -m mypy --cache-dir "$venv/.mypy_cache" python/spectral_mesh
echo "mypy: $((SECONDS - t0)) s"
if [ "$#" -eq 0 ]; then set -- tests; fi
exec "$py" -m pytest -q -p no:cacheprovider "$@"
