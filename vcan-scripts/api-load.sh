#!/usr/bin/env bash
# The worst API load we can make within the client limit, against a running
# mission at time scale 1 (issue 12): irslam-sim serve + irslamd on the loopback
# bus, a mission started, then for SECONDS (default 30) api.max_clients hostile
# clients at once:
#   - pipelining maximum-size lines of '[' (rejected by the depth check),
#   - pipelining maximum-size valid `status` requests (padded params: a full parse),
#   - pipelining `map` requests (map floods), reading the answers,
#   - subscribing at the maximum rate (50 Hz),
#   - slowloris and idle connections that try to hold slots,
# every client reconnecting at once when closed. Meanwhile one more client,
# the measurer, subscribes at 50 Hz and keeps each period's `jitter_last` (the
# notification payload is built once per period, so this samples the periods);
# irslamd's watchdog pings go to a NOTIFY_SOCKET we read (WATCHDOG_USEC=2 s,
# pings every 1 s). At the end a `stop` must get through, and it prints the
# period statistics, the sampled jitter percentiles, the watchdog gaps, the API
# counters and the load average.
#   vcan-scripts/api-load.sh [SECONDS]      (IRSLAM_BUILD=dir of a built tree)
#   API_LOAD_CLIENTS=0 vcan-scripts/api-load.sh   the same measurement without load
#   API_LOAD_NICE=19 vcan-scripts/api-load.sh     the load client niced
#   API_LOAD_RT=0 vcan-scripts/api-load.sh        irslamd's threads put back to normal
#                                                 scheduling (irslamd makes its loop SCHED_FIFO 10
#                                                 and its API thread 9 itself: realtime_priority)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
seconds=${1:-30}
bin=$IRSLAM_BUILD
[ -x "$bin/daemon/irslamd" ] && [ -x "$bin/sim/irslam-sim" ] && [ -x "$bin/daemon/irslamctl" ] ||
  irslam_build
run=$(mktemp -d /tmp/irslam-api-load.XXXXXX)
out=$run/out
mkdir -p "$out"
sock=$run/irslamd.sock
export NOTIFY_SOCKET=$run/notify WATCHDOG_USEC=2000000
irslam_start "$run" "unix:$run/bus" "$sock" 1 "$out" "$IRSLAM_ROOT/tests/worlds/fig14.json"
# API_LOAD_RT=0: every thread back to SCHED_OTHER, for comparison.
if [ "${API_LOAD_RT:-}" = 0 ]; then chrt -a -o -p 0 "${IRSLAM_PIDS[1]}"; fi
"$bin/daemon/irslamctl" --socket "$sock" start >/dev/null
echo "api-load: mission started; ${seconds}s of hostile API load (time scale 1)" >&2

# API_LOAD_NICE=19: the load client runs niced (tells our own cost from the CPU the attacker takes).
${API_LOAD_NICE:+nice -n "$API_LOAD_NICE"} python3 - "$sock" "$NOTIFY_SOCKET" "$seconds" "$IRSLAM_ROOT/daemon/irslamd.conf" <<'EOF'
import json, os, re, selectors, socket, sys, time

sock_path, notify_path, seconds, conf = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
text = re.sub(r'//[^\n]*', '', open(conf).read())
api = json.loads(text)["api"]
max_clients, max_line = api["max_clients"], api["max_line_bytes"]

notify = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
notify.bind(notify_path)
notify.setblocking(False)
pings = []

sel = selectors.DefaultSelector()
deep_line = b'[' * (max_line - 1) + b'\n'
pad = max_line - 100
big_status = (json.dumps({"jsonrpc": "2.0", "id": 1, "method": "status",
                          "params": {"pad": "x" * pad}}) + "\n").encode()
map_line = b'{"jsonrpc":"2.0","id":2,"method":"map"}\n'
sub_line = b'{"jsonrpc":"2.0","id":3,"method":"subscribe","params":{"rate":50}}\n'
kinds = ["deep", "big", "map", "sub", "slowloris", "idle"]
stats = {k: {"connects": 0, "sent": 0, "recv": 0, "closed": 0} for k in kinds}

class Client:
    def __init__(self, kind):
        self.kind = kind
        self.connect()
    def connect(self):
        self.s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.s.setblocking(False)
        try:
            self.s.connect(sock_path)
        except (BlockingIOError, ConnectionRefusedError, OSError):
            pass
        stats[self.kind]["connects"] += 1
        self.out = sub_line if self.kind == "sub" else b''
        self.last_drip = 0
        sel.register(self.s, selectors.EVENT_READ | selectors.EVENT_WRITE, self)
    def refill(self):
        if len(self.out) < 1 << 16:
            if self.kind == "deep": self.out += deep_line
            elif self.kind == "big": self.out += big_status
            elif self.kind == "map": self.out += map_line * 16
    def on_write(self):
        if self.kind == "slowloris":
            now = time.monotonic()
            if now - self.last_drip < 0.5: return
            self.last_drip = now
            self.out = b'{'
        elif self.kind != "sub":
            self.refill()
        if not self.out: return
        try:
            n = self.s.send(self.out)
            stats[self.kind]["sent"] += n
            self.out = self.out[n:]
        except BlockingIOError:
            pass
        except OSError:
            self.reconnect()
    def on_read(self):
        try:
            data = self.s.recv(1 << 20)
        except BlockingIOError:
            return
        except OSError:
            data = b''
        if not data:
            self.reconnect()
            return
        stats[self.kind]["recv"] += len(data)
    def reconnect(self):
        stats[self.kind]["closed"] += 1
        try: sel.unregister(self.s)
        except Exception: pass
        self.s.close()
        self.connect()

