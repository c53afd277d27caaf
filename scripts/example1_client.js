#!/usr/bin/env node
// The thesis's example 1 (ch. 5, figure 5.1) as a program in another language: a Node.js
// client of `workcell serve` (protocol v1, docs/protocol.md), no packages needed.
//
// Usage: node scripts/example1_client.js [PORT] [HOST] [TOKEN]
//   (defaults 5260, 127.0.0.1; the token also from WORKCELL_TOKEN, else, for a server on
//   this machine, from its user-only token file, as the Python client does)
// Prints one JSON line: {"sim_time_s": ..., "frames": ..., "joints_deg": [...]}.
// An error reply ends the program with exit status 1 and the error's type, as the
// thesis's programs end.
"use strict";

const fs = require("fs");
const net = require("net");
const os = require("os");
const path = require("path");

const USAGE = `Usage: node scripts/example1_client.js [PORT] [HOST] [TOKEN]

Runs the thesis's example 1 against a running \`workcell serve\` (protocol v1) and prints
one JSON line: {"sim_time_s": ..., "frames": ..., "joints_deg": [...]}.
  PORT   the server's port (default 5260)
  HOST   the server's address (default 127.0.0.1)
  TOKEN  the server's token (default: $WORKCELL_TOKEN, else the token file a local
         workcell serve writes; see docs/protocol.md, "Security")
Start a server first, e.g.: workcell serve --port 5260`;

const args = process.argv.slice(2);
if (args.includes("-h") || args.includes("--help")) {
  console.log(USAGE);
  process.exit(0);
}
const port = Number(args[0] || 5260);
if (!Number.isInteger(port) || port < 1 || port > 65535) {
  console.error(`not a port number: ${JSON.stringify(args[0])} (1..65535)\n\n${USAGE}`);
  process.exit(2);
}
const host = args[1] || "127.0.0.1";
const token = args[2] || process.env.WORKCELL_TOKEN || localToken(port, host);

// The token file `workcell serve` writes (docs/protocol.md, "Security").
function localToken(port, host) {
  if (!["127.0.0.1", "::1", "localhost"].includes(host)) return null;
  const env = process.env;
  const dir =
    env.WORKCELL_RUNTIME_DIR ||
    (env.XDG_RUNTIME_DIR
      ? path.join(env.XDG_RUNTIME_DIR, "workcell")
      : path.join(os.homedir(), ".local", "share", "workcell", "runtime"));
  try {
    return JSON.parse(fs.readFileSync(path.join(dir, `server-${port}.json`), "utf8")).token;
  } catch {
    return null;
  }
}
const rad = (degrees) => degrees.map((d) => (d * Math.PI) / 180);

const socket = net.createConnection({ port, host });
socket.setNoDelay(true);
socket.setEncoding("utf8");

let buffered = "";
const waiting = []; // resolvers of lines not yet read
const lines = []; // lines read, not yet asked for
socket.on("data", (chunk) => {
  buffered += chunk;
  let i;
  while ((i = buffered.indexOf("\n")) >= 0) {
    const line = buffered.slice(0, i);
    buffered = buffered.slice(i + 1);
    if (waiting.length) waiting.shift()(line);
    else lines.push(line);
  }
});
socket.on("error", (err) => {
  console.error(`connection error: ${err.message}`);
  process.exit(2);
});

function readLine() {
  if (lines.length) return Promise.resolve(lines.shift());
  return new Promise((resolve) => waiting.push(resolve));
}

let nextId = 0;
async function call(command, args = {}) {
  const id = ++nextId;
  socket.write(JSON.stringify({ id, command, args }) + "\n");
  const reply = JSON.parse(await readLine());
  if (reply.error) {
    console.error(`${reply.error.type}: ${reply.error.message}`);
    socket.destroy();
    process.exit(1);
  }
  if (reply.id !== id) throw new Error(`reply to ${reply.id}, expected ${id}`);
  return reply.result;
}

async function main() {
  const hello = JSON.parse(await readLine());
  if (hello.protocol !== "workcell" || hello.version !== 1) {
    throw new Error(`not a workcell protocol v1 server: ${JSON.stringify(hello)}`);
  }
  await call("hello", { version: 1, token }); // the first message, always
  await call("example_cell", { name: "joints" });
  await call("simulate", { mode: "path", dt: 0.01 });
  // figure 5.1: speed 0.3 rad/s; relative move; absolute move; back to the start
  await call("set_speed", { robot: "puma", speed: 0.3 });
  await call("move_joints_relative", { robot: "puma", dq: rad([-70, -10, 10, 30, -20, -10]) });
  await call("move_joints_absolute", { robot: "puma", q: rad([-60, 0, -70, 0, 90, 30]) });
  await call("move_joints_absolute", { robot: "puma", q: rad([0, 0, -90, 0, 90, 0]) });
  const simTime = await call("sim_time");
  const frames = await call("frames");
  const q = await call("joints", { robot: "puma" });
  await call("bye");
  socket.end();
  console.log(
    JSON.stringify({
      sim_time_s: simTime,
      frames,
      joints_deg: q.map((r) => Math.round(((r * 180) / Math.PI) * 1e9) / 1e9),
    })
  );
}

main().catch((err) => {
  console.error(err.message);
  process.exit(2);
});
