#!/usr/bin/env python3
"""Error against the published uncertainty over time (issue 12, honest uncertainty).

    uncertainty_plot.py --gt GT.tum --est EST.tum --uncertainty EST.unc --out plot.svg [--title T] [--t0 S --t1 S]

EST.unc is fploc-pose-logger's uncertainty_file (t status xx xy xyaw yy yyaw yawyaw). Per pose (ground truth
at the same time stamp, nearest within 5 ms): the horizontal error |e| (black) and 3 sigma of the published
covariance along the error's direction (blue) and along the weakest horizontal direction (light blue); under
the axes the status band (OK green, POOR amber, LOST red). A consistent covariance keeps the black curve under
the blue one nearly everywhere; "POOR before the error grows" means amber starts before the black curve rises.
Prints a one-line summary (poses, false OK, first POOR, first error > 0.3 m) on stdout.
"""
import argparse
import bisect
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "pylib"))
from fploc_tools import read_tum  # noqa: E402


def read_unc(path):
    out = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            v = line.split()
            if not v or v[0].startswith("#"):
                continue
            if len(v) != 8:
                raise SystemExit(f"{path}:{n}: expected 't status xx xy xyaw yy yyaw yawyaw'")
            out.append((float(v[0]), int(v[1]), [float(x) for x in v[2:]]))
    return out


def series(gt, est, unc, t0=None, t1=None):
    gts = [r[0] for r in gt]
    ut = {round(u[0], 4): u for u in unc}
    rows = []
    for e in est:
        t = e[0]
        if (t0 is not None and t < t0) or (t1 is not None and t > t1):
            continue
        i = bisect.bisect_left(gts, t)
        c = [j for j in (i - 1, i) if 0 <= j < len(gts)]
        if not c:
            continue
        j = min(c, key=lambda k: abs(gts[k] - t))
        u = ut.get(round(t, 4))
        if abs(gts[j] - t) > 0.005 or u is None:
            continue
        ex, ey = e[1] - gt[j][1], e[2] - gt[j][2]
        xx, xy, _, yy, _, _ = u[2]
        err = math.hypot(ex, ey)
        # Variance along the error direction and the largest one (eigenvalue of the 2x2 block).
        if err > 0:
            dx, dy = ex / err, ey / err
            along = xx * dx * dx + 2 * xy * dx * dy + yy * dy * dy
        else:
            along = max(xx, yy)
        tr, det = xx + yy, xx * yy - xy * xy
        big = tr / 2 + math.sqrt(max(0.0, tr * tr / 4 - det))
        rows.append((t, err, 3 * math.sqrt(max(0.0, along)), 3 * math.sqrt(max(0.0, big)), u[1]))
    return rows


def svg(rows, title, path, W=1000, H=420, ymax=None):
    L, R, T, B = 60, 20, 30, 70
    ta, tb = rows[0][0], rows[-1][0]
    ymax = ymax or max(0.3, min(5.0, 1.2 * max(r[1] for r in rows)))
    X = lambda t: L + (W - L - R) * (t - ta) / max(tb - ta, 1e-9)  # noqa: E731
    Y = lambda v: T + (H - T - B) * (1 - min(v, ymax) / ymax)  # noqa: E731
    o = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
         f'<rect width="{W}" height="{H}" fill="white"/>', f'<text x="{L}" y="18">{title}</text>']
    step = 0.1 if ymax <= 1 else (0.5 if ymax <= 3 else 1.0)
    v = 0.0
    while v <= ymax + 1e-9:
        o.append(f'<line x1="{L}" x2="{W - R}" y1="{Y(v):.1f}" y2="{Y(v):.1f}" stroke="#ddd"/>')
        o.append(f'<text x="{L - 6}" y="{Y(v) + 4:.1f}" text-anchor="end">{v:.1f}</text>')
        v += step
    span = tb - ta
    ts = 10 if span <= 120 else (30 if span <= 400 else 60)
    t = math.ceil(ta / ts) * ts
    while t <= tb:
        o.append(f'<line x1="{X(t):.1f}" x2="{X(t):.1f}" y1="{T}" y2="{H - B}" stroke="#eee"/>')
        o.append(f'<text x="{X(t):.1f}" y="{H - B + 14}" text-anchor="middle">{t - rows[0][0] + 0:.0f}</text>')
        t += ts
    o.append(f'<line x1="{L}" x2="{W - R}" y1="{Y(0.3):.1f}" y2="{Y(0.3):.1f}" stroke="#c00" stroke-dasharray="4 3"/>')
    for idx, col, w in ((3, "#9cf", 1.2), (2, "#15c", 1.2), (1, "#000", 1.4)):
        pts = " ".join(f"{X(r[0]):.1f},{Y(r[idx]):.1f}" for r in rows)
        o.append(f'<polyline fill="none" stroke="{col}" stroke-width="{w}" points="{pts}"/>')
    cols = {0: "#3a3", 1: "#e90", 2: "#c00"}
    for a, b in zip(rows, rows[1:]):
        o.append(f'<rect x="{X(a[0]):.1f}" y="{H - B + 22}" width="{max(0.5, X(b[0]) - X(a[0])):.2f}" height="12" '
                 f'fill="{cols.get(a[4], "#888")}"/>')
    o.append(f'<text x="{L}" y="{H - 10}">time [s]; black: horizontal error [m]; blue: 3 sigma along the error; light blue: '
             f'3 sigma along the weakest direction; red dashed: 0.3 m; band: status OK / POOR / LOST</text>')
    o.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(o) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gt", required=True)
    ap.add_argument("--est", required=True)
    ap.add_argument("--uncertainty", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--title", default="")
    ap.add_argument("--t0", type=float)
    ap.add_argument("--t1", type=float)
    ap.add_argument("--ymax", type=float)
    a = ap.parse_args()
    rows = series(read_tum(a.gt), read_tum(a.est), read_unc(a.uncertainty), a.t0, a.t1)
    if not rows:
        raise SystemExit(f"{a.est}: no pose with both a ground truth and an uncertainty record")
    svg(rows, a.title, a.out, ymax=a.ymax)
    false_ok = sum(1 for r in rows if r[4] == 0 and r[1] > 0.3)
    outside = sum(1 for r in rows if r[1] > r[2])
    first_poor = next((r[0] for r in rows if r[4] == 1), None)
    first_big = next((r[0] for r in rows if r[1] > 0.3), None)
    print(f"{len(rows)} poses, false OK {false_ok}, error outside 3 sigma {outside} ({100 * outside / len(rows):.1f} %), "
          f"POOR {sum(1 for r in rows if r[4] == 1)}, first POOR at t={first_poor}, first error > 0.3 m at t={first_big}, "
          f"max error {max(r[1] for r in rows):.3f} m")


if __name__ == "__main__":
    main()
