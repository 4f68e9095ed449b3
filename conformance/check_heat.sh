#!/usr/bin/env bash
# Heat-kernel columns, bi-harmonic and commute-time distances and HKS against an
# independent NumPy computation from SciPy's eigsh (shift-invert) basis, to 1e-8.
# Arguments: CLI PYTHON.
set -euo pipefail
# shellcheck source=conformance/common.sh
source "$(dirname "$0")/common.sh"
build_example spectral_fields
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
pass=0; fail=0
# mesh k t anchors
while read -r m k t anchors; do
  out="$work/$m"; mkdir -p "$out"
  # shellcheck disable=SC2086
  "$ex" "$meshes/$m.off" "$out" "$k" "$t" $anchors > /dev/null
  # shellcheck disable=SC2086
  if "$py" "$root/conformance/heat_distances.py" "$meshes/$m.off" "$k" "$t" $anchors --outdir "$out"; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1)); echo "FAIL: $m"
  fi
done <<'LIST'
eight 60 0.01 0 100
cactus 80 0.05 3 200
sphere966 49 0.1 0 500
cow 100 0.001 10 1000
hand 100 0.01 5 600
LIST
echo "heat and distances vs SciPy: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
