#!/usr/bin/env bash
# Creates (once) the virtual environment of the eigensolver benchmark (bench/eigs_scipy.py:
# NumPy, SciPy and scikit-sparse for the CHOLMOD route) and prints its python path.
# Idempotent: re-runs pip only when the pinned requirements below change.
#
# scikit-sparse 0.4.16 is the last release that builds against SuiteSparse 5 (Debian
# bookworm's libsuitesparse-dev 5.12); 0.5 needs SuiteSparse 7. The headers come from apt.
#
# env: SPECTRAL_MESH_BENCH_VENV (default: ROOT/.venv-bench), PYTHON3 (default: python3).
# Separate from scripts/setup-python.sh (the conformance suite's venv).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="${SPECTRAL_MESH_BENCH_VENV:-$root/.venv-bench}"
python3="${PYTHON3:-python3}"
requirements=(
  "numpy==2.4.6"
  "scipy==1.17.1"
  "scikit-sparse==0.4.16"
)

if [ ! -f /usr/include/suitesparse/cholmod.h ]; then
  echo "setup-bench-python: installing libsuitesparse-dev (CHOLMOD headers)" >&2
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get -o DPkg::Lock::Timeout=600 update -qq >&2
  DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=600 install -y -qq libsuitesparse-dev >&2
fi

stamp="$venv/.requirements.sha"
want="$(printf '%s\n' "${requirements[@]}" | sha256sum | cut -d' ' -f1)"
if [ ! -x "$venv/bin/python" ]; then
  "$python3" -m venv "$venv" >&2
fi
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  # scikit-sparse 0.4.16 has no wheels: pip builds it (Cython, against CHOLMOD).
  "$venv/bin/pip" install --quiet --disable-pip-version-check "${requirements[@]}" >&2
  "$venv/bin/python" -c "import sksparse.cholmod, scipy, numpy" >&2
  echo "$want" > "$stamp"
fi
echo "$venv/bin/python"