# The measurer: status notifications at 50 Hz, one sample per period.
meas = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
meas.connect(sock_path)
meas.sendall(b'{"jsonrpc":"2.0","id":1,"method":"subscribe","params":{"rate":50}}\n')
meas.setblocking(False)
meas_buf = b''
samples = {}  # ticks -> jitter_last
meas_evicted = 0
def read_meas():
    global meas_buf, meas, meas_evicted
    try:
        data = meas.recv(1 << 20)
    except BlockingIOError:
        return
    except OSError:
        data = b''
    if not data:  # evicted (it is idle between its requests): subscribe again
        meas_evicted += 1
        sel.unregister(meas)
        meas.close()
        meas = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        meas.connect(sock_path)
        meas.sendall(b'{"jsonrpc":"2.0","id":1,"method":"subscribe","params":{"rate":50}}\n')
        meas.setblocking(False)
        meas_buf = b''
        sel.register(meas, selectors.EVENT_READ, "meas")
        return
    meas_buf += data
    while b'\n' in meas_buf:
        line, meas_buf = meas_buf.split(b'\n', 1)
        m = json.loads(line)
        if m.get("method") == "status":
            p = m["params"]["period"]
            samples[p["ticks"]] = p["jitter_last"]
sel.register(meas, selectors.EVENT_READ, "meas")
sel.register(notify, selectors.EVENT_READ, "notify")

# With the measurer, max_clients clients: the server is full from the start.
plan = ["deep", "big", "map", "sub", "deep", "big", "map", "slowloris", "idle"]
hostile = int(os.environ.get("API_LOAD_CLIENTS", max_clients - 1))  # 0: a baseline without load
clients = [Client(plan[i % len(plan)]) for i in range(hostile)]
t_end = time.monotonic() + seconds
while time.monotonic() < t_end:
    for key, ev in sel.select(timeout=0.05):
        if key.data == "meas":
            read_meas()
        elif key.data == "notify":
            try:
                while True:
                    msg = notify.recv(4096)
                    if b"WATCHDOG=1" in msg: pings.append(time.monotonic())
            except BlockingIOError:
                pass
        else:
            if ev & selectors.EVENT_READ: key.data.on_read()
            if ev & selectors.EVENT_WRITE: key.data.on_write()

# A stop must get through while all of this still goes on.
t0 = time.monotonic()
ctl = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
ctl.settimeout(5)
ctl.connect(sock_path)
ctl.sendall(b'{"jsonrpc":"2.0","id":7,"method":"stop"}\n')
reply = b''
while b'\n' not in reply:
    d = ctl.recv(65536)
    if not d: break
    reply += d
stop_ms = (time.monotonic() - t0) * 1e3
for c in clients:
    try: c.s.close()
    except Exception: pass
time.sleep(0.3)
ctl = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
ctl.settimeout(5)
ctl.connect(sock_path)
ctl.sendall(b'{"jsonrpc":"2.0","id":8,"method":"status"}\n')
buf = b''
while b'\n' not in buf:
    buf += ctl.recv(1 << 20)
status = json.loads(buf.split(b'\n')[0])["result"]

per = status["period"]
js = sorted(samples.values())
def pct(q):
    return js[min(len(js) - 1, int(q * len(js)))] * 1e3 if js else float('nan')
gaps = [b - a for a, b in zip(pings, pings[1:])]
print("api-load: %.0f s of load, %d hostile clients + 1 measurer (re-subscribed %d times)" % (
    seconds, hostile, meas_evicted))
print("  stop during the load: %s in %.1f ms" % (json.loads(reply.split(b'\n')[0]).get("result", reply[:80]), stop_ms))
print("  period: target %.3f s, ticks %d (expected ~%d), overruns %d, work_max %.3f ms, loop scheduling: %s" % (
    per["target"], per["ticks"], int(status["uptime"] / per["target"]), per["overruns"], per["work_max"] * 1e3,
    per.get("scheduling", "?")))
print("  jitter: mean %.3f ms, max %.3f ms; sampled %d periods: p50 %.3f ms, p99 %.3f ms, p99.9 %.3f ms, max %.3f ms" % (
    per["jitter_mean"] * 1e3, per["jitter_max"] * 1e3, len(js), pct(0.5), pct(0.99), pct(0.999),
    js[-1] * 1e3 if js else float('nan')))
if gaps:
    print("  watchdog: %d pings, gap min %.3f s, max %.3f s (nominal 1.000 s): worst lateness %.1f ms" % (
        len(pings), min(gaps), max(gaps), (max(gaps) - 1.0) * 1e3))
else:
    print("  watchdog: fewer than 2 pings seen")
print("  api: " + json.dumps(status["api"]))
print("  clients: " + json.dumps(stats))
print("  load average: " + open("/proc/loadavg").read().strip())
EOF
