// irslam-foxglove against the running stack, through Foxglove's own client library
// (@foxglove/ws-protocol): irslam-sim serve + irslamd on the loopback bus, time-scaled,
// as tests/integration/e2e_test.cc starts them. Subscribes to /pose, /state, /tf and
// /map/lines and checks real values against `irslamctl status --json` and
// `irslamctl map --out`. Also: the bridge started before irslamd says "disconnected",
// then connects; irslamd stopped and started again: it reconnects.
//   IRSLAM_BINARY_DIR=build IRSLAM_SOURCE_DIR=. node --test tests/foxglove/foxglove.test.mjs
import { test } from "node:test";
import assert from "node:assert/strict";
import { spawn, execFile } from "node:child_process";
import { mkdtempSync, writeFileSync, readFileSync, rmSync, openSync, mkdirSync } from "node:fs";
import { tmpdir } from "node:os";
import { join, dirname } from "node:path";
import { fileURLToPath } from "node:url";
import { promisify } from "node:util";
import wsProtocol from "@foxglove/ws-protocol"; // CommonJS: no named exports in ESM
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol;

const here = dirname(fileURLToPath(import.meta.url));
const src = process.env.IRSLAM_SOURCE_DIR ?? join(here, "..", "..");
const bin = process.env.IRSLAM_BINARY_DIR ?? join(src, "build");
const scale = Number(process.env.IRSLAM_TEST_TIME_SCALE || 10);
const wallS = (s10) => (s10 * 10) / scale; // a wall-time limit chosen for 10x
const sleep = (s) => new Promise((r) => setTimeout(r, s * 1000));
const run = promisify(execFile);

const dir = mkdtempSync(join(tmpdir(), "irslam-foxglove-"));
const socket = join(dir, "irslamd.sock");
const bus = `unix:${dir}/bus`;
const children = [];

function start(name, args) {
  const log = openSync(join(dir, `${name}.log`), "a");
  const child = spawn(args[0], args.slice(1), { stdio: ["ignore", log, log] });
  children.push(child);
  return child;
}

async function ctl(...args) {
  const { stdout } = await run(join(bin, "daemon", "irslamctl"), ["--socket", socket, ...args], {
    timeout: 300000,
  });
  return stdout;
}

async function status() {
  return JSON.parse(await ctl("status", "--json"));
}

async function startDaemon() {
  const d = start("daemon", [join(bin, "daemon", "irslamd"), "--can", bus, "--socket", socket,
    "--time-scale", String(scale), "--config", join(dir, "irslamd.conf")]);
  for (let i = 0; i < 400; i++) {
    try {
      const s = await status();
      if (s.controller?.alive === true) return d;
    } catch { /* not up yet */ }
    await sleep(0.05);
  }
  throw new Error("irslamd never answered or never heard the controller");
}

// The bridge on a free port: the port from its "listening on ws://..." line.
async function startBridge() {
  const b = spawn(join(bin, "daemon", "irslam-foxglove"),
    ["--socket", socket, "--listen", "127.0.0.1:0", "--rate", "20", "--map-period", "0.5"],
    { stdio: ["ignore", "ignore", "pipe"] });
  children.push(b);
  let text = "";
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`irslam-foxglove did not start:\n${text}`)), 10000);
    b.stderr.on("data", (d) => {
      text += d.toString();
      writeFileSync(join(dir, "foxglove.log"), text);
      const m = /listening on ws:\/\/127\.0\.0\.1:(\d+)/.exec(text);
      if (m) {
        clearTimeout(timer);
        resolve(Number(m[1]));
      }
    });
    b.on("exit", (code) => reject(new Error(`irslam-foxglove exited (${code}):\n${text}`)));
  });
}

// A Foxglove client that keeps the latest message of each topic and every /state.
function connect(port, topics) {
  const client = new FoxgloveClient({
    ws: new WebSocket(`ws://127.0.0.1:${port}`, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]),
  });
  const view = { client, latest: {}, states: [], channels: {}, serverInfo: null, counts: {} };
  const subTopic = new Map();
  const decoder = new TextDecoder();
  client.on("serverInfo", (info) => { view.serverInfo = info; });
  client.on("advertise", (channels) => {
    for (const ch of channels) {
      view.channels[ch.topic] = ch;
      if (topics.includes(ch.topic)) subTopic.set(client.subscribe(ch.id), ch.topic);
    }
  });
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const topic = subTopic.get(subscriptionId);
    const msg = JSON.parse(decoder.decode(data));
    view.latest[topic] = { timestamp, msg };
    view.counts[topic] = (view.counts[topic] ?? 0) + 1;
    if (topic === "/state") view.states.push(msg);
  });
  return view;
}

async function until(what, pred, seconds) {
  const end = Date.now() + seconds * 1000;
  while (Date.now() < end) {
    if (pred()) return;
    await sleep(0.05);
  }
  assert.fail(`timed out waiting for ${what}`);
}

function yaw(q) {
  return 2 * Math.atan2(q.z, q.w);
}
function angleDiff(a, b) {
  return Math.atan2(Math.sin(a - b), Math.cos(a - b));
}

