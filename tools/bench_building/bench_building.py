#!/usr/bin/env python3
"""fploc bench building: height and attitude under real buildings' ceilings, through the real graph.

For every (plan, scenario): `fploc sim` writes an LCM log (OS-1 scans + IMU) and the ground truth;
`fploc replay` runs graphs/paper.pbtxt on it (segmenter, features, matcher, optimizer in one process,
lock-step); the windowed optimizer's final poses (WO) are scored against the ground truth at each pose's
own time (linear interpolation of the truth, no alignment): horizontal ATE (rmse of the x/y error),
|z error| median and p99, roll/pitch error p99 (the larger of the two per pose), LOST count (the matcher's
LOST transitions, reported as node errors), NEES median of the published (x, y, yaw) covariance
(`nees_median`, 3 if consistent), false OK (`false_ok`: poses with status OK more than 0.3 m off
horizontally), POOR poses (`poor_poses`), and ms per scan per node (thread CPU time).

Scenarios: the `building-*` ones (sim/ceiling_map.h: areas with their own ceiling heights and a sloped
roof, a double-height atrium, lamps/beams/ducts/a drop-ceiling grid, all mixed) and `auto-loop-medium`
with the simulator's default ceiling patches, on every shipped plan (data/plans) unless --plan is given.
Targets (issue 11): z p99 <= 2 cm, roll/pitch p99 <= 0.2 deg, horizontal ATE <= 1 cm, no LOST.

Prints one JSON document on stdout ({"rows": [...], "targets": {...}}); progress on stderr. With --plots DIR
writes z against ground truth over time per row (SVG with axes and legend, and a text-free PNG:
grid lines every 1 cm and 10 s, truth green, estimate red).
"""
import argparse
import bisect
import json
import math
import os
import shutil
import sys
import tempfile

ROOT = os.environ.get("FPLOC_ROOT") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BIN = os.environ.get("FPLOC_BIN") or os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(ROOT, "tools", "pylib"))
import fploc_tools  # noqa: E402
from fploc_tools import log, read_tum, yaw_of  # noqa: E402

SCENARIOS = ["building-areas-medium", "building-atrium-medium", "building-clutter-medium", "building-mixed-medium",
             "auto-loop-medium"]
PIPELINE = ("segmenter", "features", "matcher", "optimizer")
TARGETS = {"z_err_p99_m": 0.02, "rp_err_p99_deg": 0.2, "ate_xy_m": 0.01, "lost": 0}


def run(cmd):
    return fploc_tools.run(cmd, "fploc bench building")


def roll_pitch(q):
    x, y, z, w = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    return roll, pitch


def pct(v, q):
    s = sorted(v)
    return s[min(len(s) - 1, int(q * len(s)))] if s else None


