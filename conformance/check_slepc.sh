#!/usr/bin/env bash
# Eigenpairs against SLEPc (Krylov-Schur, shift-invert, CHOLMOD; Debian's python3-slepc4py,
# installed by bench/setup-slepc.sh with apt when missing): eigenvalues to 1e-9 relative,
# eigenvector subspaces per cluster (principal angles < 1e-6), fem and voronoi-cot on shared
# meshes with boundaries, several components and near-multiple eigenvalues. Arguments:
# CLI PYTHON (the conformance venv's python is not used: petsc4py needs Debian's NumPy).
set -euo pipefail
# shellcheck source=conformance/common.sh
source "$(dirname "$0")/common.sh"
slepc_py="$(bash "$root/bench/setup-slepc.sh")"
pass=0; fail=0
while read -r m k mass; do
  if log="$("$slepc_py" "$root/conformance/eigs_slepc.py" "$meshes/$m.off" --k "$k" \
      --mass "$mass" --cli "$cli" 2>&1)"; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1)); echo "FAIL: $m ($mass)"; echo "$log"
  fi
done <<'LIST'
sphere966 40 fem
homer 40 fem
mesh_with_border 30 voronoi-cot
blobby_3cc 30 fem
hand 40 voronoi-cot
cow 50 fem
knot1 50 voronoi-cot
LIST
echo "eigenpairs vs SLEPc: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
