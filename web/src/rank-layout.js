// A quick layout for graphs too large for ELK to lay out while someone waits (a thousand
// components took ELK seconds to tens of seconds on a loaded machine): columns by rank (the longest
// path from a source, feedback connections left out), the columns wrapped into rows so the graph
// fills a panel, connections drawn orthogonally between rows. Returns ELK's output shape, so the
// drawing is the same for both.

const GAP_X = 64;
const GAP_Y = 24;
const ROW_GAP = 48;

export function rankLayout(children, edges, portY) {
  const index = new Map(children.map((c, i) => [c.id, i]));
  const node = (portId) => index.get(portId.slice(0, portId.indexOf(':')));
  const succ = children.map(() => []);
  const indegree = children.map(() => 0);
  for (const e of edges) {
    if (e.feedback) continue;
    const a = node(e.sources[0]);
    const b = node(e.targets[0]);
    if (a === b) continue;
    succ[a].push(b);
    indegree[b]++;
  }
  // Kahn's order; what a cycle leaves unvisited takes the rank after its visited predecessors.
  const rank = children.map(() => 0);
  const queue = children.map((_, i) => i).filter((i) => indegree[i] === 0);
  const seen = new Set(queue);
  for (let q = 0; q < queue.length; q++) {
    const a = queue[q];
    for (const b of succ[a]) {
      rank[b] = Math.max(rank[b], rank[a] + 1);
      if (--indegree[b] === 0 && !seen.has(b)) {
        seen.add(b);
        queue.push(b);
      }
    }
  }
  const ranks = Math.max(0, ...rank) + 1;
  const columns = Array.from({ length: ranks }, () => []);
  children.forEach((c, i) => columns[rank[i]].push(i));
  const colWidth = columns.map((col) => Math.max(0, ...col.map((i) => children[i].width)));
  const colHeight = columns.map((col) => col.reduce((s, i) => s + children[i].height + GAP_Y, -GAP_Y));
  const rowHeightAll = Math.max(...colHeight);
  const meanWidth = colWidth.reduce((s, w) => s + w + GAP_X, 0) / ranks;
  // Columns per row for a panel-like shape (about 1.6 wide for 1 high).
  const perRow = Math.max(1, Math.min(ranks, Math.round(Math.sqrt((ranks * 1.6 * (rowHeightAll + ROW_GAP)) / meanWidth))));

  const placed = children.map((c) => ({ ...c, x: 0, y: 0 }));
  let y = 0;
  let width = 0;
  const rowOf = [];
  const rowBottom = [];
  for (let r0 = 0; r0 < ranks; r0 += perRow) {
    const row = r0 / perRow;
    let x = 0;
    let height = 0;
    for (let k = r0; k < Math.min(ranks, r0 + perRow); k++) {
      let cy = y;
      for (const i of columns[k]) {
        placed[i].x = x + (colWidth[k] - children[i].width) / 2;
        placed[i].y = cy;
        cy += children[i].height + GAP_Y;
        rowOf[i] = row;
      }
      height = Math.max(height, colHeight[k]);
      x += colWidth[k] + GAP_X;
    }
    width = Math.max(width, x - GAP_X);
    y += height;
    rowBottom[row] = y;
    y += ROW_GAP;
  }

  const laidEdges = edges.map((e) => {
    const a = node(e.sources[0]);
    const b = node(e.targets[0]);
    const s = { x: placed[a].x + placed[a].width, y: placed[a].y + portY(e.sources[0]) };
    const t = { x: placed[b].x, y: placed[b].y + portY(e.targets[0]) };
    let bends;
    if (rowOf[a] === rowOf[b] && t.x > s.x) {
      const mx = (s.x + t.x) / 2;
      bends = [{ x: mx, y: s.y }, { x: mx, y: t.y }];
    } else {
      // Down into the gap below the source's row, across, and up or down into the target.
      const gy = rowBottom[rowOf[a]] + ROW_GAP / 2;
      bends = [{ x: s.x + GAP_X / 3, y: s.y }, { x: s.x + GAP_X / 3, y: gy }, { x: t.x - GAP_X / 3, y: gy }, { x: t.x - GAP_X / 3, y: t.y }];
    }
    return { id: e.id, sections: [{ startPoint: s, bendPoints: bends, endPoint: t }] };
  });
  return { width, height: y - ROW_GAP, children: placed, edges: laidEdges };
}
