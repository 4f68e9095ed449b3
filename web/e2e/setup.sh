#!/usr/bin/env bash
# Installs what the browser tests need: Debian's chromium (apt) and, unless
# --browser-only, the page's npm packages (three.js, playwright-core) in web/node_modules.
# Idempotent: does nothing for what is there. apt waits up to 10 minutes for another
# install (a benchmark's set-up, say) to release its lock. scripts/test.sh runs it with
# --browser-only beside the Rust build (the web crate's build script runs `npm ci`
# itself); web/e2e/run.sh runs it whole.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
cd "$ROOT"
if [ ! -x /usr/bin/chromium ]; then
  apt-get -o DPkg::Lock::Timeout=600 update -qq && apt-get -o DPkg::Lock::Timeout=600 install -y -qq chromium >/dev/null
fi
if [ "${1:-}" != --browser-only ] \
   && { [ ! -d web/node_modules/three ] || [ ! -d web/node_modules/playwright-core ]; }; then
  (cd web && npm ci --no-audit --no-fund)
fi
