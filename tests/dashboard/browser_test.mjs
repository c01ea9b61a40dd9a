// Browser test of the dashboard: Debian's chromium driven headless by playwright-core, against
// fploc-dashboard fed by fake publishers over LCM (inside the network namespace ctest gives us).
// Checks: the page loads, the trail grows, every node is in the table, a killed node turns red and
// green again after restart, a launcher "restarting" report turns a node red, the page reconnects by
// itself after a server restart, a pose lagging the sensor is said ("pose N s behind the sensor") and the text
// goes when it catches up, the ATE and rate plots' axes start at 0. Measures pose->browser latency, the dashboard's CPU with two
// browsers attached at 10 Hz and the push rate. Writes dashboard.png + dashboard_browser.json.
import { chromium } from 'playwright-core';
import { spawn } from 'node:child_process';
import { readFileSync, mkdirSync, writeFileSync, copyFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const HERE = dirname(fileURLToPath(import.meta.url));
const ROOT = process.env.FPLOC_ROOT || join(HERE, '../..');
const BUILD = process.env.FPLOC_BUILD_DIR || join(ROOT, 'build');
const BIN = join(BUILD, 'bin');
const OUT = process.env.FPLOC_ARTIFACTS || join(BUILD, 'tests/dashboard');
const URL = 'http://127.0.0.1:8080/';
const NODES = ['sim', 'segmenter', 'feature_extractor', 'matcher', 'optimizer'];
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const procs = new Set();
let failures = 0;
// Network errors in the page are expected only while the server is restarted on purpose.
let serverRestarting = false;

function start(exe, args, name) {
  const p = spawn(join(BIN, exe), args, { stdio: ['ignore', 'ignore', 'pipe'] });
  p.stderr.on('data', (d) => { if (process.env.FPLOC_VERBOSE) process.stderr.write(`[${name}] ${d}`); });
  procs.add(p);
  p.on('exit', () => procs.delete(p));
  return p;
}
const startDashboard = () => start('fploc-dashboard', ['--graph', join(ROOT, 'tests/dashboard/fake.pbtxt'), '--node', 'dashboard'], 'dashboard');
const startFake = (name, extra = []) => start('fploc-dashboard-fake', ['--name', name, ...extra], name);
async function stop(p, signal = 'SIGTERM') {
  if (p.exitCode !== null || p.signalCode !== null) return;
  const done = new Promise((r) => p.once('exit', r));
  p.kill(signal);
  await Promise.race([done, sleep(3000)]);
  if (p.exitCode === null && p.signalCode === null) { p.kill('SIGKILL'); await done; }
}
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures++;
}
async function waitFor(fn, timeoutMs, stepMs = 50) {
  const t0 = Date.now();
  for (;;) {
    const v = await fn();
    if (v) return Date.now() - t0;
    if (Date.now() - t0 > timeoutMs) return -1;
    await sleep(stepMs);
  }
}
async function serverUp() {
  return waitFor(async () => { try { return (await fetch(URL + 'api/info')).ok; } catch { return false; } }, 10000, 100);
}
const cpuTicks = (pid) => { const f = readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' '); return Number(f[11]) + Number(f[12]); };
const pct = (a, q) => { const s = [...a].sort((x, y) => x - y); return s.length ? s[Math.min(s.length - 1, Math.floor(q * s.length))] : NaN; };
const health = (page, node) => page.evaluate((n) => document.querySelector(`#nodes tr[data-node="${n}"]`)?.dataset.health ?? null, node);

