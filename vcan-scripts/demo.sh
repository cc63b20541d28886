#!/usr/bin/env bash
# README command 1: the whole mission on the simulator, through the real processes.
#   vcan-scripts/demo.sh [WORLD.json] [--mode clean|explore] [--time-scale K] [--out DIR]
# Installs what is missing, builds, starts irslam-sim (the simulated controller)
# and irslamd on vcan0 if this kernel has it, else on the loopback bus, starts the
# mission with irslamctl (by default mode clean: map the room, clean its floor,
# return to the start), shows progress, and writes DIR/map.json and DIR/map.svg
# (with the cleaned cells and the covered floor; DIR defaults to ./demo-out).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
world=$IRSLAM_ROOT/tests/worlds/fig14.json
scale=10
mode=clean
out=$PWD/demo-out
while [ $# -gt 0 ]; do
  case "$1" in
    --time-scale) scale=$2; shift 2 ;;
    --mode) mode=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    -*) echo "demo.sh: unknown option '$1'" >&2; exit 2 ;;
    *) world=$1; shift ;;
  esac
done
irslam_build
mkdir -p "$out"
out=$(cd "$out" && pwd)
run=$(mktemp -d /tmp/irslam-demo.XXXXXX)
bus=$(irslam_pick_bus "$run")
export IRSLAM_SOCKET=$run/irslamd.sock
bin=$IRSLAM_BUILD

echo "demo: world $(basename "$world"), mode $mode, bus $bus, time scale ${scale}x, output in $out"
irslam_start "$run" "$bus" "$IRSLAM_SOCKET" "$scale" "$out" "$world" --truth-out "$out/truth.json"
"$bin/daemon/irslamctl" start --mode "$mode"
"$bin/daemon/irslamctl" watch &
watch_pid=$!
# Robot-time budget: the mission's 900 s limit, and as long again for cleaning.
budget=1200
[ "$mode" = clean ] && budget=2400
limit=$(awk "BEGIN{print int($budget/$scale)+5}")
status=0
"$bin/daemon/irslamctl" wait --state done --timeout "$limit" || status=$?
kill $watch_pid 2>/dev/null || true
echo
"$bin/daemon/irslamctl" map --out "$out/map.json" --svg "$out/map.svg"
"$bin/daemon/irslamctl" status
"$bin/daemon/irslamctl" stop >/dev/null
kill -TERM "${IRSLAM_PIDS[0]}" 2>/dev/null || true
wait "${IRSLAM_PIDS[0]}" 2>/dev/null || true
if [ $status -ne 0 ]; then
  echo "demo: the mission did not reach 'done' within ${limit}s; the map so far is in $out/map.json" >&2
  exit 1
fi
echo "demo: done. Map: $out/map.json, picture: $out/map.svg, truth: $out/truth.json"
