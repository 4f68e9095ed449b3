#!/usr/bin/env bash
# Installs (once) the SLEPc peer of the eigensolver benchmarks, bench/eigs_slepc.py:
# Debian's python3-slepc4py (SLEPc 3.18 with PETSc and its CHOLMOD interface) and
# python3-scipy for the system python3, with apt-get when `import slepc4py, scipy` fails.
# Prints the python to run bench/eigs_slepc.py with (the system's, not the bench venv's:
# petsc4py is built against Debian's NumPy).
# env: SLEPC_PYTHON (default /usr/bin/python3).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
python="${SLEPC_PYTHON:-/usr/bin/python3}"
check=("$python" "$root/bench/eigs_slepc.py" --check)
if ! "${check[@]}" 2>/dev/null; then
  echo "setup-slepc: installing python3-slepc4py and python3-scipy" >&2
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get -o DPkg::Lock::Timeout=600 update -qq >&2
  DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=600 install -y -qq python3-slepc4py python3-scipy >&2
  "${check[@]}" >&2
fi
echo "$python"
