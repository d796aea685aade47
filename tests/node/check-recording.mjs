// Reads a Caravan recording the way the Foxglove app does and checks every message.
//
//   node check-recording.mjs FILE.mcap
//
// - Opens the file with @mcap/core's indexed reader (summary, chunk indexes; zstd/lz4 through
//   @mcap/support), as Foxglove does for a local file.
// - Raw channels (json + jsonschema): every array in the schema has `items`, and every message
//   validates against its channel's schema.
// - Foxglove channels (protobuf): the schema is parsed from its FileDescriptorSet with the
//   same function Foxglove uses (protobufFromBinaryDescriptor), every message is decoded and
//   validated against the official JSON schema of its type (@foxglove/schemas).
// Prints one JSON line {channels: {topic: {schema, encoding, messages}}, errors: [...]} and
// exits 1 if there is any error.
import { open } from "node:fs/promises";
import { McapIndexedReader } from "@mcap/core";
import { loadDecompressHandlers, protobufFromBinaryDescriptor } from "@mcap/support";
import * as foxgloveSchemas from "@foxglove/schemas/jsonschema.js";
import Ajv from "ajv";

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

const ajv = new Ajv({ strict: false, allErrors: false });
const errors = [];
const channels = {};
const checkers = new Map();

function arraysWithoutItems(schema, path, out) {
  if (schema?.type === "array" && schema.items === undefined) out.push(path);
  for (const [k, v] of Object.entries(schema?.properties ?? {})) arraysWithoutItems(v, `${path}.${k}`, out);
  if (schema?.items) arraysWithoutItems(schema.items, `${path}[]`, out);
}

// protobuf's Timestamp {seconds, nanos} is Foxglove's time {sec, nsec}.
function foxgloveShape(value) {
  if (Array.isArray(value)) return value.map(foxgloveShape);
  if (value && typeof value === "object") {
    const keys = Object.keys(value);
    if (keys.length === 2 && "seconds" in value && "nanos" in value) {
      return { sec: Number(value.seconds), nsec: value.nanos };
    }
    return Object.fromEntries(keys.map((k) => [k, foxgloveShape(value[k])]));
  }
  return value;
}

for (const channel of reader.channelsById.values()) {
  const schema = reader.schemasById.get(channel.schemaId);
  channels[channel.topic] = { schema: schema?.name, encoding: channel.messageEncoding, messages: 0 };
  if (channel.messageEncoding === "json" && schema?.encoding === "jsonschema") {
    const json = JSON.parse(new TextDecoder().decode(schema.data));
    const missing = [];
    arraysWithoutItems(json, channel.topic, missing);
    if (missing.length) errors.push(`${channel.topic}: arrays without items: ${missing.join(", ")}`);
    const validate = ajv.compile(json);
    checkers.set(channel.id, (data) => {
      const value = JSON.parse(new TextDecoder().decode(data));
      return validate(value) ? null : ajv.errorsText(validate.errors);
    });
  } else if (channel.messageEncoding === "protobuf" && schema?.encoding === "protobuf") {
    const type = protobufFromBinaryDescriptor(schema.data).lookupType(schema.name);
    const official = foxgloveSchemas[schema.name.replace(/^foxglove\./, "")];
    if (!official) {
      errors.push(`${channel.topic}: ${schema.name} is not a Foxglove well-known schema`);
      continue;
    }
    const validate = ajv.compile(official);
    checkers.set(channel.id, (data) => {
      const message = type.toObject(type.decode(data), { longs: Number, enums: Number, bytes: String, defaults: true });
      const value = foxgloveShape(message);
      return validate(value) ? null : ajv.errorsText(validate.errors);
    });
  } else {
    errors.push(`${channel.topic}: unexpected encoding ${channel.messageEncoding} / ${schema?.encoding}`);
  }
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
