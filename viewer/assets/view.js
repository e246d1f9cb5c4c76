// nec view player: BVH clips side by side as skeletons, with play/pause, scrub, speed, orbit camera,
// a caption under each clip and a ground grid. The page's bootstrap links 'three', 'nec:BVHLoader',
// 'nec:GLTFLoader' and 'nec:OrbitControls' to the embedded three.js modules; the clips come from the
// page's JSON block (#nec-clips: name, captions, joints, end_sites, frames, fps, sides and translated per
// joint, bvh = id of the BVH text block, reference = nec's joint positions at a few frames, and for a
// rigged asset mesh = id of a GLB whose first animation is the clip: its skinned mesh moves with the bones).
//
// Layout: each clip is scaled so that its largest pose extent over the motion is BODY_SIZE, stands on
// the ground (its lowest point over the motion at y = 0) and gets its own lane along x, as wide as its
// footprint over the whole motion. The page evaluates the BVH frames itself (no AnimationMixer), so any
// joint name works; its status block reports what three.js loaded, for scripts and tests. Shorter clips
// hold their last frame until the longest one loops; `view.html#t=2.5` opens paused at 2.5 s.
import * as THREE from 'three';
import { BVHLoader } from 'nec:BVHLoader';
import { GLTFLoader } from 'nec:GLTFLoader';
import { OrbitControls } from 'nec:OrbitControls';

const BODY_SIZE = 1.0;         // scene units: the largest pose extent of every clip after scaling
const LANE_GAP = 0.6;          // scene units between the footprints of neighbouring clips
const BONE_RADIUS = 0.013;     // scene units
const JOINT_RADIUS = 0.021;    // scene units
const BOUND_SAMPLES = 600;     // frames sampled per clip for its bounds and root path
const GRID_CELL = 0.25;        // scene units
const VIEW_AZIMUTH = 0.22;     // radians from +z towards +x: nearly frontal, so lanes sit side by side
const VIEW_ELEVATION = 0.3;    // radians above the horizon
const SIDE_COLORS = { 1: 0x2f6fd8, [-1]: 0xd8502d };  // joints on the left / right (nec's joint_side)
const CLIP_COLORS = [0x414857, 0x6b5233, 0x2f6048, 0x633a66, 0x2e5a6b];  // joints on neither side, per clip

const status = window.necStatus;

// The clip's asset as three.js loads a GLB (null without one).
function parseMesh(meta) {
  if (!meta.mesh) return Promise.resolve(null);
  const bytes = window.necBytes(meta.mesh);
  return new Promise((resolve, reject) => new GLTFLoader().parse(bytes.buffer, '', resolve, reject));
}

