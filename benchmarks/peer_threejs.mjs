// Peer benchmark: three.js BVHLoader.parse on the same files as bench_motion.
//
//   node benchmarks/peer_threejs.mjs [--warmup N] [--repeat N] FILE.bvh ...
//
// Reads every file once, parses them all `warmup` times untimed (JIT), then
// `repeat` timed passes; prints one JSON line with the median, min and max
// throughput in MB/s (10^6 bytes of BVH text per second), as scripts/bench.sh
// expects. Bytes are counted as UTF-8 file sizes, like bench_motion does.
// three is installed by scripts/bench.sh (npm install --prefix benchmarks).
import { readFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';
import { BVHLoader } from 'three/examples/jsm/loaders/BVHLoader.js';

function parseArguments(argv) {
  const options = { warmup: 2, repeat: 5, files: [] };
  for (let i = 0; i < argv.length; ++i) {
    if (argv[i] === '--warmup') options.warmup = Number(argv[++i]);
    else if (argv[i] === '--repeat') options.repeat = Number(argv[++i]);
    else options.files.push(argv[i]);
  }
  if (options.files.length === 0 || !(options.repeat >= 1) || !(options.warmup >= 0)) {
    console.error('usage: node peer_threejs.mjs [--warmup 2] [--repeat 5] FILE.bvh ...');
    process.exit(2);
  }
  return options;
}

function median(values) {
  const sorted = [...values].sort((a, b) => a - b);
  const middle = Math.floor(sorted.length / 2);
  return sorted.length % 2 ? sorted[middle] : (sorted[middle - 1] + sorted[middle]) / 2;
}

const options = parseArguments(process.argv.slice(2));
const buffers = options.files.map((path) => readFileSync(path));
const texts = buffers.map((buffer) => buffer.toString('utf8'));
const bytes = buffers.reduce((sum, buffer) => sum + buffer.length, 0);
const loader = new BVHLoader();

let sink = 0;  // keeps the results alive
function parseAll() {
  for (const text of texts) sink += loader.parse(text).skeleton.bones.length;
}

for (let i = 0; i < options.warmup; ++i) parseAll();
const mbPerSecond = [];
for (let i = 0; i < options.repeat; ++i) {
  const start = performance.now();
  parseAll();
  const seconds = (performance.now() - start) / 1000;
  mbPerSecond.push(bytes / 1e6 / seconds);
}
console.log(JSON.stringify({
  peer: 'three.js BVHLoader.parse',
  node: process.version,
  files: texts.length,
  megabytes: bytes / 1e6,
  median_mb_per_s: median(mbPerSecond),
  min_mb_per_s: Math.min(...mbPerSecond),
  max_mb_per_s: Math.max(...mbPerSecond),
  runs_mb_per_s: mbPerSecond,
  bones_seen: sink,
}));
