import { formatCount, formatRate, svg, el } from './dom.js';
import { rankLayout } from './rank-layout.js';

// The task's graph laid out by ELK (layered, left to right, ports fixed on the sides), drawn in SVG
// once per task message; stats messages then only change texts and colours, so that a graph of a
// thousand components stays live at the server's ten updates a second.

const NODE_TOP = 62;  // the node's status lines; its port rows start below them
const PORT_ROW = 14;
const CHAR = 6.6;     // an estimate of a label's character width, for sizing nodes before drawing

// Above this many components the graph is laid out by rank (rank-layout.js), not by ELK.
export const ELK_MAX_COMPONENTS = 150;

// ELK, loaded and set up when the first graph is laid out, not when the page starts: its set-up is
// long, and the live stream and the first drawing should not wait for it.
let elk = null;
async function elkLayout(graph) {
  if (!elk) {
    const { default: ELK } = await import('elkjs/lib/elk.bundled.js');
    elk ??= new ELK();
  }
  return elk.layout(graph);
}

// "comp.port" -> [component, port]: the longest component name that prefixes it, since a name
// inside a composite may itself hold dots. `names` is a Set.
function splitEndpoint(endpoint, names) {
  for (let dot = endpoint.lastIndexOf('.'); dot > 0; dot = endpoint.lastIndexOf('.', dot - 1)) {
    const name = endpoint.slice(0, dot);
    if (names.has(name)) return [name, endpoint.slice(dot + 1)];
  }
  const dot = endpoint.lastIndexOf('.');
  return dot < 0 ? [endpoint, ''] : [endpoint.slice(0, dot), endpoint.slice(dot + 1)];
}

function setText(node, text) {
  if (node.textContent !== text) node.textContent = text;
}

function setIfChanged(node, name, value) {
  if (node.getAttribute(name) !== value) node.setAttribute(name, value);
}

export const connectionKey = (c) => `${c.from}->${c.to}`;

export class GraphView {
  constructor(container, { onSelect } = {}) {
    this.container = container;
    this.onSelect = onSelect;
    this.svg = svg('svg', { class: 'graph-svg' });
    this.root = svg('g');
    this.svg.append(this.root);
    this.message = el('div', { class: 'panel-message' }, 'waiting for the task…');
    this.caption = el('div', { class: 'graph-caption' });
    container.append(this.svg, this.message, this.caption);
    this.view = { x: 0, y: 0, k: 1 };
    this.nodes = new Map();
    this.edges = new Map();
    this.layoutGeneration = 0;
    this.drawn = false;
    this.layoutMs = null;
    this.installPanZoom();
  }

  // Drawn at once by rank, then, for a graph ELK lays out in reasonable time, again by ELK when its
  // layout is ready: ELK's first layout in a page costs seconds on a loaded machine (its code is
  // set up then), and the graph should not wait for it.
  async setTask(task, latestStats) {
    const generation = ++this.layoutGeneration;
    this.drawn = false;
    this.layoutMs = null;
    const names = task.components.map((c) => c.name);
    const graph = this.elkGraph(task, names);
    this.message.hidden = task.components.length > 0;
    this.message.textContent = 'the task has no components';
    const quick = rankLayout(graph.children, graph.edges, (portId) => this.portY.get(portId));
    this.show(task, quick, 'rank', latestStats);
    performance.mark('fba-graph-drawn');
    if (task.components.length > ELK_MAX_COMPONENTS || !task.components.length) return;
    const start = performance.now();
    let laid;
    try {
      laid = await elkLayout(graph);
    } catch (e) {
      this.caption.textContent = `laid out by rank: ELK failed (${e.message ?? e})`;
      return;
    }
    if (generation !== this.layoutGeneration) return;  // a newer task arrived meanwhile
    this.layoutMs = performance.now() - start;
    this.show(task, laid, 'elk', latestStats);
    performance.mark('fba-graph-laid-out');
  }

  show(task, laid, by, latestStats) {
    const selected = this.selected;
    this.layoutBy = by;
    this.caption.textContent = by === 'elk' ? '' : task.components.length > ELK_MAX_COMPONENTS
      ? `${task.components.length} components: laid out by rank, in rows (ELK above ${ELK_MAX_COMPONENTS} would keep you waiting)`
      : 'laid out by rank until ELK\'s layout is ready…';
    this.draw(task, laid);
    // The user's own pan and zoom are kept when ELK's layout replaces the first one.
    if (by === 'rank' || !this.userMoved) this.fit();
    this.drawn = true;
    if (selected && this.nodes.has(selected)) this.select(selected);
    const stats = this.pendingStats ?? latestStats?.();
    if (stats) this.drawStats(stats);
  }

