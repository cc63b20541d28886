#!/usr/bin/env bash
# README command 2: installs what is missing, builds, runs every test.
#   vcan-scripts/test.sh [--werror] [--sanitize]
# Unit tests, then the integration tests with real processes (irslam-sim serve +
# irslamd + irslamctl over the loopback bus, time-scaled).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cmake_args=()
# Tests the first ctest run leaves out (beside the cleaning runs through the real
# processes, which run after it).
skip='^CleanE2eTest[.]'
for arg in "$@"; do
  case "$arg" in
    --werror) cmake_args+=(-DIRSLAM_WERROR=ON) ;;
    --sanitize)
      cmake_args+=(-DIRSLAM_SANITIZE=ON)
      IRSLAM_BUILD=$IRSLAM_ROOT/build-asan
      # Instrumented processes are slower: run robot time at 5x, not 10x.
      export IRSLAM_TEST_TIME_SCALE=${IRSLAM_TEST_TIME_SCALE:-5}
      # No benchmarks here: they are timed in the plain build (docs/benchmarks.md).
      cmake_args+=(-DIRSLAM_BENCHMARKS=OFF)
      # The statistical subsets gate rates over generated rooms; the plain build's
      # run checks them on the same seeds (in process a seed fixes the mission), so
      # here they would only repeat it 3x slower. Every code path they take still
      # runs under the sanitizers in the paper-world missions, the cleaning and
      # relocalisation tests and the runs through the real processes.
      skip+='|^Profiles/CampaignSubsetTest[.]|^CleanCampaignSubsetTest[.]'
      skip+='|^RelocTest[.]StopStartAndRelocaliseKeepTheCellsDoneOverWorldsAndSeeds$' ;;
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
# The cleaning runs through the real processes (CleanE2eTest) are one sample each
# of a whole mission whose course differs from run to run with the periods' timing
# (in process a seed fixes it): their plumbing checks are exact, but the mission
# they ride on ends otherwise now and then (4 failures in 28 sanitizer runs,
# docs/reliability.md). They run after the rest, and one that fails is run once
# more (ctest says so); the mission's rates are the campaigns' to gate.
status=0
ctest --output-on-failure -j2 --timeout 600 -E "$skip" || status=$?
ctest --output-on-failure -j2 --timeout 600 -R '^CleanE2eTest[.]' --repeat until-pass:2 || status=$?
exit "$status"