def score(gt, est):
    """Per pose: truth interpolated at the pose's time (roll/pitch from the nearer truth sample)."""
    ts = [g[0] for g in gt]
    t0 = gt[0][0]
    series, exy, ez, erp = [], [], [], []
    for e in est:
        i = bisect.bisect_left(ts, e[0])
        if i <= 0 or i >= len(gt):
            continue
        a, b = gt[i - 1], gt[i]
        f = (e[0] - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 0.0
        p = [a[k] + f * (b[k] - a[k]) for k in (1, 2, 3)]
        r1, p1 = roll_pitch(e[4:8])
        r0, p0 = roll_pitch((a if f < 0.5 else b)[4:8])
        exy.append((e[1] - p[0]) ** 2 + (e[2] - p[1]) ** 2)
        ez.append(abs(e[3] - p[2]))
        erp.append(max(abs(r1 - r0), abs(p1 - p0)))
        series.append((e[0] - t0, e[3], p[2]))
    if not ez:
        return None, series
    return {"poses": len(ez), "ate_xy_m": round(math.sqrt(sum(exy) / len(exy)), 5),
            "z_err_median_m": round(pct(ez, 0.5), 5), "z_err_p99_m": round(pct(ez, 0.99), 5),
            "z_err_max_m": round(max(ez), 5), "rp_err_p99_deg": round(math.degrees(pct(erp, 0.99)), 4),
            "rp_err_max_deg": round(math.degrees(max(erp)), 4)}, series


def plot_z(series, title, path):
    """z estimate and truth against time, SVG (axes in s and m)."""
    W, H, L, R, T, B = 900, 320, 60, 20, 30, 40
    t1 = max(s[0] for s in series) or 1.0
    zs = [s[1] for s in series] + [s[2] for s in series]
    z0, z1 = min(zs), max(zs)
    pad = max(0.01, 0.1 * (z1 - z0))
    z0, z1 = z0 - pad, z1 + pad
    X = lambda t: L + (W - L - R) * t / t1  # noqa: E731
    Y = lambda z: T + (H - T - B) * (z1 - z) / (z1 - z0)  # noqa: E731
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="11">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<text x="{L}" y="18" font-size="13">{title}</text>',
           f'<line x1="{L}" y1="{H - B}" x2="{W - R}" y2="{H - B}" stroke="black"/>',
           f'<line x1="{L}" y1="{T}" x2="{L}" y2="{H - B}" stroke="black"/>']
    for k in range(6):
        t = t1 * k / 5
        z = z0 + (z1 - z0) * k / 5
        out.append(f'<text x="{X(t):.1f}" y="{H - B + 15}" text-anchor="middle">{t:.0f} s</text>')
        out.append(f'<text x="{L - 4}" y="{Y(z) + 4:.1f}" text-anchor="end">{z:.3f}</text>')
        out.append(f'<line x1="{L}" y1="{Y(z):.1f}" x2="{W - R}" y2="{Y(z):.1f}" stroke="#eee"/>')
    for idx, colour, name in ((2, "#2a7", "ground truth z [m]"), (1, "#c22", "estimate z [m] (WO)")):
        pts = " ".join(f"{X(s[0]):.1f},{Y(s[idx]):.1f}" for s in series)
        out.append(f'<polyline fill="none" stroke="{colour}" stroke-width="1.2" points="{pts}"/>')
    out.append(f'<text x="{W - R - 260}" y="18" fill="#2a7">ground truth z</text>')
    out.append(f'<text x="{W - R - 150}" y="18" fill="#c22">estimate z (WO)</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out))


def plot_png(series, path, W=900, H=300):
    """The same plot as a PNG without text (for image viewers): grey grid every 1 cm of z and every 10 s,
    truth green, estimate red. Written with zlib only."""
    import struct
    import zlib
    t1 = max(s[0] for s in series) or 1.0
    zs = [s[1] for s in series] + [s[2] for s in series]
    z0, z1 = min(zs) - 0.005, max(zs) + 0.005
    img = [bytearray(b"\xff" * (3 * W)) for _ in range(H)]

    def px(x, y, c):
        if 0 <= x < W and 0 <= y < H:
            img[y][3 * x:3 * x + 3] = bytes(c)
    X = lambda t: int((W - 1) * t / t1)  # noqa: E731
    Y = lambda z: int((H - 1) * (z1 - z) / (z1 - z0))  # noqa: E731
    z = math.ceil(z0 * 100) / 100
    while z < z1:
        for x in range(W):
            px(x, Y(z), (225, 225, 225))
        z += 0.01
    for t in range(0, int(t1) + 1, 10):
        for y in range(H):
            px(X(t), y, (225, 225, 225))

    def line(a, b, c):
        (x0, y0), (x1, y1) = a, b
        n = max(abs(x1 - x0), abs(y1 - y0), 1)
        for i in range(n + 1):
            px(x0 + (x1 - x0) * i // n, y0 + (y1 - y0) * i // n, c)
    for idx, c in ((2, (30, 160, 80)), (1, (200, 30, 30))):
        pts = [(X(s[0]), Y(s[idx])) for s in series]
        for a, b in zip(pts, pts[1:]):
            line(a, b, c)
    raw = b"".join(b"\x00" + bytes(r) for r in img)
    chunk = lambda tag, data: struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))  # noqa: E731
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def bench(a, work, plan, layers, scenario):
    name = f"{os.path.splitext(os.path.basename(plan))[0]}:{scenario}"
    d = os.path.join(work, name.replace(":", "-"))
    os.makedirs(d, exist_ok=True)
    logf, gt_path = os.path.join(d, "log.lcm"), os.path.join(d, "gt.tum")
    cmd = [os.path.join(BIN, "fploc-sim"), "--scenario", scenario, "--seed", str(a.seed), "--plan", plan,
           "--out", logf, "--gt", gt_path]
    for layer in layers:
        cmd += ["--layers", layer]
    if a.duration:
        cmd += ["--duration", str(a.duration)]
    log(f"[{name}] simulating ...")
    _, err = run(cmd)
    info = [l.strip() for l in err.splitlines() if "ceilings" in l or "clutter" in l]
    gt = read_tum(gt_path)
    x0, y0, yaw0 = gt[0][1], gt[0][2], yaw_of(gt[0])
    wo = os.path.join(d, "wo.tum")
    unc = os.path.join(d, "wo.unc")
    sets = [f"wo_logger.uncertainty_file={unc}", f"matcher.plan.file={plan}", f"optimizer.plan.file={plan}", f"matcher.initial_pose.x={x0!r}",
            f"matcher.initial_pose.y={y0!r}", f"matcher.initial_pose.yaw={yaw0!r}", "matcher.initial_search_m=0.3",
            f"wo_logger.file={wo}", f"sfr_logger.file={os.path.join(d, 'sfr.tum')}",
            f"odom_logger.file={os.path.join(d, 'odom.tum')}", f"odom_map_logger.file={os.path.join(d, 'odom_map.tum')}",
            f"odometry.initial_pose.x={x0!r}", f"odometry.initial_pose.y={y0!r}", f"odometry.initial_pose.yaw={yaw0!r}",
            f"odometry_map.initial_pose.x={x0!r}", f"odometry_map.initial_pose.y={y0!r}",
            f"odometry_map.initial_pose.yaw={yaw0!r}"]
    for n in ("matcher", "optimizer"):
        for layer in layers:
            sets.append(f"{n}.plan.layers={layer}")
    cmd = [os.path.join(BIN, "fploc-replay"), "--graph", a.graph, "--log", logf, "--json"]
    for s in sets:
        cmd += ["--set", s]
    log(f"[{name}] replaying {len(gt)} scans ...")
    rep = json.loads(run(cmd)[0].strip().splitlines()[-1])
    os.remove(logf)
    nodes = {n["name"]: n for n in rep["nodes"]}
    scans = nodes.get("features", {}).get("messages", 1) or 1
    ms = {n: round(nodes[n].get("cpu_ms", nodes[n]["total_ms"]) / scans, 3) for n in PIPELINE if n in nodes}
    row = {"plan": os.path.relpath(plan, ROOT), "scenario": scenario, "scans": scans, "sim": info,
           "lost": nodes.get("matcher", {}).get("errors", 0), "ms_per_scan": ms}
    est = read_tum(wo) if os.path.exists(wo) else []
    m, series = score(gt, est)
    row.update(m or {"poses": 0})
    # Honest uncertainty (issue 12): NEES of the published covariance and false OK (status OK, > 0.3 m off).
    ev = fploc_tools.fploc_eval(BIN, gt_path, wo, "fploc bench building", uncertainty=unc) if est else None
    if ev and "nees_median" in ev:
        row["nees_median"] = ev["nees_median"]
        row["false_ok"] = ev["false_ok_poses"]
        row["poor_poses"] = (fploc_tools.status_counts(unc) or [0, 0, 0])[1]
    if m:
        row["meets_targets"] = (m["z_err_p99_m"] <= TARGETS["z_err_p99_m"] and m["rp_err_p99_deg"] <= TARGETS["rp_err_p99_deg"]
                                and m["ate_xy_m"] <= TARGETS["ate_xy_m"] and row["lost"] == 0)
    if a.plots and series:
        path = os.path.join(a.plots, name.replace(":", "-") + "-z.svg")
        plot_z(series, f"{name}: z p99 {100 * m['z_err_p99_m']:.2f} cm, rp p99 {m['rp_err_p99_deg']:.3f} deg", path)
        row["plot"] = path
        plot_png(series, path[:-4] + ".png")
        row["plot_png"] = path[:-4] + ".png"
    log(f"[{name}] ATE xy {100 * row.get('ate_xy_m', float('nan')):.2f} cm, z med/p99 "
        f"{100 * row.get('z_err_median_m', float('nan')):.2f}/{100 * row.get('z_err_p99_m', float('nan')):.2f} cm, "
        f"rp p99 {row.get('rp_err_p99_deg', float('nan')):.3f} deg, LOST {row['lost']}, "
        f"NEES {row.get('nees_median')}, false OK {row.get('false_ok')}, ms/scan {ms}")
    return row


