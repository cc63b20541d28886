#!/usr/bin/env bash
# Fuzzes every parser irslamd and irslam-sim expose (libFuzzer, clang, with
# AddressSanitizer + UndefinedBehaviorSanitizer): JSON-RPC request lines, whole
# API sessions (many lines on one connection through the real server), CAN
# frames (through the decoder, the controller client and the whole core), world
# files, config files, the daemon's saved-map files and candump -L logs. Each
# runs SECONDS (default 60) from its committed seed corpus in
# tests/fuzz/corpus/<name>/ plus the corpus grown by earlier runs; any crash
# fails (exit 1) and leaves its input in build-fuzz/artifacts/.
#   vcan-scripts/fuzz.sh [SECONDS] [TARGET...]
# Environment:
#   IRSLAM_FUZZ_STATE  where the grown corpora, the logs and the ledger are kept
#                      (default build-fuzz/); point it at a directory the CI keeps
#                      between runs and the corpora and the execution totals
#                      accumulate across runs at no extra time.
#   IRSLAM_FUZZ_RUNS   also stop each target after this many executions.
#   IRSLAM_FUZZ_NICE   run the fuzzers at this niceness (e.g. 19 for a long
#                      campaign on a shared machine).
#   IRSLAM_FUZZ_JOBS   targets fuzzed at once (default: the number of cores);
#                      each has SECONDS on a core of its own.
# Every run appends one line per target to $IRSLAM_FUZZ_STATE/ledger.tsv (UTC
# end time, target, seconds, executions, result, commit) and prints each target's
# total over the ledger; its libFuzzer log (final stats included) is kept in
# $IRSLAM_FUZZ_STATE/logs/.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(jsonrpc api_session can world config map replay)

bash "$IRSLAM_ROOT/vcan-scripts/install-deps.sh" --fuzz
build=$IRSLAM_ROOT/build-fuzz
state=${IRSLAM_FUZZ_STATE:-$build}
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
CC=clang CXX=clang++ cmake -S "$IRSLAM_ROOT" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DIRSLAM_FUZZ=ON -DIRSLAM_BENCHMARKS=OFF -DIRSLAM_WERROR=ON "${launcher[@]}" >/dev/null
cmake --build "$build" -j"$(nproc)" --target fuzz_all

commit=$(git -C "$IRSLAM_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
mkdir -p "$build/artifacts" "$state/logs"
ledger=$state/ledger.tsv
[ -f "$ledger" ] || printf 'ended\ttarget\tseconds\texecutions\tresult\tcommit\n' >"$ledger"
extra=()
[ -z "${IRSLAM_FUZZ_RUNS:-}" ] || extra+=(-runs="$IRSLAM_FUZZ_RUNS")
# One target: its run, its log, its ledger line. Returns 1 on a crash or an interrupt.
fuzz_one() {
  local t=$1 work log start result rc execs
  work=$state/corpus/$t  # new inputs go here, the committed seeds stay as they are
  mkdir -p "$work"
  # The shipped config is a seed too (not copied into the corpus: one file).
  if [ "$t" = config ]; then cp "$IRSLAM_ROOT/daemon/irslamd.conf" "$work/shipped.conf"; fi
  # (The pid: two runs of one target on one corpus may start in the same second.)
  log=$state/logs/$t-$(date -u +%Y%m%dT%H%M%SZ)-$$.log
  echo "fuzz.sh: $t for ${seconds}s" >&2
  start=$(date +%s)
  result=ok
  rc=0
  nice -n "${IRSLAM_FUZZ_NICE:-0}" "$build/tests/fuzz/fuzz_$t" -max_total_time="$seconds" \
    -timeout=10 -rss_limit_mb=2048 -max_len=8192 -print_final_stats=1 "${extra[@]}" \
    -artifact_prefix="$build/artifacts/$t-" "$work" "$IRSLAM_ROOT/tests/fuzz/corpus/$t" 2>"$log" || rc=$?
  if [ "$rc" -eq 72 ]; then  # libFuzzer's exit code after SIGINT: stopped by hand, stats printed
    echo "fuzz.sh: $t interrupted" >&2
    result=interrupted
  elif [ "$rc" -ne 0 ]; then
    echo "fuzz.sh: $t FAILED (log: $log; input in $build/artifacts/)" >&2
    tail -40 "$log" >&2
    result=crash
  fi
  cp "$log" "$build/$t.log"
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$t" "$(( $(date +%s) - start ))" \
    "${execs:-0}" "$result" "$commit" >>"$ledger"
  grep -E "stat::number_of_executed_units|cov:" "$log" | tail -2 >&2 || true
  awk -F'\t' -v t="$t" 'NR > 1 && $2 == t { n += $4; s += $3; if ($5 == "crash") c++ }
    END { printf "fuzz.sh: %s in total (%s): %d executions, %d s, %d crashes\n", t, FILENAME, n, s, c }' \
    "$ledger" >&2
  [ "$result" = ok ]
}

# The targets run side by side, one per core (IRSLAM_FUZZ_JOBS, default nproc):
# each still gets its SECONDS on a core of its own, and the whole run takes
# ceil(targets / jobs) x SECONDS instead of targets x SECONDS.
jobs_max=${IRSLAM_FUZZ_JOBS:-$(nproc)}
status=0
pids=()
for t in "${targets[@]}"; do
  fuzz_one "$t" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$jobs_max" ]; then
    for p in "${pids[@]}"; do wait "$p" || status=1; done
    pids=()
  fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
