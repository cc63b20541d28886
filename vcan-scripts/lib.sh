# Shared by demo.sh and test.sh: locate the project and build it.
IRSLAM_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
IRSLAM_BUILD=${IRSLAM_BUILD:-$IRSLAM_ROOT/build}

irslam_build() {  # irslam_build [extra cmake args...]
  bash "$IRSLAM_ROOT/vcan-scripts/install-deps.sh"
  cmake -S "$IRSLAM_ROOT" -B "$IRSLAM_BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
  cmake --build "$IRSLAM_BUILD" -j"$(nproc)"
}

# Prints the bus to use: vcan0 when this kernel has (or can make) it, else a
# loopback bus directory under $1.
irslam_pick_bus() {
  if [ "${IRSLAM_BUS:-}" != "" ]; then echo "$IRSLAM_BUS"; return; fi
  if bash "$IRSLAM_ROOT/vcan-scripts/vcan-up.sh" vcan0 2>/dev/null; then
    echo vcan0
  else
    echo "unix:$1/bus"
  fi
}
