import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { UrdfRobot } from './urdf-robot.js';
import { el } from './dom.js';

// The 3D scene in the world frame (z up, the table at z = 0): the octree model's occupied leaves as
// one InstancedMesh of boxes coloured by height, the space not yet carved as translucent boxes, the
// leaves refined for grasping (a grasp criterion split their parent: synthesis's regions, a
// graspable contour) and synthesis's regions highlighted, the camera poses visited as numbered
// frusta, the grasps, the reach trajectory as the path of the palm (the robot posed at each
// waypoint), and the robot the arm sends. It renders only when something changed.
//
// The grasps come from two grasp views: synthesis's candidates after each analysis (the best one
// with its palm at the pregrasp), and the selected grasp once there is one.

const COLORS = {
  low: new THREE.Color(0x2f6db5),
  high: new THREE.Color(0xf2c14e),
  uncarved: 0x8fa8c8,
  refine: 0xff3d9a,
  regions: 0xff3d9a,
  candidate: 0x7fb8d8,
  selected: [0xe74c3c, 0x27ae60, 0x2e86de, 0xf39c12],
  approach: 0xffd166,
  palm: 0xd0d7e2,
  passedOver: 0x5d6978,
  trajectory: 0xc77dff,
};

const POSE_COLORS = [0x2bb673, 0x4cc9f0, 0xf4a261, 0xb388eb];

export const LAYERS = [
  ['occupied', 'occupied leaves', '#c99a4a'],
  ['uncarved', 'not yet carved', '#8fa8c8'],
  ['refine', 'refined for grasping', '#ff3d9a'],
  ['views', 'camera views, in order', '#2bb673'],
  ['candidates', 'candidate grasps', '#7fb8d8'],
  ['selected', 'selected grasp', '#e74c3c'],
  ['trajectory', 'reach: the palm\'s path', '#c77dff'],
  ['robot', 'robot', '#9aa4b1'],
];

// The same quaternion order as the protocol: [qw, qx, qy, qz].
const quaternion = (r) => new THREE.Quaternion(r[1], r[2], r[3], r[0]);

function leafMesh(material, capacity) {
  const mesh = new THREE.InstancedMesh(new THREE.BoxGeometry(1, 1, 1), material, Math.max(1, capacity));
  mesh.count = 0;
  mesh.frustumCulled = false;
  return mesh;
}

function labelSprite(text, color) {
  const canvas = document.createElement('canvas');
  canvas.width = 64;
  canvas.height = 64;
  const c = canvas.getContext('2d');
  c.fillStyle = 'rgba(12,16,22,0.75)';
  c.beginPath();
  c.arc(32, 32, 26, 0, Math.PI * 2);
  c.fill();
  c.fillStyle = color;
  c.font = 'bold 34px sans-serif';
  c.textAlign = 'center';
  c.textBaseline = 'middle';
  c.fillText(text, 32, 34);
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: new THREE.CanvasTexture(canvas), depthTest: false }));
  sprite.scale.set(0.022, 0.022, 1);
  sprite.renderOrder = 10;
  return sprite;
}

// A camera's frustum in its own frame: OpenCV's convention, looking along +z, y down.
function frustumGeometry() {
  const d = 0.05, w = 0.032, h = 0.024;
  const c = [[-w, -h, d], [w, -h, d], [w, h, d], [-w, h, d]];
  const p = [];
  for (const q of c) p.push(0, 0, 0, ...q);
  for (let i = 0; i < 4; i++) p.push(...c[i], ...c[(i + 1) % 4]);
  p.push(-w * 0.5, -h, d, 0, -h * 1.6, d, 0, -h * 1.6, d, w * 0.5, -h, d);  // a tick on the image's top edge
  return new THREE.BufferGeometry().setAttribute('position', new THREE.Float32BufferAttribute(p, 3));
}

function disposeTree(object) {
  object.traverse((o) => {
    o.geometry?.dispose?.();
    if (o.material) for (const m of [].concat(o.material)) { m.map?.dispose?.(); m.dispose?.(); }
  });
}

