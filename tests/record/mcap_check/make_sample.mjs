#!/usr/bin/env node
// Writes small sample MCAP files with @mcap/core's McapWriter, for self-testing check.mjs.
//
//   node make_sample.mjs OUTDIR
//
// Creates OUTDIR/sample-none.mcap, sample-lz4.mcap and sample-zstd.mcap. Each holds:
//   - /joint_states: sensor_msgs/msg/JointState (ros2msg schema, cdr encoding, made with
//     @foxglove/cdr's CdrWriter), 200 messages, sequence 0..199, 1 ms apart
//   - /hub/status: json, no schema, 20 messages with one deliberate sequence gap
//   - one Metadata record and one Attachment
// Small chunks (4 KiB) so each file has several chunks.
//
// zstd chunks use @foxglove/wasm-zstd's compress. @foxglove/wasm-lz4 can only decompress, so lz4
// chunks are made by the small LZ4 frame encoder below (greedy matcher, written for this test).

import { open, mkdir } from "node:fs/promises";
import path from "node:path";
import process from "node:process";

import { McapWriter } from "@mcap/core";
import * as zstd from "@foxglove/wasm-zstd";
import { CdrWriter } from "@foxglove/cdr";

// ------------------------------------------------------------------------------ LZ4 frame encoder
// xxHash32 for short inputs (< 16 bytes): only used for the frame descriptor checksum.
function xxh32Short(bytes, seed = 0) {
  const P1 = 2654435761, P2 = 2246822519, P3 = 3266489917, P4 = 668265263, P5 = 374761393;
  if (bytes.length >= 16) throw new Error("xxh32Short: input too long");
  const rotl = (x, r) => ((x << r) | (x >>> (32 - r))) >>> 0;
  let h = (seed + P5 + bytes.length) >>> 0;
  let i = 0;
  for (; i + 4 <= bytes.length; i += 4) {
    const w = (bytes[i] | (bytes[i + 1] << 8) | (bytes[i + 2] << 16) | (bytes[i + 3] << 24)) >>> 0;
    h = (h + Math.imul(w, P3)) >>> 0;
    h = Math.imul(rotl(h, 17), P4) >>> 0;
  }
  for (; i < bytes.length; i++) {
    h = (h + Math.imul(bytes[i], P5)) >>> 0;
    h = Math.imul(rotl(h, 11), P1) >>> 0;
  }
  h ^= h >>> 15;
  h = Math.imul(h, P2) >>> 0;
  h ^= h >>> 13;
  h = Math.imul(h, P3) >>> 0;
  h ^= h >>> 16;
  return h >>> 0;
}

// One LZ4 block (raw block format), greedy with a 4-byte hash table.
function lz4Block(src) {
  const n = src.length;
  const out = [];
  const pushLen = (len) => {
    for (; len >= 255; len -= 255) out.push(255);
    out.push(len);
  };
  const u32 = (p) => (src[p] | (src[p + 1] << 8) | (src[p + 2] << 16) | (src[p + 3] << 24)) >>> 0;
  const table = new Int32Array(1 << 16).fill(-1);
  let anchor = 0;
  let i = 0;
  const lastMatchStart = n - 12; // a match may not start in the last 12 bytes
  const matchEndLimit = n - 5; // the last 5 bytes are always literals
  while (i <= lastMatchStart) {
    const v = u32(i);
    const h = Math.imul(v, 2654435761) >>> 16;
    const ref = table[h];
    table[h] = i;
    if (ref >= 0 && i - ref <= 0xffff && u32(ref) === v) {
      let len = 4;
      while (i + len < matchEndLimit && src[ref + len] === src[i + len]) len++;
      const lit = i - anchor;
      const ml = len - 4;
      out.push((Math.min(lit, 15) << 4) | Math.min(ml, 15));
      if (lit >= 15) pushLen(lit - 15);
      for (let k = anchor; k < i; k++) out.push(src[k]);
      out.push((i - ref) & 0xff, (i - ref) >> 8);
      if (ml >= 15) pushLen(ml - 15);
      i += len;
      anchor = i;
    } else {
      i++;
    }
  }
  const lit = n - anchor;
  out.push(Math.min(lit, 15) << 4);
  if (lit >= 15) pushLen(lit - 15);
  for (let k = anchor; k < n; k++) out.push(src[k]);
  return Uint8Array.from(out);
}

