#!/usr/bin/env bash
# Harmonic (k = 1) and bi-harmonic (k = 2) maps against libigl's igl.harmonic on shared
# meshes, with 2 and 6 default constraints. Arguments: CLI PYTHON (the CLI is unused:
# the fields come from the harmonic_field example).
set -euo pipefail
# shellcheck source=conformance/common.sh
source "$(dirname "$0")/common.sh"
build_example harmonic_field
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
pass=0; fail=0
for m in sphere966 cow hand elephant knot1 eight mesh_with_border elephant-with-holes holes; do
  for c in 2 6; do
    f="$meshes/$m.off"
    "$ex" "$f" 1 fem "$work/h1.txt" "extremes=$c" > "$work/c.txt"
    "$ex" "$f" 2 mixed-voronoi "$work/h2.txt" "extremes=$c" > /dev/null
    if "$py" "$root/conformance/harmonic_libigl.py" "$f" "$work/c.txt" \
        --harmonic "$work/h1.txt" --biharmonic "$work/h2.txt" --tol 1e-8; then
      pass=$((pass + 1))
    else
      fail=$((fail + 1)); echo "FAIL: $m with $c constraints"
    fi
  done
done
echo "harmonic vs libigl: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
