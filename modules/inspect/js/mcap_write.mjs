// Writes an MCAP file with Foxglove's reference writer (@mcap/core) from the stream bricklayer-export
// sends on stdin. Each frame: one kind byte, a big-endian u32 length, then a u32 header length, a JSON
// header and a body:
//   S  schema    {id, name, schema} (a JSON Schema) or {id, foxglove: "CompressedImage"|"RawImage"}
//   C  channel   {id, schema, topic}
//   M  message   {c, s, t, p} + the message's JSON text (t, p: log and publish time, ns as text)
//   I  image     {c, s, t, p, sec, nsec, frame_id, format} + the compressed bytes -> foxglove.CompressedImage
//   R  raw image {c, s, t, p, sec, nsec, frame_id, width, height, encoding, step} + pixels -> foxglove.RawImage
//   E  end of stream: the writer writes the summary and exits 0
// Usage: node mcap_write.mjs OUT.mcap < frames
import { open } from "node:fs/promises";
import { createRequire } from "node:module";
import { McapWriter } from "@mcap/core";
import { FileHandleWritable } from "@mcap/nodejs";

const require = createRequire(import.meta.url);
const foxglove = require("@foxglove/schemas/jsonschema.js");

const out = process.argv[2];
if (!out) {
  console.error("usage: node mcap_write.mjs OUT.mcap < frames");
  process.exit(2);
}
const handle = await open(out, "w");
const writer = new McapWriter({
  writable: new FileHandleWritable(handle),
  useStatistics: true,
  useSummaryOffsets: true,
  useChunks: true,
  useChunkIndex: true,
  useMessageIndex: true,
  chunkSize: 4 * 1024 * 1024,
});
await writer.start({ profile: "", library: "bricklayer-export (@mcap/core)" });

const encoder = new TextEncoder();
const schemaIds = new Map();
const channelIds = new Map();
let ended = false;

async function handleFrame(kind, header, body) {
  switch (kind) {
    case "S": {
      let name, schema;
      if (header.foxglove) {
        schema = foxglove[header.foxglove];
        if (!schema) throw new Error(`@foxglove/schemas has no ${header.foxglove}`);
        name = `foxglove.${header.foxglove}`;
      } else {
        name = header.name;
        schema = header.schema;
      }
      const id = await writer.registerSchema({ name, encoding: "jsonschema", data: encoder.encode(JSON.stringify(schema)) });
      schemaIds.set(header.id, id);
      break;
    }
    case "C": {
      const schemaId = schemaIds.get(header.schema);
      if (schemaId === undefined) throw new Error(`channel ${header.topic}: unknown schema ${header.schema}`);
      const id = await writer.registerChannel({ topic: header.topic, messageEncoding: "json", schemaId, metadata: new Map() });
      channelIds.set(header.id, id);
      break;
    }
    case "M":
    case "I":
    case "R": {
      const channelId = channelIds.get(header.c);
      if (channelId === undefined) throw new Error(`message on unknown channel ${header.c}`);
      let data = body;
      if (kind !== "M") {
        const image = {
          timestamp: { sec: header.sec, nsec: header.nsec },
          frame_id: header.frame_id,
        };
        if (kind === "I") {
          image.data = Buffer.from(body).toString("base64");
          image.format = header.format;
        } else {
          Object.assign(image, { width: header.width, height: header.height, encoding: header.encoding, step: header.step });
          image.data = Buffer.from(body).toString("base64");
        }
        data = encoder.encode(JSON.stringify(image));
      }
      await writer.addMessage({ channelId, sequence: header.s, logTime: BigInt(header.t), publishTime: BigInt(header.p), data });
      break;
    }
    case "E":
      ended = true;
      break;
    default:
      throw new Error(`unknown frame kind '${kind}'`);
  }
}

let pending = Buffer.alloc(0);
try {
  for await (const chunk of process.stdin) {
    pending = pending.length ? Buffer.concat([pending, chunk]) : chunk;
    let at = 0;
    while (pending.length - at >= 5) {
      const length = pending.readUInt32BE(at + 1);
      if (pending.length - at - 5 < length) break;
      const kind = String.fromCharCode(pending[at]);
      const headerLength = pending.readUInt32BE(at + 5);
      const header = JSON.parse(pending.toString("utf8", at + 9, at + 9 + headerLength));
      const body = pending.subarray(at + 9 + headerLength, at + 5 + length);
      await handleFrame(kind, header, body);
      at += 5 + length;
    }
    pending = pending.subarray(at);
  }
} finally {
  // Whatever arrived is closed into a valid, indexed file.
  await writer.end();
  await handle.close();
}
if (!ended) {
  console.error("mcap_write: the stream ended without its end frame (the exporter stopped early); the file holds what arrived");
  process.exit(1);
}
