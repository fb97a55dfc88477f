#!/usr/bin/env node
// Independent check of an MCAP file written by `concert bag record` (libs/bag), with Foxglove's
// own libraries: @mcap/core reads it twice, through its summary and indexes (McapIndexedReader,
// chunk CRCs checked) and record by record (McapStreamReader, CRCs checked), and
// @foxglove/omgidl-serialization decodes every message with the IDL text its channel's schema
// carries, as Foxglove does.
//
// Usage: mcap_check.mjs FILE [--messages] [--stream-only]
//   --messages     print every decoded message (JSON lines after the report)
//   --stream-only  read record by record only (a file cut short has no summary)
// Prints one JSON report line: header, channels with their message counts (indexed and
// streamed), statistics, decoded counts; exits 1 with {"error": ...} when a reader fails.
import { open } from "node:fs/promises";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { parseIDL } from "@foxglove/omgidl-parser";
import { MessageReader } from "@foxglove/omgidl-serialization";

const args = process.argv.slice(2);
const file = args.find((a) => !a.startsWith("--"));
const printMessages = args.includes("--messages");
const streamOnly = args.includes("--stream-only");
if (!file) {
  process.stderr.write("usage: mcap_check.mjs FILE [--messages] [--stream-only]\n");
  process.exit(2);
}

// JSON with 64-bit integers as plain numbers (JSON.stringify refuses bigint) and typed arrays
// as arrays.
function toJson(v) {
  if (typeof v === "bigint") return v.toString();
  if (v instanceof Map) return toJson(Object.fromEntries(v));
  if (ArrayBuffer.isView(v)) return "[" + Array.from(v, toJson).join(",") + "]";
  if (Array.isArray(v)) return "[" + v.map(toJson).join(",") + "]";
  if (v !== null && typeof v === "object") {
    return "{" + Object.entries(v).map(([k, x]) => JSON.stringify(k) + ":" + toJson(x)).join(",") + "}";
  }
  return JSON.stringify(v);
}

const decoders = new Map(); // schema id -> MessageReader
function decoderFor(schema) {
  if (!decoders.has(schema.id)) {
    if (schema.encoding !== "omgidl") throw new Error(`schema ${schema.name}: encoding '${schema.encoding}', not omgidl`);
    const text = new TextDecoder().decode(schema.data);
    decoders.set(schema.id, new MessageReader(schema.name, parseIDL(text)));
  }
  return decoders.get(schema.id);
}

const report = { file };
const lines = [];
const handle = await open(file, "r");
try {
  const decompressHandlers = await loadDecompressHandlers();
  const decoded = {};
  const decode = (channel, schema, message) => {
    if (channel.messageEncoding !== "cdr") throw new Error(`${channel.topic}: message encoding '${channel.messageEncoding}'`);
    const value = decoderFor(schema).readMessage(message.data);
    decoded[channel.topic] = (decoded[channel.topic] ?? 0) + 1;
    if (printMessages) {
      lines.push(toJson({ topic: channel.topic, sequence: message.sequence, log_time: message.logTime,
                          publish_time: message.publishTime, value }));
    }
  };

  if (!streamOnly) {
    const { size } = await handle.stat();
    const readable = {
      size: async () => BigInt(size),
      read: async (offset, length) => {
        const buffer = new Uint8Array(Number(length));
        const { bytesRead } = await handle.read(buffer, 0, Number(length), Number(offset));
        if (bytesRead !== Number(length)) throw new Error(`short read at ${offset}`);
        return buffer;
      },
    };
    const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    report.header = reader.header;
    report.statistics = reader.statistics;
    report.chunks = reader.chunkIndexes.length;
    report.data_section_crc = reader.dataSectionCrc;
    report.channels = [...reader.channelsById.values()].map((c) => ({
      id: c.id, topic: c.topic, schema: reader.schemasById.get(c.schemaId)?.name ?? "",
      schema_encoding: reader.schemasById.get(c.schemaId)?.encoding ?? "", message_encoding: c.messageEncoding,
      metadata: c.metadata, indexed: 0, streamed: 0,
    }));
    const byId = new Map(report.channels.map((c) => [c.id, c]));
    let last = -1n;
    for await (const message of reader.readMessages({ validateCrcs: true })) {
      if (message.logTime < last) throw new Error(`indexed messages out of log time order at ${message.logTime}`);
      last = message.logTime;
      byId.get(message.channelId).indexed += 1;
      decode(reader.channelsById.get(message.channelId), reader.schemasById.get(reader.channelsById.get(message.channelId).schemaId), message);
    }
    report.metadata = [];
    for await (const m of reader.readMetadata()) report.metadata.push({ name: m.name, metadata: m.metadata });
  }

  // Record by record, as a player reading a stream would.
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  const { size } = await handle.stat();
  const chunk = new Uint8Array(1 << 20);
  for (let offset = 0; offset < size; ) {
    const { bytesRead } = await handle.read(chunk, 0, chunk.length, offset);
    stream.append(chunk.subarray(0, bytesRead));
    offset += bytesRead;
  }
  const channels = new Map();
  const schemas = new Map();
  const records = {};
  let streamed = 0;
  for (let r; (r = stream.nextRecord()); ) {
    records[r.type] = (records[r.type] ?? 0) + 1;
    if (r.type === "Schema") schemas.set(r.id, r);
    if (r.type === "Channel") channels.set(r.id, r);
    if (r.type === "Message") {
      streamed += 1;
      const c = report.channels?.find((x) => x.id === r.channelId);
      if (c) c.streamed += 1;
      if (streamOnly) decode(channels.get(r.channelId), schemas.get(channels.get(r.channelId).schemaId), r);
    }
  }
  report.stream = { done: stream.done(), bytes_remaining: stream.bytesRemaining(), records, messages: streamed };
  if (streamOnly) {
    report.stream.channels = [...channels.values()].map((c) => ({ id: c.id, topic: c.topic,
      schema: schemas.get(c.schemaId)?.name ?? "" }));
  }
  report.decoded = decoded;
} catch (e) {
  process.stdout.write(toJson({ file, error: String(e?.message ?? e) }) + "\n");
  process.exit(1);
} finally {
  await handle.close();
}
process.stdout.write(toJson(report) + "\n");
for (const line of lines) process.stdout.write(line + "\n");
