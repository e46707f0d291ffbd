// Checks each message from fba-run against the protocol (docs/live-view.md) before a view uses it,
// so that bad data is reported by name and field instead of breaking a panel. check(msg) returns
// a list of problems, empty when the message is usable.

const isObject = (v) => v !== null && typeof v === 'object' && !Array.isArray(v);
const isNumber = (v) => typeof v === 'number' && Number.isFinite(v);
const isString = (v) => typeof v === 'string';
const isNumberArray = (v, n) => Array.isArray(v) && (n === undefined || v.length === n) && v.every(isNumber);

function need(problems, where, cond, what) {
  if (!cond) problems.push(`${where}: ${what}`);
}

function checkFlatLeaves(problems, where, v, name) {
  need(problems, where, v === undefined || (isNumberArray(v) && v.length % 4 === 0),
    `"${name}" must be a flat array of numbers, 4 per leaf (x, y, z, edge)`);
}

function checkGrasp(problems, where, g) {
  if (!isObject(g)) return problems.push(`${where}: a grasp must be an object`);
  need(problems, where, Array.isArray(g.contacts) && g.contacts.every((c) => isNumberArray(c, 3)),
    '"contacts" must be a list of [x, y, z]');
  need(problems, where, g.normals === undefined || (Array.isArray(g.normals) && g.normals.every((c) => isNumberArray(c, 3))),
    '"normals" must be a list of [x, y, z]');
  need(problems, where, g.approach === undefined || g.approach === null || isNumberArray(g.approach, 3), '"approach" must be [x, y, z]');
  if (g.palm !== undefined && g.palm !== null) checkPose(problems, `${where} palm`, g.palm);
}

function checkPose(problems, where, p) {
  need(problems, where, isObject(p) && isNumberArray(p.position, 3), '"position" must be [x, y, z]');
  need(problems, where, isObject(p) && isNumberArray(p.rotation, 4), '"rotation" must be a quaternion [qw, qx, qy, qz]');
}

function checkView(problems, where, v) {
  if (!isObject(v)) return problems.push(`${where}: "view" must be an object`);
  switch (v.kind) {
    case 'image':
      need(problems, where, isNumber(v.width) && isNumber(v.height) && v.width > 0 && v.height > 0, '"width" and "height" must be positive numbers');
      need(problems, where, v.encoding === 'jpeg' || v.encoding === 'png', `"encoding" must be jpeg or png, not ${JSON.stringify(v.encoding)}`);
      need(problems, where, isString(v.data), '"data" must be a base64 string');
      need(problems, where, v.contours === undefined || (Array.isArray(v.contours) && v.contours.every(
        (c) => Array.isArray(c) && c.every((p) => isNumberArray(p, 2)))), '"contours" must be a list of lists of [x, y]');
      break;
    case 'model':
      checkFlatLeaves(problems, where, v.occupied, 'occupied');
      need(problems, where, v.occupied !== undefined, '"occupied" is missing');
      checkFlatLeaves(problems, where, v.uncarved, 'uncarved');
      checkFlatLeaves(problems, where, v.refine, 'refine');
      need(problems, where, v.bounds === undefined || isNumberArray(v.bounds, 6), '"bounds" must be [xmin, ymin, zmin, xmax, ymax, zmax]');
      break;
    case 'pose':
      checkPose(problems, where, v);
      break;
    case 'grasps':
      need(problems, where, Array.isArray(v.candidates), '"candidates" must be a list');
      if (Array.isArray(v.candidates)) v.candidates.forEach((g, i) => checkGrasp(problems, `${where} candidate ${i}`, g));
      if (v.selected !== null && v.selected !== undefined) checkGrasp(problems, `${where} selected`, v.selected);
      break;
    case 'regions':
      need(problems, where, Array.isArray(v.boxes) && v.boxes.every((b) => isNumberArray(b, 6)), '"boxes" must be a list of [xmin, ymin, zmin, xmax, ymax, zmax]');
      break;
    case 'joints':
      need(problems, where, Array.isArray(v.names) && v.names.every(isString), '"names" must be a list of strings');
      need(problems, where, isNumberArray(v.positions) && Array.isArray(v.names) && v.positions.length === v.names.length,
        '"positions" must be numbers, one per name');
      break;
    case 'robot':
      need(problems, where, isString(v.urdf), '"urdf" must be the URDF\'s text');
      break;
    case 'trajectory':
      need(problems, where, Array.isArray(v.names) && Array.isArray(v.points) &&
        v.points.every((p) => isObject(p) && isNumberArray(p.positions, v.names.length)), '"points" must each have "positions", one per name');
      break;
    default:
      // A kind this page does not know yet is listed, not fatal: the server may be newer.
      problems.push(`${where}: unknown view kind ${JSON.stringify(v.kind)} (shown as data only)`);
  }
}

function checkComponentList(problems, where, list, fields) {
  if (!Array.isArray(list)) return problems.push(`${where}: "components" must be a list`);
  list.forEach((c, i) => {
    need(problems, `${where} component ${i}`, isObject(c) && isString(c.name), '"name" must be a string');
    for (const f of fields) need(problems, `${where} component ${c?.name ?? i}`, isObject(c) && f in c, `"${f}" is missing`);
  });
}

export function check(msg) {
  const problems = [];
  if (!isObject(msg)) return ['a message must be a JSON object'];
  const where = `"${msg.type}" message`;
  switch (msg.type) {
    case 'task':
      need(problems, where, isString(msg.task), '"task" (its name) must be a string');
      checkComponentList(problems, where, msg.components, ['type', 'inputs', 'outputs']);
      if (Array.isArray(msg.components)) msg.components.forEach((c) =>
        need(problems, `${where} component ${c?.name}`, Array.isArray(c?.inputs) && Array.isArray(c?.outputs), '"inputs" and "outputs" must be lists'));
      need(problems, where, Array.isArray(msg.connections) && msg.connections.every((c) => isObject(c) && isString(c.from) && isString(c.to)),
        '"connections" must be a list of {from, to}');
      break;
    case 'stats':
      need(problems, where, isNumber(msg.t), '"t" must be a number');
      checkComponentList(problems, where, msg.components, []);
      need(problems, where, msg.connections === undefined || Array.isArray(msg.connections), '"connections" must be a list');
      break;
    case 'event':
      need(problems, where, isNumber(msg.index) && isNumber(msg.t), '"index" and "t" must be numbers');
      need(problems, where, isString(msg.source) && isString(msg.name), '"source" and "name" must be strings');
      break;
    case 'view':
      need(problems, where, isString(msg.port), '"port" must be a string');
      checkView(problems, `view of ${msg.port}`, msg.view);
      break;
    case 'end':
      need(problems, where, isString(msg.outcome), '"outcome" must be a string');
      break;
    default:
      problems.push(`unknown message type ${JSON.stringify(msg.type)}`);
  }
  return problems;
}