def main():
    ap = argparse.ArgumentParser(prog="fploc bench building", description=__doc__.splitlines()[0])
    ap.add_argument("--plan", action="append", help="floor plan(s) (default: data/plans/room.json and corridor.json)")
    ap.add_argument("--layers", help="comma-separated plan layer globs (with --plan)")
    ap.add_argument("--scenario", action="append", help=f"scenario(s), comma-separated or repeated (default: {', '.join(SCENARIOS)})")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=0, help="simulate only this many seconds (tests)")
    ap.add_argument("--graph", default=os.path.join(ROOT, "graphs", "paper.pbtxt"))
    ap.add_argument("--plots", help="write z-against-ground-truth SVGs into this folder")
    ap.add_argument("--keep", help="keep the work folder here")
    ap.add_argument("--json", action="store_true", help="(JSON is always printed on stdout)")
    a = ap.parse_args()
    plans = [os.path.abspath(p) for p in (a.plan or [os.path.join(ROOT, "data", "plans", "room.json"),
                                                     os.path.join(ROOT, "data", "plans", "corridor.json")])]
    for p in plans:
        if not os.path.exists(p):
            ap.error(f"--plan {p}: no such file")
    layers = [l for l in (a.layers or "").split(",") if l]
    a.graph = os.path.abspath(a.graph)
    if a.plots:
        os.makedirs(a.plots, exist_ok=True)
    work = a.keep or tempfile.mkdtemp(prefix="fploc-bench-building-", dir=os.environ.get("TMPDIR", "/tmp"))
    os.makedirs(work, exist_ok=True)
    rows = []
    try:
        for p in plans:
            # --scenario A,B and --scenario A --scenario B mean the same (as --layers everywhere).
            for s in [x for arg in (a.scenario or SCENARIOS) for x in arg.split(",") if x]:
                rows.append(bench(a, work, p, layers, s))
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    print(json.dumps({"rows": rows, "targets": TARGETS, "seed": a.seed, "graph": os.path.relpath(a.graph, ROOT),
                      "all_meet_targets": all(r.get("meets_targets") for r in rows)}, indent=1))


if __name__ == "__main__":
    main()