function loadClip(meta, index, gltf) {
  const { skeleton, clip } = new BVHLoader().parse(window.necText(meta.bvh));
  const bones = skeleton.bones;  // file order: joints and end sites
  const tracks = clip.tracks;    // per joint: position, quaternion
  const isEndSite = (bone) => bone.name === 'ENDSITE' && bone.children.length === 0;
  const joints = bones.filter((bone) => !isEndSite(bone));
  if (tracks.length !== 2 * joints.length) {
    throw new Error(`${meta.name}: ${tracks.length} tracks for ${joints.length} joints`);
  }
  const positions = joints.map((_, k) => tracks[2 * k].values);      // (J)(T * 3)
  const rotations = joints.map((_, k) => tracks[2 * k + 1].values);  // (J)(T * 4)
  // BVHLoader adds position channels to the joint's offset; nec (like Blender) lets them replace it.
  const offsets = joints.map((bone) => bone.position.clone());
  for (let k = 0; k < joints.length; ++k) {
    if (!meta.translated[k]) continue;
    const p = positions[k];
    for (let i = 0; i < p.length; i += 3) {
      p[i] -= offsets[k].x;
      p[i + 1] -= offsets[k].y;
      p[i + 2] -= offsets[k].z;
    }
  }
  const times = tracks.length ? tracks[0].times : [];
  const frames = times.length;
  const fps = frames > 1 && times[1] > 0 ? 1 / times[1] : meta.fps;
  const quaternion = [0, 0, 0, 1];

  // Pose at a fractional frame: positions interpolated linearly, rotations by slerp.
  const setPose = (frame) => {
    const f = Math.min(Math.max(frame, 0), Math.max(frames - 1, 0));
    const i0 = Math.floor(f);
    const i1 = Math.min(i0 + 1, frames - 1);
    const w = f - i0;
    for (let k = 0; k < joints.length; ++k) {
      const p = positions[k];
      joints[k].position.set(p[3 * i0] + (p[3 * i1] - p[3 * i0]) * w, p[3 * i0 + 1] + (p[3 * i1 + 1] - p[3 * i0 + 1]) * w,
                             p[3 * i0 + 2] + (p[3 * i1 + 2] - p[3 * i0 + 2]) * w);
      THREE.Quaternion.slerpFlat(quaternion, 0, rotations[k], 4 * i0, rotations[k], 4 * i1, w);
      joints[k].quaternion.fromArray(quaternion);
    }
  };

  // Bounds over the motion in file units, the largest per-frame pose extent and the root's path.
  const root = bones[0];
  const world = new THREE.Vector3();
  const low = new THREE.Vector3(Infinity, Infinity, Infinity);
  const high = new THREE.Vector3(-Infinity, -Infinity, -Infinity);
  const frameLow = new THREE.Vector3();
  const frameHigh = new THREE.Vector3();
  const rootPath = [];
  let size = 0;
  const step = Math.max(1, Math.floor(frames / BOUND_SAMPLES));
  const samples = [];
  for (let t = 0; t < frames; t += step) samples.push(t);
  if (frames > 0 && samples[samples.length - 1] !== frames - 1) samples.push(frames - 1);
  for (const t of samples) {
    setPose(t);
    root.updateMatrixWorld(true);
    frameLow.set(Infinity, Infinity, Infinity);
    frameHigh.set(-Infinity, -Infinity, -Infinity);
    for (const bone of bones) {
      world.setFromMatrixPosition(bone.matrixWorld);
      frameLow.min(world);
      frameHigh.max(world);
    }
    low.min(frameLow);
    high.max(frameHigh);
    size = Math.max(size, frameHigh.x - frameLow.x, frameHigh.y - frameLow.y, frameHigh.z - frameLow.z);
    world.setFromMatrixPosition(root.matrixWorld);
    rootPath.push(world.x, world.z);
  }
  if (!(size > 0)) size = 1;

  // Largest distance between the joints as shown and nec's forward kinematics, relative to the body size.
  let referenceError = 0;
  for (const { frame, positions: expected } of meta.reference) {
    setPose(frame);
    root.updateMatrixWorld(true);
    joints.forEach((bone, k) => {
      world.setFromMatrixPosition(bone.matrixWorld);
      referenceError = Math.max(referenceError, world.distanceTo(new THREE.Vector3(...expected[k])) / size);
    });
  }
  const scale = BODY_SIZE / size;

  // Visuals, in file units under the scaled group: a sphere per joint and end site, a cylinder per bone.
  const sideOf = (bone) => {
    const k = joints.indexOf(isEndSite(bone) ? bone.parent : bone);
    return k >= 0 && meta.sides ? meta.sides[k] || 0 : 0;
  };
  const materials = new Map();
  const material = (side) => {
    if (!materials.has(side)) {
      const color = SIDE_COLORS[side] ?? CLIP_COLORS[index % CLIP_COLORS.length];
      materials.set(side, new THREE.MeshStandardMaterial({ color, roughness: 0.55, metalness: 0.0 }));
    }
    return materials.get(side);
  };
  const sphere = new THREE.SphereGeometry(1, 16, 12);
  const cylinder = new THREE.CylinderGeometry(1, 1, 1, 12, 1);
  const boneRadius = BONE_RADIUS / scale;
  const links = [];  // [child bone, cylinder mesh] with the mesh in the parent's frame
  for (const bone of bones) {
    const ball = new THREE.Mesh(sphere, material(sideOf(bone)));
    ball.scale.setScalar((isEndSite(bone) ? 0.7 : bone === root ? 1.35 : 1) * JOINT_RADIUS / scale);
    bone.add(ball);
    if (bone.parent && bone.parent.isBone) {
      const stick = new THREE.Mesh(cylinder, material(sideOf(bone)));
      bone.parent.add(stick);
      links.push([bone, stick]);
    }
  }
  const up = new THREE.Vector3(0, 1, 0);
  const direction = new THREE.Vector3();
  const updateLinks = () => {
    for (const [bone, stick] of links) {
      const length = bone.position.length();
      stick.visible = length > 1e-9;
      if (!stick.visible) continue;
      direction.copy(bone.position).divideScalar(length);
      stick.position.copy(bone.position).multiplyScalar(0.5);
      stick.quaternion.setFromUnitVectors(up, direction);
      stick.scale.set(boneRadius, length, boneRadius);
    }
  };

  const group = new THREE.Group();
  group.add(root);
  group.scale.setScalar(scale);
  const path = new Float32Array(rootPath.length / 2 * 3);
  for (let i = 0; i < rootPath.length / 2; ++i) path.set([rootPath[2 * i], low.y + 0.004 / scale, rootPath[2 * i + 1]], 3 * i);
  const trail = new THREE.Line(new THREE.BufferGeometry().setAttribute('position', new THREE.BufferAttribute(path, 3)),
                               new THREE.LineBasicMaterial({ color: CLIP_COLORS[index % CLIP_COLORS.length], transparent: true, opacity: 0.45 }));
  group.add(trail);

  const duration = frames > 1 ? (frames - 1) / fps : 0;
  const mesh = gltf ? attachMesh(gltf, meta, group, joints, size, fps) : null;
  return {
    meta, group, bones, joints, frames, fps, duration, scale, low, high, referenceError, mesh,
    endSites: bones.length - joints.length,
    show(time) {
      this.frame = Math.min(time, duration) * fps;
      setPose(this.frame);
      updateLinks();
      if (mesh) mesh.mixer.setTime(Math.min(time, duration));
    },
  };
}

