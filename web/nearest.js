// Distance from a point to the nearest floor-plan element through a uniform grid (built once per plan),
// to show which projected features lie on the plan ("matched") and which do not (clutter, errors).
export class PlanIndex {
  constructor(plan, cell = 0.5, reach = 0.3) {
    this.cell = cell; this.reach = reach; this.cells = new Map();
    const b = plan && plan.bounds;
    if (!b) return;
    for (const e of plan.elements) {
      let x0, y0, x1, y1;
      if (e.type === 'segment') { x0 = Math.min(e.a[0], e.b[0]); x1 = Math.max(e.a[0], e.b[0]); y0 = Math.min(e.a[1], e.b[1]); y1 = Math.max(e.a[1], e.b[1]); }
      else { x0 = e.c[0] - e.r; x1 = e.c[0] + e.r; y0 = e.c[1] - e.r; y1 = e.c[1] + e.r; }
      // Every cell within `reach` of the element's box (so a look-up needs only its own cell).
      const cx0 = Math.floor((x0 - reach) / cell), cx1 = Math.floor((x1 + reach) / cell);
      const cy0 = Math.floor((y0 - reach) / cell), cy1 = Math.floor((y1 + reach) / cell);
      if ((cx1 - cx0 + 1) * (cy1 - cy0 + 1) > 1e5) continue;  // absurdly large element: skip
      for (let i = cx0; i <= cx1; i++) for (let j = cy0; j <= cy1; j++) {
        const k = i * 1e6 + j;
        let l = this.cells.get(k);
        if (!l) this.cells.set(k, l = []);
        l.push(e);
      }
    }
  }
  // Distance to the nearest element, or Infinity when none is within `reach`.
  distance(x, y) {
    const l = this.cells.get(Math.floor(x / this.cell) * 1e6 + Math.floor(y / this.cell));
    if (!l) return Infinity;
    let best = Infinity;
    for (const e of l) best = Math.min(best, elementDistance(e, x, y));
    return best;
  }
}

function elementDistance(e, x, y) {
  if (e.type === 'segment') {
    const dx = e.b[0] - e.a[0], dy = e.b[1] - e.a[1], L = dx * dx + dy * dy;
    const t = L > 0 ? Math.max(0, Math.min(1, ((x - e.a[0]) * dx + (y - e.a[1]) * dy) / L)) : 0;
    return Math.hypot(x - e.a[0] - t * dx, y - e.a[1] - t * dy);
  }
  const px = x - e.c[0], py = y - e.c[1], d = Math.hypot(px, py);
  if (e.type === 'circle') return Math.abs(d - e.r);
  // Arc: counter-clockwise from a0 to a1.
  let a = Math.atan2(py, px);
  while (a < e.a0) a += 2 * Math.PI;
  if (a <= e.a1) return Math.abs(d - e.r);
  const end = (t) => Math.hypot(x - e.c[0] - e.r * Math.cos(t), y - e.c[1] - e.r * Math.sin(t));
  return Math.min(end(e.a0), end(e.a1));
}
