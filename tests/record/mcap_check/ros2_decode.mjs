// Reads ROS 2 messages the way Foxglove Studio does when it opens a ROS 2 bag: each
// schema's ros2msg text parsed by @foxglove/rosmsg, each CDR message read by
// @foxglove/rosmsg2-serialization's MessageReader. The message is then written again by
// its MessageWriter, which must give back the same bytes: a field read wrong or bytes
// left unread show up there, not only a read that throws.

import { parse } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";

const MAX_PROBLEMS_PER_TOPIC = 3;

// Typed arrays and 64-bit integers as JSON can hold them.
export function plain(value) {
  if (typeof value === "bigint") return String(value);
  if (ArrayBuffer.isView(value)) return Array.from(value, plain);
  if (Array.isArray(value)) return value.map(plain);
  if (value && typeof value === "object")
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, plain(v)]));
  return value;
}

function sameBytes(a, b) {
  if (a.length !== b.length) return false;
  for (let i = 0; i < a.length; i++) if (a[i] !== b[i]) return false;
  return true;
}

export class Ros2Decoder {
  constructor(problem) {
    this.problem = problem;
    this.codecs = new Map(); // schema id -> {reader, writer} or null when its text did not parse
    this.decoded = new Map(); // topic -> messages read and written back the same
    this.failed = new Map(); // topic -> messages that were not
    this.first = new Map(); // schema name -> its first message, read
  }

  // Takes a message when its channel is CDR under a ros2msg schema; others are not ROS 2.
  take(schema, channel, data) {
    if (!schema || schema.encoding !== "ros2msg" || channel.messageEncoding !== "cdr") return;
    const codec = this.codec(schema);
    if (!codec) return this.fail(channel.topic, "its schema did not parse");
    let message;
    try {
      message = codec.reader.readMessage(data);
    } catch (e) {
      return this.fail(channel.topic, `MessageReader: ${e.message}`);
    }
    let again;
    try {
      again = codec.writer.writeMessage(message);
    } catch (e) {
      return this.fail(channel.topic, `MessageWriter: ${e.message}`);
    }
    if (!sameBytes(again, data))
      return this.fail(channel.topic, `read and written again, ${data.length} bytes became ${again.length} different ones`);
    this.decoded.set(channel.topic, (this.decoded.get(channel.topic) ?? 0) + 1);
    if (!this.first.has(schema.name)) this.first.set(schema.name, plain(message));
  }

  codec(schema) {
    if (!this.codecs.has(schema.id)) {
      try {
        const definitions = parse(new TextDecoder().decode(schema.data), { ros2: true });
        this.codecs.set(schema.id, { reader: new MessageReader(definitions), writer: new MessageWriter(definitions) });
      } catch (e) {
        this.problem(`ros2: schema ${schema.name} (id ${schema.id}) does not parse as ros2msg: ${e.message}`);
        this.codecs.set(schema.id, null);
      }
    }
    return this.codecs.get(schema.id);
  }

  fail(topic, why) {
    const count = (this.failed.get(topic) ?? 0) + 1;
    this.failed.set(topic, count);
    if (count <= MAX_PROBLEMS_PER_TOPIC) this.problem(`ros2: a message on ${topic}: ${why}`);
  }

  summary() {
    return {
      decoded: Object.fromEntries(this.decoded),
      failed: Object.fromEntries(this.failed),
      first: Object.fromEntries(this.first),
    };
  }
}
