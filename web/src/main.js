import './style.css';
import { RunState } from './run-state.js';
import { GraphView } from './graph-view.js';
import { SceneView } from './scene-view.js';
import { ImagesView } from './images-view.js';
import { TimelineView } from './timeline-view.js';
import { connectLive } from './connection.js';
import { el, formatCount, formatRate, formatTime } from './dom.js';

// The page: one RunState fed by a source (a report's embedded messages, the live WebSocket, or in
// development a recorded file), and the panels that draw it.

const $ = (id) => document.getElementById(id);
const state = new RunState();
const graph = new GraphView($('graph'), { onSelect: showDetails });
const scene = new SceneView($('scene'));
const images = new ImagesView($('images'));
const timeline = new TimelineView($('timeline'));
let source = 'none';
let connection = { state: 'none', text: '' };

function setStatus(kind, text) {
  connection = { state: kind, text };
  if (kind === 'problem') state.addProblem(text);
  renderHeader();
}

function renderHeader() {
  const t = state.task;
  $('task-name').textContent = t ? t.task : 'fba';
  $('task-file').textContent = t ? `${t.file ?? ''}${t.run_id ? ' · run ' + t.run_id : ''}` : '';
  $('task-size').textContent = t ? `${t.components.length} components · ${t.connections.length} connections` : '';
  const badge = $('run-status');
  let kind, text;
  if (state.end) {
    const ok = state.end.exit_code === 0;
    kind = ok ? 'good' : 'bad';
    text = `${state.end.outcome} (exit ${state.end.exit_code ?? '?'})`;
  } else if (source === 'report') {
    kind = 'bad';
    text = 'no end message: the run stopped without one';
  } else {
    kind = connection.state === 'live' ? 'live' : connection.state === 'retrying' || connection.state === 'error' ? 'bad' : 'plain';
    text = connection.state === 'live' ? 'running' : connection.text || 'waiting for data';
  }
  badge.className = `status ${kind}`;
  badge.textContent = text;
  $('run-time').textContent = state.task ? formatTime(state.now) : '';
  $('run-source').textContent = source === 'report' ? 'report (recorded run)' : source === 'live' ? connection.text : source;
  const reason = $('end-reason');
  reason.hidden = !state.end;
  if (state.end) reason.textContent = state.end.reason ?? '';
}

function showDetails(node) {
  const box = $('details');
  if (!node) {
    box.hidden = true;
    return;
  }
  const c = node.component;
  const s = node.stats ?? {};
  const ports = (list, dir) => list.map((p) => el('div', { class: 'port-line' }, `${dir} ${p.name}`, el('span', { class: 'muted' }, ` ${p.type}`)));
  box.replaceChildren(
    el('div', { class: 'details-title' }, c.name, el('button', { class: 'small', onclick: () => graph.select(null) }, '×')),
    el('div', { class: 'muted' }, `${c.type} · ${c.kind ?? ''}`),
    c.doc ? el('p', { class: 'doc' }, c.doc) : null,
    ...ports(c.inputs, '→'),
    ...ports(c.outputs, '←'),
    el('table', { class: 'details-stats' }, ...[
      ['state', `${s.state ?? '–'}${s.stage ? ' · ' + s.stage : ''}`],
      ['invocations', formatCount(s.invocations)],
      ['samples in / out', `${formatCount(s.samples_in)} / ${formatCount(s.samples_out)}`],
      ['rate', formatRate(s.rate_hz)],
      ['errors', formatCount(s.errors)],
    ].map(([k, v]) => el('tr', {}, el('td', {}, k), el('td', {}, v)))));
  box.hidden = false;
}

function renderProblems() {
  const box = $('problems');
  box.hidden = state.problems.length === 0;
  const list = state.problems.slice(-20);
  box.replaceChildren(el('strong', {}, `${state.problems.length} problem${state.problems.length > 1 ? 's' : ''} in the data received:`),
    ...list.map((p) => el('div', {}, p)));
}

