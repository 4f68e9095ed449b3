#!/usr/bin/env bash
# The long fuzz run of RELIABILITY.md: builds every target once (no sanitizer, or
# FUZZ_SANITIZER=address with RUSTC_BOOTSTRAP=1), copies the binaries aside (so a rebuild
# while it runs changes nothing), then runs each target for SECONDS under `nice -n 19`,
# FUZZ_JOBS targets at a time (default 1), with the limits of fuzz/run.sh (2 s per input,
# 2048 MB) and a corpus kept in fuzz/corpus/TARGET across runs. Findings go to
# fuzz/artifacts/TARGET/; the first crash, hang or out-of-memory stops that target (except
# a known open hang of known-open.txt: fork mode records those and goes on). After each
# target its corpus is replayed once to print the coverage reached (`cov`, `ft`, corpus
# size) into fuzz/logs/long-summary.txt, with the runs and the mean executions per second.
#
#   bash fuzz/long-run.sh SECONDS [TARGET ...]        # default: every target
#   FUZZ_JOBS=2 bash fuzz/long-run.sh 180             # two targets at a time
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here"
# No `npm ci` from the web crate's build script (as scripts/fuzz-smoke.sh).
export SPECTRAL_MESH_NO_NPM=1
seconds="${1:?usage: fuzz/long-run.sh SECONDS [TARGET ...]}"
shift
san="${FUZZ_SANITIZER:-none}"
jobs="${FUZZ_JOBS:-1}"
if [ "$#" -gt 0 ]; then targets=("$@"); else mapfile -t targets < <(cargo fuzz list); fi
# One target: build that one only (cargo fuzz build takes one name or none).
only=()
[ "${#targets[@]}" -eq 1 ] && only=("${targets[0]}")
nice -n 19 cargo fuzz build -s "$san" "${only[@]}" || exit 1
bin="$here/target/long-run-bin-$san"
rm -rf "$bin" && mkdir -p "$bin" logs
for t in "${targets[@]}"; do
  cp "$here/target/x86_64-unknown-linux-gnu/release/$t" "$bin/"
done
echo "commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- .. || echo '+changes'), sanitizer $san, ${seconds} s per target, $jobs at a time, started $(date -u +%FT%TZ), load $(cut -d' ' -f1-3 /proc/loadavg)" \
  | tee -a logs/long-summary.txt

run_one() {
  local t="$1"
  local dict log opts t0 rc cov execs rate found
  dict="$(awk -v t="$t" '$1 == t {print $2}' dicts/targets.txt)"
  log="logs/long-$t.log"
  mkdir -p "corpus/$t" "artifacts/$t"
  opts=(-max_total_time="$seconds" -timeout=2 -rss_limit_mb=2048 -print_final_stats=1
        -artifact_prefix="$here/artifacts/$t/")
  # Fork mode (which goes on after a hang) only for a known open hang; elsewhere the
  # first finding stops the target, to be fixed before fuzzing on.
  if awk -v t="$t" '$1 == t && $2 == "timeout" {f = 1} END {exit !f}' known-open.txt; then
    opts+=(-fork=1 -ignore_timeouts=1)
  fi
  [ -n "$dict" ] && [ "$dict" != - ] && opts+=(-dict="$here/dicts/$dict.dict")
  t0=$SECONDS
  nice -n 19 "$bin/$t" "${opts[@]}" "corpus/$t" "seeds/$t" >"$log" 2>&1
  rc=$?
  cov="$(nice -n 19 "$bin/$t" -runs=0 "corpus/$t" 2>&1 | grep -a -m1 'INITED' | sed 's/.*INITED //')"
  # Executions: libFuzzer's final statistics, or the last status line of fork mode.
  execs="$(grep -a 'stat::number_of_executed_units' "$log" | tail -1 | awk '{print $2}')"
  [ -n "$execs" ] || execs="$(grep -a -E '^#[0-9]+: cov' "$log" | tail -1 | sed -E 's/^#([0-9]+):.*/\1/')"
  rate="$(grep -a 'stat::average_exec_per_sec' "$log" | tail -1 | awk '{print $2}')"
  [ -n "$rate" ] || rate="$(grep -a -E '^#[0-9]+: cov' "$log" | tail -1 | sed -E 's/.*exec\/s:? ([0-9]+).*/\1/')"
  found="$(ls "artifacts/$t" | wc -l)"
  echo "$t: rc $rc, $((SECONDS - t0)) s, runs $execs, exec/s $rate, corpus replay: $cov, artifacts $found" \
    | tee -a logs/long-summary.txt
}

running=0
for t in "${targets[@]}"; do
  run_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n
    running=$((running - 1))
  fi
done
wait
echo "finished $(date -u +%FT%TZ)" | tee -a logs/long-summary.txt
