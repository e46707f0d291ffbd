import { el, formatTime } from './dom.js';

// The newest image of each image port, with its contours drawn over it: one card per port, in the
// order the ports first sent one. Decoding is asynchronous; a newer image that arrives meanwhile
// wins, and an image that cannot be decoded says so on its card.

function base64Bytes(data) {
  const bin = atob(data);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return bytes;
}

const CONTOUR_COLORS = ['#00e08a', '#ff3d9a', '#ffd166', '#4cc9f0'];

export class ImagesView {
  constructor(container) {
    this.container = container;
    this.cards = new Map();
    this.message = el('div', { class: 'panel-message' }, 'no image yet');
    container.append(this.message);
  }

  reset() {
    for (const c of this.cards.values()) c.card.remove();
    this.cards.clear();
    this.message.hidden = false;
  }

  card(port) {
    let c = this.cards.get(port);
    if (c) return c;
    const canvas = el('canvas', { class: 'image-canvas' });
    const title = el('div', { class: 'image-title' }, port);
    const caption = el('div', { class: 'image-caption' });
    const card = el('figure', { class: 'image-card', 'data-port': port }, title, canvas, caption);
    this.container.append(card);
    c = { card, canvas, caption, generation: 0 };
    this.cards.set(port, c);
    this.message.hidden = true;
    return c;
  }

  async setImage(msg) {
    const v = msg.view;
    const c = this.card(msg.port);
    const generation = ++c.generation;
    let bitmap;
    try {
      const blob = new Blob([base64Bytes(v.data)], { type: v.encoding === 'png' ? 'image/png' : 'image/jpeg' });
      bitmap = await createImageBitmap(blob);
    } catch (e) {
      if (generation !== c.generation) return;
      c.caption.textContent = `#${msg.seq ?? '?'}: the ${v.encoding} image could not be decoded (${e.message ?? e})`;
      c.caption.classList.add('error');
      return;
    }
    if (generation !== c.generation) return;
    c.caption.classList.remove('error');
    const canvas = c.canvas;
    canvas.width = v.width;
    canvas.height = v.height;
    const g = canvas.getContext('2d');
    g.drawImage(bitmap, 0, 0, v.width, v.height);
    bitmap.close?.();
    const contours = v.contours ?? [];
    g.lineWidth = Math.max(1.5, v.width / 320);
    g.lineJoin = 'round';
    contours.forEach((contour, i) => {
      if (contour.length < 2) return;
      g.strokeStyle = CONTOUR_COLORS[i % CONTOUR_COLORS.length];
      g.beginPath();
      g.moveTo(contour[0][0], contour[0][1]);
      for (let k = 1; k < contour.length; k++) g.lineTo(contour[k][0], contour[k][1]);
      g.closePath();
      g.stroke();
    });
    const points = contours.reduce((s, c) => s + c.length, 0);
    c.caption.textContent = `#${msg.seq ?? '?'} at ${formatTime(msg.t)} · ${v.width}×${v.height} ${v.encoding} · ` +
      (contours.length ? `${contours.length} contour${contours.length > 1 ? 's' : ''}, ${points} points` : 'no contours');
    c.shown = { seq: msg.seq, contours: contours.length };
  }
}
