// Bird's-eye view of the floor plan (metres, y up) on a canvas with pan (drag) and zoom (wheel).
export class MapView {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.scale = 40;          // pixels per metre
    this.cx = 0; this.cy = 0; // plan point at the canvas centre
    this.plan = null;
    this.layers = [];         // functions (ctx, view) drawn after the plan
    this.dirty = true;
    this.userMoved = false;
    this.resize();
    new ResizeObserver(() => this.resize()).observe(canvas);
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => {
      drag = { x: e.clientX, y: e.clientY, cx: this.cx, cy: this.cy };
      canvas.setPointerCapture(e.pointerId);
      canvas.style.cursor = 'grabbing';
    });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      this.cx = drag.cx - (e.clientX - drag.x) / this.scale;
      this.cy = drag.cy + (e.clientY - drag.y) / this.scale;
      this.userMoved = true;
      this.invalidate();
    });
    const end = () => { drag = null; canvas.style.cursor = 'grab'; };
    canvas.addEventListener('pointerup', end);
    canvas.addEventListener('pointercancel', end);
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      const r = canvas.getBoundingClientRect();
      const [px, py] = this.toPlan(e.clientX - r.left, e.clientY - r.top);
      const f = Math.exp(-e.deltaY * 0.0015);
      this.scale = Math.min(2000, Math.max(0.5, this.scale * f));
      // Keep the point under the cursor fixed.
      const [qx, qy] = this.toPlan(e.clientX - r.left, e.clientY - r.top);
      this.cx += px - qx; this.cy += py - qy;
      this.userMoved = true;
      this.invalidate();
    }, { passive: false });
    canvas.addEventListener('dblclick', () => this.fit());
  }
  resize() {
    const dpr = window.devicePixelRatio || 1;
    const r = this.canvas.getBoundingClientRect();
    this.w = Math.max(1, r.width); this.h = Math.max(1, r.height);
    this.canvas.width = Math.round(this.w * dpr); this.canvas.height = Math.round(this.h * dpr);
    this.dpr = dpr;
    if (!this.userMoved) this.fit(false);
    this.invalidate();
  }
  // keepView: another floor of the same building (same x/y frame): the view stays where it is.
  setPlan(plan, keepView = false) {
    this.plan = plan;
    if (!keepView) { this.userMoved = false; this.fit(false); }
    this.invalidate();
  }
  fit(user = true) {
    const b = this.plan && this.plan.bounds;
    if (!b) return;
    const m = 0.06;
    const sx = this.w / ((b[2] - b[0]) * (1 + 2 * m) || 1), sy = this.h / ((b[3] - b[1]) * (1 + 2 * m) || 1);
    this.scale = Math.max(0.5, Math.min(sx, sy));
    this.cx = (b[0] + b[2]) / 2; this.cy = (b[1] + b[3]) / 2;
    if (user) this.userMoved = false;
    this.invalidate();
  }
  centerOn(x, y) { this.cx = x; this.cy = y; this.invalidate(); }
  toScreen(x, y) { return [this.w / 2 + (x - this.cx) * this.scale, this.h / 2 - (y - this.cy) * this.scale]; }
  toPlan(sx, sy) { return [this.cx + (sx - this.w / 2) / this.scale, this.cy - (sy - this.h / 2) / this.scale]; }
  invalidate() {
    if (this.dirty && this.pending) return;
    this.dirty = true;
    if (!this.pending) { this.pending = true; requestAnimationFrame(() => { this.pending = false; this.draw(); }); }
  }
  draw() {
    this.dirty = false;
    const c = this.ctx;
    c.setTransform(this.dpr, 0, 0, this.dpr, 0, 0);
    c.clearRect(0, 0, this.w, this.h);
    this.drawGrid(c);
    this.drawPlan(c);
    for (const layer of this.layers) layer(c, this);
    this.drawScaleBar(c);
  }
  drawGrid(c) {
    // 1 m grid (coarser when zoomed out).
    let step = 1;
    while (step * this.scale < 25) step *= 5;
    const [x0, y1] = this.toPlan(0, 0), [x1, y0] = this.toPlan(this.w, this.h);
    c.strokeStyle = '#eef0f3'; c.lineWidth = 1;
    c.beginPath();
    for (let x = Math.floor(x0 / step) * step; x <= x1; x += step) { const [sx] = this.toScreen(x, 0); c.moveTo(sx, 0); c.lineTo(sx, this.h); }
    for (let y = Math.floor(y0 / step) * step; y <= y1; y += step) { const [, sy] = this.toScreen(0, y); c.moveTo(0, sy); c.lineTo(this.w, sy); }
    c.stroke();
  }
  drawPlan(c) {
    if (!this.plan) return;
    c.strokeStyle = '#374151'; c.lineWidth = Math.max(1.2, Math.min(3, 0.05 * this.scale));
    c.lineCap = 'round';
    c.beginPath();
    for (const e of this.plan.elements) {
      if (e.type === 'segment') {
        const [ax, ay] = this.toScreen(e.a[0], e.a[1]), [bx, by] = this.toScreen(e.b[0], e.b[1]);
        c.moveTo(ax, ay); c.lineTo(bx, by);
      } else if (e.type === 'circle' || e.type === 'arc') {
        const [sx, sy] = this.toScreen(e.c[0], e.c[1]);
        const a0 = e.type === 'arc' ? e.a0 : 0, a1 = e.type === 'arc' ? e.a1 : 2 * Math.PI;
        // Plan angles are counter-clockwise with y up; the canvas has y down.
        c.moveTo(sx + e.r * this.scale * Math.cos(a0), sy - e.r * this.scale * Math.sin(a0));
        c.arc(sx, sy, e.r * this.scale, -a0, -a1, true);
      }
    }
    c.stroke();
  }
  drawScaleBar(c) {
    const target = 100 / this.scale;
    const p = Math.pow(10, Math.floor(Math.log10(target)));
    const len = [1, 2, 5, 10].map((k) => k * p).find((v) => v >= target * 0.6) || p;
    const px = len * this.scale, x = this.w - px - 14, y = this.h - 14;
    c.strokeStyle = '#111827'; c.lineWidth = 2;
    c.beginPath(); c.moveTo(x, y); c.lineTo(x + px, y); c.moveTo(x, y - 4); c.lineTo(x, y + 4); c.moveTo(x + px, y - 4); c.lineTo(x + px, y + 4); c.stroke();
    c.fillStyle = '#111827'; c.font = '11px "DejaVu Sans", sans-serif'; c.textAlign = 'center';
    c.fillText(`${len >= 1 ? len : len.toFixed(2)} m`, x + px / 2, y - 6);
  }
  // Helpers for layers.
  polyline(c, pts, color, width) {
    if (pts.length < 2) return;
    c.strokeStyle = color; c.lineWidth = width; c.lineJoin = 'round';
    c.beginPath();
    let [x, y] = this.toScreen(pts[0][0], pts[0][1]);
    c.moveTo(x, y);
    for (let i = 1; i < pts.length; i++) { [x, y] = this.toScreen(pts[i][0], pts[i][1]); c.lineTo(x, y); }
    c.stroke();
  }
  arrow(c, x, y, yaw, color, filled, size = 14) {
    const [sx, sy] = this.toScreen(x, y);
    c.save();
    c.translate(sx, sy); c.rotate(-yaw);
    c.beginPath(); c.moveTo(size, 0); c.lineTo(-size * 0.6, size * 0.55); c.lineTo(-size * 0.3, 0); c.lineTo(-size * 0.6, -size * 0.55); c.closePath();
    c.lineWidth = 2; c.strokeStyle = color;
    if (filled) { c.fillStyle = color; c.fill(); } else { c.fillStyle = 'rgba(255,255,255,.6)'; c.fill(); }
    c.stroke();
    c.restore();
  }
}
