// The page's first paint, measured in Debian's Chromium (issue 33's targets: under 1 s for the grasp
// task, under 3 s for a 1000-component graph). A figure for docs/results.md, not a test:
//   node web/scripts/first-paint.mjs --fba-run build/release/bin/fba-run --source-dir . [--runs 3] [--tasks grasp,chain1000]
// For each task, fba-run --serve 0 runs it (the grasp task on the threaded executor, in real time)
// and a fresh page opens its address: the browser's own
// first-paint and first-contentful-paint entries (performance.getEntriesByType('paint')), and when
// the graph was drawn (the page's mark fba-graph-drawn, laid out by rank) and redrawn by ELK (mark
// fba-graph-laid-out; up to 150 components), each from navigation start.
// The 1000-component graph is a chain of examples.passthrough like tools/runtime-benchmark's.
import fs from 'node:fs';
import path from 'node:path';
import { launchBrowser } from '../tests/browser.mjs';
import { FbaRun, testArguments, temporaryFolder } from '../tests/fba-run.mjs';

const { fbaRun, sourceDir } = testArguments();
const runsArg = process.argv.indexOf('--runs');
const runs = runsArg > 0 ? Number(process.argv[runsArg + 1]) : 3;
const tasksArg = process.argv.indexOf('--tasks');
const tasks = (tasksArg > 0 ? process.argv[tasksArg + 1] : 'grasp,chain1000').split(',');
const dir = temporaryFolder('first-paint');

function chainTask(components) {
  const hops = components - 2;
  let y = 'task: chain_1000\ncomponents:\n  src: { type: examples.counter, params: { count: 1000000000000, rate: 100 } }\n';
  for (let i = 0; i < hops; i++) y += `  p${i}: { type: examples.passthrough }\n`;
  y += '  sink: { type: examples.sink, params: { expected: 1000000000000 } }\nconnections:\n';
  let prev = 'src';
  for (let i = 0; i <= hops; i++) {
    const next = i < hops ? `p${i}` : 'sink';
    y += `  - ${prev}.out -> ${next}.in\n`;
    prev = next;
  }
  const file = path.join(dir, `chain_${components}.yaml`);
  fs.writeFileSync(file, y);
  return file;
}

async function measure(name, args) {
  const rows = [];
  for (let r = 0; r < runs; r++) {
    // The browser first: the grasp task's run is over in seconds, and fba-run exits with it.
    const browser = await launchBrowser();
    const page = await browser.context.newPage();
    const fba = new FbaRun(fbaRun, [...args, '--serve', '0', '--output-dir', path.join(dir, `${name}-${r}`)], { cwd: sourceDir });
    try {
      const url = await fba.url;
      await page.goto(url);
      await page.waitForFunction(() => window.fbaDebug?.graph.drawn && (fbaDebug.graph.layoutBy === 'elk' || fbaDebug.graph.nodes > 150),
        null, { timeout: 600_000 });
      rows.push(await page.evaluate(() => {
        const paint = Object.fromEntries(performance.getEntriesByType('paint').map((e) => [e.name, e.startTime]));
        const mark = (name) => performance.getEntriesByName(name).pop()?.startTime;
        return { fp: paint['first-paint'], fcp: paint['first-contentful-paint'], open: mark('fba-live-open'), task: mark('fba-task-received'),
          graph: mark('fba-graph-drawn'), elk: mark('fba-graph-laid-out'), layout: fbaDebug.graph.layoutMs,
          nodes: fbaDebug.graph.nodes };
      }));
    } finally {
      await browser.close();
      await fba.stop();
    }
  }
  const median = (k) => rows.map((x) => x[k]).sort((a, b) => a - b)[Math.floor(rows.length / 2)];
  const ms = (v) => (v === undefined ? '–' : `${(v / 1000).toFixed(2)} s`);
  console.log(`${name} (${rows[0].nodes} components), median of ${runs}: first paint ${ms(median('fp'))}, ` +
    `first contentful paint ${ms(median('fcp'))}, stream open ${ms(median('open'))}, task message ${ms(median('task'))}, graph drawn ${ms(median('graph'))}, ` +
    `redrawn by ELK ${ms(median('elk'))} (its layout ${ms(median('layout'))})`);
  for (const x of rows) console.log(`  run: fp ${ms(x.fp)}, fcp ${ms(x.fcp)}, open ${ms(x.open)}, task ${ms(x.task)}, graph ${ms(x.graph)}, ELK ${ms(x.elk)} (layout ${ms(x.layout)})`);
}

try {
  if (tasks.includes('grasp')) await measure('grasp', ['tasks/grasp.yaml', '-e', 'threaded']);  // real time: the run lasts while the page loads
  if (tasks.includes('chain1000')) await measure('chain of 1000', [chainTask(1000)]);
} finally {
  fs.rmSync(dir, { recursive: true, force: true });
}
