#!/usr/bin/env bash
# Creates (once) the virtual environment with the Python peers the conformance suite
# compares against, and prints its python path. Idempotent: re-runs only pip when the
# requirements changed.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="${SPECTRAL_MESH_VENV:-$root/.venv}"
req="$root/conformance/requirements.txt"
stamp="$venv/.requirements.sha"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv" >&2
fi
want="$(sha256sum "$req" | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$req" >&2
  echo "$want" > "$stamp"
fi
echo "$venv/bin/python"