// LZ4 frame: independent blocks, 4 MiB max block size, no checksums, no content size.
function lz4Frame(data) {
  const BLOCK = 4 << 20;
  const flg = 0x60; // version 01, block independence
  const bd = 0x70; // 4 MiB max block
  const parts = [Uint8Array.of(0x04, 0x22, 0x4d, 0x18, flg, bd, (xxh32Short(Uint8Array.of(flg, bd)) >>> 8) & 0xff)];
  for (let off = 0; off < data.length; off += BLOCK) {
    const raw = data.subarray(off, Math.min(data.length, off + BLOCK));
    const comp = lz4Block(raw);
    const stored = comp.length < raw.length ? comp : raw;
    const size = new Uint8Array(4);
    new DataView(size.buffer).setUint32(0, stored.length | (stored === raw ? 0x80000000 : 0), true);
    parts.push(size, stored);
  }
  parts.push(new Uint8Array(4)); // end mark
  const total = parts.reduce((a, p) => a + p.length, 0);
  const out = new Uint8Array(total);
  let o = 0;
  for (const p of parts) {
    out.set(p, o);
    o += p.length;
  }
  return out;
}

// ------------------------------------------------------------------------------ MCAP writing
class FileWritable {
  #fh;
  #pos = 0n;
  constructor(fh) {
    this.#fh = fh;
  }
  async write(buf) {
    let done = 0;
    while (done < buf.byteLength) {
      const { bytesWritten } = await this.#fh.write(buf, done, buf.byteLength - done);
      done += bytesWritten;
    }
    this.#pos += BigInt(buf.byteLength);
  }
  position() {
    return this.#pos;
  }
}

const JOINT_STATE_MSG = `# Sample schema text (ros2msg)
std_msgs/Header header
string[] name
float64[] position
float64[] velocity
float64[] effort
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
`;

const JOINTS = ["shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3"];

function jointStateCdr(t /* bigint ns */, k) {
  const w = new CdrWriter();
  w.int32(Number(t / 1_000_000_000n));
  w.uint32(Number(t % 1_000_000_000n));
  w.string("base_link");
  w.sequenceLength(JOINTS.length);
  for (const j of JOINTS) w.string(j);
  w.float64Array(JOINTS.map((_, i) => Math.sin(k * 0.01 + i)), true);
  w.float64Array(JOINTS.map((_, i) => Math.cos(k * 0.01 + i) * 0.01), true);
  w.float64Array(JOINTS.map((_, i) => i * 0.5), true);
  return w.data;
}

async function writeSample(file, compressChunk) {
  const fh = await open(file, "w");
  try {
    const writer = new McapWriter({ writable: new FileWritable(fh), chunkSize: 4096, compressChunk });
    await writer.start({ profile: "ros2", library: "afhub mcap_check make_sample.mjs" });
    const schemaId = await writer.registerSchema({
      name: "sensor_msgs/msg/JointState",
      encoding: "ros2msg",
      data: new TextEncoder().encode(JOINT_STATE_MSG),
    });
    const joints = await writer.registerChannel({
      topic: "/joint_states",
      schemaId,
      messageEncoding: "cdr",
      metadata: new Map([["offered_qos_profiles", ""]]),
    });
    const status = await writer.registerChannel({
      topic: "/hub/status",
      schemaId: 0,
      messageEncoding: "json",
      metadata: new Map(),
    });
    const t0 = 1_700_000_000_000_000_000n;
    let statusSeq = 0;
    for (let k = 0; k < 200; k++) {
      const t = t0 + BigInt(k) * 1_000_000n;
      await writer.addMessage({
        channelId: joints,
        sequence: k,
        logTime: t,
        publishTime: t,
        data: jointStateCdr(t, k),
      });
      if (k % 10 === 0) {
        if (k === 100) statusSeq++; // one deliberate gap
        await writer.addMessage({
          channelId: status,
          sequence: statusSeq++,
          logTime: t,
          publishTime: t,
          data: new TextEncoder().encode(JSON.stringify({ tick: k })),
        });
      }
    }
    await writer.addMetadata({ name: "afhub", metadata: new Map([["scenario", "sample"], ["seed", "42"]]) });
    await writer.addAttachment({
      name: "notes.txt",
      mediaType: "text/plain",
      logTime: t0,
      createTime: t0,
      data: new TextEncoder().encode("sample attachment\n"),
    });
    await writer.end();
  } finally {
    await fh.close();
  }
}

const outDir = process.argv[2];
if (!outDir) {
  process.stderr.write("usage: node make_sample.mjs OUTDIR\n");
  process.exit(2);
}
await mkdir(outDir, { recursive: true });
await zstd.isLoaded;
const variants = {
  none: undefined,
  lz4: (d) => ({ compression: "lz4", compressedData: lz4Frame(d) }),
  zstd: (d) => ({ compression: "zstd", compressedData: zstd.compress(d, 3) }),
};
for (const [name, compress] of Object.entries(variants)) {
  const file = path.join(outDir, `sample-${name}.mcap`);
  await writeSample(file, compress);
  process.stdout.write(`${file}\n`);
}
