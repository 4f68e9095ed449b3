#!/usr/bin/env bash
# End-to-end tests of the web app in headless Chromium (Debian's package) driven by
# playwright-core. Builds the release CLI (`spectral-mesh`, its page assets embedded by
# build.rs), starts `spectral-mesh serve` on a free port of 127.0.0.1, runs
# `node --test web/e2e/*.test.mjs` (release.test.mjs copies the binary to an empty folder
# and serves from there), stops the server. About 2-4 minutes on 2 loaded cores after the
# build (most of it eigenbases: 3torus, a 10k-vertex torus at k = 100).
#   SPECTRAL_MESH_SHARED_MESHES  folder with sphere966.off (default: ../shared/meshes beside
#                                the clone; under CI it must be set)
#   SPECTRAL_MESH_SHARED_POINTS  folder with kitten.xyz (default: the points folder beside
#                                the meshes' folder); points.test.mjs skips its
#                                real-cloud test without it
#   SPECTRAL_MESH_WEB_BENCH=1    also run the ~100k-vertex, k = 200 input-to-picture benchmark
#   SPECTRAL_MESH_SCREENSHOT     where the test saves its screenshot of the app (default:
#                                target/e2e/web-app.png; set it to docs/web-app.png to
#                                refresh the README's picture)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
cd "$ROOT"

bash web/e2e/setup.sh

# The release CLI: SPECTRAL_MESH_CLI when given (scripts/test.sh gives the one its test build
# made), else built here.
BIN=${SPECTRAL_MESH_CLI:-}
if [ -z "$BIN" ]; then
  cargo build --release -q -p spectral-mesh-cli
  BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release/spectral-mesh"
fi
export SPECTRAL_MESH_RELEASE_BIN="$BIN"

if [ -z "${SPECTRAL_MESH_SHARED_MESHES:-}" ] && [ -f "$ROOT/../shared/meshes/sphere966.off" ]; then
  SPECTRAL_MESH_SHARED_MESHES="$ROOT/../shared/meshes"
fi
if [ -z "${SPECTRAL_MESH_SHARED_MESHES:-}" ] && [ "${CI:-}" = true ]; then
  echo "SPECTRAL_MESH_SHARED_MESHES is not set under CI: the tests on shared meshes would be skipped" >&2
  exit 1
fi
export SPECTRAL_MESH_SHARED_MESHES="${SPECTRAL_MESH_SHARED_MESHES:-}"
# The shared point clouds: the points folder beside the meshes' folder.
if [ -z "${SPECTRAL_MESH_SHARED_POINTS:-}" ] && [ -n "$SPECTRAL_MESH_SHARED_MESHES" ]; then
  SPECTRAL_MESH_SHARED_POINTS="$(cd "$SPECTRAL_MESH_SHARED_MESHES/.." && pwd)/points"
fi
export SPECTRAL_MESH_SHARED_POINTS="${SPECTRAL_MESH_SHARED_POINTS:-}"

LOG=$(mktemp)
"$BIN" serve --host 127.0.0.1 --port 0 --cache-mib 2048 >"$LOG" 2>&1 &
PID=$!
cleanup() { kill "$PID" 2>/dev/null || true; wait "$PID" 2>/dev/null || true; rm -f "$LOG"; }
trap cleanup EXIT

URL=""
for _ in $(seq 1 200); do
  URL=$(grep -o 'http://[^ ]*' "$LOG" || true)
  [ -n "$URL" ] && break
  if ! kill -0 "$PID" 2>/dev/null; then cat "$LOG"; echo "server did not start"; exit 1; fi
  sleep 0.1
done
[ -n "$URL" ] || { cat "$LOG"; echo "server printed no URL"; exit 1; }
echo "server at $URL (pid $PID)"
export SPECTRAL_MESH_URL="$URL"
# The screenshot goes to the build folder unless asked for: a test run leaves the
# repository as it found it.
export SPECTRAL_MESH_SCREENSHOT="${SPECTRAL_MESH_SCREENSHOT:-${CARGO_TARGET_DIR:-$ROOT/target}/e2e/web-app.png}"

# Arguments: only these test files (e.g. web/e2e/figures.test.mjs); default all.
if [ $# -gt 0 ]; then
  node --test --test-concurrency=1 "$@"
else
  node --test --test-concurrency=1 "$ROOT"/web/e2e/*.test.mjs
fi