// The asset's scene (in the clip's units and axes, as nec reads the GLB) under the clip's group, played by
// an AnimationMixer; how far its bones are from nec's joints at the reference frames, relative to the body size.
function attachMesh(gltf, meta, group, joints, size, fps) {
  const model = gltf.scene;
  if (meta.up === 'z') model.rotation.x = -Math.PI / 2;  // as nec turned the clip
  group.add(model);
  let skinned = 0;
  model.traverse((object) => { if (object.isSkinnedMesh) ++skinned; });
  const mixer = new THREE.AnimationMixer(model);
  if (gltf.animations.length === 0) throw new Error(`${meta.name}: the asset's GLB holds no animation`);
  mixer.clipAction(gltf.animations[0]).play();
  const nodes = joints.map((bone) => model.getObjectByName(THREE.PropertyBinding.sanitizeNodeName(bone.name)));
  const world = new THREE.Vector3();
  let error = 0;
  let compared = 0;
  for (const { frame, positions: expected } of meta.reference) {
    mixer.setTime(frame / fps);
    group.updateMatrixWorld(true);
    nodes.forEach((node, k) => {
      if (!node) return;
      group.worldToLocal(node.getWorldPosition(world));
      error = Math.max(error, world.distanceTo(new THREE.Vector3(...expected[k])) / size);
      ++compared;
    });
  }
  return { mixer, skinned, error, compared };
}

// Lanes along x, each clip standing on y = 0 and centred on its footprint.
function layOut(clips) {
  let cursor = 0;
  for (const clip of clips) {
    const width = (clip.high.x - clip.low.x) * clip.scale;
    clip.laneX = cursor + width / 2;
    clip.box = new THREE.Box3(
      new THREE.Vector3(cursor, 0, (clip.low.z - clip.high.z) * clip.scale / 2),
      new THREE.Vector3(cursor + width, (clip.high.y - clip.low.y) * clip.scale, (clip.high.z - clip.low.z) * clip.scale / 2));
    cursor += width + LANE_GAP;
  }
  const shift = -(cursor - LANE_GAP) / 2;
  const scene = new THREE.Box3();
  for (const clip of clips) {
    clip.laneX += shift;
    clip.box.translate(new THREE.Vector3(shift, 0, 0));
    scene.union(clip.box);
    const center = clip.low.clone().add(clip.high).multiplyScalar(0.5);
    clip.group.position.set(clip.laneX - clip.scale * center.x, -clip.scale * clip.low.y, -clip.scale * center.z);
  }
  return scene;
}

