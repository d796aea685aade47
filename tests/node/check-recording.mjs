// Reads a Caravan recording the way the Foxglove app does and checks every message.
//
//   node check-recording.mjs FILE.mcap
//
// Opens the file with @mcap/core's indexed reader (summary, chunk indexes; zstd/lz4 through
// @mcap/support), as Foxglove does for a local file, and checks each channel and message as
// checks.mjs says.
// Prints one JSON line {channels: {topic: {schema, encoding, messages}}, errors: [...]} and
// exits 1 if there is any error.
import { open } from "node:fs/promises";
import { McapIndexedReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { channelChecker } from "./checks.mjs";

const file = process.argv[2];
const handle = await open(file, "r");
const readable = {
  size: async () => BigInt((await handle.stat()).size),
  read: async (offset, length) => {
    const buffer = new Uint8Array(Number(length));
    await handle.read(buffer, 0, Number(length), Number(offset));
    return buffer;
  },
};
const reader = await McapIndexedReader.Initialize({
  readable,
  decompressHandlers: await loadDecompressHandlers(),
});

const errors = [];
const channels = {};
const checkers = new Map();

for (const channel of reader.channelsById.values()) {
  const schema = reader.schemasById.get(channel.schemaId);
  channels[channel.topic] = { schema: schema?.name, encoding: channel.messageEncoding, messages: 0 };
  const check = channelChecker(channel.topic, channel.messageEncoding, schema?.name, schema?.encoding, schema?.data, errors);
  if (check) checkers.set(channel.id, check);
}

for await (const message of reader.readMessages()) {
  const channel = reader.channelsById.get(message.channelId);
  channels[channel.topic].messages += 1;
  const check = checkers.get(message.channelId);
  const problem = check ? check(message.data) : null;
  if (problem && errors.length < 50) errors.push(`${channel.topic} message ${message.sequence}: ${problem}`);
}
await handle.close();
console.log(JSON.stringify({ channels, errors }));
process.exit(errors.length ? 1 : 0);
