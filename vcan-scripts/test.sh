#!/usr/bin/env bash
# README command 2: installs what is missing, builds, runs every test.
#   vcan-scripts/test.sh [--werror] [--sanitize]
# Unit tests, then the integration tests with real processes (irslam-sim serve +
# irslamd + irslamctl over the loopback bus, time-scaled).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cmake_args=()
for arg in "$@"; do
  case "$arg" in
    --werror) cmake_args+=(-DIRSLAM_WERROR=ON) ;;
    --sanitize)
      cmake_args+=(-DIRSLAM_SANITIZE=ON)
      IRSLAM_BUILD=$IRSLAM_ROOT/build-asan
      # Instrumented processes are slower: run robot time at 5x, not 10x.
      export IRSLAM_TEST_TIME_SCALE=${IRSLAM_TEST_TIME_SCALE:-5} ;;
    *) echo "test.sh: unknown option '$arg'" >&2; exit 2 ;;
  esac
done
irslam_build "${cmake_args[@]}"
# The Foxglove test's npm packages (@foxglove/ws-protocol, ws; pinned in
# tests/foxglove/package-lock.json). Without them ctest reports foxglove_node skipped.
if command -v npm >/dev/null && [ ! -f "$IRSLAM_ROOT/tests/foxglove/node_modules/@foxglove/ws-protocol/package.json" ]; then
  (cd "$IRSLAM_ROOT/tests/foxglove" && npm ci --no-audit --no-fund --loglevel=error) ||
    echo "test.sh: npm ci in tests/foxglove failed: the Foxglove node test will be skipped" >&2
fi
cd "$IRSLAM_BUILD"
ctest --output-on-failure -j2 --timeout 600