  elkGraph(task, names) {
    this.portY = new Map();
    const nameSet = new Set(names);
    // Each connection's ends, split once: per component below they are looked up, not searched.
    const ends = task.connections.map((con) => [splitEndpoint(con.from, nameSet), splitEndpoint(con.to, nameSet)]);
    const extraOut = new Map();
    const extraIn = new Map();
    for (const [[fc, fp], [tc, tp]] of ends) {
      if (!extraOut.has(fc)) extraOut.set(fc, new Set());
      if (!extraIn.has(tc)) extraIn.set(tc, new Set());
      extraOut.get(fc).add(fp);
      extraIn.get(tc).add(tp);
    }
    const children = task.components.map((c, i) => {
      const inputs = [...c.inputs];
      const outputs = [...c.outputs];
      // A connection may name a port the interface did not list (an optional one): give it a place.
      for (const p of extraOut.get(c.name) ?? []) if (!outputs.some((o) => o.name === p)) outputs.push({ name: p, type: '' });
      for (const p of extraIn.get(c.name) ?? []) if (!inputs.some((o) => o.name === p)) inputs.push({ name: p, type: '' });
      c._ports = { inputs, outputs };
      inputs.forEach((p, j) => this.portY.set(`n${i}:in:${p.name}`, NODE_TOP + PORT_ROW * j + 7));
      outputs.forEach((p, j) => this.portY.set(`n${i}:out:${p.name}`, NODE_TOP + PORT_ROW * j + 7));
      const longest = Math.max(c.name.length * 1.15, (c.type ?? '').length, 26,
        Math.max(0, ...inputs.map((p) => p.name.length)) + Math.max(0, ...outputs.map((p) => p.name.length)) + 4);
      const width = Math.round(Math.min(320, 20 + longest * CHAR));
      const height = NODE_TOP + PORT_ROW * Math.max(inputs.length, outputs.length) + 6;
      const ports = [
        ...inputs.map((p, j) => ({ id: `n${i}:in:${p.name}`, x: -4, y: NODE_TOP + PORT_ROW * j + 3, width: 8, height: 8,
          layoutOptions: { 'elk.port.side': 'WEST' } })),
        ...outputs.map((p, j) => ({ id: `n${i}:out:${p.name}`, x: width - 4, y: NODE_TOP + PORT_ROW * j + 3, width: 8, height: 8,
          layoutOptions: { 'elk.port.side': 'EAST' } })),
      ];
      return { id: `n${i}`, width, height, ports, layoutOptions: { 'elk.portConstraints': 'FIXED_POS' } };
    });
    const index = new Map(names.map((n, i) => [n, i]));
    const edges = [];
    task.connections.forEach((con, k) => {
      const [[fc, fp], [tc, tp]] = ends[k];
      if (!index.has(fc) || !index.has(tc)) return;
      edges.push({ id: `e${k}`, feedback: !!con.feedback, sources: [`n${index.get(fc)}:out:${fp}`], targets: [`n${index.get(tc)}:in:${tp}`] });
    });
    const big = children.length > 60;  // wrapped into rows from here: a long chain would be a line
    return {
      id: 'root',
      layoutOptions: {
        'elk.algorithm': 'layered',
        'elk.direction': 'RIGHT',
        'elk.edgeRouting': 'ORTHOGONAL',
        'elk.layered.spacing.nodeNodeBetweenLayers': '64',
        'elk.spacing.nodeNode': '24',
        'elk.layered.feedbackEdges': 'true',
        // A long chain laid in one row is a line nobody can read: wrapped into rows, it fills the panel.
        ...(big ? { 'elk.layered.wrapping.strategy': 'MULTI_EDGE', 'elk.aspectRatio': '1.6',
          'elk.layered.thoroughness': '1' } : {}),
      },
      children,
      edges,
    };
  }

