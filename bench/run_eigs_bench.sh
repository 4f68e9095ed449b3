#!/usr/bin/env bash
# Superseded by bench/eigs_grid.sh (alternating routes, SuperLU and CHOLMOD, medians,
# table). Kept as a shim: runs the grid on one mesh for the given k values.
# usage: bench/run_eigs_bench.sh MESH "K1 K2 ..." [RUNS]
set -euo pipefail
mesh="$1"; ks="$2"; runs="${3:-3}"
exec "$(dirname "$0")/eigs_grid.sh" --sizes "" --mesh "$mesh" --ks "${ks// /,}" --runs "$runs"