test("irslam-foxglove serves the running stack to @foxglove/ws-protocol", { timeout: 560000 }, async (t) => {
  t.after(() => {
    for (const c of children) if (c.exitCode === null) c.kill("SIGKILL");
    if (process.env.IRSLAM_KEEP_TEST_DIR) console.log(`test directory: ${dir}`);
    else rmSync(dir, { recursive: true, force: true });
  });
  mkdirSync(join(dir, "state"));
  writeFileSync(join(dir, "irslamd.conf"), JSON.stringify({
    controller: { timeout_s: Math.max(0.1, 0.1 * scale) },
    state: { dir: join(dir, "state") },
  }));
  start("sim", [join(bin, "sim", "irslam-sim"), "serve", "--can", bus, "--world",
    join(src, "tests", "worlds", "wall_follow_fig14.json"), "--time-scale", String(scale)]);

  // The bridge first: no irslamd yet, /state says so.
  const port = await startBridge();
  const view = connect(port, ["/pose", "/state", "/tf", "/map/lines"]);
  await until("the first /state", () => view.states.length > 0, 10);
  assert.equal(view.serverInfo.name, "irslam-foxglove");
  assert.equal(view.channels["/pose"].schemaName, "foxglove.PoseInFrame");
  assert.equal(view.channels["/pose"].encoding, "json");
  assert.equal(view.channels["/map/lines"].schemaName, "foxglove.SceneUpdate");
  assert.equal(JSON.parse(view.channels["/tf"].schema).title, "foxglove.FrameTransform");
  assert.equal(view.states.at(-1).connected, false);
  assert.equal(view.states.at(-1).state, "disconnected");

  let daemon = await startDaemon();
  await until("/state connected", () => view.states.at(-1).connected === true, 15);
  assert.equal(view.states.at(-1).state, "idle");

  await ctl("start");
  // While it runs: /pose moves, /tf follows it, /state says the running state.
  await until("the robot moving in /pose", () => {
    const p = view.latest["/pose"]?.msg.pose.position;
    return p && Math.hypot(p.x, p.y) > 0.2;
  }, wallS(60));
  const running = view.states.at(-1).state;
  assert.ok(!["idle", "done", "fault", "disconnected"].includes(running), `state while running: ${running}`);
  const tf = view.latest["/tf"].msg;
  assert.equal(tf.parent_frame_id, "map");
  assert.equal(tf.child_frame_id, "base_link");
  // The status pose now and the latest /pose: within what the robot travels in 0.5 s of wall time.
  const moving = await status();
  const p = view.latest["/pose"].msg.pose.position;
  assert.ok(Math.hypot(p.x - moving.pose[0], p.y - moving.pose[1]) < 0.5 * 0.5 * scale,
    `/pose (${p.x}, ${p.y}) vs status (${moving.pose})`);

  await ctl("wait", "--state", "done", "--timeout", String(wallS(120)));
  await until("/state done", () => view.states.at(-1).state === "done", 5);
  // A fresh /pose after done (the robot stands still), then compare with irslamctl status.
  const n = view.counts["/pose"];
  await until("fresh /pose messages", () => view.counts["/pose"] >= n + 3, 5);
  const s = await status();
  const last = view.latest["/pose"].msg;
  assert.equal(last.frame_id, "map");
  assert.ok(Math.abs(last.pose.position.x - s.pose[0]) < 0.01, `x ${last.pose.position.x} vs ${s.pose[0]}`);
  assert.ok(Math.abs(last.pose.position.y - s.pose[1]) < 0.01, `y ${last.pose.position.y} vs ${s.pose[1]}`);
  assert.ok(Math.abs(angleDiff(yaw(last.pose.orientation), s.pose[2])) < 0.01,
    `theta ${yaw(last.pose.orientation)} vs ${s.pose[2]}`);
  const st = view.states.at(-1);
  assert.equal(st.state, s.state);
  assert.equal(st.lines, s.lines);
  assert.ok(Math.abs(st.pose.x - s.pose[0]) < 0.01);
  const tfDone = view.latest["/tf"].msg;
  assert.ok(Math.abs(tfDone.translation.x - s.pose[0]) < 0.01);
  // The log time of a message is the header's timestamp, wall clock, in ns.
  const stamp = view.latest["/pose"].timestamp;
  assert.ok(Math.abs(Number(stamp / 1000000n) - Date.now()) < 10000, `timestamp ${stamp}`);

  // /map/lines: one entity per line of the map irslamctl writes, at its place.
  await ctl("map", "--out", join(dir, "map.json"));
  const map = JSON.parse(readFileSync(join(dir, "map.json"), "utf8"));
  await until("/map/lines with the final map", () =>
    view.latest["/map/lines"]?.msg.entities.length === map.lines.length, 5);
  const lines = view.latest["/map/lines"].msg;
  assert.equal(lines.deletions[0].type, 1);
  for (const l of map.lines) {
    const e = lines.entities.find((x) => x.id === `line/${l.id}`);
    assert.ok(e, `line ${l.id} in /map/lines`);
    const seg = e.lines[0].points;
    assert.ok(Math.abs(seg[0].x - l.p0[0]) < 1e-6 && Math.abs(seg[1].y - l.p1[1]) < 1e-6, `line ${l.id} end points`);
    assert.equal(e.lines[1].type, 1); // the covariance ellipse, a LINE_LOOP
  }

  // irslamd stops: /state says disconnected; it starts again: the bridge reconnects.
  daemon.kill("SIGTERM");
  await until("/state disconnected", () => view.states.at(-1).connected === false, 10);
  daemon = await startDaemon();
  await until("/state connected again", () => view.states.at(-1).connected === true, 15);
  view.client.close();
});
