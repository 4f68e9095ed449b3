#!/usr/bin/env bash
# End-to-end tests of the web app in headless Chromium (Debian's package) driven by
# playwright-core. Builds the release CLI (`spectral-mesh`, its page assets embedded by
# build.rs), starts `spectral-mesh serve` on a free port of 127.0.0.1, runs
# `node --test web/e2e/*.test.mjs` (release.test.mjs copies the binary to an empty folder
# and serves from there), stops the server. About 2-4 minutes on 2 loaded cores after the
# build (most of it eigenbases: 3torus, a 10k-vertex torus at k = 100).
#   SPECTRAL_MESH_SHARED_MESHES  folder with sphere966.off (default: ../shared/meshes beside
#                                the clone, then /work/shared/meshes)
#   SPECTRAL_MESH_SHARED_POINTS  folder with kitten.xyz (default: ../shared/points beside the
#                                clone, then /work/shared/points); points.test.mjs skips its
#                                real-cloud test without it
#   SPECTRAL_MESH_WEB_BENCH=1    also run the ~100k-vertex, k = 200 input-to-picture benchmark
#   SPECTRAL_MESH_SCREENSHOT     where the test saves its screenshot of the app (default:
#                                target/e2e/web-app.png; set it to docs/web-app.png to
#                                refresh the README's picture)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
cd "$ROOT"

if [ ! -x /usr/bin/chromium ]; then
  apt-get update -qq && apt-get install -y -qq chromium >/dev/null
fi
if [ ! -d web/node_modules/three ] || [ ! -d web/node_modules/playwright-core ]; then
  (cd web && npm ci --no-audit --no-fund)
fi

cargo build --release -q -p spectral-mesh-cli
BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release/spectral-mesh"
export SPECTRAL_MESH_RELEASE_BIN="$BIN"

if [ -z "${SPECTRAL_MESH_SHARED_MESHES:-}" ]; then
  for d in "$ROOT/../shared/meshes" /work/shared/meshes; do
    if [ -f "$d/sphere966.off" ]; then SPECTRAL_MESH_SHARED_MESHES="$d"; break; fi
  done
fi
export SPECTRAL_MESH_SHARED_MESHES="${SPECTRAL_MESH_SHARED_MESHES:-}"
if [ -z "${SPECTRAL_MESH_SHARED_POINTS:-}" ]; then
  for d in "$ROOT/../shared/points" /work/shared/points; do
    if [ -f "$d/kitten.xyz" ]; then SPECTRAL_MESH_SHARED_POINTS="$d"; break; fi
  done
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
