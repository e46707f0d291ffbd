// The grasp task's run watched live, then its report opened from disk: fba-run tasks/grasp.yaml
// --serve 0 --serve-keep --output-dir D in Debian's Chromium. Live, the model renders as one box per
// occupied leaf of the newest model message, every camera pose visited is there in order, the
// reach trajectory is drawn as the palm's path by the robot the arm sent, and the grasp views hold
// the candidates synthesis found (the first few) and the palm at the pregrasp the planner chose;
// after the run fba-run keeps serving it (a page opened then is sent the whole run) until SIGTERM,
// and exits with the run's status; D/report.html opens from file:// with no server and shows the
// same. Conditions are waited for, never a time.
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

// What a page shows of the run once its end is in: its counts, the poses per port (their seqs in
// the order kept), and where the page's robot puts the trajectory's link at the pregrasp.
async function shown(page, reach) {
  return page.evaluate((pregrasp) => ({
    source: fbaDebug.source,
    nodes: fbaDebug.graph.nodes,
    model: fbaDebug.model,
    problems: fbaDebug.problems,
    status: document.getElementById('run-status').textContent,
    poses: Object.fromEntries([...fbaDebug.state.poses].map(([port, list]) => [port, list.map((m) => m.seq)])),
    trajectoryView: fbaDebug.state.views.get('reach.trajectory')?.view.points.length ?? null,
    palmAtPregrasp: pregrasp ? fbaDebug.scene.linkPositionAt(pregrasp.names, pregrasp.positions) : null,
  }), reach ? { names: reach.trajectory.names, positions: reach.pregrasp_joints } : null);
}

// The checks both pages pass once the run is over: what the summary says the run did, drawn.
function expectTheRunDrawn(where, s, summary) {
  // Every pose each pose port sent, in order: its seqs 0 .. (what the port pushed) - 1, none missing.
  const ports = Object.keys(s.poses);
  expect(ports.includes('arm.camera_pose'), `${where}: no camera pose shown (pose ports: ${ports.join(', ')})`);
  for (const port of ports) {
    const sent = summary.connections.find((c) => c.from === port)?.pushed;
    const seqs = s.poses[port];
    expect(Number.isInteger(sent), `${where}: the summary has no connection from ${port}`);
    const every = Array.from({ length: sent }, (_, i) => i);
    expect(JSON.stringify(seqs) === JSON.stringify(every),
      `${where}: ${port} sent ${sent} poses; the page has seqs [${seqs.join(', ')}], not each once in order`);
  }
  expect(s.poses['arm.camera_pose'].length >= 3, `${where}: ${s.poses['arm.camera_pose'].length} camera poses, fewer than the 3 initial views`);

  // The grasp views: the selected grasp, the first candidates of the analysis it was selected on
  // (the summary has them all) and its palm at the pregrasp, where the reach planner put it.
  const candidates = summary.components.synthesis?.results?.candidates?.grasps;
  expect(Array.isArray(candidates) && candidates.length > 0, `${where}: the summary holds no candidates from synthesis`);
  expect(s.model.selected, `${where}: no selected grasp drawn`);
  expect(s.model.candidatesFound === candidates.length && s.model.candidates > 0 && s.model.candidates <= candidates.length,
    `${where}: ${s.model.candidates} candidates drawn of ${s.model.candidatesFound}, synthesis reported ${candidates.length}`);
  const palm = summary.components.reach.results.reach.pregrasp_palm.position;
  const palmOff = s.model.palm ? Math.hypot(...s.model.palm.position.map((x, i) => x - palm[i])) : Infinity;
  expect(palmOff < 1e-4, `${where}: the palm is drawn at ${JSON.stringify(s.model.palm?.position)}, the planner's pregrasp at ${JSON.stringify(palm)}`);
  expect(s.model.robotLinks > 0, `${where}: no robot drawn`);

  // The reach trajectory: the palm's path, a point per waypoint, posed by the page's URDF as the
  // planner's kinematics pose it (the palm at the pregrasp joints where the planner said).
  const reach = summary.components.reach.results.reach;
  expect(s.model.trajectoryLink === 'palm', `${where}: the trajectory is drawn for ${s.model.trajectoryLink} (${s.model.trajectoryProblem}), not the palm`);
  expect(s.model.trajectoryPathPoints === reach.trajectory.points.length || s.model.trajectoryPathPoints === s.trajectoryView,
    `${where}: the palm's path has ${s.model.trajectoryPathPoints} points; the trajectory ${reach.trajectory.points.length} waypoints (its view ${s.trajectoryView})`);
  expect(s.model.trajectoryPathPoints > 1, `${where}: the palm's path has ${s.model.trajectoryPathPoints} points`);
  const want = reach.pregrasp_palm.position;
  const got = s.palmAtPregrasp?.position;
  const off = got ? Math.hypot(got[0] - want[0], got[1] - want[1], got[2] - want[2]) : Infinity;
  expect(off < 0.002, `${where}: the page puts the palm at the pregrasp joints at ${JSON.stringify(got)}, the planner at ${JSON.stringify(want)} (${(off * 1000).toFixed(1)} mm apart)`);
}

