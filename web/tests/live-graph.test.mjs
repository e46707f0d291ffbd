// The live view of a running task: fba-run tasks/examples/chain.yaml --serve 0, endless, in Debian's
// Chromium. The page draws the task's graph and its rates are live (they change between two reads);
// the queues show their fill. Conditions are waited for, never a time: a loaded machine only slows it.
import fs from 'node:fs';
import { launchBrowser } from './browser.mjs';
import { FbaRun, testArguments, temporaryFolder } from './fba-run.mjs';
import { run, step, expect } from './check.mjs';

const { fbaRun, sourceDir } = testArguments();
const WAIT = { timeout: 600_000, polling: 100 };
const RATE = /(\d+(?:\.\d+)?) (?:k|M)?Hz/;

run(async (cleanup) => {
  const dir = temporaryFolder('live-graph');
  cleanup((error) => (error ? console.log(`kept ${dir}`) : fs.rmSync(dir, { recursive: true, force: true })));
  // Counts no run reaches: the task runs until the test stops it.
  const fba = new FbaRun(fbaRun, ['tasks/examples/chain.yaml', '--set', 'source.count=1000000000000', '--set', 'sink.expected=1000000000000',
    '--serve', '0', '--output-dir', dir], { cwd: sourceDir });
  cleanup(async () => {
    const { code, signal } = await fba.stop();
    console.log(`fba-run stopped: ${code ?? signal}`);
  });
  const url = await fba.url;
  const browser = await launchBrowser();
  cleanup(() => browser.close());
  const page = await browser.context.newPage();
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(e.message));

  await step('the page served by fba-run draws the task graph: five components, four connections', async () => {
    await page.goto(url);
    await page.waitForFunction(() => window.fbaDebug?.graph.drawn, null, WAIT);
    const names = await page.$$eval('.node', (nodes) => nodes.map((n) => n.dataset.name).sort());
    expect(names.join() === 'first,second,sink,source,third', `components drawn: ${names.join()}`);
    const edges = await page.$$eval('.edge', (e) => e.length);
    expect(edges === 4, `connections drawn: ${edges}, expected 4`);
  });

  await step('the sink\'s rate is live: it changes between two reads', async () => {
    const selector = '.node[data-name="sink"] .node-rates';
    const read = () => page.$eval(selector, (e) => e.textContent);
    await page.waitForFunction(([s, re]) => new RegExp(re).test(document.querySelector(s)?.textContent ?? ''), [selector, RATE.source], WAIT);
    // The sink's count of samples taken, as the page last received it (the drawn count is rounded).
    const taken = () => page.evaluate(() => window.fbaDebug.state.stats.components.find((c) => c.name === 'sink').samples_in);
    const first = (await read()).match(RATE)[0];
    const firstTaken = await taken();
    // A new rate drawn, above zero, and more samples taken: on a loaded machine a 100 ms window may
    // pass with no sample taken by the sink, and the page then rightly shows 0 Hz for it; the next
    // windows see the flow again. A chain that stopped never gets here, and the wait fails the test.
    await page.waitForFunction(([s, re, f, before]) => {
      const m = (document.querySelector(s)?.textContent ?? '').match(new RegExp(re));
      const sink = window.fbaDebug.state.stats.components.find((c) => c.name === 'sink');
      return m && m[0] !== f && Number(m[1]) > 0 && sink.samples_in > before;
    }, [selector, RATE.source, first, firstTaken], WAIT);
    const second = (await read()).match(RATE)[0];
    console.log(`   sink: ${first}, then ${second}; samples taken: ${firstTaken}, then ${await taken()}`);
  });

  await step('the task is shown running, and every connection shows its queue fill', async () => {
    await page.waitForFunction(() => document.getElementById('run-status').textContent === 'running', null, WAIT);
    await page.waitForFunction(() => [...document.querySelectorAll('.queue-label')].every((l) => /^\d+\/(\d+|∞) · /.test(l.textContent)), null, WAIT);
    const states = await page.$$eval('.node-state', (s) => s.map((e) => e.textContent));
    expect(states.every((s) => /^(idle|queued|running|finished)/.test(s)), `component states: ${states.join(', ')}`);
  });

  await step('clicking a component shows its type, ports and counts', async () => {
    await page.click('.node[data-name="second"] .node-name');
    await page.waitForFunction(() => !document.getElementById('details').hidden, null, WAIT);
    const text = await page.$eval('#details', (e) => e.textContent);
    expect(/second/.test(text) && /examples\.passthrough/.test(text) && /samples in \/ out/.test(text), `the details say: ${text}`);
  });

  await step('no problem with the data and no script error', async () => {
    const problems = await page.evaluate(() => window.fbaDebug.problems);
    expect(problems.length === 0, `the page reported: ${problems.join('; ')}`);
    expect(pageErrors.length === 0, `script errors: ${pageErrors.join('; ')}`);
  });
});
