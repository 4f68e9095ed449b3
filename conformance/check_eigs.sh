#!/usr/bin/env bash
# Eigenpairs against SciPy's eigsh (shift-invert): eigenvalues to 1e-9 relative,
# eigenvector subspaces per cluster (principal angles < 1e-6), for fem and voronoi-cot on
# ten shared meshes. Arguments: CLI PYTHON.
set -euo pipefail
py="$2"
root="$(cd "$(dirname "$0")/.." && pwd)"
meshes="${SPECTRAL_MESH_SHARED_MESHES:-}"
[ -n "$meshes" ] || { echo "skipped: SPECTRAL_MESH_SHARED_MESHES unset"; exit 0; }
cargo build --release --quiet -p spectral-mesh --example bench_eigs
ex="$root/target/release/examples/bench_eigs"
pass=0; fail=0
while read -r m k; do
  for mass in fem voronoi-cot; do
    if "$py" "$root/conformance/eigs_scipy.py" "$meshes/$m.off" --k "$k" --mass "$mass" --bin "$ex" > /tmp/eigs_conf.$$ 2>&1; then
      pass=$((pass + 1))
    else
      fail=$((fail + 1)); echo "FAIL: $m ($mass)"; cat /tmp/eigs_conf.$$
    fi
  done
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
rm -f /tmp/eigs_conf.$$
echo "eigenpairs vs SciPy: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
