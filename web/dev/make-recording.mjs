// Writes dev/recording.jsonl: a hand-made run of the grasp task, one protocol message a line
// (docs/live-view.md), for working on the page without fba-run:
//   node dev/make-recording.mjs && npx vite   then open /?replay=/dev/recording.jsonl
// Not a test and not a figure: a bottle-like cylinder carved from five views, made up here.
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const urdf = fs.readFileSync(path.join(here, '../../hardware/robots/wrist_camera_arm.urdf'), 'utf8');

function png(width, height, pixel) {
  const raw = Buffer.alloc((width * 3 + 1) * height);
  for (let y = 0; y < height; y++) {
    raw[y * (width * 3 + 1)] = 0;
    for (let x = 0; x < width; x++) raw.set(pixel(x, y), y * (width * 3 + 1) + 1 + 3 * x);
  }
  const crcTable = Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c >>> 0;
  });
  const crc = (buf) => {
    let c = 0xffffffff;
    for (const b of buf) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
    return (c ^ 0xffffffff) >>> 0;
  };
  const chunk = (type, data) => {
    const len = Buffer.alloc(4);
    len.writeUInt32BE(data.length);
    const td = Buffer.concat([Buffer.from(type), data]);
    const c = Buffer.alloc(4);
    c.writeUInt32BE(crc(td));
    return Buffer.concat([len, td, c]);
  };
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0);
  ihdr.writeUInt32BE(height, 4);
  ihdr.set([8, 2, 0, 0, 0], 8);
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', ihdr),
    chunk('IDAT', zlib.deflateSync(raw)), chunk('IEND', Buffer.alloc(0))]);
}

const port = (name, type) => ({ name, type });
const components = [
  { name: 'start', type: 'examples.counter', kind: 'sensor', doc: 'one sample', inputs: [], outputs: [port('out', 'int')] },
  { name: 'arm', type: 'sim.arm', kind: 'actuator', doc: 'the arm carrying the wrist camera', inputs: [port('target', 'Pose'), port('trajectory', 'Trajectory')], outputs: [port('pose', 'Pose'), port('joint_state', 'JointState')] },
  { name: 'camera', type: 'sim.camera', kind: 'sensor', doc: 'the wrist camera', inputs: [port('pose', 'Pose')], outputs: [port('image', 'CalibratedImage')] },
  { name: 'contours', type: 'vision.contour_extraction', kind: 'filter', doc: 'silhouettes', inputs: [port('image', 'CalibratedImage')], outputs: [port('silhouette', 'Silhouette')] },
  { name: 'carver', type: 'vision.octree_carver', kind: 'filter', doc: 'carves the octree', inputs: [port('silhouette', 'Silhouette'), port('regions', 'Regions')], outputs: [port('model', 'OctreeModel')] },
  { name: 'synthesis', type: 'grasp.synthesis', kind: 'filter', doc: 'selects a grasp or asks for detail', inputs: [port('model', 'OctreeModel')], outputs: [port('grasps', 'Grasps'), port('regions', 'Regions'), port('selected', 'Grasp')] },
  { name: 'planner', type: 'grasp.exploration_planner', kind: 'filter', doc: 'the next view', inputs: [port('start', 'int'), port('model', 'OctreeModel')], outputs: [port('view', 'Pose')] },
  { name: 'hand', type: 'sim.hand', kind: 'actuator', doc: 'the three-finger hand', inputs: [port('grasp', 'Grasp')], outputs: [port('result', 'GraspResult')] },
];
const connections = [
  ['start.out', 'planner.start'], ['planner.view', 'arm.target'], ['arm.pose', 'camera.pose'], ['camera.image', 'contours.image'],
  ['contours.silhouette', 'carver.silhouette'], ['carver.model', 'synthesis.model'], ['carver.model', 'planner.model'],
  ['synthesis.regions', 'carver.regions', true], ['synthesis.selected', 'hand.grasp'],
].map(([from, to, feedback]) => ({ from, to, policy: 'lossless', capacity: 16, feedback: !!feedback }));

const out = [];
out.push({ type: 'task', run_id: 'dev-recording', task: 'grasp', file: 'tasks/grasp.yaml', components, connections });
out.push({ type: 'view', port: 'arm.robot', data_type: 'fba.RobotDescription', seq: 0, t: 0, view: { kind: 'robot', urdf, name: 'wrist_camera_arm.urdf' } });

