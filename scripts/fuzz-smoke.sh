#!/usr/bin/env bash
# Fuzz smoke test, a CI step of scripts/test.sh: builds every fuzz target of fuzz/
# (cargo fuzz, libFuzzer, no sanitizer, stable toolchain) once, replays each target's
# committed seeds and fuzzes it for the time left, all within one budget. Fails when a
# target finds a crash (panic, abort, stack overflow), a hang (one input over 2 s) or an
# out-of-memory (over 2048 MB), or when the targets do not build; the input is left in
# fuzz/artifacts/TARGET/ and the command to reproduce it is printed.
#
#   bash scripts/fuzz-smoke.sh                                  # CI: every target, 180 s in all
#   FUZZ_BUDGET=600 bash scripts/fuzz-smoke.sh                  # longer, same split
#   FUZZ_SECONDS=300 bash scripts/fuzz-smoke.sh read_ply_binary filter   # fixed time per target
#
# Budget: FUZZ_BUDGET seconds (default 180) for the whole step, counted from its start:
# installing cargo-fuzz when it is missing, building the targets, then the time left split
# evenly among the targets, at least FUZZ_MIN_SECONDS (default 3) each (so a slow build
# makes the step run over the budget rather than skip targets). FUZZ_SECONDS fixes the
# time per target instead. The long runs are fuzz/long-run.sh (RELIABILITY.md).
#
# The targets are built once (`cargo fuzz build`) and their binaries copied to a folder
# of this run, which runs them directly (fuzz/run.sh with FUZZ_BIN): no `cargo fuzz run`
# per target re-checking the build (about 2 s each), and a run sharing the build folder
# cannot swap the binaries under this one (the build and the copy hold a lock on it).
#
# The build keeps its target folder in FUZZ_TARGET_DIR: by default fuzz/target, and under
# CI (CI=true) ~/.cache/spectral-mesh/fuzz-target-KEY, KEY a hash of fuzz/Cargo.lock, the
# toolchain (`rustc -vV`) and the cargo-fuzz version, so that the next CI run on the same
# machine rebuilds only what changed (a clean clone would otherwise rebuild every
# instrumented dependency: several minutes; see RELIABILITY.md, "CI cost"); the three
# most recently used such folders are kept. A stale folder cannot make the step pass
# wrongly: cargo rebuilds whatever its sources or flags changed (a fresh clone's files are
# all newer than the folder's last build), the key only keeps folders of other
# dependencies and toolchains from piling up in one.
#
# Missing tools never fail the step: without cargo-fuzz (installed here from crates.io
# when missing) or a C++ compiler (libFuzzer is C++), it says why and exits 0.
# FUZZ_SMOKE=skip skips the step.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root/fuzz"
# The web crate's build script would run `npm ci` for the page's three.js when
# web/node_modules is missing: the fuzz targets do not serve the page (the same setting in
# fuzz/run.sh and fuzz/long-run.sh, so that they share one build).
export SPECTRAL_MESH_NO_NPM=1
t0=$SECONDS
budget="${FUZZ_BUDGET:-180}"
min_seconds="${FUZZ_MIN_SECONDS:-3}"
version=0.13.2

skip() {
  echo "fuzz smoke skipped: $*"
  exit 0
}
[ "${FUZZ_SMOKE:-}" = skip ] && skip "FUZZ_SMOKE=skip"

if ! command -v c++ >/dev/null 2>&1 && ! command -v g++ >/dev/null 2>&1 \
   && ! command -v clang++ >/dev/null 2>&1; then
  skip "no C++ compiler (c++, g++ or clang++) to build libFuzzer"
fi
if ! cargo fuzz --version 2>/dev/null | grep -q " $version"; then
  echo "installing cargo-fuzz $version (crates.io)"
  if ! cargo install --locked --quiet cargo-fuzz --version "$version"; then
    skip "cargo-fuzz $version is not installed and could not be installed"
  fi
fi
echo "cargo-fuzz ready: $((SECONDS - t0)) s"

