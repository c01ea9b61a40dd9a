// fploc dashboard page: plan + poses + features on a map, plots, node health. Data: GET /api/plan,
// /api/history once (and after every reconnect), then Server-Sent Events from /api/events.
import { MapView } from './map.js';
import { Plot } from './plot.js';
import { PlanIndex } from './nearest.js';
import { planDiffLayer } from './plandiff.js';
import { FloorView } from './floors.js';

const $ = (id) => document.getElementById(id);
const DEG = 180 / Math.PI;
const css = getComputedStyle(document.documentElement);
const color = (n) => css.getPropertyValue(n).trim();
const COL = { est: color('--est'), gt: color('--gt'), fp: color('--fp'), corner: color('--corner'), surface: color('--surface') };

// Visible to tests (playwright reads it) and handy in the console.
const S = window.__fploc = {
  connected: false, reconnects: 0, events: {}, latencies: [], rxLatencies: [], trail: [], gtTrail: [],
  pose: null, gt: null, frame: null, features: null, nodes: [], stats: null,
  robots: [], fleet: {}, selected: null, ownNodes: null,
};
const MAX_TRAIL = 50000;
const MATCH_M = 0.15;  // a projected feature this close to a plan element counts as matched
let planIndex = null;

const map = new MapView($('map'));
const plots = {
  ate: new Plot($('plot-ate'), [{ label: 'ATE', color: '#dc2626' }, { label: 'error', color: '#9ca3af' }], { digits: 3, zero: true, minSpan: 0.02 }),
  rp: new Plot($('plot-rp'), [{ label: 'roll', color: COL.est }, { label: 'pitch', color: '#ea580c' },
    { label: 'gt roll', color: COL.est, dash: [3, 3], at: 0 }, { label: 'gt pitch', color: '#ea580c', dash: [3, 3], at: 1 }], { digits: 2, minSpan: 0.5 }),
  z: new Plot($('plot-z'), [{ label: 'z', color: COL.est }, { label: 'gt z', color: COL.gt, dash: [3, 3], at: 0 }], { digits: 3, minSpan: 0.05 }),
  rate: new Plot($('plot-rate'), [{ label: 'frames', color: COL.fp }, { label: 'poses', color: COL.est }], { digits: 1, zero: true, minSpan: 1 }),
};
S.plots = plots;  // (tests read the plotted series)

