// A page given bad data says what is wrong and shows what it can, never a blank page: the built
// report.html template filled in here by hand (as fba-run does, marker replaced) and opened from disk.
//   node web/tests/bad-data.test.mjs --web-dir build/release/share/fba/web
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { launchBrowser } from './browser.mjs';
import { temporaryFolder } from './fba-run.mjs';
import { run, step, expect } from './check.mjs';

const i = process.argv.indexOf('--web-dir');
if (i < 0) throw new Error('usage: node bad-data.test.mjs --web-dir DIR (the built page: share/fba/web)');
const template = fs.readFileSync(path.join(process.argv[i + 1], 'report.html'), 'utf8');
const WAIT = { timeout: 600_000, polling: 100 };

const task = {
  type: 'task', run_id: 'r', task: 'bad_data', file: 'bad.yaml',
  components: [
    { name: 'a', type: 'examples.counter', kind: 'sensor', doc: '', inputs: [], outputs: [{ name: 'out', type: 'int' }] },
    { name: 'b', type: 'examples.sink', kind: 'actuator', doc: '', inputs: [{ name: 'in', type: 'int' }], outputs: [] },
  ],
  connections: [{ from: 'a.out', to: 'b.in', policy: 'lossless', capacity: 4, feedback: false }],
};

// What fba-run writes in place of the marker, "</" escaped the same way.
function report(dir, name, json) {
  const data = `<script type="application/json" id="fba-report">${json.replaceAll('</', '<\\/')}</script>`;
  const file = path.join(dir, name);
  fs.writeFileSync(file, template.replace('<!--FBA_REPORT_DATA-->', () => data));
  return pathToFileURL(file).href;
}

run(async (cleanup) => {
  const dir = temporaryFolder('bad-data');
  cleanup((error) => (error ? console.log(`kept ${dir}`) : fs.rmSync(dir, { recursive: true, force: true })));
  const browser = await launchBrowser();
  cleanup(() => browser.close());
  const problemsOf = async (url) => {
    const page = await browser.context.newPage();
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    await page.goto(url);
    await page.waitForFunction(() => window.fbaDebug && !document.getElementById('problems').hidden, null, WAIT);
    const text = await page.$eval('#problems', (e) => e.textContent);
    return { page, text, errors };
  };

  await step('the template without data says it holds no run', async () => {
    const { text, errors } = await problemsOf(pathToFileURL(path.join(process.argv[i + 1], 'report.html')).href);
    expect(/holds no run data/.test(text), `the page says: ${text}`);
    expect(!errors.length, errors.join('; '));
  });

  await step('data that is not JSON is named, not a blank page', async () => {
    const { text } = await problemsOf(report(dir, 'not-json.html', '{"messages": [ {"type": "task", '));
    expect(/embedded data could not be read/.test(text) && /no task message/.test(text), `the page says: ${text}`);
  });

  await step('a bad model view is named by its field; the graph and the good views are still shown', async () => {
    const messages = [task,
      { type: 'view', port: 'a.model', data_type: 'OctreeModel', seq: 1, t: 0.1, view: { kind: 'model', occupied: [0, 0, 0] } },
      { type: 'event', index: 0, t: 0.2, source: 'b', name: 'done', payload: { n: 1 } },
      { type: 'end', outcome: 'success', exit_code: 0, reason: 'b.done', summary: {} }];
    const { page, text, errors } = await problemsOf(report(dir, 'bad-model.html', JSON.stringify({ messages })));
    expect(/view of a\.model.*"occupied" must be a flat array of numbers, 4 per leaf/.test(text), `the page says: ${text}`);
    await page.waitForFunction(() => fbaDebug.graph.drawn && fbaDebug.events === 1 && fbaDebug.ended, null, WAIT);
    const shown = await page.evaluate(() => ({ nodes: fbaDebug.graph.nodes, model: fbaDebug.model.occupiedInstances,
      status: document.getElementById('run-status').textContent }));
    expect(shown.nodes === 2 && shown.model === 0 && shown.status === 'success (exit 0)', JSON.stringify(shown));
    expect(!errors.length, errors.join('; '));
  });

  await step('a message before the task message, and an unknown one, are named', async () => {
    const messages = [{ type: 'stats', t: 1, components: [], connections: [] }, task, { type: 'surprise' }];
    const { text } = await problemsOf(report(dir, 'order.html', JSON.stringify({ messages })));
    expect(/"stats" message came before the task message/.test(text) && /unknown message type "surprise"/.test(text), `the page says: ${text}`);
  });
});
