#!/usr/bin/env bash
# Creates and brings up a virtual CAN interface (default vcan0). Needs root.
#   vcan-scripts/vcan-up.sh [IFACE]
# Exit status 0 when the interface is up; 1 with a message when this kernel has
# no vcan (use the loopback bus then: --can unix:PATH).
set -euo pipefail
iface=${1:-vcan0}
if ip link show "$iface" >/dev/null 2>&1; then
  ip link set "$iface" up
  exit 0
fi
modprobe vcan 2>/dev/null || true
if ! ip link add dev "$iface" type vcan 2>/dev/null; then
  echo "vcan-up: cannot create $iface: this kernel has no vcan support (use --can unix:PATH)" >&2
  exit 1
fi
ip link set "$iface" up
echo "vcan-up: $iface is up" >&2