// ---- map layers ------------------------------------------------------------------------------
// Other robots on the same plan (fleet): trail and pose in their colour, named.
map.layers.push((c, v) => {
  for (const [name, r] of Object.entries(S.fleet)) {
    drawOnShownFloor(c, v, r.trail, r.color, (q) => q[3]);
    if (r.pose && r.pose.x !== null) {
      v.arrow(c, r.pose.x, r.pose.y, r.pose.yaw, r.color, true);
      const [sx, sy] = v.toScreen(r.pose.x, r.pose.y);
      c.fillStyle = r.color; c.font = 'bold 13px sans-serif'; c.fillText(name, sx + 12, sy - 12);
    }
  }
  const own = S.robots.find((r) => r.own);
  if (own && own.name && S.pose && S.pose.x !== null && S.robots.length > 1) {
    const [sx, sy] = v.toScreen(S.pose.x, S.pose.y);
    c.fillStyle = COL.est; c.font = 'bold 13px sans-serif'; c.fillText(own.name, sx + 12, sy - 12);
  }
});
// In a building, a trail is drawn only where it is on the floor the map shows (a point of unknown floor counts as
// on it); the ground truth, which names no floor, takes the floor of the estimate at its time: both trails are in
// time order, so one cursor walks the estimate along the ground truth.
function floorOfEstimateAt(trail) {
  let k = -1;
  return (q) => {
    while (k + 1 < trail.length && trail[k + 1][2] <= q[2]) k++;
    return k >= 0 ? trail[k][3] : null;
  };
}
function drawOnShownFloor(c, v, trail, color, floorOf, width = 2) {
  const shown = floors.shown;
  if (floors.floors.length < 2 || !shown) { v.polyline(c, trail, color, width); return; }
  let run = [];
  for (const q of trail) {
    const f = floorOf(q);
    if (!f || f === shown) { run.push(q); continue; }
    v.polyline(c, run, color, width);
    run = [];
  }
  v.polyline(c, run, color, width);
}
map.layers.push((c, v) => {
  // The ground truth wide and underneath: where the estimate agrees with it (mm) it shows as a green band
  // along the blue line instead of vanishing under it.
  drawOnShownFloor(c, v, S.gtTrail, COL.gt, floorOfEstimateAt(S.trail), 6);
  drawOnShownFloor(c, v, S.trail, COL.est, (q) => q[3]);
  const f = S.features;
  // Project with the frame pose of the same scan when it is here (it arrives just after the features).
  const fpose = f && (S.frame && S.frame.scan_seq === f.scan_seq && S.frame.x !== null ? S.frame : f.pose);
  if (f && fpose && $('showfeat').checked) {
    // Points within MATCH_M of a plan element are drawn filled ("matched"), the others hollow.
    const cs = Math.cos(fpose.yaw), sn = Math.sin(fpose.yaw), r = 2, n = f.kind.length;
    const wx = new Float64Array(n), wy = new Float64Array(n), near = new Uint8Array(n);
    let matched = 0;
    for (let k = 0; k < n; k++) {
      const px = f.xy[2 * k], py = f.xy[2 * k + 1];
      wx[k] = fpose.x + cs * px - sn * py; wy[k] = fpose.y + sn * px + cs * py;
      near[k] = planIndex && planIndex.distance(wx[k], wy[k]) <= MATCH_M ? 1 : 0;
      matched += near[k];
    }
    S.featuresMatched = n ? matched / n : null;
    // What was drawn, for the browser test: the scan, its points on the plan and which of them count as matched.
    S.featuresDrawn = { scan_seq: f.scan_seq, wx, wy, near };
    for (const kind of ['s', 'c']) {
      for (const m of [1, 0]) {
        c.beginPath();
        for (let k = 0; k < n; k++) {
          if (f.kind[k] !== kind || near[k] !== m) continue;
          const [sx, sy] = v.toScreen(wx[k], wy[k]);
          c.moveTo(sx + r + 1, sy); c.arc(sx, sy, kind === 'c' ? r + 1 : r, 0, 2 * Math.PI);
        }
        const col = kind === 'c' ? COL.corner : COL.surface;
        if (m) { c.fillStyle = col; c.fill(); } else { c.strokeStyle = col; c.lineWidth = 1; c.stroke(); }
      }
    }
  }
  if (S.gt) v.arrow(c, S.gt.x, S.gt.y, S.gt.yaw, COL.gt, false);
  if (S.frame && S.frame.x !== null) v.arrow(c, S.frame.x, S.frame.y, S.frame.yaw, COL.fp, false, 9);
  if (S.pose) {
    const p = S.pose;
    if (p.sigma_xy > 0) {
      const [sx, sy] = v.toScreen(p.x, p.y);
      c.strokeStyle = 'rgba(31,111,235,.35)'; c.lineWidth = 1;
      c.beginPath(); c.arc(sx, sy, Math.max(3, 2 * p.sigma_xy * v.scale), 0, 2 * Math.PI); c.stroke();
    }
    v.arrow(c, p.x, p.y, p.yaw, p.status === 0 ? COL.est : '#dc2626', true);
  }
});

map.layers.push(planDiffLayer(S));  // where the building no longer matches the plan (fploc-plan-diff)

// ---- trail handling (the optimiser re-publishes poses of its window: replace by utime) --------
// A trail point is [x, y, utime, floor] (floor: the pose's floor name, null when unknown); from an /api/history
// est row [utime, x, y, z, roll, pitch, yaw, err, floor]:
const trailPoint = ([u, x, y, , , , , , f]) => [x, y, u, f || null];
function addToTrail(trail, utime, x, y, floor = null) {
  if (x === null || y === null) return;
  const q = [x, y, utime, floor || null];
  for (let k = trail.length - 1; k >= 0 && k >= trail.length - 200; k--) {
    if (trail[k][2] === utime) { trail[k] = q; return; }
    if (trail[k][2] < utime) break;
  }
  if (trail.length && trail[trail.length - 1][2] > utime) return;  // late and outside the window: ignore
  trail.push(q);
  if (trail.length > MAX_TRAIL) trail.splice(0, trail.length - MAX_TRAIL);
}

