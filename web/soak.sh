#!/usr/bin/env bash
# Soak test of the web server, on 127.0.0.1 only (see web/soak.mjs for the mix and what
# passes). Starts the release CLI's `serve` with the limits below, runs the clients, and
# prints a table of requests by kind (status codes, p50/p99 latency) and the server's
# memory over time. Not part of CI: the full run takes about SECONDS + 2 minutes.
#   usage: web/soak.sh [SECONDS [CLIENTS [BURST]]]     (defaults 300 16 24)
#          web/soak.sh --quick                        (10 s, 4 clients, burst 4: ~40 s in all)
# Environment: SPECTRAL_MESH_CLI (the CLI binary; default: built with cargo --release),
# SOAK_OUT (the JSON record; default target/soak.json).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
if [ "${1:-}" = "--quick" ]; then
  SECONDS_=10 CLIENTS=4 BURST=4 IDLE=3
else
  SECONDS_=${1:-300} CLIENTS=${2:-16} BURST=${3:-24} IDLE=20
fi
BIN=${SPECTRAL_MESH_CLI:-}
if [ -z "$BIN" ]; then
  cargo build --release -q -p spectral-mesh-cli
  BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release/spectral-mesh"
fi
OUT=${SOAK_OUT:-$ROOT/target/soak.json}
LOG=$(mktemp)
# The limits the soak runs under (web/soak.mjs knows the upload cap, max-k and the
# request deadline).
# mimalloc returns freed pages to the system lazily (see RELIABILITY.md): purge at once so
# that the memory after the load shows what the server holds.
export MIMALLOC_PURGE_DELAY=${MIMALLOC_PURGE_DELAY:-0}
"$BIN" serve --port 0 --memory-mib 768 --cache-mib 384 --max-upload-mib 2 \
  --max-k 200 --max-jobs 2 --max-queued 8 --job-idle-seconds 5 --request-seconds 10 \
  --idle-seconds "$IDLE" >"$LOG" 2>&1 &
PID=$!
cleanup() { kill "$PID" 2>/dev/null || true; wait "$PID" 2>/dev/null || true; rm -f "$LOG"; }
trap cleanup EXIT
URL=""
for _ in $(seq 1 300); do
  URL=$(grep -o 'http://[^ ]*' "$LOG" || true); [ -n "$URL" ] && break
  kill -0 "$PID" 2>/dev/null || break
  sleep 0.1
done
[ -n "$URL" ] || { echo "the server did not start:"; cat "$LOG"; exit 1; }
echo "soak: $URL (pid $PID), ${SECONDS_} s x $CLIENTS clients, burst $BURST; load: $(cut -d' ' -f1-3 /proc/loadavg)"
status=0
node web/soak.mjs "$URL" "$PID" "$SECONDS_" "$CLIENTS" "$BURST" "$IDLE" "$OUT" || status=$?
kill -0 "$PID" 2>/dev/null || { echo "the server died:"; cat "$LOG"; status=1; }
echo "record: $OUT"
exit $status