export class SceneView {
  constructor(container) {
    this.container = container;
    this.layerVisible = Object.fromEntries(LAYERS.map(([k]) => [k, true]));
    this.info = el('div', { class: 'scene-info' });
    this.legend = el('div', { class: 'scene-legend' });
    this.message = el('div', { class: 'panel-message' }, 'no 3D data yet: models, camera views and grasps appear here when the task sends them');
    container.append(this.legend, this.info, this.message);
    this.stats = { occupiedInstances: 0, occupiedInMessage: 0, uncarvedInstances: 0, refineInstances: 0, poses: 0,
      candidates: 0, candidatesFound: 0, selected: false, palm: false, robotLinks: 0, modelPort: null, modelSeq: null,
      trajectoryPort: null, trajectoryWaypoints: 0, trajectoryPathPoints: 0, trajectoryLink: null, trajectoryProblem: null };
    this.poseLists = new Map();
    this.graspViews = new Map();  // port -> its newest grasps view
    try {
      this.renderer = new THREE.WebGLRenderer({ antialias: true });
    } catch (e) {
      this.renderer = null;
      this.message.textContent = `the 3D view needs WebGL, which this browser did not provide (${e.message}); the other panels work without it`;
      this.message.classList.add('error');
      return;
    }
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    this.renderer.setClearColor(0x151a21);
    this.renderer.domElement.classList.add('scene-canvas');
    container.prepend(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.005, 20);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(0.45, -0.55, 0.4);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0, 0.08);
    this.controls.addEventListener('change', () => this.invalidate());
    this.controls.update();

    this.scene.add(new THREE.HemisphereLight(0xdfe8f5, 0x3a3328, 1.4));
    const sun = new THREE.DirectionalLight(0xffffff, 1.8);
    sun.position.set(0.6, -0.4, 1.2);
    this.scene.add(sun);
    this.decor = new THREE.Group();
    const grid = new THREE.GridHelper(1.2, 24, 0x3b4654, 0x262e38);
    grid.rotation.x = Math.PI / 2;  // the table, z = 0
    this.decor.add(grid, new THREE.AxesHelper(0.05));
    this.scene.add(this.decor);

    this.occupied = leafMesh(new THREE.MeshStandardMaterial({ roughness: 0.75, metalness: 0.05 }), 1);
    this.uncarved = leafMesh(new THREE.MeshBasicMaterial({ color: COLORS.uncarved, transparent: true, opacity: 0.07, depthWrite: false }), 1);
    this.refine = leafMesh(new THREE.MeshBasicMaterial({ color: COLORS.refine, transparent: true, opacity: 0.45, depthWrite: false }), 1);
    this.layers = {
      occupied: new THREE.Group(), uncarved: new THREE.Group(), refine: new THREE.Group(), views: new THREE.Group(),
      candidates: new THREE.Group(), selected: new THREE.Group(), trajectory: new THREE.Group(), robot: new THREE.Group(),
    };
    for (const g of Object.values(this.layers)) this.scene.add(g);
    this.layers.occupied.add(this.occupied);
    this.layers.uncarved.add(this.uncarved);
    this.layers.refine.add(this.refine);
    this.bounds = new THREE.Box3Helper(new THREE.Box3(), 0x56616f);
    this.bounds.visible = false;
    this.decor.add(this.bounds);
    this.regions = new THREE.Group();
    this.layers.refine.add(this.regions);
    this.buildLegend();
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  buildLegend() {
    this.legend.replaceChildren(...LAYERS.map(([key, label, color]) => el('label', { class: 'legend-item' },
      el('input', { type: 'checkbox', checked: true, 'data-layer': key, onchange: (ev) => this.setLayer(key, ev.target.checked) }),
      el('span', { class: 'swatch', style: `background:${color}` }), label)),
    el('button', { class: 'small', onclick: () => this.fit(), title: 'frame the model (also: double click)' }, 'fit'));
    this.renderer.domElement.addEventListener('dblclick', () => this.fit());
  }