run(async (cleanup) => {
  const browser = await launchBrowser();
  cleanup(() => browser.close());
  const pageErrors = [];
  const dir = temporaryFolder('grasp-run');
  cleanup((error) => (error ? console.log(`kept ${dir}`) : fs.rmSync(dir, { recursive: true, force: true })));
  // --serve-keep: the run in simulation ends in seconds, maybe before the page connects; fba-run
  // then goes on serving it, so the page has the whole run however late it comes.
  const fba = new FbaRun(fbaRun, ['tasks/grasp.yaml', '-e', 'threaded', '--serve', '0', '--serve-keep', '--output-dir', dir], { cwd: sourceDir });
  cleanup(() => fba.stop());
  const url = await fba.url;
  const live = await browser.context.newPage();
  live.on('pageerror', (e) => pageErrors.push(`live: ${e.message}`));
  // When the candidates came, on the run's clock: each analysis's while the run goes on.
  const candidateTimes = [];
  live.on('websocket', (ws) => ws.on('framereceived', ({ payload }) => {
    const m = JSON.parse(payload);
    if (m.type === 'view' && m.port === 'synthesis.candidates') candidateTimes.push(m.t.toFixed(2));
  }));
  await live.goto(url);

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

  let end;
  await step('live: the run ends, the page says how, and fba-run keeps serving it', async () => {
    await live.waitForFunction(() => fbaDebug.ended, null, WAIT);
    await fba.said('still serving its live view');
    end = await live.evaluate(() => fbaDebug.state.end);
    const status = await live.$eval('#run-status', (e) => e.textContent);
    console.log(`   the run ended ${end.outcome} (exit ${end.exit_code}); the page says: ${status}`);
    expect(end.exit_code === 0, `the grasp run did not hold the object (exit ${end.exit_code}: ${end.reason}); its stderr:\n${fba.stderr}`);
    expect(status.includes(`exit ${end.exit_code}`), `the status "${status}" does not give the exit code ${end.exit_code}`);
    expect(fba.running, 'fba-run exited after the run despite --serve-keep');
  });

  const reach = end.summary.components.reach?.results?.reach;
  await step('live: every camera pose in order, the grasp with its candidates and palm, the palm\'s path', async () => {
    expect(reach?.ok && reach.trajectory, `the run planned no reach: ${JSON.stringify(reach)}`);
    await live.waitForFunction(() => fbaDebug.model.trajectoryPathPoints > 0 || fbaDebug.model.trajectoryProblem, null, WAIT);
    const s = await shown(live, reach);
    console.log(`   poses: ${Object.entries(s.poses).map(([p, l]) => `${p} ${l.length}`).join(', ')}; ${s.model.candidates} candidates; ` +
      `the ${s.model.trajectoryLink}'s path: ${s.model.trajectoryPathPoints} points`);
    expectTheRunDrawn('live', s, end.summary);
    console.log(`   the live page was sent candidates at t = ${candidateTimes.join(', ')} s; the run lasted ${end.summary.wall_time_s?.toFixed?.(2) ?? "?"} s`);
  });

  await step('live: a page opened after the end is sent the whole run', async () => {
    const late = await browser.context.newPage();
    late.on('pageerror', (e) => pageErrors.push(`late: ${e.message}`));
    await late.goto(url);
    await late.waitForFunction(() => fbaDebug.ended && fbaDebug.graph.drawn, null, WAIT);
    const s = await shown(late, reach);
    expect(s.source === 'live', `the late page took its data from ${s.source}`);
    expectTheRunDrawn('late page', s, end.summary);
    await late.close();
  });

  await step('SIGTERM ends the serving; fba-run exits with the run\'s status', async () => {
    const exit = await fba.stop('SIGTERM');
    expect(exit.code === end.exit_code, `fba-run exited ${exit.code ?? exit.signal} on SIGTERM, the run's status is ${end.exit_code}`);
  });

  const reportFile = path.join(dir, 'report.html');
  const messages = await step('the report is written, its messages readable', async () => {
    expect(fs.existsSync(reportFile), `no report.html in ${dir}: ${fs.readdirSync(dir).join(', ')}`);
  }).then(() => reportMessages(reportFile));
  const task = messages.find((m) => m.type === 'task');
  const lastModel = messages.filter((m) => m.type === 'view' && m.view?.kind === 'model').pop();

  await step('report.html opens from disk with no server: the graph, the model, the poses, grasps and path of its data', async () => {
    const page = await browser.context.newPage();
    page.on('pageerror', (e) => pageErrors.push(`report: ${e.message}`));
    const requests = [];
    page.on('request', (r) => { if (!r.url().startsWith('file:') && !r.url().startsWith('data:') && !r.url().startsWith('blob:')) requests.push(r.url()); });
    await page.goto(pathToFileURL(reportFile).href);
    await page.waitForFunction(() => window.fbaDebug?.graph.drawn && fbaDebug.ended, null, WAIT);
    const s = await shown(page, reach);
    expect(s.source === 'report', `the page took its data from ${s.source}, not the report`);
    expect(s.nodes === task.components.length, `${s.nodes} components drawn, the report's task has ${task.components.length}`);
    expect(lastModel, 'the report holds no model view');
    const leaves = lastModel.view.occupied.length / 4;
    expect(s.model.occupiedInstances === leaves, `${s.model.occupiedInstances} boxes drawn, the report's last model has ${leaves} occupied leaves`);
    const pixels = await page.evaluate(() => fbaDebug.modelPixels());
    expect(pixels > 0, 'the report\'s model painted no pixel');
    expectTheRunDrawn('report', s, end.summary);
    expect(requests.length === 0, `the report asked the network for: ${requests.join(', ')}`);
    expect(s.problems.length === 0, `the report page reported: ${s.problems.join('; ')}`);
    console.log(`   report.html: ${(fs.statSync(reportFile).size / 1e6).toFixed(2)} MB, ${messages.length} messages, ${leaves} occupied leaves`);
  });

  await step('no script error on any page', async () => {
    expect(pageErrors.length === 0, pageErrors.join('; '));
  });
});
