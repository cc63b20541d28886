#!/usr/bin/env bash
# Fuzzes every parser irslamd and irslam-sim expose (libFuzzer, clang, with
# AddressSanitizer + UndefinedBehaviorSanitizer): JSON-RPC request lines, whole
# API sessions (many lines on one connection through the real server), CAN
# frames (through the decoder, the controller client and the whole core), world
# files, config files and the daemon's saved-map files. Each runs SECONDS (default 60) from its committed seed
# corpus in tests/fuzz/corpus/<name>/; any crash fails (exit 1) and leaves its
# input in build-fuzz/artifacts/.
#   vcan-scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(jsonrpc api_session can world config map replay)

bash "$IRSLAM_ROOT/vcan-scripts/install-deps.sh" --fuzz
build=$IRSLAM_ROOT/build-fuzz
CC=clang CXX=clang++ cmake -S "$IRSLAM_ROOT" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DIRSLAM_FUZZ=ON -DIRSLAM_BENCHMARKS=OFF -DIRSLAM_WERROR=ON >/dev/null
cmake --build "$build" -j"$(nproc)" --target fuzz_all

mkdir -p "$build/artifacts"
status=0
for t in "${targets[@]}"; do
  work=$build/corpus/$t  # new inputs go here, the committed seeds stay as they are
  mkdir -p "$work"
  # The shipped config is a seed too (not copied into the corpus: one file).
  if [ "$t" = config ]; then cp "$IRSLAM_ROOT/daemon/irslamd.conf" "$work/shipped.conf"; fi
  echo "fuzz.sh: $t for ${seconds}s" >&2
  if ! "$build/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
       -max_len=8192 -print_final_stats=1 -artifact_prefix="$build/artifacts/$t-" \
       "$work" "$IRSLAM_ROOT/tests/fuzz/corpus/$t" 2>"$build/$t.log"; then
    echo "fuzz.sh: $t FAILED (log: $build/$t.log; input in $build/artifacts/)" >&2
    tail -40 "$build/$t.log" >&2
    status=1
  else
    grep -E "stat::number_of_executed_units|cov:" "$build/$t.log" | tail -2 >&2 || true
  fi
done
exit $status
