// Reads an MCAP file back with Foxglove's reference readers and checks it, for the export tests and
// for anyone who wants to know a file is whole:
// - the indexed reader (summary, chunk and message indexes) yields every message, CRCs validated;
// - the streaming reader reads the file record by record to its footer and counts the same messages;
// - every message parses as JSON and validates against its channel's JSON Schema (ajv);
// - the statistics record's message count equals what was read.
// Usage: node mcap_check.mjs FILE.mcap [--dump OUT.jsonl]
//   --dump writes one line per message in log-time order: topic, schema, log and publish time (ns, as
//   text), sequence, and the message (images: format, frame_id, timestamp, data_bytes, data_sha256).
// Prints a JSON summary on stdout; exits 1 on the first problem (with the reason on stderr).
import { createHash } from "node:crypto";
import { createReadStream, createWriteStream } from "node:fs";
import { open } from "node:fs/promises";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { FileHandleReadable } from "@mcap/nodejs";
import Ajv from "ajv";

const args = process.argv.slice(2);
const file = args[0];
const dumpAt = args.indexOf("--dump");
const dumpPath = dumpAt >= 0 ? args[dumpAt + 1] : undefined;
if (!file) {
  console.error("usage: node mcap_check.mjs FILE.mcap [--dump OUT.jsonl]");
  process.exit(2);
}

function fail(why) {
  console.error(`mcap_check: ${file}: ${why}`);
  process.exit(1);
}

const decoder = new TextDecoder("utf-8", { fatal: true });
const ajv = new Ajv({ allErrors: false, strict: false });
const validators = new Map();

const handle = await open(file, "r");
const reader = await McapIndexedReader.Initialize({ readable: new FileHandleReadable(handle) });
for (const [id, schema] of reader.schemasById) {
  if (schema.encoding !== "jsonschema") fail(`schema ${schema.name} has encoding ${schema.encoding}`);
  validators.set(id, ajv.compile(JSON.parse(decoder.decode(schema.data))));
}
const dump = dumpPath ? createWriteStream(dumpPath) : undefined;
const perTopic = {};
let count = 0;
for await (const m of reader.readMessages({ validateCrcs: true })) {
  const channel = reader.channelsById.get(m.channelId);
  if (!channel) fail(`message on unknown channel ${m.channelId}`);
  if (channel.messageEncoding !== "json") fail(`${channel.topic}: message encoding ${channel.messageEncoding}`);
  const schema = reader.schemasById.get(channel.schemaId);
  let value;
  try {
    value = JSON.parse(decoder.decode(m.data));
  } catch (e) {
    fail(`${channel.topic} message ${m.sequence}: not JSON: ${e.message}`);
  }
  const validate = validators.get(channel.schemaId);
  if (!validate(value)) fail(`${channel.topic} message ${m.sequence} does not match ${schema.name}: ${ajv.errorsText(validate.errors)}`);
  perTopic[channel.topic] = (perTopic[channel.topic] ?? 0) + 1;
  ++count;
  if (dump) {
    let message = value;
    if (schema.name === "foxglove.CompressedImage" || schema.name === "foxglove.RawImage") {
      const bytes = Buffer.from(value.data, "base64");
      message = { ...value, data: undefined, data_bytes: bytes.length, data_sha256: createHash("sha256").update(bytes).digest("hex") };
    }
    const line = JSON.stringify({
      topic: channel.topic, schema: schema.name, log_time_ns: m.logTime.toString(),
      publish_time_ns: m.publishTime.toString(), sequence: m.sequence, message,
    });
    if (!dump.write(line + "\n")) await new Promise((r) => dump.once("drain", r));
  }
}
if (dump) await new Promise((r) => dump.end(r));
await handle.close();

// The same file through the streaming reader, record by record, to its footer.
const stream = new McapStreamReader({ validateCrcs: true });
let streamed = 0;
let footer = false;
for await (const chunk of createReadStream(file)) {
  stream.append(chunk);
  for (let record; (record = stream.nextRecord()); ) {
    if (record.type === "Message") ++streamed;
    if (record.type === "Footer") footer = true;
  }
}
if (!stream.done() || !footer) fail("the streaming reader did not reach the footer");
if (streamed !== count) fail(`the streaming reader read ${streamed} messages, the indexed reader ${count}`);
const stated = reader.statistics ? Number(reader.statistics.messageCount) : -1;
if (stated !== count) fail(`the statistics record says ${stated} messages, ${count} were read`);
console.log(JSON.stringify({ messages: count, channels: reader.channelsById.size, schemas: reader.schemasById.size, topics: perTopic }));