// ---- readouts ---------------------------------------------------------------------------------
// Why the pose is not OK: the state line (telemetry detail) of the node publishing FPLOC_POSE, e.g. the optimizer's
// "POOR: a second fit 1.47 m / 0.0 deg away explains 98 %" (pose_t carries the status only).
function poseReason() {
  // (a robot's channels are "R/FPLOC_POSE"; a node's line may start "scan N: ")
  const n = (S.nodes || []).find((m) => m.detail && (m.ports || []).some((q) => q.output && /(^|\/)FPLOC_POSE$/.test(q.channel)));
  return n ? ` · ${n.detail.replace(/^scan \d+: /, '').replace(/^(POOR|LOST): /, '')}` : '';
}
const fmt = (v, d = 3) => (v === null || v === undefined || !Number.isFinite(v) ? '–' : v.toFixed(d));
function renderPoseBox() {
  const fr = S.selected ? S.fleet[S.selected] : null;
  const p = fr ? fr.pose : S.pose, g = fr ? null : S.gt, f = fr ? null : S.frame;
  const rows = [
    ['x, y, z [m]', p ? `${fmt(p.x)}, ${fmt(p.y)}, ${fmt(p.z)}` : '–'],
    ['roll, pitch, yaw [°]', p ? `${fmt(p.roll * DEG, 2)}, ${fmt(p.pitch * DEG, 2)}, ${fmt(p.yaw * DEG, 1)}` : '–'],
    ['status', p ? (['OK', 'POOR', 'LOST'][p.status] ?? p.status) + (p.status !== 0 && !fr ? poseReason() : '') : '–'],
    ['floor', p ? floors.describe(p.floor) : '–'],
    ['ATE so far', p && p.ate_n ? `${fmt(p.ate_rmse)} m (${p.ate_n} poses)` : (g ? 'waiting for matches' : 'no ground truth')],
    ['frame pose', f ? `${f.status_text || (['OK', 'POOR', 'LOST', 'NOT INITIALISED'][f.status] ?? f.status)} · inliers ${fmt(100 * f.inlier_ratio, 0)} % · ${fmt(f.solve_ms, 1)} ms` : '–'],
    ['features', S.features ? `${S.features.n} (shown ${S.features.shown})` +
      (S.featuresMatched !== null && S.featuresMatched !== undefined ? ` · ${(100 * S.featuresMatched).toFixed(0)} % on the plan` : '') : '–'],
  ];
  $('posebox').tBodies[0].replaceChildren(...rows.map(([k, v]) => {
    const tr = document.createElement('tr');
    const a = document.createElement('td'); a.textContent = k;
    const b = document.createElement('td'); b.textContent = v;
    tr.append(a, b); return tr;
  }));
}
let poseBoxPending = false;
function schedulePoseBox() {
  if (poseBoxPending) return;
  poseBoxPending = true;
  setTimeout(() => { poseBoxPending = false; renderPoseBox(); }, 100);
}

// Every input's latency, for the tooltip of the latency cells.
function portLatencies(n) {
  const lines = (n.ports || []).filter((p) => !p.output)
    .map((p) => `${p.port} (${p.channel}): ${fmt(p.rate_hz, 1)} Hz, p50 ${fmt(p.latency_p50_ms, 2)} ms, p99 ${fmt(p.latency_p99_ms, 2)} ms`);
  lines.push(`all handlers and timers: p50 ${fmt(n.latency_p50_ms, 2)} ms, p99 ${fmt(n.latency_p99_ms, 2)} ms`);
  return lines.join('\n');
}

