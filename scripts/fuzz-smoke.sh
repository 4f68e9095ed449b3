#!/usr/bin/env bash
# Fuzz smoke test: builds every fuzz target of fuzz/ (cargo fuzz, libFuzzer, no sanitizer,
# stable toolchain) and runs each for FUZZ_SECONDS seconds (default 30) from its committed
# seeds. Fails when any target finds a crash (panic, abort, stack overflow), a hang (one
# input over 2 s) or an out-of-memory (over 2048 MB); the input is left in
# fuzz/artifacts/TARGET/ and the command to reproduce it is printed.
#
#   bash scripts/fuzz-smoke.sh                 # every target, 30 s each
#   FUZZ_SECONDS=300 bash scripts/fuzz-smoke.sh read_ply_binary filter
#
# Cost on the 2-core CI machine: installing cargo-fuzz once (about 25 s, skipped when the
# pinned version is there), building the instrumented targets (about 4.5 min from a clean
# fuzz/target, seconds when nothing changed), then FUZZ_SECONDS per target: 16 targets x
# 30 s = 8 min. About 13 min in all on a clean checkout, 8 min when fuzz/target is kept.
# See RELIABILITY.md for the long runs.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root/fuzz"
seconds="${FUZZ_SECONDS:-30}"
version=0.13.2

if ! cargo fuzz --version 2>/dev/null | grep -q " $version"; then
  echo "installing cargo-fuzz $version"
  cargo install --locked --quiet cargo-fuzz --version "$version" || {
    echo "cargo-fuzz $version could not be installed" >&2
    exit 1
  }
fi

if [ "$#" -gt 0 ]; then
  targets=("$@")
else
  mapfile -t targets < <(cargo fuzz list)
fi

t0=$SECONDS
# One build of every target (they share the instrumented library).
if ! cargo fuzz build -s none 2>&1 | tail -3; then
  echo "fuzz targets did not build" >&2
  exit 1
fi
echo "build: $((SECONDS - t0)) s"

# A fresh corpus each run (the committed seeds are the starting point), unless the
# caller keeps one in FUZZ_CORPUS.
if [ -n "${FUZZ_CORPUS:-}" ]; then
  corpus="$FUZZ_CORPUS"
else
  corpus="$(mktemp -d)"
  trap 'rm -rf "$corpus"' EXIT
fi
mkdir -p logs
summary() {
  grep -a -E '^#[0-9]+.*cov: ' "$1" | tail -1 \
    | sed -E 's/^#([0-9]+)[^c]*cov: ([0-9]+) ft: ([0-9]+) corp: ([^ ]+).*/\1 runs, cov \2, ft \3, corpus \4/'
}
failed=()
for t in "${targets[@]}"; do
  log="logs/smoke-$t.log"
  before="$(ls "artifacts/$t" 2>/dev/null | wc -l)"
  if FUZZ_CORPUS="$corpus" bash run.sh "$t" "$seconds" >"$log" 2>&1; then
    echo "ok   $t: $(summary "$log")"
    after="$(ls "artifacts/$t" 2>/dev/null | wc -l)"
    if [ "$after" -gt "$before" ]; then
      echo "     warning: $((after - before)) new input(s) of a known open bug in fuzz/artifacts/$t/ (fuzz/known-open.txt)"
    fi
  else
    failed+=("$t")
    echo "FAIL $t"
    grep -a -E -A1 "panicked|ERROR: libFuzzer|Test unit written|Reproduce with" "$log" | head -12
    echo "     (full log: fuzz/$log)"
  fi
done
echo "fuzz smoke: ${#targets[@]} targets, ${seconds} s each, $((SECONDS - t0)) s in all"
if [ "${#failed[@]}" -gt 0 ]; then
  echo "failed targets: ${failed[*]} (inputs in fuzz/artifacts/; see fuzz/README.md)" >&2
  exit 1
fi
