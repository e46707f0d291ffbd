import { el, svg, formatTime } from './dom.js';

// The run's events: a strip with one row per source on the run's time axis, and the list, newest
// first, with a filter. The list keeps the page quick on long runs by drawing only the newest rows
// that match; the strip is redrawn at most once a frame.

const MAX_ROWS = 400;
const ROW = 12;

function severity(name) {
  if (/fail|error|drop|fault|abort|timeout|gap|unreach/i.test(name)) return 'bad';
  if (/done|success|held|selected|finish|complete/i.test(name)) return 'good';
  return 'plain';
}

function payloadText(payload) {
  if (payload === undefined || payload === null) return '';
  const s = typeof payload === 'string' ? payload : JSON.stringify(payload);
  return s.length > 240 ? s.slice(0, 240) + '…' : s;
}

export class TimelineView {
  constructor(container, { onPick } = {}) {
    this.container = container;
    this.onPick = onPick;
    this.filter = el('input', { type: 'search', class: 'timeline-filter', placeholder: 'filter events (source, name, payload)',
      oninput: () => this.renderList() });
    this.strip = svg('svg', { class: 'timeline-strip' });
    this.list = el('div', { class: 'timeline-list' });
    this.count = el('span', { class: 'timeline-count' });
    container.append(el('div', { class: 'timeline-bar' }, this.filter, this.count), this.strip, this.list);
    this.events = [];
    this.end = 0;
  }

  reset() {
    this.events = [];
    this.end = 0;
    this.schedule();
  }

  add(event) {
    this.events.push(event);
    this.schedule();
  }

  setNow(t) {
    if (t > this.end) {
      this.end = t;
      this.schedule();
    }
  }

  schedule() {
    if (this.pending) return;
    this.pending = requestAnimationFrame(() => {
      this.pending = 0;
      this.renderStrip();
      this.renderList();
    });
  }

  renderStrip() {
    const width = Math.max(100, this.strip.getBoundingClientRect().width || 600);
    const sources = [...new Set(this.events.map((e) => e.source))];
    const end = Math.max(this.end, ...this.events.slice(-1).map((e) => e.t), 1e-3);
    const left = 110;
    const x = (t) => left + ((width - left - 8) * t) / end;
    const height = 18 + ROW * Math.max(1, sources.length);
    this.strip.setAttribute('height', height);
    const parts = [];
    sources.forEach((s, i) => {
      parts.push(svg('text', { class: 'strip-source', x: left - 6, y: 10 + ROW * i + 9, 'text-anchor': 'end' }, s));
      parts.push(svg('line', { class: 'strip-row', x1: left, x2: width - 8, y1: 10 + ROW * i + 6, y2: 10 + ROW * i + 6 }));
    });
    const rowOf = new Map(sources.map((s, i) => [s, i]));
    for (const e of this.events) {
      const r = svg('rect', { class: `strip-event ${severity(e.name)}`, x: x(e.t) - 1.5, y: 10 + ROW * rowOf.get(e.source) + 1, width: 3, height: 10 });
      r.append(svg('title', {}, `${formatTime(e.t)} ${e.source}.${e.name}`));
      parts.push(r);
    }
    for (let k = 0; k <= 4; k++) {
      const t = (end * k) / 4;
      parts.push(svg('text', { class: 'strip-tick', x: x(t), y: height - 1, 'text-anchor': k === 0 ? 'start' : k === 4 ? 'end' : 'middle' }, formatTime(t)));
    }
    this.strip.replaceChildren(...parts);
  }

  renderList() {
    const q = this.filter.value.trim().toLowerCase();
    const rows = [];
    let matched = 0;
    for (let i = this.events.length - 1; i >= 0; i--) {
      const e = this.events[i];
      const payload = payloadText(e.payload);
      if (q && !`${e.source} ${e.name} ${payload}`.toLowerCase().includes(q)) continue;
      matched++;
      if (rows.length >= MAX_ROWS) continue;
      rows.push(el('div', { class: `event-row ${severity(e.name)}`, title: 'payload in full: click', onclick: (ev) => {
        ev.currentTarget.classList.toggle('expanded');
        this.onPick?.(e);
      } },
      el('span', { class: 'event-t' }, formatTime(e.t)),
      el('span', { class: 'event-name' }, `${e.source}.${e.name}`),
      el('span', { class: 'event-payload' }, payload),
      el('pre', { class: 'event-full' }, e.payload === undefined ? '' : JSON.stringify(e.payload, null, 2))));
    }
    this.list.replaceChildren(...rows);
    if (!this.events.length) this.list.append(el('div', { class: 'panel-message inline' }, 'no event yet'));
    this.count.textContent = `${this.events.length} event${this.events.length === 1 ? '' : 's'}` +
      (q ? `, ${matched} matching` : '') + (matched > MAX_ROWS ? ` (newest ${MAX_ROWS} shown)` : '');
  }
}