function renderNodes(msg) {
  S.nodes = msg.nodes;
  renderNodeTable(msg);
}
function renderNodeTable(msg) {
  const body = $('nodes').tBodies[0];
  const rows = msg.nodes.map((n) => {
    const tr = document.createElement('tr');
    tr.className = n.health;
    tr.dataset.node = n.node;
    if (n.detail) tr.dataset.detail = n.detail;
    tr.dataset.health = n.health;
    const state = n.health === 'bad' ? (n.reason || n.state) : n.state + (n.reporter === 'launcher' ? ' (launcher)' : '');
    const seen = n.age_s !== null, num = (v, d) => (seen ? fmt(v, d) : '–');
    const work = n.work_port !== null && n.work_port !== undefined;
    const cells = [n.node, state, num(n.rate_hz, 1), work ? n.work_port : '–',
      num(work ? n.work_p50_ms : n.latency_p50_ms, 2), num(work ? n.work_p99_ms : n.latency_p99_ms, 2), num(n.cpu_percent, 1),
      String(n.dropped), String(n.restarts), n.age_s === null ? 'never' : `${fmt(n.age_s, 1)} s ago`,
      [n.detail, n.last_error].filter(Boolean).join(' | ')];
    for (const [i, text] of cells.entries()) {
      const td = document.createElement('td');
      td.textContent = text;
      if (i === 0) td.title = `${n.executable} pid ${n.pid}`;
      if (i >= 3 && i <= 5) td.title = portLatencies(n);
      if (i === cells.length - 1) {
        td.title = text;
        if (n.last_error) td.className = 'err';  // a node's own state line (detail) alone is not an error
      }
      tr.append(td);
    }
    return tr;
  });
  body.replaceChildren(...rows);
  const bad = msg.nodes.filter((n) => n.health === 'bad').length;
  $('summary').textContent = `${msg.nodes.length} nodes${bad ? `, ${bad} down` : ''}`;
}

// ---- data ---------------------------------------------------------------------------------------
let t0 = null;  // plot time origin (s)
const tsec = (utime) => { const t = utime / 1e6; if (t0 === null) t0 = t; return t - t0; };

// Poses skipped by the rate cap or a stalled browser leave gaps: fetch them from /api/history.
function mergeTrail(trail, pts) {
  const all = trail.concat(pts).sort((a, b) => a[2] - b[2]);
  const out = [];
  for (const q of all) { if (out.length && out[out.length - 1][2] === q[2]) out[out.length - 1] = q; else out.push(q); }
  return out.slice(-MAX_TRAIL);
}
let fillSince = null, fillBusy = false;
function fillGap(since) {
  fillSince = fillSince === null ? since : Math.min(fillSince, since);
  S.fillPending = true;
  if (fillBusy) return;  // the running fill picks it up when done
  fillBusy = true;
  setTimeout(async () => {
    while (fillSince !== null) {
      const from = fillSince; fillSince = null;
      try {
        const h = await (await fetch(`/api/history?since=${from}`, { cache: 'no-store' })).json();
        S.trail = mergeTrail(S.trail, h.est.map(trailPoint));
        S.gtTrail = mergeTrail(S.gtTrail, h.gt.map(([u, x, y]) => [x, y, u]));
        S.gapFills = (S.gapFills || 0) + 1;
        map.invalidate();
      } catch (e) { await new Promise((r) => setTimeout(r, 1000)); if (fillSince === null) fillSince = from; }
    }
    fillBusy = false;
    S.fillPending = false;
  }, 100);
}

// Belt and braces: every 5 s re-read the last 10 s of history (poses lost in ways a seq gap does not show).
setInterval(() => { if (S.connected && S.trail.length) fillGap(S.trail[S.trail.length - 1][2] - 10e6); }, 5000);