// Moves the camera so that every corner of every box projects inside [-fill, fill] of the view,
// looking at the centre of their union.
function frameBoxes(camera, controls, boxes, fill = 0.85) {
  const union = new THREE.Box3();
  for (const box of boxes) union.union(box);
  const target = union.getCenter(new THREE.Vector3());
  const direction = new THREE.Vector3(Math.sin(VIEW_AZIMUTH) * Math.cos(VIEW_ELEVATION), Math.sin(VIEW_ELEVATION),
                                      Math.cos(VIEW_AZIMUTH) * Math.cos(VIEW_ELEVATION));
  let distance = Math.max(union.getSize(new THREE.Vector3()).length(), 1);
  const corner = new THREE.Vector3();
  for (let iteration = 0; iteration < 10; ++iteration) {
    camera.position.copy(target).addScaledVector(direction, distance);
    camera.lookAt(target);
    camera.updateMatrixWorld(true);
    let extent = 0;
    for (const box of boxes) {
      for (let i = 0; i < 8; ++i) {
        corner.set(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z).project(camera);
        extent = Math.max(extent, Math.abs(corner.x), Math.abs(corner.y));
      }
    }
    distance *= Math.max(0.5, Math.min(2, extent / fill));
  }
  camera.near = distance / 200;
  camera.far = distance * 50;
  camera.updateProjectionMatrix();
  controls.target.copy(target);
  controls.update();
}

// Whether every joint of every clip projects inside the view.
function allVisible(camera, clips) {
  const p = new THREE.Vector3();
  for (const clip of clips) {
    clip.group.updateMatrixWorld(true);
    for (const bone of clip.bones) {
      p.setFromMatrixPosition(bone.matrixWorld).project(camera);
      if (Math.abs(p.x) > 1 || Math.abs(p.y) > 1 || p.z > 1) return false;
    }
  }
  return true;
}

function makeLabel(clip) {
  const element = document.createElement('div');
  element.className = 'label';
  const name = document.createElement('span');
  name.className = 'name';
  name.textContent = clip.meta.name;
  element.append(name);
  if (clip.meta.captions.length > 0) {  // the first; the others are rephrasings
    const caption = document.createElement('span');
    caption.className = 'caption';
    caption.textContent = clip.meta.captions[0];
    element.append(caption);
  }
  const meta = document.createElement('span');
  meta.className = 'meta';
  element.append(meta);
  document.getElementById('labels').append(element);
  const anchor = new THREE.Vector3();
  return (camera, width, height) => {
    meta.textContent = `${clip.joints.length} joints · ${clip.fps.toFixed(0)} fps · frame ${Math.round(clip.frame)} / ${clip.frames - 1}`;
    anchor.setFromMatrixPosition(clip.bones[0].matrixWorld).setY(0).project(camera);  // on the ground under the root
    element.style.display = anchor.z < 1 ? '' : 'none';
    return { element, x: ((anchor.x + 1) / 2) * width, y: ((1 - anchor.y) / 2) * height + 14,
             width: element.offsetWidth, height: element.offsetHeight };
  };
}

// Puts the labels at their anchors, moving a label down below any earlier one it would overlap.
function placeLabels(labels) {
  const placed = [];
  for (const label of [...labels].sort((a, b) => a.y - b.y)) {
    for (const other of placed) {
      const apart = Math.abs(label.x - other.x) >= (label.width + other.width) / 2 + 4;
      if (!apart && label.y < other.y + other.height + 4 && label.y + label.height > other.y - 4) {
        label.y = other.y + other.height + 4;
      }
    }
    placed.push(label);
    label.element.style.left = `${label.x}px`;
    label.element.style.top = `${label.y}px`;
  }
}

