#!/usr/bin/env bash
# Eigenpairs against SciPy's eigsh (shift-invert): eigenvalues to 1e-9 relative,
# eigenvector subspaces per cluster (principal angles < 1e-6), for fem and voronoi-cot on
# ten shared meshes. Arguments: CLI PYTHON.
set -euo pipefail
# shellcheck source=conformance/common.sh
source "$(dirname "$0")/common.sh"
build_example bench_eigs
# The 20 cases run two at a time (each is mostly Python start-up and one eigsh), one log
# per case, printed when it fails.
logs="$(mktemp -d)"
trap 'rm -rf "$logs"' EXIT
cases() {
  while read -r m k; do
    for mass in fem voronoi-cot; do echo "$m $k $mass"; done
  done <<'LIST'
sphere966 40
eight 40
homer 50
mesh_with_border 40
hand 50
blobby_3cc 30
cow 50
elephant 50
knot1 50
holes 50
LIST
}
run_case() {
  local m="$1" k="$2" mass="$3"
  if "$py" "$root/conformance/eigs_scipy.py" "$meshes/$m.off" --k "$k" --mass "$mass" --bin "$ex" \
      > "$logs/$m.$mass.log" 2>&1; then
    touch "$logs/$m.$mass.ok"
  fi
}
export -f run_case
export py root meshes ex logs
cases | xargs -P 2 -L 1 bash -c 'run_case "$@"' _
pass=0; fail=0
while read -r m _k mass; do
  if [ -e "$logs/$m.$mass.ok" ]; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1)); echo "FAIL: $m ($mass)"; cat "$logs/$m.$mass.log"
  fi
done < <(cases)
echo "eigenpairs vs SciPy: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