function onPose(p) {
  // A seq gap, or the first event after loading the history (poses may have come in between).
  if (S.trail.length && (S.lastPoseSeq === undefined || p.seq > S.lastPoseSeq + 1)) fillGap(S.trail[S.trail.length - 1][2]);
  S.lastPoseSeq = p.seq;
  S.pose = p;
  floors.setRobotFloor(p.floor);
  addToTrail(S.trail, p.utime, p.x, p.y, p.floor);
  const lat = Date.now() - p.utime / 1000;
  if (lat > -50 && lat < 10000) {  // only when the stamp is this machine's wall clock (live runs)
    S.latencies.push(lat);
    // Part of it spent before the dashboard received the message (LCM + publisher), same clock.
    if (p.rx_us) S.rxLatencies.push((p.rx_us - p.utime) / 1000);
    if (S.latencies.length > 10000) { S.latencies.splice(0, 5000); S.rxLatencies.splice(0, 5000); }
    S.lastLatency = lat;
  }
  const t = tsec(p.utime);
  plots.ate.push(t, [p.ate_n ? p.ate_rmse : null, p.err]);
  plots.rp.push(t, [p.roll * DEG, p.pitch * DEG, null, null]);
  plots.z.push(t, [p.z, null]);
  if ($('follow').checked) map.centerOn(p.x, p.y);
  map.invalidate();
  schedulePoseBox();
}
function onGt(g) {
  if (S.gtTrail.length && (S.lastGtSeq === undefined || g.seq > S.lastGtSeq + 1)) fillGap(S.gtTrail[S.gtTrail.length - 1][2]);
  S.lastGtSeq = g.seq;
  S.gt = g;
  addToTrail(S.gtTrail, g.utime, g.x, g.y);
  const t = tsec(g.utime);
  plots.rp.push(t, [null, null, g.roll * DEG, g.pitch * DEG]);
  plots.z.push(t, [null, g.z]);
  map.invalidate();
}

async function loadStatic() {
  const [plan, hist] = await Promise.all([
    fetch('/api/plan', { cache: 'no-store' }).then((r) => r.json()),
    fetch('/api/history', { cache: 'no-store' }).then((r) => r.json()),
  ]);
  if (plan) { map.setPlan(plan); planIndex = new PlanIndex(plan); }
  await floors.load().catch((e) => console.warn('floors', e));
  S.trail = []; S.gtTrail = []; t0 = null; S.lastPoseSeq = undefined; S.lastGtSeq = undefined;
  Object.values(plots).forEach((p) => p.clear());
  let sq = 0, n = 0;
  for (const [utime, x, y, z, roll, pitch, , err, floor] of hist.est) {
    addToTrail(S.trail, utime, x, y, floor);
    const t = tsec(utime);
    if (err !== null) { sq += err * err; n++; }
    plots.ate.push(t, [n ? Math.sqrt(sq / n) : null, err]);
    plots.rp.push(t, [roll * DEG, pitch * DEG, null, null]);
    plots.z.push(t, [z, null]);
  }
  for (const [utime, x, y, z, roll, pitch] of hist.gt) {
    addToTrail(S.gtTrail, utime, x, y);
    const t = tsec(utime);
    plots.z.push(t, [null, z]);
    if (roll !== undefined) plots.rp.push(t, [null, null, roll * DEG, pitch * DEG]);  // (older dashboards: x, y, z only)
  }
  for (const [utime, frameHz, poseHz] of hist.rates || []) plots.rate.push(tsec(utime), [frameHz, poseHz]);
  map.invalidate();
}

function setConnected(ok) {
  S.connected = ok;
  $('conn').textContent = ok ? 'live' : 'disconnected';
  $('conn').className = 'badge ' + (ok ? 'ok' : 'bad');
  $('banner').classList.toggle('hidden', ok);
}