  draw(task, laid) {
    this.root.replaceChildren();
    this.nodes.clear();
    this.edges.clear();
    this.bounds = { width: laid.width ?? 0, height: laid.height ?? 0 };
    const edgeLayer = svg('g', { class: 'edges' });
    const nodeLayer = svg('g', { class: 'nodes' });
    this.root.append(edgeLayer, nodeLayer);

    const byId = new Map(laid.children.map((n) => [n.id, n]));
    task.components.forEach((c, i) => {
      const n = byId.get(`n${i}`);
      const g = svg('g', { class: `node kind-${c.kind ?? 'filter'}`, transform: `translate(${n.x},${n.y})`, 'data-name': c.name });
      const box = svg('rect', { class: 'node-box', width: n.width, height: n.height, rx: 5 });
      const stripe = svg('rect', { class: 'node-stripe', width: 4, height: n.height, rx: 2 });
      const title = svg('text', { class: 'node-name', x: 10, y: 15 }, c.name);
      const type = svg('text', { class: 'node-type', x: 10, y: 29 }, `${c.type ?? ''}${c.kind ? ' · ' + c.kind : ''}`);
      const dot = svg('circle', { class: 'state-dot state-unknown', cx: 14, cy: 39, r: 4 });
      const state = svg('text', { class: 'node-state', x: 22, y: 43 }, 'no stats yet');
      const rates = svg('text', { class: 'node-rates', x: 10, y: 57 }, '');
      const tip = svg('title', {}, `${c.name} (${c.type})${c.doc ? '\n' + c.doc : ''}`);
      g.append(tip, box, stripe, title, type, dot, state, rates);
      const { inputs, outputs } = c._ports;
      inputs.forEach((p, j) => g.append(
        svg('rect', { class: 'port', x: -4, y: NODE_TOP + PORT_ROW * j + 3, width: 8, height: 8 }),
        svg('text', { class: 'port-label', x: 8, y: NODE_TOP + PORT_ROW * j + 11 }, p.name)));
      outputs.forEach((p, j) => g.append(
        svg('rect', { class: 'port', x: n.width - 4, y: NODE_TOP + PORT_ROW * j + 3, width: 8, height: 8 }),
        svg('text', { class: 'port-label', x: n.width - 8, y: NODE_TOP + PORT_ROW * j + 11, 'text-anchor': 'end' }, p.name)));
      nodeLayer.append(g);
      this.nodes.set(c.name, { g, box, dot, state, rates, component: c });
    });

    const edgeById = new Map((laid.edges ?? []).map((e) => [e.id, e]));
    task.connections.forEach((con, k) => {
      const e = edgeById.get(`e${k}`);
      if (!e || !e.sections?.length) return;
      const g = svg('g', { class: `edge${con.feedback ? ' feedback' : ''}` });
      let longest = null;
      let d = '';
      for (const s of e.sections) {
        const pts = [s.startPoint, ...(s.bendPoints ?? []), s.endPoint];
        d += `M${pts.map((p) => `${p.x},${p.y}`).join('L')}`;
        for (let i = 1; i < pts.length; i++) {
          const len = Math.abs(pts[i].x - pts[i - 1].x) + Math.abs(pts[i].y - pts[i - 1].y);
          if (!longest || len > longest.len) longest = { len, a: pts[i - 1], b: pts[i] };
        }
      }
      const path = svg('path', { class: 'edge-path', d });
      const tip = svg('title', {}, `${con.from} → ${con.to}\n${con.policy ?? ''}${con.capacity ? ', capacity ' + con.capacity : ''}${con.feedback ? ', feedback' : ''}`);
      g.append(tip, path);
      // The queue meter sits on the edge's longest segment, where it has room.
      const mx = (longest.a.x + longest.b.x) / 2;
      const my = (longest.a.y + longest.b.y) / 2;
      const meter = svg('g', { class: 'queue', transform: `translate(${mx - 15},${my - 4})` });
      const back = svg('rect', { class: 'queue-back', width: 30, height: 6, rx: 1 });
      const fill = svg('rect', { class: 'queue-fill', width: 0, height: 6, rx: 1 });
      const label = svg('text', { class: 'queue-label', x: 15, y: -3, 'text-anchor': 'middle' }, '');
      meter.append(back, fill, label);
      g.append(meter);
      edgeLayer.append(g);
      this.edges.set(connectionKey(con), { g, path, fill, label, connection: con });
    });
  }

  // Stats come up to ten times a second: drawn once a frame at most (the newest wins), and only the
  // texts and attributes that changed are touched, which keeps a thousand components cheap.
  updateStats(stats) {
    this.pendingStats = stats;
    if (this.statsFrame || !this.drawn) return;
    this.statsFrame = requestAnimationFrame(() => {
      this.statsFrame = 0;
      this.drawStats(this.pendingStats);
    });
  }

