#!/usr/bin/env bash
# Checks systemd/irslamd.service: `systemd-analyze verify` is clean and the
# offline security exposure is at most 3.0 (docs/systemd.md records the score).
set -euo pipefail
src=$1
bin=$2
command -v systemd-analyze >/dev/null || { echo "systemd-analyze missing"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The unit names /usr/bin/irslamd; point it at the build's binary for the check.
sed "s|/usr/bin/irslamd|$bin/daemon/irslamd|" "$src/systemd/irslamd.service" > "$tmp/irslamd.service"
out=$(systemd-analyze verify "$tmp/irslamd.service" 2>&1 || true)
if [ -n "$out" ]; then
  echo "systemd-analyze verify: $out"
  exit 1
fi
score=$(systemd-analyze security --offline=true "$tmp/irslamd.service" 2>&1 |
        sed -n 's/.*Overall exposure level for irslamd.service: \([0-9.]*\).*/\1/p')
echo "exposure: $score"
# A stalled loop stops the WATCHDOG=1 pings: systemd must then kill and restart it.
unit=$src/systemd/irslamd.service
grep -qx 'WatchdogSec=2s' "$unit" || { echo "no WatchdogSec=2s"; exit 1; }
grep -qx 'Restart=on-failure' "$unit" || { echo "no Restart=on-failure (restarts after a watchdog timeout)"; exit 1; }
grep -qx 'NotifyAccess=main' "$unit" || { echo "no NotifyAccess=main"; exit 1; }
awk -v s="$score" 'BEGIN { exit !(s != "" && s <= 3.0) }'
echo "1 passed, 0 failed"