function connect() {
  const es = new EventSource('/api/events');
  let everOpen = false;
  es.addEventListener('open', async () => {
    if (S.wasDisconnected) {  // the server may have restarted: trails and plan start again
      S.reconnects++;
      try { await loadStatic(); } catch (e) { console.warn('reload after reconnect failed', e); }
    }
    everOpen = true;
    S.wasDisconnected = false;
    setConnected(true);
  });
  es.addEventListener('error', () => {
    if (everOpen || !S.connected) S.wasDisconnected = true;
    setConnected(false);
  });
  const on = (name, fn) => es.addEventListener(name, (ev) => {
    S.events[name] = (S.events[name] || 0) + 1;
    let msg;
    try { msg = JSON.parse(ev.data); } catch (e) { console.warn('bad event', name, e); return; }
    fn(msg);
  });
  on('pose', onPose);
  on('gt', onGt);
  on('frame_pose', (f) => { S.frame = f; map.invalidate(); schedulePoseBox(); });
  on('features', (f) => { S.features = f; map.invalidate(); });
  on('plan_diff', (d) => { S.planDiff = d; map.invalidate(); });
  on('nodes', (m) => { S.ownNodes = m; if (!S.selected) renderNodes(m); });
  on('robots', (list) => onRobots(list, on));
  on('stats', (s) => {
    S.stats = s;
    const t = S.pose ? tsec(S.pose.utime) : null;
    if (t !== null) plots.rate.push(t, [s.frame_rate_hz, s.pose_rate_hz]);
    const l = S.latencies.slice(-50).sort((a, b) => a - b);
    // How far the pose lags the newest sensor time seen (ground truth or the matcher's frame, both stamped
    // with the scan's time): a localizer that falls behind shows here even when the stamps are not this
    // machine's clock (replay, simulated time) and the latency above is not shown.
    const newest = Math.max(S.gt ? S.gt.utime : 0, S.frame ? S.frame.utime : 0);
    const behind = S.pose && newest ? (newest - S.pose.utime) / 1e6 : null;
    // The optimizer's final poses trail the newest frame by design (up to max_final_delay_s, 1 s by default, plus
    // a frame): "behind" starts at 3 s, well past that, so a healthy run never shows it.
    const stale = behind !== null && behind > 3;
    $('latency').textContent = (l.length ? `latency p50 ${l[l.length >> 1].toFixed(0)} ms · ` : '') +
      (stale ? `pose ${behind.toFixed(1)} s behind the sensor · ` : '') + `${s.clients} viewer(s)`;
    $('latency').classList.toggle('stale', stale);
  });
  on('plan_changed', async () => { try { const plan = await (await fetch('/api/plan')).json(); map.setPlan(plan); planIndex = new PlanIndex(plan); } catch (e) { /* next reconnect */ } });
}

// ---- fleet: the robots this dashboard shows; a selector picks whose nodes and readouts are listed
function onRobots(list, on) {
  S.robots = list;
  for (const r of list) {
    if (r.own || S.fleet[r.name]) continue;
    const f = S.fleet[r.name] = { color: r.color, trail: [], pose: null, nodes: null };
    on(`pose@${r.name}`, (p) => { f.pose = p; addToTrail(f.trail, p.utime, p.x, p.y, p.floor); map.invalidate(); if (S.selected === r.name) schedulePoseBox(); });
    on(`nodes@${r.name}`, (m) => { f.nodes = m; if (S.selected === r.name) renderNodeTable(m); });
    fetch(`/api/history?robot=${encodeURIComponent(r.name)}`, { cache: 'no-store' }).then((x) => x.json())
      .then((h) => { f.trail = mergeTrail(f.trail, h.est.map(trailPoint)); map.invalidate(); })
      .catch(() => {});
  }
  const sel = $('robot');
  sel.classList.toggle('hidden', list.length < 2);
  sel.replaceChildren(...list.map((r) => {
    const o = document.createElement('option');
    o.value = r.own ? '' : r.name;
    o.textContent = (r.name || 'this robot') + (r.own ? ' (own graph)' : '');
    o.style.color = r.color;
    return o;
  }));
  sel.value = S.selected || '';
}
$('robot').addEventListener('change', () => {
  S.selected = $('robot').value || null;
  const f = S.selected ? S.fleet[S.selected] : null;
  $('robot').style.color = f ? f.color : '';
  if (!S.selected) { if (S.ownNodes) renderNodes(S.ownNodes); } else if (f && f.nodes) renderNodeTable(f.nodes);
  else $('nodes').tBodies[0].replaceChildren();
  renderPoseBox();
});

$('fit').addEventListener('click', () => map.fit());
// The map shows the pose's floor, or the floor picked in the selector (same x/y frame: the view stays).
const floors = new FloorView($('floor'), (plan) => { map.setPlan(plan, true); planIndex = new PlanIndex(plan); renderPoseBox(); });
$('showfeat').addEventListener('change', () => map.invalidate());
$('follow').addEventListener('change', () => map.invalidate());
setConnected(false);
$('banner').classList.add('hidden');  // no banner before the first attempt
loadStatic().catch((e) => console.warn('initial load failed', e)).finally(connect);
renderPoseBox();