let browser;
try {
  mkdirSync(OUT, { recursive: true });
  let dash = startDashboard();
  const fakes = {};
  fakes.sim = startFake('sim', ['--sim', '--rate', '10']);
  for (const n of NODES.slice(1)) fakes[n] = startFake(n);
  check((await serverUp()) >= 0, 'dashboard answers on 127.0.0.1:8080');

  browser = await chromium.launch({
    executablePath: process.env.FPLOC_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync'],
  });
  const pages = [];
  const pageErrors = [];
  for (let i = 0; i < 2; i++) {
    const ctx = await browser.newContext({ viewport: { width: 1440, height: 900 } });
    const page = await ctx.newPage();
    page.on('pageerror', (e) => pageErrors.push(String(e)));
      page.on('console', (m) => {
      if (m.type() !== 'error') return;
      if (serverRestarting && /ERR_CONNECTION_REFUSED|ERR_INCOMPLETE_CHUNKED_ENCODING|ERR_EMPTY_RESPONSE/.test(m.text())) return;
      pageErrors.push(m.text());
    });
    await page.goto(URL);
    pages.push(page);
  }
  const [page] = pages;
  check((await waitFor(() => page.evaluate(() => window.__fploc?.connected), 5000)) >= 0, 'page loads and connects (SSE)');
  check(await page.evaluate(() => document.title === 'fploc dashboard'), 'title');

  // Trail grows.
  const trail0 = await page.evaluate(() => window.__fploc.trail.length);
  await sleep(2000);
  const trail1 = await page.evaluate(() => window.__fploc.trail.length);
  check(trail1 >= trail0 + 10, `trail grows (${trail0} -> ${trail1} poses in 2 s at 10 Hz)`);
  check(await page.evaluate(() => window.__fploc.gtTrail.length > 10), 'ground-truth trail present');
  check(await page.evaluate(() => (window.__fploc.features?.xy.length ?? 0) > 100), 'features received');
  // Most features lie on the plan; the cabinet (not in the plan) gives some off the plan. The fake robot drives
  // an ellipse in 30 s and the pillar hides the cabinet for ~2 s of it (10-12 s after the start: 0-1 % of the
  // points on it): a start slowed by load used to land the one reading there (99.7-100 % on the plan). So wait
  // for a drawn scan that sees the cabinet, then check that scan point by point: its points on the cabinet are
  // drawn off the plan, nearly all the others on it.
  const CAB = { x0: 9.0, x1: 10.0, y0: 1.2, y1: 1.8 }, CAB_TOL = 0.1;  // tests/dashboard/fake_graph.cpp's cabinet
  const drawn = () => page.evaluate(({ b, tol }) => {
    const d = window.__fploc.featuresDrawn;
    if (!d) return null;
    let n = d.near.length, cab = 0, cabOff = 0, rest = 0, restOn = 0;
    for (let k = 0; k < n; k++) {
      const inCab = d.wx[k] > b.x0 - tol && d.wx[k] < b.x1 + tol && d.wy[k] > b.y0 - tol && d.wy[k] < b.y1 + tol;
      if (inCab) { cab++; cabOff += d.near[k] ? 0 : 1; } else { rest++; restOn += d.near[k]; }
    }
    return { seq: d.scan_seq, n, cab, cabOff, rest, restOn, onPlan: window.__fploc.featuresMatched };
  }, { b: CAB, tol: CAB_TOL });
  let seen = null;
  const tCab = await waitFor(async () => { seen = await drawn(); return seen && seen.n > 100 && seen.cab >= 0.01 * seen.n; }, 8000);
  check(tCab >= 0, `a drawn scan sees the cabinet (after ${tCab} ms: ${seen ? `${seen.cab} of ${seen.n} points on it` : 'no scan drawn'})`);
  if (seen) {
    check(seen.onPlan > 0.6 && seen.onPlan < 0.995, `features on the plan vs off it (${(100 * seen.onPlan).toFixed(1)} % on the plan, scan ${seen.seq})`);
    check(seen.cab > 0 && seen.cabOff === seen.cab, `the cabinet's points are drawn off the plan (${seen.cabOff} of ${seen.cab})`);
    check(seen.rest > 0 && seen.restOn >= 0.98 * seen.rest, `the other points are drawn on the plan (${seen.restOn} of ${seen.rest})`);
  }

  // A POOR pose names its reason (the publishing node's telemetry detail; the fake is POOR 3 s of every 10).
  const statusRow = () => page.evaluate(() => [...document.querySelectorAll('#posebox tr')].find((r) => r.cells[0]?.textContent === 'status')?.cells[1]?.textContent ?? '');
  const tPoor = await waitFor(async () => (await statusRow()).startsWith('POOR · a second fit 1.20 m'), 12000);
  check(tPoor >= 0, `a POOR status names its reason ("${await statusRow()}")`);

  // Every node in the table, all green.
  const everyNode = [...NODES, 'dashboard'];
  const allOk = await waitFor(async () => {
    const h = await Promise.all(everyNode.map((n) => health(page, n)));
    return h.every((x) => x === 'ok');
  }, 4000);
  check(allOk >= 0, `node table shows every node green: ${everyNode.join(', ')}`);
  check((await health(page, 'imu_driver')) === 'bad', 'a graph node that never sent a heartbeat is listed red');
  check((await health(page, 'spare')) === null, 'disabled graph nodes are not listed');

  // A page opened mid-run draws the plots from /api/history: the ground truth's roll/pitch (it had only z)
  // and the frame/pose rates (they had no history), not only what arrives after it opened.
  {
    const late = await (await browser.newContext({ viewport: { width: 1200, height: 800 } })).newPage();
    late.on('pageerror', (e) => pageErrors.push(String(e)));
    await late.goto(URL);
    await waitFor(() => late.evaluate(() => window.__fploc?.connected && window.__fploc.gtTrail.length > 0), 5000, 10);
    const h = await late.evaluate(() => {
      const S = window.__fploc;
      return { gt: S.gtTrail.length, gtRoll: S.plots.rp.data[2].length, rates: S.plots.rate.data[1].length };
    });
    check(h.gt > 20 && h.gtRoll >= h.gt - 5, `a page opened mid-run plots the ground truth's roll from the history (${h.gtRoll} points, ${h.gt} gt poses)`);
    check(h.rates >= 4, `a page opened mid-run plots the rates from the history (${h.rates} points)`);
    await late.context().close();
  }

  // Measurement window: two browsers attached, 10 Hz poses.
  await Promise.all(pages.map((p) => p.evaluate(() => { window.__fploc.latencies = []; window.__fploc.rxLatencies = []; window.__fploc.mark = { ...window.__fploc.events, t: performance.now() }; })));
  const cpu0 = cpuTicks(dash.pid), w0 = Date.now();
  await sleep(10000);
  const cpu1 = cpuTicks(dash.pid), w1 = Date.now();
  const cpuPercent = 100 * ((cpu1 - cpu0) / 100) / ((w1 - w0) / 1000);  // USER_HZ = 100
  const perPage = await Promise.all(pages.map((p) => p.evaluate(() => {
    const S = window.__fploc, dt = (performance.now() - S.mark.t) / 1000;
    const rate = (k) => ((S.events[k] || 0) - (S.mark[k] || 0)) / dt;
    return { latencies: S.latencies, rx: S.rxLatencies, pose_hz: rate('pose'), features_hz: rate('features'), nodes_hz: rate('nodes') };
  })));
  const lat = perPage.flatMap((p) => p.latencies), rx = perPage.flatMap((p) => p.rx);
  const loadavg = readFileSync('/proc/loadavg', 'utf8').split(' ').slice(0, 3).map(Number);
  const results = {
    browsers: 2,
    input_rate_hz: 10,
    window_s: (w1 - w0) / 1000,
    dashboard_cpu_percent_of_one_core: Number(cpuPercent.toFixed(2)),
    latency_ms: { n: lat.length, p50: pct(lat, 0.5), p95: pct(lat, 0.95), p99: pct(lat, 0.99), max: Math.max(...lat) },
    // Stamp -> dashboard receive (publisher + LCM + the dashboard's handler queue): the rest is HTTP + browser.
    to_dashboard_ms: { p50: pct(rx, 0.5), p95: pct(rx, 0.95), p99: pct(rx, 0.99) },
    loadavg_1_5_15: loadavg,
    push_rate_hz_per_browser: perPage.map((p) => ({ pose: +p.pose_hz.toFixed(2), features: +p.features_hz.toFixed(2), nodes: +p.nodes_hz.toFixed(2) })),
  };
  console.log(JSON.stringify(results));
  check(lat.length >= 150, `latency samples from both browsers (${lat.length})`);
  // Reported, not asserted (speed is measured, never asserted in tests): the target is p50 <= 100 ms.
  console.log(`note pose -> browser latency p50 ${results.latency_ms.p50.toFixed(1)} ms, p95 ${results.latency_ms.p95.toFixed(1)} ms ` +
    `(target <= 100; load average ${loadavg[0]}); dashboard CPU ${results.dashboard_cpu_percent_of_one_core} % of one core`);

  // A node that stops heartbeating turns red, and green again when it comes back.
  await stop(fakes.matcher, 'SIGKILL');
  const tRed = await waitFor(async () => (await health(page, 'matcher')) === 'bad', 6000);
  check(tRed >= 0, `killed node turns red (after ${tRed} ms; threshold 2 s without heartbeat)`);
  check(await page.evaluate(() => document.querySelector('#nodes tr[data-node="matcher"]').classList.contains('bad')), 'red row style');
  fakes.matcher = startFake('matcher');
  const tGreen = await waitFor(async () => (await health(page, 'matcher')) === 'ok', 4000);
  check(tGreen >= 0, `restarted node turns green again (after ${tGreen} ms)`);

  // The launcher reports a node as restarting: red at once.
  // The launcher reports a node as restarting (1 Hz, on its behalf, while the process is gone): red
  // with that reason, then green when the node's own heartbeat is back.
  await stop(fakes.feature_extractor, 'SIGKILL');
  const launcher = startFake('feature_extractor', ['--state', 'restarting', '--reporter', 'launcher', '--duration', '3']);
  const stateText = () => page.evaluate(() => document.querySelector('#nodes tr[data-node="feature_extractor"] td:nth-child(2)')?.textContent ?? '');
  const tLaunch = await waitFor(async () => (await health(page, 'feature_extractor')) === 'bad' && (await stateText()).includes('restarting'), 3000, 20);
  check(tLaunch >= 0, `launcher-reported "restarting" turns the node red (after ${tLaunch} ms: "${await stateText()}")`);
  await stop(launcher);
  fakes.feature_extractor = startFake('feature_extractor');
  check((await waitFor(async () => (await health(page, 'feature_extractor')) === 'ok', 4000)) >= 0, 'and green again when it heartbeats');

  await sleep(2500);  // let the trail get longer for the picture
  // Poses the page missed (rate cap, stalls) are filled in from /api/history: the page's trail holds
  // every pose the server has in the same time range.
  await sleep(5200);  // one periodic history re-read
  await waitFor(() => page.evaluate(() => !window.__fploc.fillPending), 3000);
  const trailCheck = await page.evaluate(async () => {
    const t = window.__fploc.trail, have = new Set(t.map((p) => p[2]));
    const h = await (await fetch('/api/history', { cache: 'no-store' })).json();
    const lo = t[0][2], hi = t[t.length - 1][2] - 1e6;  // the last second may still be filling
    const inRange = h.est.filter((e) => e[0] >= lo && e[0] <= hi);
    const miss = inRange.filter((e) => !have.has(e[0]));
    return { server: inRange.length, missing: miss.length, where: miss.map((e) => `${((e[0] - lo) / 1e6).toFixed(2)}/${((hi - lo) / 1e6).toFixed(2)} s`).join(' '), fills: window.__fploc.gapFills || 0 };
  });
  check(trailCheck.missing === 0, `page trail has every pose the server has (${trailCheck.server} poses, ${trailCheck.missing} missing ${trailCheck.where}, ${trailCheck.fills} gap fills)`);
  // Plots of quantities that cannot be negative (ATE, horizontal error, frame and pose rates) have their axis
  // from 0, not from a margin below it (a user trial read "ATE so far" from -0.010 and "frame rate" from -1.2).
  const axes = await page.evaluate(() => Object.fromEntries(['ate', 'rate'].map((k) => {
    const p = window.__fploc.plots[k];
    return [k, { axis: p.axis ?? null, points: p.data.reduce((n, d) => n + d.length, 0) }];
  })));
  for (const [k, a] of Object.entries(axes))
    check(a.points > 0 && a.axis && a.axis[0] === 0 && a.axis[1] > 0,
      `plot '${k}' axis starts at 0 (${a.axis ? a.axis.map((v) => v.toFixed(4)).join(' .. ') : 'not drawn'}, ${a.points} points)`);
  await page.screenshot({ path: join(OUT, 'dashboard.png') });
  if (process.env.FPLOC_SCREENSHOT) copyFileSync(join(OUT, 'dashboard.png'), process.env.FPLOC_SCREENSHOT);

  // Server restart: banner while down, reconnect by itself, trail grows again.
  serverRestarting = true;
  await stop(dash);
  const tBanner = await waitFor(() => page.evaluate(() => !document.getElementById('banner').classList.contains('hidden')), 4000);
  check(tBanner >= 0, `disconnected banner shown (after ${tBanner} ms)`);
  dash = startDashboard();
  const tBack = await waitFor(() => page.evaluate(() => window.__fploc.connected && window.__fploc.reconnects > 0), 8000);
  check(tBack >= 0, `page reconnects by itself after a server restart (after ${tBack} ms)`);
  const r0 = await page.evaluate(() => window.__fploc.trail.length);
  await sleep(1500);
  const r1 = await page.evaluate(() => window.__fploc.trail.length);
  check(r1 > r0 && (await page.evaluate(() => document.getElementById('banner').classList.contains('hidden'))), `trail grows again, banner gone (${r0} -> ${r1})`);

  // A pose that falls behind the sensor (the sim fake restarted with its pose stamps lagging from 1 s on, 0.75 s per
  // s, for 7 s: at most 5.25 s, then caught up): the top bar says "pose N s behind the sensor" (red) once the lag
  // passes 3 s (shown rounded: "3.0" for 3.04 s), and the text goes when the pose catches up.
  {
    await stop(fakes.sim);
    fakes.sim = startFake('sim', ['--sim', '--rate', '10', '--pose-lag-at', '1', '--pose-lag-for', '7']);
    const bar = () => page.evaluate(() => { const e = document.getElementById('latency'); return { text: e.textContent, stale: e.classList.contains('stale') }; });
    let seen = null;
    const tBehind = await waitFor(async () => { const b = await bar(); if (/pose \d+\.\d s behind the sensor/.test(b.text) && b.stale) seen = b.text; return seen !== null; }, 10000, 100);
    const lag = seen ? Number(seen.match(/pose (\d+\.\d) s behind/)[1]) : NaN;
    check(tBehind >= 0 && lag >= 3 && lag <= 5.3, `a lagging pose: "${seen ?? (await bar()).text}" in the top bar, red (after ${tBehind} ms)`);
    let after = null;
    const tCaught = await waitFor(async () => { const b = await bar(); after = b; return !b.text.includes('behind the sensor') && !b.stale; }, 8000, 100);
    check(tBehind >= 0 && tCaught >= 0, `and gone when it catches up (after ${tCaught} ms: "${after?.text}")`);
  }

  check(pageErrors.length === 0, `no errors in the page${pageErrors.length ? ': ' + pageErrors.slice(0, 3).join(' | ') : ''}`);
  writeFileSync(join(OUT, 'dashboard_browser.json'), JSON.stringify({ ...results, failures }, null, 2));
  console.log(`screenshot: ${join(OUT, 'dashboard.png')}`);
} catch (e) {
  console.log(`FAIL ${e.stack || e}`);
  failures++;
} finally {
  if (browser) await browser.close().catch(() => {});
  await Promise.all([...procs].map((p) => stop(p)));
}
console.log(failures ? `${failures} check(s) failed` : 'all checks passed');
process.exit(failures ? 1 : 0);
