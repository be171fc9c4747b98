#!/usr/bin/env node
// Independent MCAP file checker for afhub's own MCAP writer.
//
//   node check.mjs FILE.mcap [--jointstate TOPIC] [--pretty]
//
// Reads FILE three ways and cross-checks them:
//   1. linear:    @mcap/core McapStreamReader over the whole file (validateCrcs: true)
//   2. structure: a small walk written here over the raw bytes (record framing, DataEnd and
//                 data-section CRC, footer offsets, chunk/message-index/chunk-index/summary-offset
//                 consistency)
//   3. indexed:   @mcap/core McapIndexedReader over a FileHandle, readMessages() over everything
// and, in the linear pass, every CDR message under a ros2msg schema as Foxglove Studio reads
// ROS 2 bags (ros2_decode.mjs): "ros2" in the JSON.
//
// Prints ONE JSON object on stdout and exits 0 when no problem was found.
// Exits 1 (reason(s) on stderr) on any read error or problem; exits 2 on bad usage.
// A parse/CRC/decompression failure in the linear pass or indexed-reader initialisation stops
// the check at once (no JSON). Consistency problems found after that (counts, indexes,
// statistics, JointState decoding) are collected: the JSON is still printed, with "ok": false and
// "problems": [...], and every problem is also written to stderr before exiting 1.
// "records" counts every record McapStreamReader returned (records inside chunks included, so a
// Schema repeated in the summary counts twice); "topLevelRecords" counts the file's own records.
//
// Number conventions in the JSON:
//   - every value that is a uint64 field of an MCAP record (log/publish times, the Statistics
//     record's messageCount, messageStartTime, messageEndTime and channelMessageCounts values)
//     is a decimal STRING;
//   - everything else (record ids, uint16/uint32 record fields, counts made by this checker such
//     as "messages", "chunks", per-channel "messages", "sequenceGaps") is a JSON number.
//   - chunk compression is reported with the spec's exact string; "" means uncompressed.
// "warnings" lists things the spec makes optional but afhub's writer is expected to produce
// (CRCs, summary offsets, metadata index, channels repeated in the summary...). They don't fail.

import { open } from "node:fs/promises";
import process from "node:process";

import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import lz4Decompress from "@foxglove/wasm-lz4";
import * as zstd from "@foxglove/wasm-zstd";
import { CdrReader, EncapsulationKind } from "@foxglove/cdr";

import { Ros2Decoder } from "./ros2_decode.mjs";

const OPCODE_NAMES = {
  0x01: "Header",
  0x02: "Footer",
  0x03: "Schema",
  0x04: "Channel",
  0x05: "Message",
  0x06: "Chunk",
  0x07: "MessageIndex",
  0x08: "ChunkIndex",
  0x09: "Attachment",
  0x0a: "AttachmentIndex",
  0x0b: "Statistics",
  0x0c: "Metadata",
  0x0d: "MetadataIndex",
  0x0e: "SummaryOffset",
  0x0f: "DataEnd",
};
const OP = Object.fromEntries(Object.entries(OPCODE_NAMES).map(([k, v]) => [v, Number(k)]));
const MAGIC = [0x89, 0x4d, 0x43, 0x41, 0x50, 0x30, 0x0d, 0x0a];

function opName(op) {
  return OPCODE_NAMES[op] ?? `Unknown(0x${op.toString(16).padStart(2, "0")})`;
}

class CheckError extends Error {}

// ---------------------------------------------------------------------------------------------
// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320), as used by MCAP. Own implementation so
// the data-section CRC check does not depend on the library under comparison.
const CRC_TABLE = (() => {
  const t = new Uint32Array(256);
  for (let n = 0; n < 256; n++) {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    t[n] = c >>> 0;
  }
  return t;
})();

