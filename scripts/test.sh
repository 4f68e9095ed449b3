#!/usr/bin/env bash
# Runs every test: format and lint checks, the Rust test suite, and the conformance
# suite against libigl and SciPy (installed into .venv on first use).
#
# Real meshes: set SPECTRAL_MESH_SHARED_MESHES to the folder of shared meshes
# (.ci/run sets it to ../shared/meshes). Unset, the tests that need them say they
# were skipped; set to a missing folder, they fail.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
passed=0
failed=0
failures=()
step() {
  local name="$1"; shift
  echo "=== $name"
  local t0=$SECONDS
  if "$@"; then
    passed=$((passed + 1)); echo "--- ok: $name ($((SECONDS - t0)) s)"
  else
    failed=$((failed + 1)); failures+=("$name"); echo "--- FAILED: $name ($((SECONDS - t0)) s)"
  fi
}

# A clean build needs a few GB (debug + release targets, the Python venv, Chromium). A
# full disk otherwise shows up as a linker crash ("Bus error") deep in cargo test.
free_kb=$(df -Pk . | awk 'NR==2 {print $4}')
echo "disk: $((free_kb / 1024)) MiB free in $root"
if [ "${free_kb:-0}" -lt $((6 * 1024 * 1024)) ]; then
  echo "warning: less than 6 GiB free; the build may fail with 'No space left on device'" >&2
fi

if [ -n "${SPECTRAL_MESH_SHARED_MESHES:-}" ] && [ ! -d "$SPECTRAL_MESH_SHARED_MESHES" ]; then
  echo "SPECTRAL_MESH_SHARED_MESHES=$SPECTRAL_MESH_SHARED_MESHES is not a folder" >&2
  exit 1
fi

# Installs that wait on the network rather than the processors run beside the Rust build:
# the Python peers (scripts/setup-python.sh) and Debian's chromium for the browser tests.
# Their output goes to target/ci-logs; the steps that need them wait for them.
mkdir -p target/ci-logs
bash scripts/setup-python.sh >target/ci-logs/python-path 2>target/ci-logs/setup-python.log &
setup_python=$!
bash web/e2e/setup.sh --browser-only >target/ci-logs/setup-browser.log 2>&1 &
setup_browser=$!
# SLEPc for conformance/check_slepc.sh (Debian's python3-slepc4py; apt waits for the
# browser's install to release its lock). Waited for before the conformance checks; the
# check runs the same script, which then finds it installed (or says why it is not).
bash bench/setup-slepc.sh >target/ci-logs/slepc-python 2>target/ci-logs/setup-slepc.log &
setup_slepc=$!

step "cargo fmt --check" cargo fmt --all -- --check
# One build serves everything: clippy and the tests use the release profile, so the tests,
# the CLI the conformance scripts run, the browser tests' server and the Python wheel share
# the same compiled dependencies (and clippy shares their build scripts and macros).
step "cargo clippy" cargo clippy --release --workspace --all-targets --quiet -- -D warnings
# Also replays every fuzz seed and regression input through its target's checks
# (crates/spectral-mesh-fuzz); the fuzzing itself is scripts/fuzz-smoke.sh and
# fuzz/long-run.sh, run apart (RELIABILITY.md).
step "cargo test" cargo test --release --workspace --quiet --no-fail-fast
# Every public item's documentation builds without a broken or private link (the release
# profile shares the build scripts and macros compiled above).
step "cargo doc" env RUSTDOCFLAGS="-D warnings" cargo doc --release --workspace --no-deps --quiet
# The CLI the tests ran (their build made it, with the workspace's features: a separate
# `cargo build -p spectral-mesh-cli` would resolve them otherwise and rebuild the library).
cli="$root/target/release/spectral-mesh"
step "release CLI from the test build" test -x "$cli"

if ! wait "$setup_python"; then
  cat target/ci-logs/setup-python.log
  echo "python peers could not be installed"; exit 1
fi
py="$(cat target/ci-logs/python-path)"
wait "$setup_slepc" || cat target/ci-logs/setup-slepc.log
if [ -n "${SPECTRAL_MESH_SHARED_MESHES:-}" ]; then
  meshes=("$SPECTRAL_MESH_SHARED_MESHES"/*.off)
  step "conformance: operators vs libigl" "$py" conformance/operators_libigl.py --cli "$cli" "${meshes[@]}"
else
  echo "skipped: conformance on shared meshes (SPECTRAL_MESH_SHARED_MESHES unset)"
fi
for s in conformance/check_*.sh; do
  [ -e "$s" ] || continue
  step "conformance: $(basename "$s" .sh)" bash "$s" "$cli" "$py"
done

# The Python package: a release wheel built by pip (maturin) into the conformance venv,
# then its pytest suite (conformance with libigl, robust-laplacian, SciPy, LaPy; inputs;
# threads and Ctrl-C). Measured: 3-8 min for the build from scratch on 2 cores, about
# 1 min for the tests.
step "python package (build, install, pytest)" env SPECTRAL_MESH_CLI="$cli" bash scripts/test-python.sh

# The web server under a bounded load (about 40 s; the long soak is web/soak.sh).
step "web server soak (quick)" env SPECTRAL_MESH_CLI="$cli" SOAK_OUT="$root/target/soak-quick.json" bash web/soak.sh --quick

# The web app in headless Chromium (Debian's chromium, installed above beside the build).
wait "$setup_browser" || { cat target/ci-logs/setup-browser.log; echo "chromium could not be installed (the browser step will say why)"; }
step "web app end-to-end (headless Chromium)" env SPECTRAL_MESH_CLI="$cli" bash web/e2e/run.sh

echo
echo "disk: target folder $(du -sh target 2>/dev/null | cut -f1), $(($(df -Pk . | awk 'NR==2 {print $4}') / 1024)) MiB free"
if [ "$failed" -gt 0 ]; then
  printf 'failed step: %s\n' "${failures[@]}"
fi
echo "steps: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
