#!/usr/bin/env bash
# The soak test (not part of every CI run; `cmake --build build --target soak`):
# irslam-sim serve + irslamd for HOURS of robot time (default 2), time-scaled,
# with faults injected all along (loss, duplicates, reordering, corruption, loss
# bursts, a foreign-id flood, a stuck IR sensor, an encoder glitch, a controller
# silence with reset), the mission started again each time it ends, the map read
# now and then. Samples irslamd's RSS and open fds every 10 s of wall time into
# OUT/soak.csv and fails when either grows (last quarter vs second quarter: RSS
# by more than 10 %, fds at all), when the daemon died, or when a sanitizer spoke.
#   vcan-scripts/soak.sh [--hours H] [--time-scale K] [--sanitize] [--out DIR]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
hours=2
scale=20
out=$PWD/soak-out
build_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --hours) hours=$2; shift 2 ;;
    --time-scale) scale=$2; shift 2 ;;
    --sanitize) build_args+=(-DIRSLAM_SANITIZE=ON); IRSLAM_BUILD=$IRSLAM_ROOT/build-asan; scale=10; shift ;;
    --out) out=$2; shift 2 ;;
    *) echo "soak.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
irslam_build "${build_args[@]}"
mkdir -p "$out"
out=$(cd "$out" && pwd)
run=$(mktemp -d /tmp/irslam-soak.XXXXXX)
bus="unix:$run/bus"
sock=$run/irslamd.sock
bin=$IRSLAM_BUILD
robot_s=$(awk "BEGIN{print int($hours*3600)}")
wall_s=$(awk "BEGIN{print int($robot_s/$scale)+1}")
faults="loss:p=0.01,duplicate:p=0.01,reorder:p=0.01,delay:p=0.01:max=0.02,corrupt:p=0.002"
faults+=",burst:every=97:len=0.05,flood:at=600:for=300:rate=2000,stuck_ir:sensor=5:at=1200:for=600"
faults+=",encoder_glitch:at=3000:counts=2000,silence:at=4000:for=1.5:reset=1"
echo "soak: ${hours} h of robot time at ${scale}x (${wall_s} s wall), faults: $faults" >&2
irslam_start "$run" "$bus" "$sock" "$scale" "$out" "$IRSLAM_ROOT/tests/worlds/fig14.json" --faults "$faults"
dpid=${IRSLAM_PIDS[1]}
ctl() { "$bin/daemon/irslamctl" --socket "$sock" "$@"; }
echo "wall_s,robot_s,rss_kb,fds,state,missions" > "$out/soak.csv"
missions=0
start=$(date +%s)
while :; do
  now=$(date +%s)
  el=$((now - start))
  [ "$el" -ge "$wall_s" ] && break
  kill -0 "$dpid" 2>/dev/null || { echo "soak: irslamd died" >&2; exit 1; }
  state=$(ctl status 2>/dev/null | sed -n 's/^state: *\([a-z_]*\).*/\1/p' | head -1)
  if [ "$state" = "idle" ] || [ "$state" = "done" ]; then
    ctl start >/dev/null 2>&1 && missions=$((missions + 1))
  fi
  ctl map --out "$run/map.json" >/dev/null 2>&1 || true
  rss=$(awk '/^VmRSS/ {print $2}' "/proc/$dpid/status")
  fds=$(ls "/proc/$dpid/fd" | wc -l)
  echo "$el,$((el * scale)),$rss,$fds,$state,$missions" >> "$out/soak.csv"
  sleep 10
done
kill -TERM "$dpid"
wait "$dpid" || { echo "soak: irslamd exited with an error" >&2; exit 1; }
if grep -q "Sanitizer" "$out/irslamd.log"; then
  echo "soak: a sanitizer reported an error (see $out/irslamd.log)" >&2
  exit 1
fi
# Flat: the last quarter of the samples against the second quarter (the first is
# warm-up: the map grows during the first mission, and under ASan its quarantine
# of freed memory, 256 MB, fills).
awk -F, 'NR > 1 { rss[n] = $3; fds[n] = $4; n++ }
  END {
    q = int(n / 4); if (q < 1) { print "soak: too few samples"; exit 1 }
    for (i = 0; i < q; i++) { r0 += rss[q + i]; r1 += rss[n - q + i]; if (fds[q+i] > f0) f0 = fds[q+i]; if (fds[n-q+i] > f1) f1 = fds[n-q+i] }
    r0 /= q; r1 /= q
    printf "soak: %d samples; RSS %.0f -> %.0f kB (%+.1f %%); fds %d -> %d\n", n, r0, r1, 100 * (r1 - r0) / r0, f0, f1
    if (r1 > 1.10 * r0 || f1 > f0) exit 1
  }' "$out/soak.csv"
echo "soak: ${missions} missions started; passed" >&2
