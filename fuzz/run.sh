#!/usr/bin/env bash
# Runs one fuzz target with its seeds and dictionary:
#
#   fuzz/run.sh TARGET SECONDS [LIBFUZZER_OPTION ...]
#
# libFuzzer through cargo fuzz, without a sanitizer (`-s none`: stable toolchain, see
# fuzz/README.md), with the limits every finding is judged by: a single input may take
# at most 2 s (`-timeout=2`, a hang otherwise; 10 s for web_body, whose inputs are
# several server requests) and the process at most 2048 MB
# (`-rss_limit_mb`, an out-of-memory otherwise). New inputs go to fuzz/corpus/TARGET
# (not committed); fuzz/seeds/TARGET is read only. A finding is written to
# fuzz/artifacts/TARGET/ and the exit status is non-zero.
#
# A target listed in fuzz/known-open.txt with KIND timeout runs in fork mode with
# -ignore_timeouts=1: its hangs are recorded but do not fail the run.
#
# Environment: FUZZ_SANITIZER (default `none`; `address` needs RUSTC_BOOTSTRAP=1 on the
# stable toolchain), FUZZ_CORPUS (default fuzz/corpus), FUZZ_TARGET_DIR (default
# fuzz/target), FUZZ_BIN (a binary of TARGET built already, e.g. by `cargo fuzz build`:
# it is run as it is, without `cargo fuzz run` and its check of the build; what
# scripts/fuzz-smoke.sh does).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here"
# No `npm ci` from the web crate's build script (as scripts/fuzz-smoke.sh).
export SPECTRAL_MESH_NO_NPM=1
target="${1:?usage: fuzz/run.sh TARGET SECONDS [LIBFUZZER_OPTION ...]}"
seconds="${2:?usage: fuzz/run.sh TARGET SECONDS [LIBFUZZER_OPTION ...]}"
shift 2
dict="$(awk -v t="$target" '$1 == t {print $2}' dicts/targets.txt)"
if [ -z "$dict" ]; then
  echo "unknown fuzz target '$target' (see fuzz/Cargo.toml and fuzz/dicts/targets.txt)" >&2
  exit 2
fi
corpus="${FUZZ_CORPUS:-$here/corpus}/$target"
mkdir -p "$corpus" "$here/seeds/$target"
# web_body's input is up to four server requests, basis jobs included (0.15-0.6 s alone,
# several times that on a loaded machine): not a tiny input, so its hang limit is 10 s.
limit=2
[ "$target" = web_body ] && limit=10
opts=(-max_total_time="$seconds" -timeout="$limit" -rss_limit_mb=2048 -print_final_stats=1)
[ "$dict" != - ] && opts+=(-dict="$here/dicts/$dict.dict")
# A known open hang (known-open.txt): record new ones and go on (fork mode).
if awk -v t="$target" '$1 == t && $2 == "timeout" {f = 1} END {exit !f}' known-open.txt; then
  echo "note: $target has a known open hang (fuzz/known-open.txt): timeouts are recorded, not fatal"
  opts+=(-fork=1 -ignore_timeouts=1)
fi
if [ -n "${FUZZ_BIN:-}" ]; then
  mkdir -p "$here/artifacts/$target"
  echo "fuzzing $target with $FUZZ_BIN; replay a finding with: cargo fuzz run -s none $target fuzz/artifacts/$target/FILE"
  exec "$FUZZ_BIN" -artifact_prefix="$here/artifacts/$target/" "${opts[@]}" "$@" "$corpus" \
    "$here/seeds/$target"
fi
target_dir=()
[ -n "${FUZZ_TARGET_DIR:-}" ] && target_dir=(--target-dir "$FUZZ_TARGET_DIR")
exec cargo fuzz run -s "${FUZZ_SANITIZER:-none}" "${target_dir[@]}" "$target" "$corpus" \
  "$here/seeds/$target" -- "${opts[@]}" "$@"