// A bottle: a cylinder of radius 3.5 cm, 19 cm tall, carved at a 4 mm edge; a shell of uncarved
// leaves on the far side; the leaves near the two contacts refined for grasping.
const edge = 0.26 / 64;
const occupied = [], uncarved = [], refine = [];
for (let x = -0.06; x < 0.06; x += edge) for (let y = -0.06; y < 0.06; y += edge) for (let z = edge / 2; z < 0.19; z += edge) {
  const r = Math.hypot(x, y);
  const shell = r > 0.035 - edge && r < 0.035;
  if (shell || (z < edge || z > 0.19 - 2 * edge) && r < 0.035) occupied.push(x, y, z, edge);
  else if (r >= 0.035 && r < 0.045 && x < -0.01) uncarved.push(x, y, z, edge);
  if (shell && Math.abs(z - 0.1) < 0.012 && Math.abs(y) < 0.012) refine.push(x, y, z, edge);
}
let t = 0;
const poses = [];
for (let i = 0; i < 5; i++) {
  const a = (-0.5 + i * 0.35) * Math.PI;
  const p = [0.3 * Math.cos(a), 0.3 * Math.sin(a), 0.2];
  // Looking at the bottle's middle: the camera's z towards it, its y (down) towards the table.
  const zc = [-p[0], -p[1], 0.1 - p[2]];
  const n = Math.hypot(...zc);
  const z = zc.map((v) => v / n);
  const xv = [z[1], -z[0], 0];
  const xn = Math.hypot(...xv);
  const xx = xv.map((v) => v / xn);
  const y = [z[1] * xx[2] - z[2] * xx[1], z[2] * xx[0] - z[0] * xx[2], z[0] * xx[1] - z[1] * xx[0]];
  const m = [[xx[0], y[0], z[0]], [xx[1], y[1], z[1]], [xx[2], y[2], z[2]]];
  const w = Math.sqrt(Math.max(0, 1 + m[0][0] + m[1][1] + m[2][2])) / 2;
  const q = [w, (m[2][1] - m[1][2]) / (4 * w), (m[0][2] - m[2][0]) / (4 * w), (m[1][0] - m[0][1]) / (4 * w)];
  poses.push({ position: p, rotation: q });
}
const W = 320, H = 240;
const image = png(W, H, (x, y) => (Math.abs(x - 160) < 45 && y > 30 && y < 220 ? [120, 90, 40] : [230, 230, 230]));
const contour = [[115, 30], [205, 30], [205, 220], [115, 220]];
for (let i = 0; i < poses.length; i++) {
  t += 0.4;
  out.push({ type: 'view', port: 'arm.pose', data_type: 'Pose', seq: i, t, view: { kind: 'pose', ...poses[i] } });
  out.push({ type: 'view', port: 'arm.joint_state', data_type: 'JointState', seq: i, t, view: { kind: 'joints',
    names: ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint'],
    positions: [0.3 * i - 0.6, -1.2, 1.4, -1.6, -1.57, 0] } });
  out.push({ type: 'view', port: 'camera.image', data_type: 'CalibratedImage', seq: i, t, view: { kind: 'image', width: W, height: H, encoding: 'png', data: image.toString('base64'), contours: [] } });
  out.push({ type: 'view', port: 'contours.silhouette', data_type: 'Silhouette', seq: i, t, view: { kind: 'image', width: W, height: H, encoding: 'png', data: image.toString('base64'), contours: [contour] } });
  out.push({ type: 'event', index: i, t, source: 'carver', name: 'view_carved', payload: { view: i + 1, leaves: occupied.length / 4 } });
  out.push({ type: 'stats', t, components: components.map((c, k) => ({ name: c.name, state: k % 3 ? 'idle' : 'running', stage: k === 4 ? 'carve' : '',
    invocations: i + 1, samples_in: i + 1, samples_out: i + 1, errors: 0, rate_hz: 2.5 + k * 0.1 * i })),
  connections: connections.map((c, k) => ({ from: c.from, to: c.to, queued: (i + k) % 5, capacity: 16, delivered: i + 1, dropped: 0, rate_hz: 2.5 })) });
}
out.push({ type: 'view', port: 'carver.model', data_type: 'OctreeModel', seq: 4, t, view: { kind: 'model', occupied, uncarved, refine,
  bounds: [-0.13, -0.13, -0.02, 0.13, 0.13, 0.24] } });
out.push({ type: 'view', port: 'synthesis.regions', data_type: 'Regions', seq: 4, t, view: { kind: 'regions', boxes: [[0.025, -0.012, 0.088, 0.04, 0.012, 0.112]] } });
const candidates = [];
for (let k = 0; k < 12; k++) {
  const a = (k / 12) * Math.PI * 2;
  const c1 = [0.035 * Math.cos(a), 0.035 * Math.sin(a), 0.1];
  const c2 = [-c1[0], -c1[1], 0.1];
  candidates.push({ contacts: [c1, c2, [c2[0], c2[1], 0.12]], normals: [[-Math.cos(a), -Math.sin(a), 0], [Math.cos(a), Math.sin(a), 0], [Math.cos(a), Math.sin(a), 0]],
    approach: [0, 0, -1], score: 0.02 + 0.003 * k, palm: null });
}
candidates.reverse();  // best first
candidates[0].palm = { position: [0, 0, 0.2], rotation: [1, 0, 0, 0] };
t += 0.3;
out.push({ type: 'view', port: 'synthesis.candidates', data_type: 'fba.GraspCandidates', seq: 4, t, view: { kind: 'grasps', candidates, selected: null, total: 40 } });
out.push({ type: 'view', port: 'synthesis.grasp', data_type: 'fba.Grasp', seq: 0, t, view: { kind: 'grasps', candidates: [], selected: { ...candidates[0], palm: null } } });
out.push({ type: 'event', index: 5, t, source: 'synthesis', name: 'selected', payload: { score: selected.score, views: 5 } });
out.push({ type: 'event', index: 6, t: t + 1, source: 'hand', name: 'held', payload: {} });
out.push({ type: 'end', outcome: 'success', exit_code: 0, reason: 'hand.held: stop_success', summary: {} });
fs.writeFileSync(path.join(here, 'recording.jsonl'), out.map((m) => JSON.stringify(m)).join('\n') + '\n');
console.log(`wrote ${out.length} messages, ${occupied.length / 4} occupied leaves`);