state.on('task', (task) => {
  images.reset();
  timeline.reset();
  scene.setTask(task);
  graph.setTask(task, () => state.stats);
  renderHeader();
  renderProblems();
});
state.on('stats', (stats) => {
  graph.updateStats(stats);
  timeline.setNow(stats.t);
  renderHeader();
});
state.on('event', (event) => {
  timeline.add(event);
  timeline.setNow(event.t);
});
state.on('view', (msg) => {
  switch (msg.view.kind) {
    case 'image': images.setImage(msg); break;
    case 'model': scene.setModel(msg); break;
    case 'pose': scene.setPoses(msg.port, state.poses.get(msg.port)); break;
    case 'grasps': scene.setGrasps(msg); break;
    case 'regions': scene.setRegions(msg); break;
    case 'joints': scene.setJoints(msg); break;
    case 'robot': scene.setRobot(msg); break;
    case 'trajectory': scene.setTrajectory(msg); break;
  }
});
state.on('end', (end) => {
  scene.setRunEnd(end.summary);
  renderHeader();
});
state.on('problem', () => renderProblems());

// What the browser tests and the figures script read: the page's own counts, not its pixels.
window.fbaDebug = {
  scene,
  state,
  get source() { return source; },
  get connection() { return connection.state; },
  get messages() { return state.messageCount; },
  get problems() { return [...state.problems]; },
  get graph() {
    return { drawn: graph.drawn, nodes: graph.nodes.size, edges: graph.edges.size, layoutMs: graph.layoutMs, layoutBy: graph.layoutBy };
  },
  get model() { return { ...scene.stats }; },
  modelPixels: () => scene.modelPixels(),
  get images() {
    return [...images.cards.entries()].map(([port, c]) => ({ port, ...(c.shown ?? {}) }));
  },
  get events() { return state.events.length; },
  get ended() { return !!state.end; },
};

// Each panel can fill the page and back (its title's button, or Escape).
for (const panel of document.querySelectorAll('.panel')) {
  const button = el('button', { class: 'small panel-max', title: 'fill the page with this panel (Escape: back)' }, '⤢');
  button.addEventListener('click', () => {
    const on = !panel.classList.contains('maximized');
    document.querySelectorAll('.panel').forEach((p) => p.classList.remove('maximized'));
    panel.classList.toggle('maximized', on);
    document.body.classList.toggle('has-maximized', on);
  });
  panel.querySelector('h2').append(button);
}
document.addEventListener('keydown', (ev) => {
  if (ev.key !== 'Escape') return;
  document.querySelectorAll('.panel').forEach((p) => p.classList.remove('maximized'));
  document.body.classList.remove('has-maximized');
});

function replay(messages) {
  if (!Array.isArray(messages)) throw new Error('"messages" must be a list');
  for (const m of messages) state.apply(m);
}

function start() {
  const embedded = document.getElementById('fba-report');
  if (embedded) {
    source = 'report';
    try {
      replay(JSON.parse(embedded.textContent).messages);
    } catch (e) {
      state.addProblem(`the report's embedded data could not be read: ${e.message}`);
    }
    if (!state.task) state.addProblem('the report holds no task message: nothing to show');
    renderHeader();
    return;
  }
  const params = new URLSearchParams(location.search);
  if (import.meta.env.DEV && params.get('replay')) {
    // Development only (vite's server): a recorded list of messages, one JSON message a line.
    source = 'recording';
    fetch(params.get('replay')).then((r) => r.text()).then((text) => {
      replay(text.split('\n').filter((l) => l.trim()).map((l) => JSON.parse(l)));
      renderHeader();
    }).catch((e) => state.addProblem(`the recording could not be read: ${e.message}`));
    return;
  }
  const token = params.get('token');
  if (!token || location.protocol === 'file:') {
    source = 'none';
    state.addProblem(location.protocol === 'file:'
      ? 'this page holds no run data: open a report.html that fba-run wrote, or the address fba-run --serve prints'
      : 'the address has no token: open the address fba-run --serve printed (…/?token=…)');
    renderHeader();
    return;
  }
  source = 'live';
  connectLive({ token, onMessage: (m) => state.apply(m), onStatus: setStatus });
  setInterval(renderHeader, 500);
}

start();