  setLayer(key, visible) {
    this.layerVisible[key] = visible;
    const box = this.legend.querySelector(`input[data-layer="${key}"]`);
    if (box) box.checked = visible;
    this.layers[key].visible = visible;
    this.invalidate();
  }

  resize() {
    if (!this.renderer) return;
    const r = this.container.getBoundingClientRect();
    const w = Math.max(1, Math.floor(r.width));
    const h = Math.max(1, Math.floor(r.height));
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.invalidate();
  }

  invalidate() {
    if (this.frame || !this.renderer) return;
    this.frame = requestAnimationFrame(() => {
      this.frame = 0;
      this.renderer.render(this.scene, this.camera);
    });
  }

  setTask(task) {
    this.stats.robotLinks = 0;
    this.poseLists.clear();
    this.graspViews.clear();
    this.trajectory = null;
    this.robot = null;
    this.robotError = null;
    this.joints = null;
    Object.assign(this.stats, { candidates: 0, candidatesFound: 0, selected: false, palm: false, trajectoryPort: null, trajectoryWaypoints: 0,
      trajectoryPathPoints: 0, trajectoryLink: null, trajectoryProblem: null });
    if (!this.renderer) return;
    for (const key of ['views', 'candidates', 'selected', 'trajectory', 'robot']) {
      disposeTree(this.layers[key]);
      this.layers[key].clear();
    }
    this.regions.clear();
    this.setLeaves(this.occupied, [], true);
    this.setLeaves(this.uncarved, []);
    this.setLeaves(this.refine, []);
    this.modelBox = null;
    this.fitted = false;
    this.updateInfo();
    this.invalidate();
  }

  // Writes the flat [x, y, z, edge, ...] leaves straight into the instance matrices.
  setLeaves(mesh, flat, colourByHeight = false) {
    const n = flat.length / 4;
    if (n > mesh.instanceMatrix.count) {
      const grown = new THREE.InstancedMesh(mesh.geometry, mesh.material, Math.ceil(n * 1.25));
      grown.frustumCulled = false;
      mesh.parent.add(grown);
      mesh.parent.remove(mesh);
      mesh.dispose();
      if (mesh === this.occupied) this.occupied = grown;
      else if (mesh === this.uncarved) this.uncarved = grown;
      else this.refine = grown;
      mesh = grown;
    }
    const m = mesh.instanceMatrix.array;
    let zmin = Infinity, zmax = -Infinity;
    for (let i = 0; i < n; i++) {
      const z = flat[4 * i + 2];
      if (z < zmin) zmin = z;
      if (z > zmax) zmax = z;
    }
    const color = new THREE.Color();
    for (let i = 0; i < n; i++) {
      const x = flat[4 * i], y = flat[4 * i + 1], z = flat[4 * i + 2], e = flat[4 * i + 3];
      m.set([e, 0, 0, 0, 0, e, 0, 0, 0, 0, e, 0, x, y, z, 1], 16 * i);
      if (colourByHeight) {
        color.lerpColors(COLORS.low, COLORS.high, zmax > zmin ? (z - zmin) / (zmax - zmin) : 0.5);
        mesh.setColorAt(i, color);
      }
    }
    mesh.count = n;
    mesh.instanceMatrix.needsUpdate = true;
    if (mesh.instanceColor) mesh.instanceColor.needsUpdate = true;
    return mesh;
  }

