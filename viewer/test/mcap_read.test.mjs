// Reads a run's flight.mcap with the MCAP project's own TypeScript library (@mcap/core), both as
// a stream (every record, chunk CRCs validated, done() at the end) and through its index (summary
// CRC, chunk indexes), and checks the message counts against the run's log.csv and scene.json.
//   node test/mcap_read.test.mjs RUN_DIR
import { readFileSync } from "node:fs";
import { join } from "node:path";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { check, finish } from "./check.mjs";

const dir = process.argv[2];
if (!dir) {
  console.error("usage: node test/mcap_read.test.mjs RUN_DIR (written with --log-format both)");
  process.exit(2);
}

const bytes = readFileSync(join(dir, "flight.mcap"));
const rows = readFileSync(join(dir, "log.csv"), "utf8").trimEnd().split("\n").length - 1;
const scene = JSON.parse(readFileSync(join(dir, "scene.json"), "utf8"));
const header = readFileSync(join(dir, "log.csv"), "utf8").split("\n", 1)[0].split(",");
const withFdd = header.includes("mi_0");
const withLio = header.includes("lio_matched");

// Stream reading: every record in file order.
const stream = new McapStreamReader({ validateCrcs: true });
stream.append(new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength));
const channels = new Map();
const schemas = new Map();
const counts = new Map();
let metadata = null;
let record;
let badJson = 0;
while ((record = stream.nextRecord())) {
  if (record.type === "Schema") schemas.set(record.id, record);
  if (record.type === "Channel") channels.set(record.id, record);
  if (record.type === "Metadata") metadata = record;
  if (record.type === "Message") {
    const topic = channels.get(record.channelId).topic;
    counts.set(topic, (counts.get(topic) || 0) + 1);
    try {
      JSON.parse(new TextDecoder().decode(record.data));
    } catch {
      badJson += 1;
    }
  }
}
check(stream.done(), "the stream reader reached the footer and the closing magic (done())");
check(badJson === 0, `every message is valid JSON (${badJson} are not)`);

const expect = (topic, n) => check((counts.get(topic) || 0) === n, `${topic}: ${counts.get(topic) || 0} messages, expected ${n}`);
for (const topic of ["/tf", "/pose", "/estimate", "/reference", "/rotors", "/rotorguard/log"]) expect(topic, rows);
if (withFdd) expect("/fdd", rows);
if (withLio) expect("/lio", rows);
const moving = scene.world.moving_boxes.reduce((n, m) => n + m.t_s.length, 0);
expect("/obstacles", 1 + moving);
expect("/planner/trajectory", scene.plans.length);
expect("/map", scene.map ? scene.map.snapshots.length : 0);

const schemaOf = (topic) => {
  for (const c of channels.values()) if (c.topic === topic) return schemas.get(c.schemaId)?.name;
  return undefined;
};
for (const [topic, name] of [["/tf", "foxglove.FrameTransform"], ["/pose", "foxglove.PoseInFrame"],
  ["/obstacles", "foxglove.SceneUpdate"], ["/map", "foxglove.PointCloud"]]) {
  check(schemaOf(topic) === name, `${topic} has schema ${name} (${schemaOf(topic)})`);
}
if (withLio) check(schemaOf("/lio") === "rotorguard.LioHealth", `/lio has schema rotorguard.LioHealth (${schemaOf("/lio")})`);
check(metadata !== null && metadata.name === "rotorguard" && metadata.metadata.has("summary"),
  "the 'rotorguard' metadata record holds the summary");

// Indexed reading: the summary (its CRC checked by the reader), chunk indexes and statistics.
const readable = {
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, length) => new Uint8Array(bytes.buffer, bytes.byteOffset + Number(offset), Number(length)),
};
const indexed = await McapIndexedReader.Initialize({ readable });
const total = [...counts.values()].reduce((a, b) => a + b, 0);
check(indexed.statistics && Number(indexed.statistics.messageCount) === total,
  `the statistics count ${indexed.statistics?.messageCount} messages, the stream ${total}`);
check(indexed.chunkIndexes.length >= 1, `${indexed.chunkIndexes.length} chunk indexes`);
let viaIndex = 0;
let lastTime = -1n;
let ordered = true;
for await (const m of indexed.readMessages()) {
  viaIndex += 1;
  if (m.logTime < lastTime) ordered = false;
  lastTime = m.logTime;
}
check(viaIndex === total, `the index reaches all ${viaIndex} of ${total} messages`);
check(ordered, "messages read through the index come in log-time order");

finish();
