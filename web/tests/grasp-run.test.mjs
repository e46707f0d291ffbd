// The grasp task's run watched live, then its report opened from disk: fba-run tasks/grasp.yaml
// --serve 0 --output-dir D in Debian's Chromium. Live, the model renders as one box per occupied
// leaf of the newest model message; after the run, D/report.html opens from file:// with no server
// and shows the same graph and the model of its embedded data. Conditions are waited for, never a time.
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { launchBrowser } from './browser.mjs';
import { FbaRun, testArguments, temporaryFolder } from './fba-run.mjs';
import { run, step, expect } from './check.mjs';

const { fbaRun, sourceDir } = testArguments();
const WAIT = { timeout: 600_000, polling: 200 };

// The report's messages, read here without the page: what the page must show.
function reportMessages(file) {
  const html = fs.readFileSync(file, 'utf8');
  expect(!html.includes('<!--FBA_REPORT_DATA-->'), 'report.html still holds the marker: fba-run did not fill it in');
  const m = /<script type="application\/json" id="fba-report">([\s\S]*?)<\/script>/.exec(html);
  expect(m, 'report.html holds no <script id="fba-report"> element');
  return JSON.parse(m[1]).messages;
}

// fba-run exits as soon as its run ends, and the grasp task in simulation ends in seconds: the
// browser is started first and the page opened the moment fba-run says where, on the threaded
// executor (the arm's moves in real time, not on a virtual clock). A run over before the page had
// its task message could show nothing live: it is said, and the run tried again, three times at most.
async function startWatchedRun(browser, cleanup, pageErrors) {
  for (let attempt = 1; attempt <= 3; attempt++) {
    const dir = temporaryFolder('grasp-run');
    const page = await browser.context.newPage();
    page.on('pageerror', (e) => pageErrors.push(`live: ${e.message}`));
    const fba = new FbaRun(fbaRun, ['tasks/grasp.yaml', '-e', 'threaded', '--serve', '0', '--output-dir', dir], { cwd: sourceDir });
    cleanup(() => fba.stop());
    const url = await fba.url;
    const connected = page.goto(url).then(() => page.waitForFunction(() => window.fbaDebug?.state.task, null, WAIT)).then(() => true, () => false);
    const got = await Promise.race([connected, fba.exited.then(() => false)]);
    if (got || await page.evaluate(() => !!window.fbaDebug?.state.task).catch(() => false)) return { dir, page, fba };
    console.log(`   attempt ${attempt}: the run was over before the page had its task message; again`);
    await fba.exited;
    await page.close();
    fs.rmSync(dir, { recursive: true, force: true });
  }
  throw new Error('three runs of the grasp task were each over before the page connected');
}

run(async (cleanup) => {
  const browser = await launchBrowser();
  cleanup(() => browser.close());
  const pageErrors = [];
  const { dir, page: live, fba } = await startWatchedRun(browser, cleanup, pageErrors);
  cleanup((error) => (error ? console.log(`kept ${dir}`) : fs.rmSync(dir, { recursive: true, force: true })));

  await step('live: the graph of the grasp task is drawn', async () => {
    await live.waitForFunction(() => window.fbaDebug?.graph.drawn, null, WAIT);
    const { nodes, components } = await live.evaluate(() => ({ nodes: fbaDebug.graph.nodes, components: fbaDebug.state.task.components.length }));
    expect(nodes === components && nodes > 5, `${nodes} components drawn of the task's ${components}`);
  });

  await step('live: the model renders, one instance per occupied leaf of the newest model message', async () => {
    await live.waitForFunction(() => fbaDebug.model.occupiedInstances > 0 && fbaDebug.model.occupiedInstances === fbaDebug.model.occupiedInMessage, null, WAIT);
    const model = await live.evaluate(() => fbaDebug.model);
    const pixels = await live.evaluate(() => fbaDebug.modelPixels());
    console.log(`   ${model.modelPort} #${model.modelSeq}: ${model.occupiedInstances} occupied leaves, ${pixels} pixels painted`);
    expect(pixels > 0, 'the occupied leaves painted no pixel of the canvas');
  });

  let exit;
  await step('live: the run ends and the page says how', async () => {
    await live.waitForFunction(() => fbaDebug.ended, null, WAIT);
    exit = await fba.exited;
    const status = await live.$eval('#run-status', (e) => e.textContent);
    console.log(`   fba-run exited ${exit.code ?? exit.signal}; the page says: ${status}`);
    expect(exit.code === 0 || exit.code === 1, `fba-run exited ${exit.code ?? exit.signal}; its stderr:\n${fba.stderr}`);
    expect(status.includes(`exit ${exit.code}`), `the status "${status}" does not give the exit code ${exit.code}`);
  });

  const reportFile = path.join(dir, 'report.html');
  const messages = await step('the report is written, its messages readable', async () => {
    expect(fs.existsSync(reportFile), `no report.html in ${dir}: ${fs.readdirSync(dir).join(', ')}`);
  }).then(() => reportMessages(reportFile));
  const task = messages.find((m) => m.type === 'task');
  const lastModel = messages.filter((m) => m.type === 'view' && m.view?.kind === 'model').pop();

  await step('report.html opens from disk with no server: the graph and the model of its data', async () => {
    expect(exit, 'fba-run is still running');
    const page = await browser.context.newPage();
    page.on('pageerror', (e) => pageErrors.push(`report: ${e.message}`));
    const requests = [];
    page.on('request', (r) => { if (!r.url().startsWith('file:') && !r.url().startsWith('data:') && !r.url().startsWith('blob:')) requests.push(r.url()); });
    await page.goto(pathToFileURL(reportFile).href);
    await page.waitForFunction(() => window.fbaDebug?.graph.drawn, null, WAIT);
    const shown = await page.evaluate(() => ({ source: fbaDebug.source, nodes: fbaDebug.graph.nodes, model: fbaDebug.model, problems: fbaDebug.problems }));
    expect(shown.source === 'report', `the page took its data from ${shown.source}, not the report`);
    expect(shown.nodes === task.components.length, `${shown.nodes} components drawn, the report's task has ${task.components.length}`);
    expect(lastModel, 'the report holds no model view');
    const leaves = lastModel.view.occupied.length / 4;
    expect(shown.model.occupiedInstances === leaves, `${shown.model.occupiedInstances} boxes drawn, the report's last model has ${leaves} occupied leaves`);
    const pixels = await page.evaluate(() => fbaDebug.modelPixels());
    expect(pixels > 0, 'the report\'s model painted no pixel');
    expect(requests.length === 0, `the report asked the network for: ${requests.join(', ')}`);
    expect(shown.problems.length === 0, `the report page reported: ${shown.problems.join('; ')}`);
    console.log(`   report.html: ${(fs.statSync(reportFile).size / 1e6).toFixed(2)} MB, ${messages.length} messages, ${leaves} occupied leaves`);
  });

  await step('no script error on either page', async () => {
    expect(pageErrors.length === 0, pageErrors.join('; '));
  });
});
