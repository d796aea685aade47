// The checks Foxglove's own readers imply, shared by check-recording.mjs and check-live.mjs.
//
// - Raw channels (json + jsonschema): every array in the schema has `items`, and every message
//   validates against its channel's schema.
// - Foxglove channels (protobuf): the schema is parsed from its FileDescriptorSet with the
//   same function Foxglove uses (protobufFromBinaryDescriptor), every message is decoded and
//   validated against the official JSON schema of its type (@foxglove/schemas).
import { protobufFromBinaryDescriptor } from "@mcap/support";
import * as foxgloveSchemas from "@foxglove/schemas/jsonschema.js";
import Ajv from "ajv";

const ajv = new Ajv({ strict: false, allErrors: false });

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

// A checker for one channel: a function from a message's bytes to an error text or null.
// Problems with the channel itself are pushed to `errors`; returns null if it cannot be checked.
export function channelChecker(topic, messageEncoding, schemaName, schemaEncoding, schemaData, errors) {
  if (messageEncoding === "json" && schemaEncoding === "jsonschema") {
    const json = JSON.parse(new TextDecoder().decode(schemaData));
    const missing = [];
    arraysWithoutItems(json, topic, missing);
    if (missing.length) errors.push(`${topic}: arrays without items: ${missing.join(", ")}`);
    const validate = ajv.compile(json);
    return (data) => {
      const value = JSON.parse(new TextDecoder().decode(data));
      return validate(value) ? null : ajv.errorsText(validate.errors);
    };
  }
  if (messageEncoding === "protobuf" && schemaEncoding === "protobuf") {
    const type = protobufFromBinaryDescriptor(schemaData).lookupType(schemaName);
    const official = foxgloveSchemas[schemaName.replace(/^foxglove\./, "")];
    if (!official) {
      errors.push(`${topic}: ${schemaName} is not a Foxglove well-known schema`);
      return null;
    }
    const validate = ajv.compile(official);
    return (data) => {
      const message = type.toObject(type.decode(data), { longs: Number, enums: Number, bytes: String, defaults: true });
      return validate(foxgloveShape(message)) ? null : ajv.errorsText(validate.errors);
    };
  }
  errors.push(`${topic}: unexpected encoding ${messageEncoding} / ${schemaEncoding}`);
  return null;
}
