import * as THREE from 'three';

// A small URDF reader: links with their visual (or, lacking one, collision) boxes, cylinders and
// spheres; meshes drawn as a box of their scale, since the page cannot read the mesh files; joints
// (revolute, continuous, prismatic, fixed, mimic) posed by the joint views. Enough to see where
// the arm is against the model; not a renderer of the robot's true shape.

const numbers = (s, n, fallback) => {
  if (!s) return fallback;
  const v = s.trim().split(/\s+/).map(Number);
  return v.length === n && v.every(Number.isFinite) ? v : fallback;
};

function readOrigin(elem) {
  const o = elem?.querySelector(':scope > origin');
  return { xyz: numbers(o?.getAttribute('xyz'), 3, [0, 0, 0]), rpy: numbers(o?.getAttribute('rpy'), 3, [0, 0, 0]) };
}

function applyOrigin(object, origin) {
  object.position.set(...origin.xyz);
  // URDF's roll, pitch, yaw about fixed axes: R = Rz(yaw) Ry(pitch) Rx(roll).
  object.rotation.set(origin.rpy[0], origin.rpy[1], origin.rpy[2], 'ZYX');
}

function geometryOf(g) {
  const box = g.querySelector('box');
  if (box) return new THREE.BoxGeometry(...numbers(box.getAttribute('size'), 3, [0.01, 0.01, 0.01]));
  const cyl = g.querySelector('cylinder');
  if (cyl) {
    const r = Number(cyl.getAttribute('radius')) || 0.01;
    const l = Number(cyl.getAttribute('length')) || 0.01;
    // URDF's cylinder runs along z, three.js's along y.
    return new THREE.CylinderGeometry(r, r, l, 20).rotateX(Math.PI / 2);
  }
  const sphere = g.querySelector('sphere');
  if (sphere) return new THREE.SphereGeometry(Number(sphere.getAttribute('radius')) || 0.01, 16, 12);
  const mesh = g.querySelector('mesh');
  if (mesh) return new THREE.BoxGeometry(...numbers(mesh.getAttribute('scale'), 3, [1, 1, 1]).map((s) => 0.05 * s));
  return null;
}

export function parseUrdf(text) {
  const doc = new DOMParser().parseFromString(text, 'application/xml');
  const error = doc.querySelector('parsererror');
  if (error) throw new Error(`the URDF is not valid XML: ${error.textContent.split('\n')[0]}`);
  const robot = doc.querySelector('robot');
  if (!robot) throw new Error('the URDF has no <robot> element');
  const links = new Map();
  for (const l of robot.querySelectorAll(':scope > link')) {
    let parts = [...l.querySelectorAll(':scope > visual')];
    if (!parts.length) parts = [...l.querySelectorAll(':scope > collision')];
    links.set(l.getAttribute('name'), parts
      .map((p) => ({ origin: readOrigin(p), geometry: p.querySelector('geometry') }))
      .filter((p) => p.geometry));
  }
  const joints = [...robot.querySelectorAll(':scope > joint')].map((j) => {
    const mimic = j.querySelector('mimic');
    return {
      name: j.getAttribute('name'),
      type: j.getAttribute('type'),
      parent: j.querySelector('parent')?.getAttribute('link'),
      child: j.querySelector('child')?.getAttribute('link'),
      origin: readOrigin(j),
      axis: numbers(j.querySelector('axis')?.getAttribute('xyz'), 3, [1, 0, 0]),
      mimic: mimic ? { joint: mimic.getAttribute('joint'), multiplier: Number(mimic.getAttribute('multiplier') ?? 1),
        offset: Number(mimic.getAttribute('offset') ?? 0) } : null,
    };
  });
  return { name: robot.getAttribute('name') ?? 'robot', links, joints };
}

export class UrdfRobot {
  constructor(text) {
    const model = parseUrdf(text);
    this.name = model.name;
    this.object = new THREE.Group();
    this.joints = new Map();
    const material = new THREE.MeshStandardMaterial({ color: 0x9aa4b1, metalness: 0.3, roughness: 0.6, transparent: true, opacity: 0.35, depthWrite: false });
    const linkObjects = new Map();
    for (const [name, parts] of model.links) {
      const g = new THREE.Group();
      g.name = name;
      for (const p of parts) {
        const geometry = geometryOf(p.geometry);
        if (!geometry) continue;
        const mesh = new THREE.Mesh(geometry, material);
        applyOrigin(mesh, p.origin);
        g.add(mesh);
      }
      linkObjects.set(name, g);
    }
    const children = new Set(model.joints.map((j) => j.child));
    for (const [name, g] of linkObjects) if (!children.has(name)) this.object.add(g);
    for (const j of model.joints) {
      const parent = linkObjects.get(j.parent);
      const child = linkObjects.get(j.child);
      if (!parent || !child) throw new Error(`joint ${j.name} joins unknown links ${j.parent} and ${j.child}`);
      const frame = new THREE.Group();
      applyOrigin(frame, j.origin);
      const motion = new THREE.Group();
      frame.add(motion);
      motion.add(child);
      parent.add(frame);
      this.joints.set(j.name, { ...j, motion, axis: new THREE.Vector3(...j.axis).normalize(), value: 0 });
    }
    this.linkCount = linkObjects.size;
    this.links = linkObjects;
  }

  hasLink(name) {
    return this.links.has(name);
  }

  // The link that a trajectory over `names` carries: the palm, else the flange or tool0, else the
  // child of the last of the joints named (the chain's tip). Null when none is known.
  carriedLink(names) {
    for (const name of ['palm', 'flange', 'tool0']) if (this.links.has(name)) return name;
    for (let i = names.length - 1; i >= 0; i--) {
      const j = this.joints.get(names[i]);
      if (j) return j.child;
    }
    return null;
  }

  // Where `link` is in the robot's frame (the page's world) with the joints `names` at each of
  // `configurations` (lists of positions, one per name); the other joints as they stand. The
  // robot's pose is left as it was.
  linkPositions(link, names, configurations) {
    const target = this.links.get(link);
    if (!target) return [];
    const saved = new Map([...this.joints].map(([n, j]) => [n, j.value]));
    const out = configurations.map((positions) => {
      this.setJoints(names, positions);
      this.object.updateMatrixWorld(true);
      return target.getWorldPosition(new THREE.Vector3());
    });
    this.setJoints([...saved.keys()], [...saved.values()]);
    this.object.updateMatrixWorld(true);
    return out;
  }

  setJoints(names, positions) {
    names.forEach((n, i) => {
      const j = this.joints.get(n);
      if (j) j.value = positions[i];
    });
    for (const j of this.joints.values()) {
      const source = j.mimic ? this.joints.get(j.mimic.joint) : null;
      const v = source ? source.value * j.mimic.multiplier + j.mimic.offset : j.value;
      if (j.type === 'revolute' || j.type === 'continuous') j.motion.quaternion.setFromAxisAngle(j.axis, v);
      else if (j.type === 'prismatic') j.motion.position.copy(j.axis).multiplyScalar(v);
    }
  }
}
