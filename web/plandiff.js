// Map layer: where the building no longer matches the plan (stream "plan_diff" from fploc-plan-diff).
// Missing plan elements dashed red where the plan has them, moved ones solid amber where they were seen
// (with the offset in cm), new structure solid green, low structure (seen only below the diff's furniture height:
// not a wall) thin dotted cyan with its top height. Unknown kinds ('?') are not drawn.
// Circles (pillars): x0,y0 centre, x1 radius.
const COL = { missing: '#dc2626', moved: '#d97706', new: '#16a34a', low: '#0891b2' };

export function planDiffLayer(S) {
  return (c, v) => {
    const d = S.planDiff;
    if (!d || !d.items) return;
    c.save();
    c.font = '11px sans-serif';
    for (const it of d.items) {
      if (!(it.kind in COL)) continue;
      c.strokeStyle = COL[it.kind];
      c.lineWidth = it.kind === 'low' ? 2 : 4;
      c.setLineDash(it.kind === 'missing' ? [8, 5] : it.kind === 'low' ? [2, 4] : []);
      c.beginPath();
      const circle = !!it.circle;
      let lx, ly;
      if (circle) {
        const [sx, sy] = v.toScreen(it.x0, it.y0);
        c.arc(sx, sy, Math.max(3, it.x1 * v.scale), 0, 2 * Math.PI);
        [lx, ly] = [sx, sy];
      } else {
        const [ax, ay] = v.toScreen(it.x0, it.y0), [bx, by] = v.toScreen(it.x1, it.y1);
        c.moveTo(ax, ay); c.lineTo(bx, by);
        [lx, ly] = [(ax + bx) / 2, (ay + by) / 2];
      }
      c.stroke();
      c.setLineDash([]);
      c.fillStyle = COL[it.kind] || '#6b7280';
      const label = it.kind === 'moved' ? `moved ${(100 * it.offset_m).toFixed(0)} cm`
        : it.kind === 'low' ? `low ${Number(it.offset_m).toFixed(1)} m` : it.kind;
      c.fillText(label, lx + 6, ly - 6);
    }
    c.restore();
  };
}