function crc32(bytes) {
  let c = 0xffffffff;
  for (let i = 0; i < bytes.length; i++) c = CRC_TABLE[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

// ---------------------------------------------------------------------------------------------
// Chunk decompression. Both wrappers insist the output size equals the chunk's uncompressed_size.
function guarded(kind, fn) {
  return (buf, size) => {
    let out;
    try {
      out = fn(buf, Number(size));
    } catch (e) {
      throw new Error(`${kind} chunk (${buf.byteLength} bytes, uncompressed_size ${size}) failed to decompress: ${e.message}`);
    }
    return sizeChecked(kind, out, size);
  };
}

function sizeChecked(kind, out, expected) {
  if (BigInt(out.byteLength) !== expected) {
    throw new Error(
      `${kind} chunk decompressed to ${out.byteLength} bytes but its uncompressed_size is ${expected}`,
    );
  }
  return out;
}

const decompressHandlers = {
  lz4: guarded("lz4", (buf, size) => lz4Decompress(buf, size)),
  zstd: guarded("zstd", (buf, size) => zstd.decompress(buf, size)),
};

function decompressChunkRecords(compression, records, uncompressedSize) {
  if (compression === "") {
    return sizeChecked("uncompressed", records, uncompressedSize);
  }
  if (records.byteLength === 0) return records;
  const handler = decompressHandlers[compression];
  if (!handler) throw new CheckError(`unsupported chunk compression ${JSON.stringify(compression)}`);
  return handler(records, uncompressedSize);
}

// ---------------------------------------------------------------------------------------------
// Minimal bounds-checked little-endian cursor for the structure walk.
class Cursor {
  constructor(bytes, start, end, what) {
    this.bytes = bytes;
    this.view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    this.pos = start;
    this.end = end;
    this.what = what;
  }
  need(n) {
    if (this.pos + n > this.end) {
      throw new CheckError(
        `${this.what}: field of ${n} bytes at offset ${this.pos} runs past the record end (${this.end})`,
      );
    }
  }
  u8() {
    this.need(1);
    return this.view.getUint8(this.pos++);
  }
  u16() {
    this.need(2);
    const v = this.view.getUint16(this.pos, true);
    this.pos += 2;
    return v;
  }
  u32() {
    this.need(4);
    const v = this.view.getUint32(this.pos, true);
    this.pos += 4;
    return v;
  }
  u64() {
    this.need(8);
    const v = this.view.getBigUint64(this.pos, true);
    this.pos += 8;
    return v;
  }
  bytesOf(n) {
    if (n > BigInt(this.end - this.pos)) {
      throw new CheckError(`${this.what}: byte field of length ${n} at offset ${this.pos} runs past the record end`);
    }
    const len = Number(n);
    const out = this.bytes.subarray(this.pos, this.pos + len);
    this.pos += len;
    return out;
  }
  str() {
    return new TextDecoder("utf-8", { fatal: true }).decode(this.bytesOf(BigInt(this.u32())));
  }
  remaining() {
    return this.end - this.pos;
  }
}

// Walk records (opcode u8, length u64, body) in bytes[start, end).
function walkRecords(bytes, start, end, what) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const recs = [];
  let off = start;
  while (off < end) {
    if (off + 9 > end) {
      throw new CheckError(`${what}: ${end - off} stray bytes at offset ${off} (too short for a record header)`);
    }
    const op = view.getUint8(off);
    const len = view.getBigUint64(off + 1, true);
    if (len > BigInt(end - off - 9)) {
      throw new CheckError(
        `${what}: ${opName(op)} record at offset ${off} has length ${len}, which runs past the end (${end})`,
      );
    }
    const length = 9 + Number(len);
    recs.push({ op, offset: off, length, body: off + 9, end: off + length });
    off += length;
  }
  return recs;
}

function mapsEqual(a, b) {
  if (a.size !== b.size) return false;
  for (const [k, v] of a) if (b.get(k) !== v) return false;
  return true;
}

function bytesEqual(a, b) {
  if (a.byteLength !== b.byteLength) return false;
  for (let i = 0; i < a.byteLength; i++) if (a[i] !== b[i]) return false;
  return true;
}

function bigMin(a, b) {
  return a === undefined || b < a ? b : a;
}
function bigMax(a, b) {
  return a === undefined || b > a ? b : a;
}

// ---------------------------------------------------------------------------------------------
// IReadable over a node FileHandle, for McapIndexedReader.
class FileReadable {
  #fh;
  #size;
  constructor(fh, size) {
    this.#fh = fh;
    this.#size = size;
  }
  async size() {
    return this.#size;
  }
  async read(offset, length) {
    if (offset < 0n || length < 0n || offset + length > this.#size) {
      throw new Error(`read of ${length} bytes at offset ${offset} is outside the file (${this.#size} bytes)`);
    }
    const n = Number(length);
    const buf = new Uint8Array(n);
    let done = 0;
    while (done < n) {
      const { bytesRead } = await this.#fh.read(buf, done, n - done, Number(offset) + done);
      if (bytesRead === 0) throw new Error(`unexpected end of file reading at offset ${Number(offset) + done}`);
      done += bytesRead;
    }
    return buf;
  }
}

// ---------------------------------------------------------------------------------------------
// sensor_msgs/msg/JointState decoded by hand from ROS 2 CDR.
function jsonNumber(x) {
  return Number.isFinite(x) ? x : String(x); // NaN / Infinity are not JSON numbers
}

function decodeJointState(data) {
  if (data.byteLength < 4) throw new CheckError(`JointState message is ${data.byteLength} bytes, too short for a CDR header`);
  const r = new CdrReader(data);
  if (r.kind !== EncapsulationKind.CDR_LE && r.kind !== EncapsulationKind.CDR_BE) {
    throw new CheckError(`JointState CDR encapsulation kind is ${r.kind}, expected CDR_LE (1) or CDR_BE (0)`);
  }
  const str = (field) => {
    const len = r.uint32();
    if (len === 0) throw new CheckError(`JointState ${field}: string length 0 (ROS 2 CDR strings carry a NUL terminator)`);
    if (r.offset + len > data.byteLength) throw new CheckError(`JointState ${field}: string of ${len} bytes runs past the message end`);
    if (data[r.offset + len - 1] !== 0) throw new CheckError(`JointState ${field}: string is not NUL-terminated`);
    return r.string(len);
  };
  const seqLen = (field, elemSize) => {
    const n = r.sequenceLength();
    if (n * elemSize > data.byteLength - r.offset) {
      throw new CheckError(`JointState ${field}: sequence length ${n} runs past the message end`);
    }
    return n;
  };
  const f64seq = (field) => Array.from(r.float64Array(seqLen(field, 8)), jsonNumber);
  try {
    const sec = r.int32();
    const nanosec = r.uint32();
    const frame_id = str("header.frame_id");
    const nNames = seqLen("name", 5);
    const name = [];
    for (let i = 0; i < nNames; i++) name.push(str(`name[${i}]`));
    const position = f64seq("position");
    const velocity = f64seq("velocity");
    const effort = f64seq("effort");
    const trailing = data.byteLength - r.offset;
    if (trailing > 7 || data.subarray(r.offset).some((b) => b !== 0)) {
      throw new CheckError(`JointState: ${trailing} unexpected trailing bytes after effort[]`);
    }
    return { encapsulation: r.kind, sec, nanosec, frame_id, name, position, velocity, effort, trailingPadding: trailing };
  } catch (e) {
    if (e instanceof CheckError) throw e;
    throw new CheckError(`JointState CDR decode failed: ${e.message}`);
  }
}

// ---------------------------------------------------------------------------------------------
async function check(file, jointTopic) {
  const problems = [];
  const warnings = [];
  const problem = (m) => problems.push(m);
  const warn = (m) => warnings.push(m);

  const fh = await open(file, "r").catch((e) => {
    throw new CheckError(`cannot open: ${e.message}`);
  });
  try {
    const size = (await fh.stat({ bigint: true })).size;
    const readable = new FileReadable(fh, size);
    const bytes = await readable.read(0n, size); // whole file: recordings under test are small
    if (size === 0n) throw new CheckError("linear: file is empty");
    if (size < 8n || !MAGIC.every((b, i) => bytes[i] === b)) {
      throw new CheckError("linear: not an MCAP file (missing leading magic \\x89MCAP0\\r\\n)");
    }

    // ------------------------------------------------------------------ 1. linear pass
    const recordCounts = {};
    const schemas = new Map(); // id -> Schema (first seen)
    const channels = new Map(); // id -> Channel
    const chanStats = new Map(); // id -> {messages, first, last, seqs: [[logTime, seq]]}
    const compressions = new Set();
    const metadata = [];
    let header, footer, dataEnd, statistics;
    let messages = 0;
    let chunks = 0;
    let attachments = 0;
    let minLog, maxLog;
    let jointMessage;
    let first = true;
    const ros2 = new Ros2Decoder(problem);

    const stream = new McapStreamReader({ includeChunks: true, validateCrcs: true, decompressHandlers });
    try {
      stream.append(bytes);
      for (let rec; (rec = stream.nextRecord()); ) {
        const key = rec.type === "Unknown" ? opName(rec.opcode) : rec.type;
        recordCounts[key] = (recordCounts[key] ?? 0) + 1;
        if (first && rec.type !== "Header") problem(`first record is ${rec.type}, not Header`);
        first = false;
        switch (rec.type) {
          case "Header":
            header = rec;
            break;
          case "Schema": {
            if (rec.id === 0) problem("Schema record with reserved id 0");
            const prev = schemas.get(rec.id);
            if (!prev) schemas.set(rec.id, rec);
            else if (prev.name !== rec.name || prev.encoding !== rec.encoding || !bytesEqual(prev.data, rec.data)) {
              problem(`Schema id ${rec.id} appears twice with different content`);
            }
            break;
          }
          case "Channel":
            if (rec.schemaId !== 0 && !schemas.has(rec.schemaId)) {
              problem(`Channel ${rec.id} (${rec.topic}) refers to schema ${rec.schemaId} before any Schema record with that id`);
            }
            channels.set(rec.id, rec);
            break;
          case "Message": {
            messages++;
            let cs = chanStats.get(rec.channelId);
            if (!cs) chanStats.set(rec.channelId, (cs = { messages: 0, first: undefined, last: undefined, seqs: [] }));
            cs.messages++;
            cs.first = bigMin(cs.first, rec.logTime);
            cs.last = bigMax(cs.last, rec.logTime);
            cs.seqs.push([rec.logTime, rec.sequence]);
            minLog = bigMin(minLog, rec.logTime);
            maxLog = bigMax(maxLog, rec.logTime);
            const channel = channels.get(rec.channelId);
            if (channel) ros2.take(schemas.get(channel.schemaId), channel, rec.data);
            if (jointTopic !== undefined && !jointMessage && channel?.topic === jointTopic) {
              jointMessage = { channelId: rec.channelId, data: rec.data.slice() };
            }
            break;
          }
          case "Chunk":
            chunks++;
            compressions.add(rec.compression);
            break;
          case "Attachment":
            attachments++;
            break;
          case "Metadata":
            metadata.push({ name: rec.name, metadata: Object.fromEntries(rec.metadata) });
            break;
          case "Statistics":
            if (statistics) problem("more than one Statistics record");
            statistics = rec;
            break;
          case "DataEnd":
            if (dataEnd) problem("more than one DataEnd record");
            dataEnd = rec;
            break;
          case "Footer":
            footer = rec;
            break;
          default:
            break;
        }
      }
    } catch (e) {
      throw new CheckError(`linear: ${e.message}`);
    }
    if (!stream.done()) {
      throw new CheckError(
        `linear: file ends before a complete Footer record and closing magic (truncated?); ${stream.bytesRemaining()} bytes left unparsed`,
      );
    }
    if (!header) problem("no Header record");
    if (!dataEnd) problem("no DataEnd record");
    if (!statistics) problem("no Statistics record");

    // ------------------------------------------------------------------ 2. indexed init
    let indexed;
    try {
      indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    } catch (e) {
      throw new CheckError(`indexed: ${e.message}`);
    }

    // ------------------------------------------------------------------ 3. structure walk
    const crc = { dataSection: false, summary: false };
    const topLevel = walkRecords(bytes, 8, Number(size) - 8, "structure");
    const topLevelCounts = {};
    for (const r of topLevel) topLevelCounts[opName(r.op)] = (topLevelCounts[opName(r.op)] ?? 0) + 1;
    const byOffset = new Map(topLevel.map((r) => [r.offset, r]));
    const footerRec = topLevel[topLevel.length - 1];
    const deIdx = topLevel.findIndex((r) => r.op === OP.DataEnd);
    if (topLevel[0]?.op !== OP.Header) problem("structure: first record after the magic is not a Header");
    if (footerRec?.op !== OP.Footer) problem("structure: last record before the closing magic is not a Footer");
    if (deIdx < 0) throw new CheckError("structure: no DataEnd record");
    const dataRecs = topLevel.slice(0, deIdx);
    const summaryRecs = topLevel.slice(deIdx + 1, topLevel.length - 1);
    const deRec = topLevel[deIdx];

    // data-section CRC (own CRC implementation)
    {
      const c = new Cursor(bytes, deRec.body, deRec.end, "DataEnd");
      const stored = c.u32();
      if (stored === 0) warn("DataEnd data_section_crc is 0 (not written)");
      else {
        const actual = crc32(bytes.subarray(0, deRec.offset));
        if (actual !== stored) problem(`data section CRC mismatch: DataEnd says ${stored}, computed ${actual}`);
        crc.dataSection = true;
      }
    }

    const DATA_OK = new Set([OP.Schema, OP.Channel, OP.Message, OP.Chunk, OP.MessageIndex, OP.Attachment, OP.Metadata]);
    const SUMMARY_OK = new Set([OP.Schema, OP.Channel, OP.ChunkIndex, OP.AttachmentIndex, OP.MetadataIndex, OP.Statistics, OP.SummaryOffset]);
    const known = (op) => OPCODE_NAMES[op] !== undefined;
    dataRecs.forEach((r, i) => {
      if (i === 0) return;
      if (known(r.op) && !DATA_OK.has(r.op)) problem(`structure: ${opName(r.op)} record at offset ${r.offset} is not allowed in the data section`);
      if (r.op === OP.MessageIndex && ![OP.Chunk, OP.MessageIndex].includes(dataRecs[i - 1].op)) {
        problem(`structure: MessageIndex at offset ${r.offset} does not follow a Chunk`);
      }
    });
    summaryRecs.forEach((r) => {
      if (known(r.op) && !SUMMARY_OK.has(r.op)) problem(`structure: ${opName(r.op)} record at offset ${r.offset} is not allowed in the summary section`);
    });
    for (const r of topLevel) {
      if (r.op === 0) problem(`structure: record with invalid opcode 0x00 at offset ${r.offset}`);
      else if (!known(r.op) && r.op < 0x80) warn(`record with reserved opcode ${opName(r.op)} at offset ${r.offset}`);
    }

    // footer offsets and summary CRC (own implementation)
    if (footerRec?.op === OP.Footer) {
      const c = new Cursor(bytes, footerRec.body, footerRec.end, "Footer");
      const summaryStart = c.u64();
      const summaryOffsetStart = c.u64();
      const summaryCrcPos = c.pos;
      const summaryCrc = c.u32();
      const expStart = summaryRecs.length ? BigInt(summaryRecs[0].offset) : 0n;
      if (summaryStart !== expStart) problem(`Footer summary_start is ${summaryStart}, expected ${expStart}`);
      const firstSO = summaryRecs.findIndex((r) => r.op === OP.SummaryOffset);
      const expSO = firstSO >= 0 ? BigInt(summaryRecs[firstSO].offset) : 0n;
      if (summaryOffsetStart !== expSO) problem(`Footer summary_offset_start is ${summaryOffsetStart}, expected ${expSO}`);
      if (firstSO >= 0 && summaryRecs.slice(firstSO).some((r) => r.op !== OP.SummaryOffset)) {
        problem("structure: SummaryOffset records are not all at the end of the summary section");
      }
      if (summaryCrc === 0) warn("Footer summary_crc is 0 (not written)");
      else {
        const from = summaryRecs.length ? summaryRecs[0].offset : footerRec.offset;
        const actual = crc32(bytes.subarray(from, summaryCrcPos));
        if (actual !== summaryCrc) problem(`summary CRC mismatch: Footer says ${summaryCrc}, computed ${actual}`);
        crc.summary = true;
      }
    }

    // chunks and their message indexes
    const chunkInfo = new Map(); // offset -> info
    for (let i = 0; i < dataRecs.length; i++) {
      const r = dataRecs[i];
      if (r.op !== OP.Chunk) continue;
      const where = `Chunk at offset ${r.offset}`;
      const c = new Cursor(bytes, r.body, r.end, where);
      const info = { rec: r, msgStart: c.u64(), msgEnd: c.u64(), uncompressedSize: c.u64() };
      info.crc = c.u32();
      info.compression = c.str();
      const recordsLen = c.u64();
      info.compressedSize = recordsLen;
      const raw = c.bytesOf(recordsLen);
      if (c.remaining() !== 0) warn(`${where}: ${c.remaining()} extra bytes after the records field`);
      if (info.crc === 0) warn(`${where}: uncompressed_crc is 0 (not written)`);
      let inner;
      try {
        inner = decompressChunkRecords(info.compression, raw, info.uncompressedSize);
      } catch (e) {
        throw new CheckError(`structure: ${where}: ${e.message}`);
      }
      const innerRecs = walkRecords(inner, 0, inner.byteLength, `${where} (inner records)`);
      const msgs = new Map(); // inner offset -> {channelId, logTime}
      let lo, hi;
      for (const ir of innerRecs) {
        if (![OP.Schema, OP.Channel, OP.Message].includes(ir.op) && (OPCODE_NAMES[ir.op] !== undefined || ir.op === 0)) {
          problem(`${where}: ${opName(ir.op)} record not allowed inside a chunk`);
        }
        if (ir.op === OP.Message) {
          const mc = new Cursor(inner, ir.body, ir.end, `${where} message`);
          const channelId = mc.u16();
          mc.u32();
          const logTime = mc.u64();
          msgs.set(ir.offset, { channelId, logTime });
          lo = bigMin(lo, logTime);
          hi = bigMax(hi, logTime);
        }
      }
      if (msgs.size && (info.msgStart !== lo || info.msgEnd !== hi)) {
        problem(`${where}: message_start/end_time ${info.msgStart}..${info.msgEnd} but its messages span ${lo}..${hi}`);
      }
      if (!msgs.size && (info.msgStart !== 0n || info.msgEnd !== 0n)) warn(`${where}: no messages but non-zero start/end time`);
      // following MessageIndex records
      info.miByChannel = new Map();
      let j = i + 1;
      while (j < dataRecs.length && dataRecs[j].op === OP.MessageIndex) j++;
      const miRecs = dataRecs.slice(i + 1, j);
      info.miStart = miRecs.length ? miRecs[0].offset : 0;
      info.miLength = miRecs.length ? miRecs[miRecs.length - 1].end - miRecs[0].offset : 0;
      const indexedOffsets = new Set();
      for (const mr of miRecs) {
        const mw = `MessageIndex at offset ${mr.offset}`;
        const mc = new Cursor(bytes, mr.body, mr.end, mw);
        const channelId = mc.u16();
        const n = mc.u32();
        if (n % 16 !== 0) problem(`${mw}: records byte length ${n} is not a multiple of 16`);
        if (info.miByChannel.has(channelId)) problem(`${mw}: second MessageIndex for channel ${channelId} after the same chunk`);
        info.miByChannel.set(channelId, mr.offset);
        for (let k = 0; k + 16 <= n; k += 16) {
          const logTime = mc.u64();
          const off = mc.u64();
          const m = msgs.get(Number(off));
          if (!m) problem(`${mw}: entry offset ${off} is not the start of a Message in the chunk`);
          else if (m.channelId !== channelId || m.logTime !== logTime) {
            problem(`${mw}: entry (${logTime}, ${off}) points at a message of channel ${m.channelId} with log time ${m.logTime}`);
          } else indexedOffsets.add(Number(off));
        }
      }
      if (msgs.size && !miRecs.length) problem(`${where}: has ${msgs.size} messages but no MessageIndex records follow it`);
      else if (miRecs.length && indexedOffsets.size !== msgs.size) {
        problem(`${where}: ${msgs.size - indexedOffsets.size} of its ${msgs.size} messages are missing from its MessageIndex records`);
      }
      chunkInfo.set(r.offset, info);
    }

    // chunk indexes (parsed by @mcap/core's indexed reader) against the chunks themselves
    if (chunks > 0 && indexed.chunkIndexes.length === 0) problem("summary has no ChunkIndex records");
    const chunkIndexed = new Set();
    for (const ci of indexed.chunkIndexes) {
      const w = `ChunkIndex for offset ${ci.chunkStartOffset}`;
      const info = chunkInfo.get(Number(ci.chunkStartOffset));
      if (!info) {
        problem(`${w}: no Chunk record starts there`);
        continue;
      }
      if (chunkIndexed.has(info.rec.offset)) problem(`${w}: chunk indexed twice`);
      chunkIndexed.add(info.rec.offset);
      const cmp = (field, got, want) => {
        if (got !== want) problem(`${w}: ${field} is ${got}, expected ${want}`);
      };
      cmp("chunk_length", ci.chunkLength, BigInt(info.rec.length));
      cmp("message_start_time", ci.messageStartTime, info.msgStart);
      cmp("message_end_time", ci.messageEndTime, info.msgEnd);
      cmp("compression", ci.compression, info.compression);
      cmp("compressed_size", ci.compressedSize, info.compressedSize);
      cmp("uncompressed_size", ci.uncompressedSize, info.uncompressedSize);
      cmp("message_index_length", ci.messageIndexLength, BigInt(info.miLength));
      const want = new Map([...info.miByChannel].map(([k, v]) => [k, BigInt(v)]));
      if (!mapsEqual(ci.messageIndexOffsets, want)) {
        problem(`${w}: message_index_offsets ${JSON.stringify([...ci.messageIndexOffsets].map(([k, v]) => [k, String(v)]))} do not match the MessageIndex records after the chunk ${JSON.stringify([...want].map(([k, v]) => [k, String(v)]))}`);
      }
    }
    if (indexed.chunkIndexes.length > 0 && chunkIndexed.size !== chunkInfo.size) {
      problem(`${chunkInfo.size - chunkIndexed.size} of ${chunkInfo.size} chunks have no ChunkIndex`);
    }

    // metadata / attachment indexes
    const checkIndexes = (kind, indexes, recOp, fields) => {
      const recs = dataRecs.filter((r) => r.op === recOp);
      if (recs.length && !indexes.length) {
        warn(`${recs.length} ${kind} record(s) but no ${kind}Index in the summary`);
        return;
      }
      const seen = new Set();
      for (const ix of indexes) {
        const r = byOffset.get(Number(ix.offset));
        const w = `${kind}Index ${JSON.stringify(ix.name)} (offset ${ix.offset})`;
        if (!r || r.op !== recOp) {
          problem(`${w}: no ${kind} record starts there`);
          continue;
        }
        seen.add(r.offset);
        if (ix.length !== BigInt(r.length)) problem(`${w}: length ${ix.length}, record is ${r.length} bytes`);
        const c = new Cursor(bytes, r.body, r.end, kind);
        fields(c, ix, w);
      }
      if (seen.size !== recs.length) problem(`${recs.length - seen.size} of ${recs.length} ${kind} records have no ${kind}Index`);
    };
    checkIndexes("Metadata", indexed.metadataIndexes, OP.Metadata, (c, ix, w) => {
      const name = c.str();
      if (name !== ix.name) problem(`${w}: record name is ${JSON.stringify(name)}`);
    });
    checkIndexes("Attachment", indexed.attachmentIndexes, OP.Attachment, (c, ix, w) => {
      const logTime = c.u64();
      const createTime = c.u64();
      const name = c.str();
      const mediaType = c.str();
      const dataSize = c.u64();
      if (logTime !== ix.logTime || createTime !== ix.createTime || name !== ix.name || mediaType !== ix.mediaType || dataSize !== ix.dataSize) {
        problem(`${w}: fields do not match the Attachment record`);
      }
    });

    // summary offsets (own parse, so duplicate groups are seen too)
    const soRecs = summaryRecs.filter((r) => r.op === OP.SummaryOffset);
    const groupOps = new Set(summaryRecs.filter((r) => r.op !== OP.SummaryOffset).map((r) => r.op));
    if (!soRecs.length && summaryRecs.length) warn("no Summary Offset section");
    const soSeen = new Set();
    for (const sr of soRecs) {
      const c = new Cursor(bytes, sr.body, sr.end, "SummaryOffset");
      const op = c.u8();
      const start = Number(c.u64());
      const len = Number(c.u64());
      const w = `SummaryOffset for ${opName(op)}`;
      if (soSeen.has(op)) problem(`${w}: appears twice`);
      soSeen.add(op);
      const group = summaryRecs.filter((r) => r.op === op);
      if (!group.length) problem(`${w}: summary has no such records`);
      else if (start !== group[0].offset || start + len !== group[group.length - 1].end) {
        problem(`${w}: covers ${start}..${start + len}, records span ${group[0].offset}..${group[group.length - 1].end}`);
      } else {
        const inside = summaryRecs.filter((r) => r.offset >= start && r.end <= start + len);
        if (inside.some((r) => r.op !== op)) problem(`${w}: group is not contiguous (other records inside)`);
      }
    }
    if (soRecs.length) for (const op of groupOps) if (!soSeen.has(op)) warn(`no SummaryOffset for the ${opName(op)} group`);

    // schemas / channels repeated in the summary
    for (const [id, ch] of channels) {
      const s = indexed.channelsById.get(id);
      if (!s) warn(`channel ${id} (${ch.topic}) is not repeated in the summary`);
      else if (s.topic !== ch.topic || s.schemaId !== ch.schemaId || s.messageEncoding !== ch.messageEncoding || !mapsEqual(s.metadata, ch.metadata)) {
        problem(`channel ${id} in the summary differs from the data section`);
      }
    }
    for (const [id, sc] of schemas) {
      const s = indexed.schemasById.get(id);
      if (!s) warn(`schema ${id} (${sc.name}) is not repeated in the summary`);
      else if (s.name !== sc.name || s.encoding !== sc.encoding || !bytesEqual(s.data, sc.data)) {
        problem(`schema ${id} in the summary differs from the data section`);
      }
    }
    for (const [id, ch] of indexed.channelsById) {
      if (!channels.has(id)) channels.set(id, ch);
      if (ch.schemaId !== 0 && !indexed.schemasById.has(ch.schemaId) && !schemas.has(ch.schemaId)) {
        problem(`channel ${id} refers to unknown schema ${ch.schemaId}`);
      }
    }
    for (const [id, sc] of indexed.schemasById) if (!schemas.has(id)) schemas.set(id, sc);
    for (const id of chanStats.keys()) if (!channels.has(id)) problem(`messages on unknown channel ${id}`);

    // ------------------------------------------------------------------ statistics
    const stats = indexed.statistics ?? statistics;
    if (stats) {
      const cmp = (field, got, want) => {
        if (got !== want) problem(`Statistics ${field} is ${got}, file has ${want}`);
      };
      cmp("message_count", stats.messageCount, BigInt(messages));
      cmp("schema_count", stats.schemaCount, schemas.size);
      cmp("channel_count", stats.channelCount, channels.size);
      cmp("attachment_count", stats.attachmentCount, attachments);
      cmp("metadata_count", stats.metadataCount, metadata.length);
      cmp("chunk_count", stats.chunkCount, chunks);
      if (messages > 0) {
        cmp("message_start_time", stats.messageStartTime, minLog);
        cmp("message_end_time", stats.messageEndTime, maxLog);
      }
      for (const [id, cs] of chanStats) {
        const n = stats.channelMessageCounts.get(id);
        if (n !== BigInt(cs.messages)) problem(`Statistics channel_message_counts[${id}] is ${n ?? "absent"}, channel has ${cs.messages} messages`);
      }
      for (const [id, n] of stats.channelMessageCounts) {
        if (!chanStats.has(id) && n !== 0n) problem(`Statistics channel_message_counts[${id}] is ${n}, channel has no messages`);
      }
    }

    // ------------------------------------------------------------------ 4. indexed messages
    let indexedMessages = 0;
    const indexedPerChannel = new Map();
    try {
      let prev;
      for await (const m of indexed.readMessages({ validateCrcs: true })) {
        indexedMessages++;
        indexedPerChannel.set(m.channelId, (indexedPerChannel.get(m.channelId) ?? 0) + 1);
        if (prev !== undefined && m.logTime < prev) problem(`indexed: readMessages went back in time (${m.logTime} after ${prev})`);
        prev = m.logTime;
      }
      for await (const _ of indexed.readMetadata()) void _;
      for await (const _ of indexed.readAttachments({ validateCrcs: true })) void _;
    } catch (e) {
      problem(`indexed: ${e.message}`);
    }
    const unchunked = topLevelCounts.Message ?? 0;
    if (unchunked) problem(`${unchunked} Message records are outside chunks, so no index covers them`);
    if (indexedMessages !== messages) problem(`indexed reader found ${indexedMessages} messages, linear read found ${messages}`);
    for (const id of new Set([...chanStats.keys(), ...indexedPerChannel.keys()])) {
      const a = chanStats.get(id)?.messages ?? 0;
      const b = indexedPerChannel.get(id) ?? 0;
      if (a !== b) problem(`channel ${id}: indexed reader found ${b} messages, linear read found ${a}`);
    }

    // ------------------------------------------------------------------ output
    const out = {
      ok: false,
      file,
      size: Number(size),
      profile: header?.profile ?? null,
      library: header?.library ?? null,
      compression: [...compressions].sort(),
      chunks,
      schemas: [...schemas.values()].sort((a, b) => a.id - b.id).map((s) => ({ id: s.id, name: s.name, encoding: s.encoding })),
      channels: [...channels.values()]
        .sort((a, b) => a.id - b.id)
        .map((c) => {
          const cs = chanStats.get(c.id);
          let gaps = 0;
          if (cs) {
            const seq = [...cs.seqs].sort((x, y) => (x[0] < y[0] ? -1 : x[0] > y[0] ? 1 : 0)); // stable
            for (let i = 1; i < seq.length; i++) if (seq[i][1] !== ((seq[i - 1][1] + 1) >>> 0)) gaps++;
          }
          return {
            id: c.id,
            topic: c.topic,
            schemaId: c.schemaId,
            messageEncoding: c.messageEncoding,
            metadata: Object.fromEntries(c.metadata),
            messages: cs?.messages ?? 0,
            firstLogTime: cs ? String(cs.first) : null,
            lastLogTime: cs ? String(cs.last) : null,
            sequenceGaps: gaps,
          };
        }),
      messages,
      attachments,
      statistics: stats
        ? {
            messageCount: String(stats.messageCount),
            schemaCount: stats.schemaCount,
            channelCount: stats.channelCount,
            attachmentCount: stats.attachmentCount,
            metadataCount: stats.metadataCount,
            chunkCount: stats.chunkCount,
            messageStartTime: String(stats.messageStartTime),
            messageEndTime: String(stats.messageEndTime),
            channelMessageCounts: Object.fromEntries([...stats.channelMessageCounts].map(([k, v]) => [String(k), String(v)])),
          }
        : null,
      metadata,
      indexedMessages,
      records: recordCounts,
      topLevelRecords: topLevelCounts,
      crcChecked: { dataSection: crc.dataSection, summary: crc.summary, chunks: [...chunkInfo.values()].filter((c) => c.crc !== 0).length },
      summaryOffsets: soRecs.length,
    };

    if (jointTopic !== undefined) {
      const ch = [...channels.values()].find((c) => c.topic === jointTopic);
      if (!ch) problem(`--jointstate: no channel with topic ${jointTopic}`);
      else {
        const sc = schemas.get(ch.schemaId);
        if (ch.messageEncoding !== "cdr") problem(`--jointstate: channel ${jointTopic} message encoding is ${JSON.stringify(ch.messageEncoding)}, expected "cdr"`);
        if (sc?.name !== "sensor_msgs/msg/JointState") problem(`--jointstate: channel ${jointTopic} schema is ${JSON.stringify(sc?.name ?? null)}, expected "sensor_msgs/msg/JointState"`);
        if (!jointMessage) problem(`--jointstate: no message on ${jointTopic}`);
        else if (ch.messageEncoding === "cdr") {
          try {
            out.jointstate = decodeJointState(jointMessage.data);
          } catch (e) {
            problem(e.message);
          }
        }
      }
    }

    if ([...schemas.values()].some((sc) => sc.encoding === "ros2msg")) out.ros2 = ros2.summary();

    out.ok = problems.length === 0;
    out.warnings = warnings;
    out.problems = problems;
    return out;
  } finally {
    await fh.close();
  }
}

// ---------------------------------------------------------------------------------------------
function usage(msg) {
  process.stderr.write(`mcap_check: ${msg}\nusage: node check.mjs FILE.mcap [--jointstate TOPIC] [--pretty]\n`);
  process.exit(2);
}

async function main(argv) {
  let file;
  let jointTopic;
  let pretty = false;
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === "--jointstate") {
      if (i + 1 >= argv.length) usage("--jointstate needs a TOPIC");
      jointTopic = argv[++i];
    } else if (a === "--pretty") pretty = true;
    else if (a.startsWith("--")) usage(`unknown option ${a}`);
    else if (file === undefined) file = a;
    else usage("only one FILE");
  }
  if (file === undefined) usage("no FILE given");

  await lz4Decompress.isLoaded;
  await zstd.isLoaded;

  let out;
  try {
    out = await check(file, jointTopic);
  } catch (e) {
    const msg = e instanceof CheckError ? e.message : `internal error: ${e.stack ?? e}`;
    process.stderr.write(`mcap_check: ${file}: ${msg}\n`);
    process.exit(1);
  }
  process.stdout.write(JSON.stringify(out, null, pretty ? 2 : undefined) + "\n");
  if (!out.ok) {
    for (const p of out.problems) process.stderr.write(`mcap_check: ${file}: ${p}\n`);
    process.exit(1);
  }
}

await main(process.argv.slice(2));