async function main() {
  const metas = JSON.parse(window.necText('nec-clips'));
  const meshes = await Promise.all(metas.map(parseMesh));
  const clips = metas.map((meta, index) => loadClip(meta, index, meshes[index]));
  for (const clip of clips) {
    const loaded = { joints: clip.joints.length, end_sites: clip.endSites, frames: clip.frames };
    for (const key of Object.keys(loaded)) {
      if (loaded[key] !== clip.meta[key]) throw new Error(`${clip.meta.name}: three.js loaded ${loaded[key]} ${key}, nec wrote ${clip.meta[key]}`);
    }
    if (!(clip.referenceError <= 1e-4)) {
      window.necFail(`${clip.meta.name}: joints are drawn up to ${clip.referenceError} body sizes away from nec's forward kinematics`);
    }
    if (clip.mesh && !(clip.mesh.compared > 0 && clip.mesh.error <= 1e-3)) {
      window.necFail(`${clip.meta.name}: the asset's bones move up to ${clip.mesh.error} body sizes away from nec's joints (${clip.mesh.compared} compared)`);
    }
  }

  const stage = document.getElementById('stage');
  const renderer = new THREE.WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  renderer.setSize(window.innerWidth, window.innerHeight);
  stage.append(renderer.domElement);

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf3f3ef);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a80, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 2.0);
  sun.position.set(3, 6, 4);
  scene.add(sun);
  for (const clip of clips) scene.add(clip.group);
  const bounds = layOut(clips);
  const extent = Math.max(Math.abs(bounds.min.x), Math.abs(bounds.max.x), Math.abs(bounds.min.z), Math.abs(bounds.max.z));
  const gridSize = 2 * Math.ceil(extent + 1);
  scene.add(new THREE.GridHelper(gridSize, Math.round(gridSize / GRID_CELL), 0xa9a9a0, 0xd6d6cf));

  const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 0.01, 1000);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.enableDamping = true;
  for (const clip of clips) clip.show(0);
  const frameAll = () => frameBoxes(camera, controls, clips.map((clip) => clip.box));
  frameAll();
  const labels = clips.map(makeLabel);

  const duration = Math.max(...clips.map((clip) => clip.duration), 0);
  const fastest = Math.max(...clips.map((clip) => clip.fps));
  const play = document.getElementById('play');
  const scrub = document.getElementById('scrub');
  const clock = document.getElementById('clock');
  const speed = document.getElementById('speed');
  let time = 0;
  let playing = true;
  const setPlaying = (on) => {
    playing = on;
    play.innerHTML = on ? '&#10073;&#10073;' : '&#9654;';
  };
  const start = /(?:^#|&)t=([0-9.]+)/.exec(window.location.hash);  // view.html#t=2.5 opens paused at 2.5 s
  if (start) {
    time = Math.min(Number(start[1]) || 0, duration);
    setPlaying(false);
  }
  play.addEventListener('click', () => setPlaying(!playing));
  scrub.addEventListener('input', () => { time = Number(scrub.value) * duration; });
  document.getElementById('frame-all').addEventListener('click', frameAll);
  window.addEventListener('keydown', (event) => {
    if (event.target instanceof HTMLInputElement || event.target instanceof HTMLSelectElement) return;
    if (event.key === ' ') {
      setPlaying(!playing);
    } else if (event.key === 'ArrowRight' || event.key === 'ArrowLeft') {
      setPlaying(false);
      time = Math.min(Math.max(time + (event.key === 'ArrowRight' ? 1 : -1) / fastest, 0), duration);
    } else if (event.key === 'f') {
      frameAll();
    } else {
      return;
    }
    event.preventDefault();
  });
  window.addEventListener('resize', () => {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
  });

  let last = performance.now();
  let rendered = 0;
  const tick = (now) => {
    const seconds = Math.min(0.1, Math.max(0, (now - last) / 1000));
    last = now;
    if (playing && duration > 0) time = (time + seconds * Number(speed.value)) % duration;
    for (const clip of clips) clip.show(time);
    scrub.value = String(duration > 0 ? time / duration : 0);
    clock.textContent = `${time.toFixed(2)} / ${duration.toFixed(2)} s`;
    controls.update();
    renderer.render(scene, camera);
    placeLabels(labels.map((measure) => measure(camera, window.innerWidth, window.innerHeight)));
    if (++rendered === 1) {
      status.state = status.errors.length ? 'error' : 'ready';
      status.ok = status.errors.length === 0;
      status.three = THREE.REVISION;
      status.visible = allVisible(camera, clips);
      status.clips = clips.map((clip) => ({
        name: clip.meta.name, joints: clip.joints.length, end_sites: clip.endSites, frames: clip.frames,
        frame: Math.round(clip.frame), time: Number(time.toFixed(4)),
        fps: Number(clip.fps.toFixed(4)), scale: Number(clip.scale.toPrecision(4)),
        reference_error: Number(clip.referenceError.toPrecision(3)),
        ...(clip.mesh ? { skinned_meshes: clip.mesh.skinned, mesh_error: Number(clip.mesh.error.toPrecision(3)) } : {}),
      }));
      window.necReport();
    }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
}

main().catch((error) => window.necFail(error && error.stack ? error.stack : error));