  drawStats(stats) {
    for (const c of stats.components ?? []) {
      const n = this.nodes.get(c.name);
      if (!n) continue;
      setIfChanged(n.dot, 'class', `state-dot state-${c.state ?? 'unknown'}`);
      setText(n.state, `${c.state ?? '?'}${c.stage ? ' · ' + c.stage : ''}`);
      const errors = c.errors ? ` · ${formatCount(c.errors)} errors` : '';
      setText(n.rates, `in ${formatCount(c.samples_in)} · out ${formatCount(c.samples_out)} · ${formatRate(c.rate_hz)}${errors}`);
      if ((c.errors ?? 0) > 0 !== n.g.classList.contains('has-errors')) n.g.classList.toggle('has-errors');
      n.stats = c;
    }
    for (const c of stats.connections ?? []) {
      const e = this.edges.get(connectionKey(c));
      if (!e) continue;
      const capacity = c.capacity || e.connection.capacity || 0;
      const ratio = capacity ? Math.min(1, (c.queued ?? 0) / capacity) : 0;
      setIfChanged(e.fill, 'width', (30 * ratio).toFixed(1));
      setIfChanged(e.fill, 'class', `queue-fill ${ratio > 0.85 ? 'full' : ratio > 0.5 ? 'half' : ''}`);
      const dropped = c.dropped ? ` · ${formatCount(c.dropped)} dropped` : '';
      setText(e.label, `${c.queued ?? 0}/${capacity || '∞'} · ${formatRate(c.rate_hz)}${dropped}`);
      if ((c.dropped ?? 0) > 0 !== e.g.classList.contains('dropping')) e.g.classList.toggle('dropping');
      e.stats = c;
    }
    if (this.selected) this.onSelect?.(this.nodes.get(this.selected));
  }

  select(name) {
    for (const [n, v] of this.nodes) v.g.classList.toggle('selected', n === name);
    this.selected = name;
    this.onSelect?.(name ? this.nodes.get(name) : null);
  }

  // Pan with a drag, zoom with the wheel around the pointer, double click to fit.
  installPanZoom() {
    let drag = null;
    // The pointer is captured only once it moves: a click stays on the component it hit.
    this.svg.addEventListener('pointerdown', (ev) => {
      drag = { id: ev.pointerId, x: ev.clientX, y: ev.clientY, vx: this.view.x, vy: this.view.y, moved: false };
    });
    this.svg.addEventListener('pointermove', (ev) => {
      if (!drag) return;
      const dx = ev.clientX - drag.x;
      const dy = ev.clientY - drag.y;
      if (!drag.moved && Math.abs(dx) + Math.abs(dy) > 3) {
        drag.moved = true;
        this.svg.setPointerCapture(drag.id);
      }
      if (!drag.moved) return;
      this.view.x = drag.vx + dx;
      this.view.y = drag.vy + dy;
      this.userMoved = true;
      this.applyView();
    });
    this.svg.addEventListener('pointerup', (ev) => {
      if (drag && !drag.moved) this.select(ev.target.closest?.('.node')?.dataset.name ?? null);
      drag = null;
    });
    this.svg.addEventListener('wheel', (ev) => {
      ev.preventDefault();
      const r = this.svg.getBoundingClientRect();
      const px = ev.clientX - r.left;
      const py = ev.clientY - r.top;
      const k = Math.min(4, Math.max(0.02, this.view.k * Math.exp(-ev.deltaY * 0.0015)));
      this.view.x = px - ((px - this.view.x) * k) / this.view.k;
      this.view.y = py - ((py - this.view.y) * k) / this.view.k;
      this.view.k = k;
      this.userMoved = true;
      this.applyView();
    }, { passive: false });
    this.svg.addEventListener('dblclick', () => {
      this.userMoved = false;
      this.fit();
    });
    new ResizeObserver(() => { if (this.fitted) this.fit(); }).observe(this.container);
  }

  fit() {
    if (!this.bounds) return;
    const r = this.container.getBoundingClientRect();
    const w = Math.max(1, r.width);
    const h = Math.max(1, r.height);
    const k = Math.min(1.5, (w - 20) / Math.max(1, this.bounds.width), (h - 20) / Math.max(1, this.bounds.height));
    this.view = { k, x: (w - this.bounds.width * k) / 2, y: (h - this.bounds.height * k) / 2 };
    this.fitted = true;
    this.applyView();
  }

  applyView() {
    this.root.setAttribute('transform', `translate(${this.view.x},${this.view.y}) scale(${this.view.k})`);
    // Too small to read: the texts are left out, which keeps a large graph quick to pan.
    this.svg.classList.toggle('far', this.view.k < 0.35);
  }
}
