// Small helpers to build the page's DOM and SVG and to format its figures.

export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k === 'class') e.className = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v === true ? '' : v);
  }
  e.append(...children.filter((c) => c !== null && c !== undefined));
  return e;
}

export function svg(tag, attrs = {}, text) {
  const e = document.createElementNS('http://www.w3.org/2000/svg', tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

export function formatCount(n) {
  if (n === undefined || n === null) return '–';
  if (n >= 1e9) return (n / 1e9).toFixed(1) + 'G';
  if (n >= 1e6) return (n / 1e6).toFixed(1) + 'M';
  if (n >= 1e4) return (n / 1e3).toFixed(1) + 'k';
  return String(n);
}

export function formatRate(hz) {
  if (hz === undefined || hz === null || !Number.isFinite(hz)) return '– Hz';
  if (hz >= 1e6) return (hz / 1e6).toFixed(2) + ' MHz';
  if (hz >= 1e3) return (hz / 1e3).toFixed(2) + ' kHz';
  if (hz >= 100) return hz.toFixed(0) + ' Hz';
  if (hz >= 1) return hz.toFixed(1) + ' Hz';
  return hz.toFixed(2) + ' Hz';
}

export function formatTime(t) {
  if (!Number.isFinite(t)) return '–';
  if (t < 60) return t.toFixed(2) + ' s';
  const m = Math.floor(t / 60);
  return `${m} min ${(t - 60 * m).toFixed(1)} s`;
}
