#!/usr/bin/env bash
# Bounded load test on 127.0.0.1 only: 8 workers x 200 requests (mixed valid / invalid)
# against the release server with a 256 MiB cache and a 1 MiB upload cap. Passes when
# every valid request succeeds, every invalid one is a 4xx with a message, the server is
# still up, and its peak RSS (VmHWM) stays under the cache cap.
#   usage: web/load_test.sh [WORKERS] [REQUESTS]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
CACHE_MIB=256
cargo build --release -q -p spectral-mesh-web --example serve
BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release/examples/serve"
LOG=$(mktemp)
"$BIN" --host 127.0.0.1 --port 0 --cache-mib "$CACHE_MIB" --max-upload-mib 1 >"$LOG" 2>&1 &
PID=$!
cleanup() { kill "$PID" 2>/dev/null || true; wait "$PID" 2>/dev/null || true; rm -f "$LOG"; }
trap cleanup EXIT
URL=""
for _ in $(seq 1 200); do
  URL=$(grep -o 'http://[^ ]*' "$LOG" || true); [ -n "$URL" ] && break; sleep 0.1
done
[ -n "$URL" ] || { cat "$LOG"; exit 1; }
status=0
node web/load_test.mjs "$URL" "${1:-8}" "${2:-200}" || status=$?
kill -0 "$PID" 2>/dev/null || { echo "server died"; status=1; }
HWM_KB=$(awk '/VmHWM/ {print $2}' "/proc/$PID/status")
echo "server peak RSS: $((HWM_KB / 1024)) MiB (cache cap $CACHE_MIB MiB)"
if [ "$HWM_KB" -ge $((CACHE_MIB * 1024)) ]; then echo "peak RSS over the cache cap"; status=1; fi
exit $status