host="$(rustc -vV | sed -n 's/^host: //p')"
if [ -z "${FUZZ_TARGET_DIR:-}" ] && [ "${CI:-}" = true ] && [ -n "${HOME:-}" ]; then
  key="$({ cat Cargo.lock; rustc -vV; cargo fuzz --version; } | sha256sum | cut -c1-16)"
  cache="$HOME/.cache/spectral-mesh"
  export FUZZ_TARGET_DIR="$cache/fuzz-target-$key"
  mkdir -p "$FUZZ_TARGET_DIR"
  touch "$FUZZ_TARGET_DIR"
  # Older keys (another lock file or toolchain): keep the three most recently used.
  ls -dt "$cache"/fuzz-target-* 2>/dev/null | tail -n +4 | xargs -r rm -rf
fi
tdir="${FUZZ_TARGET_DIR:-$root/fuzz/target}"
mkdir -p "$tdir"

if [ "$#" -gt 0 ]; then
  targets=("$@")
else
  mapfile -t targets < <(cargo fuzz list)
fi

bins="$(mktemp -d)"
if [ -n "${FUZZ_CORPUS:-}" ]; then
  corpus="$FUZZ_CORPUS"
  trap 'rm -rf "$bins"' EXIT
else
  # A fresh corpus each run (the committed seeds are the starting point), unless the
  # caller keeps one in FUZZ_CORPUS.
  corpus="$(mktemp -d)"
  trap 'rm -rf "$bins" "$corpus"' EXIT
fi

t_build=$SECONDS
# One build of every target (they share the instrumented library), and this run's copy
# of the binaries, under the folder's lock.
(
  flock 9 2>/dev/null || true
  # (pipefail: the status is cargo's, not tail's.)
  cargo fuzz build -s none --target-dir "$tdir" 2>&1 | tail -3 || exit 1
  for t in "${targets[@]}"; do
    cp "$tdir/$host/release/$t" "$bins/$t" || exit 1
  done
) 9>"$tdir/.fuzz-smoke.lock"
if [ $? -ne 0 ]; then
  echo "fuzz targets did not build" >&2
  exit 1
fi
echo "build: $((SECONDS - t_build)) s"

if [ -n "${FUZZ_SECONDS:-}" ]; then
  seconds="$FUZZ_SECONDS"
else
  left=$((budget - (SECONDS - t0)))
  seconds=$((left / ${#targets[@]}))
  [ "$seconds" -lt "$min_seconds" ] && seconds="$min_seconds"
fi
echo "fuzzing ${#targets[@]} targets, $seconds s each"

mkdir -p logs
summary() {
  grep -a -E '^#[0-9]+.*cov: ' "$1" | tail -1 \
    | sed -E 's/^#([0-9]+)[^c]*cov: ([0-9]+) ft: ([0-9]+) corp: ([^ ]+).*/\1 runs, cov \2, ft \3, corpus \4/'
}
failed=()
t_fuzz=$SECONDS
for t in "${targets[@]}"; do
  log="logs/smoke-$t.log"
  before="$(ls "artifacts/$t" 2>/dev/null | wc -l)"
  if FUZZ_BIN="$bins/$t" FUZZ_CORPUS="$corpus" bash run.sh "$t" "$seconds" >"$log" 2>&1; then
    echo "ok   $t: $(summary "$log")"
    after="$(ls "artifacts/$t" 2>/dev/null | wc -l)"
    if [ "$after" -gt "$before" ]; then
      echo "     warning: $((after - before)) new input(s) of a known open bug in fuzz/artifacts/$t/ (fuzz/known-open.txt)"
    fi
  else
    failed+=("$t")
    echo "FAIL $t"
    grep -a -E -A1 "panicked|ERROR: libFuzzer|Test unit written|Reproduce with" "$log" | head -12
    echo "     reproduce: cargo fuzz run -s none $t fuzz/artifacts/$t/FILE (full log: fuzz/$log)"
  fi
done
echo "fuzz smoke: ${#targets[@]} targets, ${seconds} s each, $((SECONDS - t0)) s in all (budget ${budget} s): build $((t_fuzz - t_build)) s, fuzzing $((SECONDS - t_fuzz)) s"
if [ "${#failed[@]}" -gt 0 ]; then
  echo "failed targets: ${failed[*]} (inputs in fuzz/artifacts/; see fuzz/README.md)" >&2
  exit 1
fi
