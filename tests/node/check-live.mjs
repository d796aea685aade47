// Reads a live Caravan group the way the Foxglove app does: over the Foxglove WebSocket
// protocol with @foxglove/ws-protocol's client, subscribing to every advertised channel and
// checking each message as checks.mjs says.
//
//   node check-live.mjs ws://127.0.0.1:PORT SECONDS TOPIC[,TOPIC…]
//
// Connects (retrying until the server listens), listens until every TOPIC has delivered a
// message or SECONDS pass, and prints one JSON line
// {server: {name, capabilities}, channels: {topic: {schema, encoding, messages}}, errors: [...]};
// exits 1 if there is any error or a TOPIC delivered nothing.
import wsProtocol from "@foxglove/ws-protocol";
const { FoxgloveClient } = wsProtocol;
import WebSocket from "ws";
import { channelChecker } from "./checks.mjs";

const [url, seconds, wanted] = process.argv.slice(2);
const required = (wanted ?? "").split(",").filter(Boolean);
const deadline = Date.now() + Number(seconds) * 1000;
const errors = [];
const channels = {};
const byChannel = new Map();
const bySubscription = new Map();
let server = null;

function finish() {
  for (const topic of required) {
    if (!channels[topic]?.messages) errors.push(`${topic}: no message received`);
  }
  console.log(JSON.stringify({ server, channels, errors }));
  process.exit(errors.length ? 1 : 0);
}

function connect() {
  // The SDK's server negotiates `foxglove.sdk.v1`, the current name of the protocol this
  // client speaks (it offers the older name `foxglove.websocket.v1` by default).
  const client = new FoxgloveClient({ ws: new WebSocket(url, ["foxglove.sdk.v1"]) });
  client.on("error", () => {});
  client.on("close", () => {
    if (server === null && Date.now() < deadline) setTimeout(connect, 200);
    else finish();
  });
  client.on("serverInfo", (info) => {
    server = { name: info.name, capabilities: info.capabilities };
  });
  client.on("advertise", (advertised) => {
    for (const c of advertised) {
      const schema = c.schemaEncoding === "protobuf"
        ? Uint8Array.from(Buffer.from(c.schema, "base64"))
        : new TextEncoder().encode(c.schema);
      channels[c.topic] = { schema: c.schemaName, encoding: c.encoding, messages: 0 };
      byChannel.set(c.id, { topic: c.topic, check: channelChecker(c.topic, c.encoding, c.schemaName, c.schemaEncoding, schema, errors) });
      bySubscription.set(client.subscribe(c.id), c.id);
    }
  });
  client.on("message", ({ subscriptionId, data }) => {
    const channel = byChannel.get(bySubscription.get(subscriptionId));
    if (!channel) return;
    channels[channel.topic].messages += 1;
    const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    const problem = channel.check ? channel.check(bytes) : null;
    if (problem && errors.length < 50) errors.push(`${channel.topic}: ${problem}`);
    if (required.every((t) => channels[t]?.messages)) {
      client.close();
    }
  });
}

setTimeout(finish, Math.max(0, deadline - Date.now()));
connect();
