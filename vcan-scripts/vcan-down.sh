#!/usr/bin/env bash
# Removes a virtual CAN interface made by vcan-up.sh (default vcan0). Needs root.
set -euo pipefail
iface=${1:-vcan0}
if ip link show "$iface" >/dev/null 2>&1; then
  ip link del dev "$iface"
fi
