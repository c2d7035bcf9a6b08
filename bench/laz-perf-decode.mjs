// SPDX-License-Identifier: GPL-3.0-or-later
// The LAZ peer of docs/benchmarks.md: decodes every record of a LAZ file with
// laz-perf (Hobu's LASzip-compatible decoder, the one PDAL's and Potree's web
// viewers use; npm package `laz-perf`, compiled to WebAssembly), on one thread
// as the package offers it. Prints the point count and the decoding time;
// with a second argument, writes the decoded records there, so that they can
// be compared byte for byte with a LAS file's point records.
// Usage: node laz-perf-decode.mjs FILE.laz [RECORDS_OUT]   (LAZPERF_DIR: the
// unpacked package, by default bench/run-laz-peer.sh's cache)
import { createRequire } from 'module';
import fs from 'fs';
import os from 'os';
import path from 'path';

const require = createRequire(import.meta.url);
const packageDir = process.env.LAZPERF_DIR || path.join(os.homedir(), '.cache', 'scandiff', 'laz-perf', 'package');
const { createLazPerf } = require(path.join(packageDir, 'lib', 'node', 'index.js'));
const [file, out] = process.argv.slice(2);
if (!file) {
  console.error('usage: node laz-perf-decode.mjs FILE.laz [RECORDS_OUT]');
  process.exit(2);
}

const lazPerf = await createLazPerf();
const bytes = fs.readFileSync(file);
const started = process.hrtime.bigint();
const filePointer = lazPerf._malloc(bytes.length);
lazPerf.HEAPU8.set(bytes, filePointer);
const reader = new lazPerf.LASZip();
reader.open(filePointer, bytes.length);
const count = reader.getCount();
const length = reader.getPointLength();
const format = reader.getPointFormat();
const record = lazPerf._malloc(length);
// The records go out in batches: one write per point would time the file system.
const batchPoints = 65536;
const batch = Buffer.alloc(batchPoints * length);
const output = out ? fs.openSync(out, 'w') : null;
let held = 0;
for (let i = 0; i < count; ++i) {
  reader.getPoint(record);
  if (output === null)
    continue;
  batch.set(lazPerf.HEAPU8.subarray(record, record + length), held * length);
  if (++held === batchPoints) {
    fs.writeSync(output, batch);
    held = 0;
  }
}
if (output !== null) {
  fs.writeSync(output, batch.subarray(0, held * length));
  fs.closeSync(output);
}
const seconds = Number(process.hrtime.bigint() - started) / 1e9;
reader.delete();
console.log(`${count} points of ${length} bytes (format ${format}) decoded in ${seconds.toFixed(3)} s`);
