#!/usr/bin/env bash
# The control loop's period budget through the real processes (issue 15):
# irslam-sim serve and irslamd on a bus at time scale 1 (real time), the whole
# mission of a world (default: the paper's Fig. 14 room), then the daemon's own
# numbers from `status`: the work per period (p50/p99/p99.9/max, the phase that
# took the worst period), overruns, jitter, the planner's counters; and from
# /proc the daemon's CPU share over the mission and its RSS (now and peak).
# Prints the load average at the start and the end: on a shared host the
# numbers are only as good as the host is quiet.
#   vcan-scripts/tick-bench.sh [WORLD.json] [--time-scale K] [--out DIR]
# Builds nothing: run after building irslamd, irslamctl and irslam-sim in
# $IRSLAM_BUILD (default build/).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
world=$IRSLAM_ROOT/tests/worlds/fig14.json
scale=1
out=$(mktemp -d /tmp/irslam-tick-bench-out.XXXXXX)
while [ $# -gt 0 ]; do
  case "$1" in
    --time-scale) scale=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    -*) echo "tick-bench.sh: unknown option '$1'" >&2; exit 2 ;;
    *) world=$1; shift ;;
  esac
done
bin=$IRSLAM_BUILD
for b in daemon/irslamd daemon/irslamctl sim/irslam-sim; do
  [ -x "$bin/$b" ] || { echo "tick-bench.sh: $bin/$b is not built" >&2; exit 2; }
done
mkdir -p "$out"
out=$(cd "$out" && pwd)
run=$(mktemp -d /tmp/irslam-tick-bench.XXXXXX)
bus=$(irslam_pick_bus "$run")
export IRSLAM_SOCKET=$run/irslamd.sock
echo "tick-bench: world $(basename "$world"), bus $bus, time scale ${scale}x, logs in $out"
echo "tick-bench: load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
irslam_start "$run" "$bus" "$IRSLAM_SOCKET" "$scale" "$out" "$world"
daemon_pid=${IRSLAM_PIDS[1]}
hz=$(getconf CLK_TCK)
cpu_ticks() { awk '{print $14 + $15}' "/proc/$daemon_pid/stat"; }
c0=$(cpu_ticks)
t0=$(date +%s.%N)
"$bin/daemon/irslamctl" start >/dev/null
limit=$(awk "BEGIN{print int(1200/$scale)+5}")
status=0
# Polled every 2 s, not `irslamctl wait` (a 20 Hz status subscription costs the
# daemon ~0.4 % of a core by itself: a client's cost, not the loop's).
end=$(awk "BEGIN{print $(date +%s) + $limit}")
status=1
while [ "$(date +%s)" -lt "${end%.*}" ]; do
  state=$("$bin/daemon/irslamctl" status --json | python3 -c 'import json,sys; print(json.load(sys.stdin)["state"])')
  [ "$state" = done ] && { status=0; break; }
  sleep 2
done
c1=$(cpu_ticks)
t1=$(date +%s.%N)
rss_kb=$(awk '/^VmRSS/{print $2}' "/proc/$daemon_pid/status")
hwm_kb=$(awk '/^VmHWM/{print $2}' "/proc/$daemon_pid/status")
# PSS (shared library pages divided among their users) and the anonymous part.
pss_kb=$(awk '/^Pss:/{print $2}' "/proc/$daemon_pid/smaps_rollup")
anon_kb=$(awk '/^Pss_Anon:/{print $2}' "/proc/$daemon_pid/smaps_rollup")
"$bin/daemon/irslamctl" status --json >"$out/status.json"
echo "tick-bench: load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$out/status.json" "$c0" "$c1" "$t0" "$t1" "$hz" "$rss_kb" "$hwm_kb" "$pss_kb" "$anon_kb" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
c0, c1, t0, t1, hz = (float(x) for x in sys.argv[2:7])
rss, hwm, pss, anon = (int(x) for x in sys.argv[7:11])
p = s["period"]
w = p["work"]
ms = lambda x: "%.3f ms" % (1e3 * x)
print("tick-bench: state %s after %.1f s robot time (%s)" % (s["state"], s["robot_time"], s["reason"]))
print("tick-bench: periods %d, overruns %d, jitter mean %s max %s; loop scheduling %s" % (
    p["ticks"], p["overruns"], ms(p["jitter_mean"]), ms(p["jitter_max"]), p.get("scheduling", "?")))
print("tick-bench: work per period p50 %s, p99 %s, p99.9 %s, max %s (tick alone: max %s)" % (
    ms(w["p50"]), ms(w["p99"]), ms(w["p999"]), ms(w["max"]), ms(p["work_max"])))
print("tick-bench: worst period at robot time %.2f s, mostly %s: %s" % (
    w["worst"]["robot_time"], w["worst"]["phase"],
    ", ".join("%s %s" % (k, ms(v)) for k, v in w["worst"].items() if k not in ("robot_time", "phase"))))
print("tick-bench: phase maxima: " + ", ".join("%s %s" % (k, ms(v)) for k, v in w["phase_max"].items()))
print("tick-bench: planner: " + json.dumps(p.get("planner", {})) + ", loop stalls %d" % p.get("loop_stalls", 0))
print("tick-bench: map store: saves %d, last %s, last_save_ms %.2f" % (
    s["map_store"]["saves"], s["map_store"]["last_result"], s["map_store"]["last_save_ms"]))
print("tick-bench: irslamd CPU %.2f %% of a core over %.1f s wall; RSS %.1f MB (peak %.1f MB), PSS %.1f MB "
      "(anonymous %.1f MB)" % (100 * (c1 - c0) / hz / (t1 - t0), t1 - t0, rss / 1024, hwm / 1024, pss / 1024,
                               anon / 1024))
PY
"$bin/daemon/irslamctl" stop >/dev/null || true
kill -TERM "${IRSLAM_PIDS[0]}" 2>/dev/null || true
if [ $status -ne 0 ]; then
  echo "tick-bench: the mission did not reach 'done' within ${limit}s" >&2
  exit 1
fi