  setModel(msg) {
    const v = msg.view;
    this.stats.modelPort = msg.port;
    this.stats.modelSeq = msg.seq;
    this.stats.occupiedInMessage = v.occupied.length / 4;
    if (!this.renderer) return;
    this.setLeaves(this.occupied, v.occupied, true);
    this.setLeaves(this.uncarved, v.uncarved ?? []);
    this.setLeaves(this.refine, v.refine ?? []);
    this.modelBox = new THREE.Box3();
    const o = v.occupied;
    for (let i = 0; i < o.length; i += 4) {
      const h = o[i + 3] / 2;
      this.modelBox.expandByPoint(new THREE.Vector3(o[i] - h, o[i + 1] - h, o[i + 2] - h));
      this.modelBox.expandByPoint(new THREE.Vector3(o[i] + h, o[i + 1] + h, o[i + 2] + h));
    }
    this.stats.occupiedInstances = this.occupied.count;
    this.stats.uncarvedInstances = this.uncarved.count;
    this.stats.refineInstances = this.refine.count;
    if (v.bounds) {
      this.bounds.box.min.set(v.bounds[0], v.bounds[1], v.bounds[2]);
      this.bounds.box.max.set(v.bounds[3], v.bounds[4], v.bounds[5]);
      this.bounds.visible = true;
    }
    this.message.hidden = true;
    if (!this.fitted) this.fit();
    this.updateInfo();
    this.invalidate();
  }

  setRegions(msg) {
    if (!this.renderer) return;
    disposeTree(this.regions);
    this.regions.clear();
    for (const b of msg.view.boxes) {
      const helper = new THREE.Box3Helper(new THREE.Box3(new THREE.Vector3(b[0], b[1], b[2]), new THREE.Vector3(b[3], b[4], b[5])), COLORS.regions);
      this.regions.add(helper);
    }
    this.stats.regions = msg.view.boxes.length;
    this.updateInfo();
    this.invalidate();
  }

  setPoses(port, list) {
    this.poseLists.set(port, list);
    this.stats.poses = [...this.poseLists.values()].reduce((s, l) => s + l.length, 0);
    if (!this.renderer) return;
    const group = this.layers.views;
    disposeTree(group);
    group.clear();
    const frustum = frustumGeometry();  // shared by this pass's frusta, freed with them by the next
    // Each pose port in its own colour (the camera's poses, a planner's targets…), numbered in order.
    [...this.poseLists.values()].forEach((poses, k) => {
      const color = new THREE.Color(POSE_COLORS[k % POSE_COLORS.length]);
      const points = [];
      poses.forEach((p, i) => {
        const latest = i === poses.length - 1;
        const lines = new THREE.LineSegments(frustum, new THREE.LineBasicMaterial({ color: latest ? color.clone().offsetHSL(0, 0, 0.2) : color }));
        lines.position.set(...p.view.position);
        lines.quaternion.copy(quaternion(p.view.rotation));
        if (latest) lines.scale.setScalar(1.3);
        group.add(lines);
        const label = labelSprite(String(i + 1), `#${color.getHexString()}`);
        label.position.set(...p.view.position).add(new THREE.Vector3(0, 0, 0.02));
        group.add(label);
        points.push(new THREE.Vector3(...p.view.position));
      });
      if (points.length > 1) {
        const path = new THREE.Line(new THREE.BufferGeometry().setFromPoints(points),
          new THREE.LineDashedMaterial({ color, dashSize: 0.01, gapSize: 0.008, transparent: true, opacity: 0.6 }));
        path.computeLineDistances();
        group.add(path);
      }
    });
    this.updateInfo();
    this.invalidate();
  }

  setGrasps(msg) {
    this.graspViews.set(msg.port, msg.view);
    this.renderGrasps();
  }

