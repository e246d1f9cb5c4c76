// Imports BVH files written by nec with three.js BVHLoader (under node) and
// checks them against nec's own reader and against the source file.
//
//   node threejs_import.mjs [--three DIR] MANIFEST.tsv
//
// MANIFEST rows (tab-separated): label, source file, file written by nec, and
// what nec's reader sees in the written file: joints, end sites, frames.
// three.js makes a Bone for every joint AND for every End Site (named
// "ENDSITE", no animation tracks), and one position + one quaternion track per
// joint with one key per frame. So we check:
//   bones - ENDSITE bones == joints, ENDSITE bones == end sites,
//   tracks == 2 * joints, keys per track == frames,
//   no console errors or warnings from the loader, and world positions of all
//   bones (end sites included) at the first, middle and last frame equal those
//   three.js computes for the source file (relative tolerance 1e-5); when
//   three.js cannot read the source alike, only the counts are checked.
// Prints one line per file; exit status 1 when any check fails.
import { readFileSync } from 'node:fs';
import { dirname, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const kTolerance = 1e-5;  // max position difference / extent of the source pose

const args = process.argv.slice(2);
let threeDir = resolve(dirname(fileURLToPath(import.meta.url)), '../../benchmarks/node_modules/three');
if (args[0] === '--three') {
  threeDir = resolve(args[1]);
  args.splice(0, 2);
}
if (args.length !== 1) {
  console.error('usage: node threejs_import.mjs [--three DIR] MANIFEST.tsv');
  process.exit(2);
}
const threePackage = JSON.parse(readFileSync(`${threeDir}/package.json`, 'utf8'));
const { BVHLoader } = await import(pathToFileURL(`${threeDir}/examples/jsm/loaders/BVHLoader.js`).href);

// Parses `path`, collecting what the loader prints instead of throwing.
function load(path) {
  const messages = [];
  const saved = { error: console.error, warn: console.warn };
  console.error = (...m) => messages.push(m.join(' '));
  console.warn = (...m) => messages.push(m.join(' '));
  try {
    return { ...new BVHLoader().parse(readFileSync(path, 'utf8')), messages };
  } catch (e) {
    messages.push(String(e));
    return { skeleton: null, clip: null, messages };
  } finally {
    Object.assign(console, saved);
  }
}

// World positions of all bones at key `frame`, set directly from the tracks.
function worldPositions(result, frame) {
  const bones = result.skeleton.bones;
  let animated = 0;
  for (const bone of bones) {
    if (bone.name === 'ENDSITE') continue;
    const position = result.clip.tracks[2 * animated].values;
    const rotation = result.clip.tracks[2 * animated + 1].values;
    bone.position.fromArray(position, 3 * frame);
    bone.quaternion.fromArray(rotation, 4 * frame);
    ++animated;
  }
  bones[0].updateMatrixWorld(true);
  return bones.map((bone) => bone.getWorldPosition(bone.position.clone()).toArray());
}

function maxDifference(a, b) {
  let difference = 0;
  let extent = 0;
  for (let i = 0; i < a.length; ++i) {
    for (let k = 0; k < 3; ++k) {
      difference = Math.max(difference, Math.abs(a[i][k] - b[i][k]));
      extent = Math.max(extent, Math.abs(a[i][k] - a[0][k]));
    }
  }
  return difference / Math.max(extent, 1e-9);
}

let failures = 0;
const rows = readFileSync(args[0], 'utf8').split('\n').filter((line) => line.trim() !== '');
for (const row of rows) {
  const [label, source, written, joints, endSites, frames] = row.split('\t');
  const expected = { joints: Number(joints), endSites: Number(endSites), frames: Number(frames) };
  const problems = [];
  const got = load(written);
  let seen = 'unreadable';
  if (got.skeleton) {
    const bones = got.skeleton.bones;
    const endSiteBones = bones.filter((bone) => bone.name === 'ENDSITE').length;
    const jointBones = bones.length - endSiteBones;
    const keys = got.clip.tracks.length > 0 ? got.clip.tracks[0].times.length : 0;
    seen = `${jointBones} joints + ${endSiteBones} end-site bones, ${got.clip.tracks.length} tracks, ${keys} frames`;
    if (jointBones !== expected.joints) problems.push(`joints ${jointBones} != nec ${expected.joints}`);
    if (endSiteBones !== expected.endSites) problems.push(`end sites ${endSiteBones} != nec ${expected.endSites}`);
    if (got.clip.tracks.length !== 2 * expected.joints) problems.push(`tracks ${got.clip.tracks.length} != 2 x joints`);
    if (keys !== expected.frames) problems.push(`frames ${keys} != nec ${expected.frames}`);
    if (got.messages.length > 0) problems.push(`loader said: ${got.messages.slice(0, 3).join(' | ')}`);
    const reference = load(source);
    if (problems.length === 0 && reference.skeleton && reference.skeleton.bones.length === bones.length) {
      const names = (r) => r.skeleton.bones.map((bone) => bone.name).join('/');
      if (names(reference) !== names(got)) problems.push('bone names or order differ from the source');
      let worst = 0;
      for (const frame of [0, Math.floor(expected.frames / 2), expected.frames - 1]) {
        if (frame < 0) continue;
        worst = Math.max(worst, maxDifference(worldPositions(reference, frame), worldPositions(got, frame)));
      }
      seen += `, max position difference vs source ${worst.toExponential(1)}`;
      if (!(worst <= kTolerance)) problems.push(`positions differ from the source by ${worst} (relative)`);
    } else if (problems.length === 0) {
      seen += ' (positions not compared: three.js does not read the source with the same bones)';
    }
  } else {
    problems.push(`loader failed: ${got.messages.join(' | ')}`);
  }
  if (problems.length > 0) ++failures;
  console.log(`three.js ${threePackage.version} ${problems.length ? 'FAIL' : 'ok  '} ${label}: ${seen}` +
              (problems.length ? `\n    ${problems.join('\n    ')}` : ''));
}
process.exit(failures > 0 ? 1 : 0);
