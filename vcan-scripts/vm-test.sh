#!/usr/bin/env bash
# The real SocketCAN path, tested: boots Debian's stock kernel in a VM (qemu; KVM
# where usable, software emulation otherwise) with vcan0, and runs the
# integration tests there on vcan0 through the SocketCAN backend, with can-utils'
# cansend/candump beside them.
#   vcan-scripts/vm-test.sh [GTEST_FILTER]
# Exit status: the tests'; 77 when this host cannot run the VM (said why).
# Cache (kernel, modules, gpio-sim): $IRSLAM_VM_CACHE, default /var/tmp/irslam-vm-cache,
# kept between runs on the same machine (~225 MB, ~30 s the first time).
# On a host that has vcan itself, no VM is needed:
#   sudo vcan-scripts/vcan-up.sh vcan0 && IRSLAM_TEST_CAN=vcan0 build/tests/integration_test
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# The VM suite is about the SocketCAN and GPIO paths. Left to the host suite: the
# whole mission (exploration quality under 2x software emulation, ~2.5 min), the
# kill -9 and the hung-loop watchdog tests (they test the daemon's persistence
# and watchdog, not the bus; the hung-loop test did not finish in the VM within
# 10 min and is not understood yet).
filter=${1:-'E2eTest.*:-E2eTest.WholeMission*:E2eTest.KillNine*:E2eTest.AHung*'}
cache=${IRSLAM_VM_CACHE:-/var/tmp/irslam-vm-cache}
scale=${IRSLAM_VM_TIME_SCALE:-2}

if ! bash "$IRSLAM_ROOT/vcan-scripts/install-deps.sh" --vm; then
  echo "vm-test: skipped: cannot install qemu/busybox (install-deps.sh --vm failed)" >&2
  exit 77
fi
avail_mb=$(df -Pm "$(dirname "$cache")" | awk 'NR==2 {print $4}')
if [ "${avail_mb:-0}" -lt 1024 ]; then
  echo "vm-test: skipped: less than 1 GiB free for the VM cache at $(dirname "$cache")" >&2
  exit 77
fi
irslam_build
cd "$IRSLAM_ROOT"
# The VM shares this directory read-write and the host's root read-only.
# gpio-sim: 8 lines of chip gpio-sim-robot, the first five named for the GPIO test.
RUN_IN_VM_GPIO_LABEL=gpio-sim-robot RUN_IN_VM_GPIO_LINES=8 \
  RUN_IN_VM_GPIO_NAMES=estop,bumper-left,bumper-right,motor-enable,status-led \
  RUN_IN_VM_CACHE=$cache RUN_IN_VM_TIMEOUT=${IRSLAM_VM_TIMEOUT:-2400} \
  bash vcan-scripts/run-in-vm.sh -- env IRSLAM_TEST_CAN=vcan0 IRSLAM_TEST_TIME_SCALE="$scale" \
  "$IRSLAM_BUILD/tests/integration_test" --gtest_filter="$filter"