  // The grasps drawn: the candidates of the newest analysis, the selected grasp, and the palm of
  // the best candidate (the selected one, once there is one) at the pregrasp.
  renderGrasps() {
    const views = [...this.graspViews.values()];
    const candidates = views.flatMap((v) => v.candidates);
    const selected = views.find((v) => v.selected)?.selected ?? null;
    const palm = selected?.palm ?? candidates.find((g) => g.palm)?.palm ?? null;
    this.stats.candidates = candidates.length;
    this.stats.candidatesFound = views.reduce((n, v) => n + (v.total ?? v.candidates.length), 0);
    this.stats.selected = !!selected;
    this.stats.palm = palm;
    this.selectedGrasp = selected;
    if (!this.renderer) return;
    for (const key of ['candidates', 'selected']) {
      disposeTree(this.layers[key]);
      this.layers[key].clear();
    }

    const scores = candidates.map((g) => g.score ?? 0);
    const lo = Math.min(...scores), hi = Math.max(...scores);
    const contacts = candidates.reduce((s, g) => s + g.contacts.length, 0);
    if (contacts) {
      const spheres = new THREE.InstancedMesh(new THREE.SphereGeometry(0.0025, 8, 6), new THREE.MeshBasicMaterial(), contacts);
      const normals = [];
      const colors = [];
      const dummy = new THREE.Object3D();
      const c = new THREE.Color();
      let k = 0;
      for (const g of candidates) {
        // Those the arm's reach check passed over, grey; the others by score.
        if (g.passed_over) c.set(COLORS.passedOver);
        else c.set(COLORS.candidate).lerp(new THREE.Color(0x00ffff), hi > lo ? ((g.score ?? 0) - lo) / (hi - lo) : 1);
        g.contacts.forEach((p, i) => {
          dummy.position.set(...p);
          dummy.updateMatrix();
          spheres.setMatrixAt(k, dummy.matrix);
          spheres.setColorAt(k++, c);
          const n = g.normals?.[i];
          if (n) {
            normals.push(...p, p[0] + n[0] * 0.02, p[1] + n[1] * 0.02, p[2] + n[2] * 0.02);
            colors.push(c.r, c.g, c.b, c.r, c.g, c.b);
          }
        });
      }
      this.layers.candidates.add(spheres);
      if (normals.length) {
        const geometry = new THREE.BufferGeometry()
          .setAttribute('position', new THREE.Float32BufferAttribute(normals, 3))
          .setAttribute('color', new THREE.Float32BufferAttribute(colors, 3));
        this.layers.candidates.add(new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true, transparent: true, opacity: 0.6 })));
      }
    }
    if (selected) this.layers.selected.add(this.graspObject(selected));
    if (palm) this.layers[selected ? 'selected' : 'candidates'].add(this.palmObject(palm));
    this.updateInfo();
    this.invalidate();
  }

  // The run is over: a reach trajectory whose view never came (the run ended before the next
  // update) is drawn from the summary's results.
  setRunEnd(summary) {
    const reach = Object.values(summary?.components ?? {}).map((c) => c?.results?.reach).find((r) => r?.trajectory);
    if (!this.trajectory && Array.isArray(reach?.trajectory?.names) && Array.isArray(reach?.trajectory?.points)) {
      this.setTrajectory({ port: 'summary: reach', view: { kind: 'trajectory', ...reach.trajectory } });
    }
  }

  // A joint trajectory (the reach planner's): the path of the link it carries, the robot's URDF
  // posed at each waypoint, with its start and end marked.
  setTrajectory(msg) {
    this.trajectory = msg;
    this.drawTrajectory();
  }

  drawTrajectory() {
    const msg = this.trajectory;
    if (!msg) return;
    const v = msg.view;
    Object.assign(this.stats, { trajectoryPort: msg.port, trajectoryWaypoints: v.points.length, trajectoryPathPoints: 0,
      trajectoryLink: null, trajectoryProblem: null });
    if (this.renderer) {
      disposeTree(this.layers.trajectory);
      this.layers.trajectory.clear();
    }
    if (!this.robot) {
      this.stats.trajectoryProblem = this.robotError ?? 'no robot description (URDF) to draw it with';
      this.updateInfo();
      return;
    }
    const link = this.robot.carriedLink(v.names);
    const known = v.names.filter((n) => this.robot.joints.has(n)).length;
    if (!link || known === 0) {
      this.stats.trajectoryProblem = `none of its joints (${v.names.join(', ')}) is in the robot's URDF`;
      this.updateInfo();
      return;
    }
    const points = this.robot.linkPositions(link, v.names, v.points.map((p) => p.positions));
    this.stats.trajectoryLink = link;
    this.stats.trajectoryPathPoints = points.length;
    if (this.renderer && points.length) {
      const color = new THREE.Color(COLORS.trajectory);
      this.layers.trajectory.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(points), new THREE.LineBasicMaterial({ color })));
      const start = new THREE.Mesh(new THREE.SphereGeometry(0.004, 12, 8), new THREE.MeshBasicMaterial({ color }));
      start.position.copy(points[0]);
      const end = new THREE.Mesh(new THREE.OctahedronGeometry(0.006), new THREE.MeshBasicMaterial({ color: color.clone().offsetHSL(0, 0, 0.2) }));
      end.position.copy(points[points.length - 1]);
      this.layers.trajectory.add(start, end);
    }
    this.updateInfo();
    this.invalidate();
  }

  // For the browser tests: where the trajectory's link is with the joints `names` at `positions`.
  linkPositionAt(names, positions) {
    if (!this.robot) return null;
    const link = this.robot.carriedLink(names);
    const [p] = this.robot.linkPositions(link, names, [positions]);
    return p ? { link, position: [p.x, p.y, p.z] } : null;
  }

  graspObject(g) {
    const group = new THREE.Group();
    const centre = new THREE.Vector3();
    g.contacts.forEach((p, i) => {
      const color = COLORS.selected[i % COLORS.selected.length];
      const s = new THREE.Mesh(new THREE.SphereGeometry(0.0045, 16, 12), new THREE.MeshBasicMaterial({ color, depthTest: false }));
      s.renderOrder = 5;
      s.position.set(...p);
      group.add(s);
      centre.add(s.position);
      const n = g.normals?.[i];
      if (n) group.add(new THREE.ArrowHelper(new THREE.Vector3(...n).normalize(), s.position, 0.04, color, 0.01, 0.006));
    });
    if (g.contacts.length) centre.divideScalar(g.contacts.length);
    if (g.approach) {
      const dir = new THREE.Vector3(...g.approach).normalize();
      group.add(new THREE.ArrowHelper(dir, centre.clone().addScaledVector(dir, -0.1), 0.1, COLORS.approach, 0.018, 0.01));
    }
    return group;
  }

  // The palm at a pose: a plate with its axes (z along the approach).
  palmObject(pose) {
    const palm = new THREE.Group();
    palm.position.set(...pose.position);
    palm.quaternion.copy(quaternion(pose.rotation));
    const plate = new THREE.Mesh(new THREE.BoxGeometry(0.09, 0.06, 0.01),
      new THREE.MeshStandardMaterial({ color: COLORS.palm, transparent: true, opacity: 0.5 }));
    palm.add(plate, new THREE.AxesHelper(0.04));
    return palm;
  }

  // The robot as the arm reads it (its URDF with the measured transforms in place), posed by the
  // newest joints, and the reach trajectory drawn with it.
  setRobot(msg) {
    if (this.renderer) {
      disposeTree(this.layers.robot);
      this.layers.robot.clear();
    }
    this.robot = null;
    this.robotError = null;
    this.stats.robotLinks = 0;
    try {
      this.robot = new UrdfRobot(msg.view.urdf);
      if (this.renderer) this.layers.robot.add(this.robot.object);
      this.stats.robotLinks = this.robot.linkCount;
      if (this.joints) this.robot.setJoints(this.joints.names, this.joints.positions);
    } catch (e) {
      this.robotError = `the robot's URDF could not be read: ${e.message}`;
    }
    this.drawTrajectory();
    this.updateInfo();
    this.invalidate();
  }

  setJoints(msg) {
    this.joints = msg.view;
    if (!this.robot) return;
    this.robot.setJoints(msg.view.names, msg.view.positions);
    this.invalidate();
  }

  fit() {
    if (!this.renderer) return;
    const box = this.modelBox ? this.modelBox.clone() : new THREE.Box3();
    if (box.isEmpty() && this.bounds.visible) box.copy(this.bounds.box);
    // The views visited belong in the picture with the model they saw.
    for (const list of this.poseLists.values()) for (const p of list) box.expandByPoint(new THREE.Vector3(...p.view.position));
    if (box.isEmpty()) box.set(new THREE.Vector3(-0.15, -0.15, 0), new THREE.Vector3(0.15, 0.15, 0.25));
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(0.03, box.getSize(new THREE.Vector3()).length() / 2);
    const distance = radius / Math.sin(THREE.MathUtils.degToRad(this.camera.fov / 2)) * 1.1;
    const dir = this.camera.position.clone().sub(this.controls.target).normalize();
    this.controls.target.copy(centre);
    this.camera.position.copy(centre).addScaledVector(dir, distance);
    this.controls.update();
    this.fitted = this.occupied.count > 0;
    this.invalidate();
  }

  updateInfo() {
    const s = this.stats;
    const lines = [];
    if (s.modelPort) lines.push(`${s.modelPort} #${s.modelSeq ?? '?'}: ${s.occupiedInstances.toLocaleString()} occupied, ` +
      `${s.uncarvedInstances.toLocaleString()} not carved, ${s.refineInstances.toLocaleString()} refined for grasping` +
      (s.regions ? `, ${s.regions} regions` : ''));
    const posePorts = [...this.poseLists.entries()];
    if (posePorts.length) lines.push(posePorts.map(([port, list], k) => el('span', {},
      el('span', { class: 'swatch', style: `background:#${new THREE.Color(POSE_COLORS[k % POSE_COLORS.length]).getHexString()}` }),
      ` ${port}: ${list.length} pose${list.length === 1 ? '' : 's'}  `)));
    if (s.candidates || s.selected) lines.push(`${s.candidates} candidate grasp${s.candidates === 1 ? '' : 's'}` +
      (s.candidatesFound > s.candidates ? ` of ${s.candidatesFound}` : '') +
      (this.selectedGrasp ? `, selected: score ${this.selectedGrasp.score?.toFixed?.(4) ?? '?'}` : ', none selected') +
      (s.palm ? `, the ${this.selectedGrasp ? 'selected' : 'best'} one's palm at the pregrasp` : ''));
    if (s.trajectoryPort) lines.push(`${s.trajectoryPort}: ${s.trajectoryWaypoints} waypoints` +
      (s.trajectoryLink ? `, the ${s.trajectoryLink}'s path drawn` : `, not drawn: ${s.trajectoryProblem}`));
    if (this.robot) lines.push(`robot ${this.robot.name}: ${s.robotLinks} links`);
    if (this.robotError) lines.push(this.robotError);
    this.info.replaceChildren(...lines.map((l) => el('div', {}, ...[].concat(l))));
  }

  // For the browser tests: the pixels the occupied leaves alone paint, against a render of nothing
  // (so the background's exact value, after colour management, does not matter). Read in the same
  // task as each render, since the drawing buffer is not kept between frames.
  modelPixels() {
    if (!this.renderer) return 0;
    const gl = this.renderer.getContext();
    const read = (only) => {
      this.scene.children.forEach((c) => { c.visible = c === only || c.isLight === true; });
      this.renderer.render(this.scene, this.camera);
      const px = new Uint8Array(gl.drawingBufferWidth * gl.drawingBufferHeight * 4);
      gl.readPixels(0, 0, gl.drawingBufferWidth, gl.drawingBufferHeight, gl.RGBA, gl.UNSIGNED_BYTE, px);
      return px;
    };
    const shown = this.scene.children.map((c) => c.visible);
    const empty = read(null);
    const model = read(this.layers.occupied);
    this.scene.children.forEach((c, i) => { c.visible = shown[i]; });
    this.invalidate();
    let n = 0;
    for (let i = 0; i < model.length; i += 4) {
      if (Math.abs(model[i] - empty[i]) + Math.abs(model[i + 1] - empty[i + 1]) + Math.abs(model[i + 2] - empty[i + 2]) > 12) n++;
    }
    return n;
  }
}
