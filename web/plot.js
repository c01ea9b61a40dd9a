// Small live line plot over a sliding time window (seconds); y range follows the data (from 0 with `zero` when
// the data are >= 0).
export class Plot {
  constructor(canvas, series, { window = 120, minSpan = 0, digits = 2, zero = false } = {}) {
    this.canvas = canvas; this.series = series; this.window = window; this.minSpan = minSpan;
    this.digits = digits; this.zero = zero;
    this.data = series.map(() => []);
    this.pending = false;
    new ResizeObserver(() => this.invalidate()).observe(canvas);
  }
  push(t, values) {
    values.forEach((v, i) => {
      if (v === null || v === undefined || !Number.isFinite(v)) return;
      const d = this.data[i];
      if (d.length && t < d[d.length - 1][0]) return;          // keep time sorted
      if (d.length && t === d[d.length - 1][0]) d[d.length - 1][1] = v; else d.push([t, v]);
      while (d.length > 4000 || (d.length && d[0][0] < t - this.window * 1.5)) d.shift();
    });
    this.invalidate();
  }
  clear() { this.data = this.series.map(() => []); this.invalidate(); }
  invalidate() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => { this.pending = false; this.draw(); });
  }
  draw() {
    const cv = this.canvas, dpr = window.devicePixelRatio || 1, r = cv.getBoundingClientRect();
    cv.width = Math.round(r.width * dpr); cv.height = Math.round(r.height * dpr);
    const c = cv.getContext('2d'), w = r.width, h = r.height;
    c.setTransform(dpr, 0, 0, dpr, 0, 0);
    c.clearRect(0, 0, w, h);
    let tmax = -Infinity;
    for (const d of this.data) if (d.length) tmax = Math.max(tmax, d[d.length - 1][0]);
    c.font = '10px "DejaVu Sans", sans-serif';
    if (!Number.isFinite(tmax)) { c.fillStyle = '#9ca3af'; c.fillText('no data', 6, h / 2 + 3); return; }
    // The window starts at the first sample until the data spans the whole window.
    let first = Infinity;
    for (const d of this.data) if (d.length) first = Math.min(first, d[0][0]);
    const span = Math.max(5, Math.min(this.window, tmax - first));
    const tmin = tmax - span;
    let lo = Infinity, hi = -Infinity;
    for (const d of this.data) for (const [t, v] of d) if (t >= tmin) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    // zero: the axis includes 0; a quantity that cannot be negative (an error, a rate: all data >= 0) starts at
    // exactly 0, with the minimum span and the margin added above only (no axis from -0.010 or -1.2).
    if (this.zero) lo = Math.min(lo, 0);
    const fromZero = this.zero && lo === 0;
    if (hi - lo < this.minSpan) {
      if (fromZero) hi = this.minSpan;
      else { const m = (hi + lo) / 2; lo = m - this.minSpan / 2; hi = m + this.minSpan / 2; }
    }
    if (hi === lo) { hi += 1e-3; if (!fromZero) lo -= 1e-3; }
    const pad = (hi - lo) * 0.08; if (!fromZero) lo -= pad; hi += pad;
    this.axis = [lo, hi];  // (tests read the drawn range)
    const L = 44, R = 4, T = 15, B = 4;  // legend above the plot area
    const X = (t) => L + (t - tmin) / span * (w - L - R), Y = (v) => T + (hi - v) / (hi - lo) * (h - T - B);
    c.strokeStyle = '#e5e7eb'; c.lineWidth = 1; c.beginPath(); c.moveTo(L, T); c.lineTo(L, h - B); c.lineTo(w - R, h - B); c.stroke();
    c.fillStyle = '#6b7280'; c.textAlign = 'right';
    c.fillText(hi.toFixed(this.digits), L - 3, T + 4); c.fillText(lo.toFixed(this.digits), L - 3, h - B - 1);
    this.series.forEach((s, i) => {
      const d = this.data[i];
      c.strokeStyle = s.color; c.lineWidth = 1.5; c.setLineDash(s.dash || []);
      c.beginPath();
      let started = false;
      for (const [t, v] of d) { if (t < tmin) continue; if (!started) { c.moveTo(X(t), Y(v)); started = true; } else c.lineTo(X(t), Y(v)); }
      c.stroke(); c.setLineDash([]);
    });
    c.textAlign = 'left';
    let x = L + 6;
    this.series.forEach((s, i) => {
      const d = this.data[i];
      // A series with `at: k` shows its value at the time of series k's latest sample (interpolated), so
      // the ground truth's number compares with the estimate's, not with a newer instant.
      const ref = s.at !== undefined ? this.data[s.at] : null;
      const v = ref ? (ref.length ? valueAt(d, ref[ref.length - 1][0]) : null) : (d.length ? d[d.length - 1][1] : null);
      const last = v === null ? '–' : v.toFixed(this.digits);
      c.fillStyle = s.color; const txt = `${s.label} ${last}`; c.fillText(txt, x, 10); x += c.measureText(txt).width + 10;
    });
  }
}

// Linear interpolation of samples [t, v] (sorted by t) at time t; null outside them.
function valueAt(d, t) {
  if (!d.length || t < d[0][0] || t > d[d.length - 1][0]) return null;
  let lo = 0, hi = d.length - 1;
  while (hi - lo > 1) { const m = (lo + hi) >> 1; if (d[m][0] <= t) lo = m; else hi = m; }
  const [t0, v0] = d[lo], [t1, v1] = d[hi];
  return t1 > t0 ? v0 + (v1 - v0) * (t - t0) / (t1 - t0) : v0;
}
