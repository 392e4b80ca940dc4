// Reads an MCAP file with @mcap/core, the format's own TypeScript library
// (an independent reader for PLR's writer), twice: as a stream (every record
// in file order, CRCs checked) and indexed (through the summary, the chunk
// indexes and the message indexes). Prints one JSON object: messages per
// topic from each, schema and message encodings, and the statistics record.
//   node tests/js/mcap_check.mjs FILE
import { readFile } from "node:fs/promises";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { decompress } from "fzstd";

const decompressHandlers = {
  zstd: (buffer, size) => {
    const out = decompress(buffer);
    if (BigInt(out.byteLength) !== size) throw new Error(`zstd: ${out.byteLength} != ${size}`);
    return out;
  },
};

const bytes = new Uint8Array(await readFile(process.argv[2]));
const result = { stream: {}, indexed: {}, encodings: [], schemas: [], statistics: null };

const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
const channels = new Map();
const schemas = new Map();
for (let r; (r = stream.nextRecord()); ) {
  if (r.type === "Schema") schemas.set(r.id, r);
  if (r.type === "Channel") channels.set(r.id, r);
  if (r.type === "Message") {
    const topic = channels.get(r.channelId).topic;
    result.stream[topic] = (result.stream[topic] ?? 0) + 1;
  }
}
if (!stream.done()) throw new Error("the stream reader did not reach the end magic");

const readable = {
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
for await (const m of indexed.readMessages({ validateCrcs: true })) {
  const topic = indexed.channelsById.get(m.channelId).topic;
  result.indexed[topic] = (result.indexed[topic] ?? 0) + 1;
}
for (const c of indexed.channelsById.values()) {
  const s = indexed.schemasById.get(c.schemaId);
  result.encodings.push([c.topic, c.messageEncoding, s.name, s.encoding, s.data.byteLength]);
}
const st = indexed.statistics;
result.statistics = st && {
  messageCount: Number(st.messageCount),
  channelCount: st.channelCount,
  chunkCount: st.chunkCount,
};
console.log(JSON.stringify(result));
