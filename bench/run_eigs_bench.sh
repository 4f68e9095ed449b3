#!/usr/bin/env bash
# Side-by-side eigenbasis benchmark: ours (bench_eigs) and SciPy eigsh shift-invert
# (SuperLU), alternating, RUNS runs each, one process per run. Prints key=value lines.
# usage: bench/run_eigs_bench.sh MESH "K1 K2 ..." [RUNS]
set -euo pipefail
mesh="$1"; ks="$2"; runs="${3:-3}"
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CARGO_TARGET_DIR:-$root/target}/release/examples/bench_eigs"
py="${PYTHON:-$root/.venv/bin/python}"
for k in $ks; do
  for r in $(seq "$runs"); do
    echo "load=$(cut -d' ' -f1 /proc/loadavg) $("$bin" "$mesh" "$k")"
    echo "load=$(cut -d' ' -f1 /proc/loadavg) $("$py" "$root/bench/eigs_scipy.py" "$mesh" "$k")"
  done
done
