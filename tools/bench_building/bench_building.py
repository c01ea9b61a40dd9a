#!/usr/bin/python3
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
roof, a double-height atrium, lamps/beams/ducts/a drop-ceiling grid, all mixed; the segmenter gets the floor's
ceilings as a building file with --building-heights, `fploc sim --ceilings-building`) and `auto-loop-medium`
with the simulator's default ceiling patches, on every shipped plan (data/plans) unless --plan is given;
and the journeys through the demo building (data/buildings/demo-building.pbtxt: building-twofloor, -ramp,
-thresholds; ramp, lift, door thresholds). A --plan may be a building (.pbtxt): the localizer gets the
building (every floor), the simulator's ground truth is absolute (z = floor elevation + height above it)
and its floor per scan (gt.floors.csv) scores the floor rows (with --building-heights the segmenter gets the building too: its floors'
ceiling areas, the floor from the pose feedback); the pose's floor comes from
pose_t.floor_index (pose logger `floor_file`); its z is absolute too (pose_t convention: the floor's
elevation + the height above it) and is scored as it is.
Targets (issue 11): z p99 <= 2 cm, roll/pitch p99 <= 0.2 deg, horizontal ATE <= 1 cm, no LOST; floor
changes recognised within 2 s, no pose on the wrong floor 3 s after arriving, ATE over the 10 s after a
lift ride <= 5 cm.

Prints one JSON document on stdout ({"rows": [...], "targets": {...}}); progress on stderr. With --plots DIR
writes z against ground truth over time per row (SVG with axes and legend, and the same as a PNG drawn
by matplotlib: truth green, estimate red).
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
import lcm_log  # noqa: E402
from fploc_tools import fmt_ms, fmt_num, log, pct, read_tum, roll_pitch, yaw_of  # noqa: E402

SCENARIOS = ["building-areas-medium", "building-atrium-medium", "building-clutter-medium", "building-mixed-medium",
             "auto-loop-medium"]
DEMO_BUILDING = os.path.join(ROOT, "data", "buildings", "demo-building.pbtxt")
BUILDING_SCENARIOS = ["building-twofloor-medium", "building-ramp-medium", "building-thresholds-medium"]
PIPELINE = ("segmenter", "features", "matcher", "optimizer")
TARGETS = {"z_err_p99_m": 0.02, "rp_err_p99_deg": 0.2, "ate_xy_m": 0.01, "lost": 0,
           "floor_recognised_s": 2.0, "wrong_floor_after_3s": 0, "ate_after_lift_m": 0.05}


def is_building(path):
    return path.endswith(".pbtxt") or path.endswith(".ifc")


def read_gt_floors(path):
    """fploc sim's per-scan ground-truth floor: CSV t,floor_index,floor,state."""
    out = []
    with open(path) as f:
        next(f)
        for line in f:
            t, idx, name, state = line.strip().split(",")
            out.append((float(t), int(idx), name, state))
    return out


def read_pose_floors(path):
    """The pose logger's floor_file: "t floor_index floor" per pose."""
    out = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            t, idx, _ = line.split(None, 2)
            out[round(float(t), 6)] = int(idx)
    return out


def floor_at(gtf, t):
    i = bisect.bisect_right([g[0] for g in gtf], t) - 1
    return gtf[max(0, i)][1]


def score_floors(gt, est, gtf, pose_floor, changes, t0_abs):
    """Floor rows: poses on the wrong floor (all, and those more than 3 s from every floor change), time from each
    floor change to the first pose on the new floor, ATE (horizontal and 3D) over the 10 s after each lift
    ride (from the car's arrival)."""
    ts_f = [g[0] for g in gtf]
    wrong, wrong_late, known = 0, 0, 0
    for e in est:
        f = pose_floor.get(round(e[0], 6), -1)
        if f < 0:
            continue
        known += 1
        i = max(0, bisect.bisect_right(ts_f, e[0]) - 1)
        if f != gtf[i][1]:
            wrong += 1
            # Beyond 3 s of every floor change (the moment of a ramp's change is a convention: its middle).
            if all(abs(e[0] - c["t"]) > 3.0 for c in changes):
                wrong_late += 1
    if known == 0:
        return {"floor_scored": False,
                "floor_note": "the poses carry no floor (pose_t.floor_index -1 or no floor file): floor rows not scored"}
    rec = []
    for c in changes:
        first = next((e[0] for e in est if e[0] >= c["t"] and pose_floor.get(round(e[0], 6), -1) == c["to_index"]), None)
        rec.append({"t": round(c["t"] - t0_abs, 2), "from": c["from"], "to": c["to"], "how": c["how"],
                    "recognised_after_s": None if first is None else round(first - c["t"], 2)})
    truth = fploc_tools.Truth(gt)
    lifts = []
    for c in changes:
        if not c["how"].startswith("lift"):
            continue
        exy, e3 = [], []
        for e in est:
            if not (c["t"] <= e[0] <= c["t"] + 10.0):
                continue
            at = truth.interpolated(e[0])
            if at is None:
                continue
            p = at[0]
            dxy = (e[1] - p[0]) ** 2 + (e[2] - p[1]) ** 2
            exy.append(dxy)
            e3.append(dxy + (e[3] - p[2]) ** 2)
        lifts.append({"t": round(c["t"] - t0_abs, 2), "poses": len(exy),
                      "ate_xy_m": round(math.sqrt(sum(exy) / len(exy)), 5) if exy else None,
                      "ate_3d_m": round(math.sqrt(sum(e3) / len(e3)), 5) if e3 else None})
    recs = [r["recognised_after_s"] for r in rec]
    return {"floor_scored": True, "poses_with_floor": known, "wrong_floor_poses": wrong,
            "wrong_floor_after_3s": wrong_late, "floor_changes": rec,
            "floor_recognised_max_s": (None if not recs or any(r is None for r in recs) else max(recs)),
            "floor_changes_missed": sum(1 for r in recs if r is None),
            "lift_rides": lifts,
            "ate_after_lift_m": max([l["ate_xy_m"] for l in lifts if l["ate_xy_m"] is not None], default=None)}


def run(cmd):
    return fploc_tools.run(cmd, "fploc bench building")


def score(gt, est):
    """Per pose: truth interpolated at the pose's time (roll/pitch from the nearer truth sample). Buildings:
    `est` z absolute as the truth (pose_t: the floor's elevation + the height above it)."""
    truth = fploc_tools.Truth(gt)
    t0 = gt[0][0]
    series, exy, ez, erp = [], [], [], []
    for e in est:
        at = truth.interpolated(e[0])
        if at is None:
            continue
        p, nearer = at
        r1, p1 = roll_pitch(e[4:8])
        r0, p0 = roll_pitch(nearer[4:8])
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


def plot_z(series, title, path, marks=()):
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
    for t in marks:
        out.append(f'<line x1="{X(t):.1f}" y1="{T}" x2="{X(t):.1f}" y2="{H - B}" stroke="#36d" stroke-dasharray="4 3"/>')
    out.append(f'<text x="{W - R - 260}" y="18" fill="#2a7">ground truth z</text>')
    out.append(f'<text x="{W - R - 150}" y="18" fill="#c22">estimate z (WO)</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out))


def plot_png(series, path, title, marks=()):
    """The same plot as a PNG (for image viewers), drawn by matplotlib (Debian's python3-matplotlib):
    truth green, estimate red, floor changes (`marks`, s) dashed blue."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(10, 3.3))
    ax.plot([s[0] for s in series], [s[2] for s in series], color="tab:green", linewidth=0.9, label="ground truth z")
    ax.plot([s[0] for s in series], [s[1] for s in series], color="tab:red", linewidth=0.9, label="estimate z (WO)")
    for t in marks:
        ax.axvline(t, color="tab:blue", linestyle="--", linewidth=0.8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("z [m]")
    ax.set_title(title, fontsize="medium")
    ax.grid(True, color="0.9")
    ax.legend(loc="upper right", fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def bench(a, work, plan, layers, scenario):
    name = f"{os.path.splitext(os.path.basename(plan))[0]}:{scenario}"
    d = os.path.join(work, name.replace(":", "-"))
    os.makedirs(d, exist_ok=True)
    logf, gt_path = os.path.join(d, "log.lcm"), os.path.join(d, "gt.tum")
    building = is_building(plan)
    cmd = [os.path.join(BIN, "fploc-sim"), "--scenario", scenario, "--seed", str(a.seed), "--plan", plan,
           "--out", logf, "--gt", gt_path, "--json"]
    for layer in layers:
        cmd += ["--layers", layer]
    if a.duration:
        cmd += ["--duration", str(a.duration)]
    if building and a.floor:
        cmd += ["--floor", a.floor]
        name += f"@{a.floor}"
        d = os.path.join(work, name.replace(":", "-"))
        os.makedirs(d, exist_ok=True)
        logf, gt_path = os.path.join(d, "log.lcm"), os.path.join(d, "gt.tum")
        cmd[cmd.index("--out") + 1], cmd[cmd.index("--gt") + 1] = logf, gt_path
    seg_building = None
    if a.building_heights and scenario.startswith("building-") and not building:
        # The segmenter gets the simulated floor's ceilings as a building file (its areas' heights).
        seg_building = os.path.join(d, "ceilings.pbtxt")
        cmd += ["--ceilings-building", seg_building]
    log(f"[{name}] simulating ...")
    out, err = run(cmd)
    simj = json.loads(out.strip().splitlines()[-1])
    info = [l.strip() for l in err.splitlines() if "ceilings" in l or "clutter" in l or "floor" in l]
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
    if building:
        start = simj.get("start_floor", "")
        sets += [f"matcher.plan.floor={start}", f"optimizer.plan.floor={start}",
                 f"wo_logger.floor_file={os.path.join(d, 'wo.floors')}"]
        if a.building_heights:
            seg_building = plan
    if seg_building:
        sets.append(f"segmenter.building.file={seg_building}")
        if building:
            sets.append(f"segmenter.building.floor={simj.get('start_floor', '')}")
    replay_log = logf
    if a.imu_late_ms:
        # The IMU later than the scans, as live on a busy machine (docs/notes/height.md, "Eleventh round").
        replay_log = os.path.join(d, f"log-imu-late-{a.imu_late_ms:g}ms.lcm")
        lcm_log.delay_channel(logf, replay_log, "OS1_IMU", int(round(a.imu_late_ms * 1000)))
    log(f"[{name}] replaying {len(gt)} scans{f' with the IMU {a.imu_late_ms:g} ms late' if a.imu_late_ms else ''} ...")
    nodes, scans, ms = fploc_tools.replay(BIN, a.graph, replay_log, sets, PIPELINE, "fploc bench building")
    if replay_log != logf:
        os.remove(replay_log)
    if not a.keep:
        os.remove(logf)  # --keep keeps the simulated log too (replay it with other options)
    row = {"plan": os.path.relpath(plan, ROOT), "scenario": scenario, "scans": scans, "sim": info,
           "segmenter_building": seg_building is not None,
           "lost": nodes.get("matcher", {}).get("errors", 0), "ms_per_scan": ms}
    if a.imu_late_ms:
        row["imu_late_ms"] = a.imu_late_ms
        row["segmenter_detail"] = nodes.get("segmenter", {}).get("detail", "")
    est = read_tum(wo) if os.path.exists(wo) else []
    floors = None
    if building:
        names = {f["name"]: i for i, f in enumerate(simj.get("floors", []))}
        wf = os.path.join(d, "wo.floors")
        pose_floor = read_pose_floors(wf) if os.path.exists(wf) else {}
        # pose_t z is absolute (the floor's elevation + the height above it), as the simulator's truth: scored
        # as it is (docs/notes/floors.md).
        changes = [dict(c, to_index=names.get(c["to"], -1)) for c in simj.get("floor_changes", []) if c["t"] <= gt[-1][0]]
        floors = score_floors(gt, est, read_gt_floors(gt_path[:-4] + ".floors.csv"), pose_floor, changes, simj.get("t0", gt[0][0]))
        row["building"] = True
    m, series = score(gt, est)
    row.update(m or {"poses": 0})
    if floors is not None:
        row.update(floors)
    # Honest uncertainty (issue 12): NEES of the published covariance and false OK (status OK, > 0.3 m off).
    ev = fploc_tools.fploc_eval(BIN, gt_path, wo, "fploc bench building", uncertainty=unc) if est else None
    if ev and "nees_median" in ev:
        row["nees_median"] = ev["nees_median"]
        row["false_ok"] = ev["false_ok_poses"]
        row["poor_poses"] = (fploc_tools.status_counts(unc) or [0, 0, 0])[1]
    if m:
        row["meets_targets"] = (m["z_err_p99_m"] <= TARGETS["z_err_p99_m"] and m["rp_err_p99_deg"] <= TARGETS["rp_err_p99_deg"]
                                and m["ate_xy_m"] <= TARGETS["ate_xy_m"] and row["lost"] == 0)
        if floors is not None:
            row["meets_targets"] = row["meets_targets"] and bool(floors.get("floor_scored")) and \
                floors.get("floor_changes_missed", 1) == 0 and \
                (floors.get("floor_recognised_max_s") is None or floors["floor_recognised_max_s"] <= TARGETS["floor_recognised_s"]) and \
                floors.get("wrong_floor_after_3s", 1) == 0 and \
                (floors.get("ate_after_lift_m") is None or floors["ate_after_lift_m"] <= TARGETS["ate_after_lift_m"])
    if a.plots and series:
        path = os.path.join(a.plots, name.replace(":", "-") + "-z.svg")
        marks = [c["t"] - gt[0][0] for c in (changes if building else [])]
        title = (f"{name}: z p99 {100 * m['z_err_p99_m']:.2f} cm, rp p99 {m['rp_err_p99_deg']:.3f} deg"
                 + (" (dashed: floor changes)" if marks else ""))
        plot_z(series, title, path, marks)
        row["plot"] = path
        plot_png(series, path[:-4] + ".png", title, marks=marks)
        row["plot_png"] = path[:-4] + ".png"
    log(f"[{name}] ATE xy {fmt_num(row.get('ate_xy_m'), 2, 100)} cm, z med/p99 "
        f"{fmt_num(row.get('z_err_median_m'), 2, 100)}/{fmt_num(row.get('z_err_p99_m'), 2, 100)} cm, "
        f"rp p99 {fmt_num(row.get('rp_err_p99_deg'), 3)} deg, LOST {row['lost']}, "
        f"NEES {fmt_num(row.get('nees_median'))}, false OK {row.get('false_ok', '-')}, ms/scan {fmt_ms(ms)}")
    if floors is not None:
        log(f"[{name}] floors: {floors_summary(floors)}")
    return row


def floors_summary(floors):
    """The floor rows of one run for the text summary: "no floor change in this run", "recognised after 1.20 s",
    "not recognised", "-" for a value not measured (no Python None, [] or nan)."""
    if not floors.get("floor_scored"):
        return floors["floor_note"]
    changes = floors.get("floor_changes") or []
    wrong = (f"wrong-floor poses {floors['wrong_floor_poses']} ({floors['wrong_floor_after_3s']} later than 3 s after "
             f"a change)")
    if not changes:
        return f"{wrong}, no floor change in this run"
    rec = ", ".join(f"{c.get('how', 'change')} " + ("not recognised" if c.get("recognised_after_s") is None
                                                     else f"recognised after {fmt_num(c['recognised_after_s'])} s")
                    for c in changes)
    lift = floors.get("ate_after_lift_m")
    if lift is not None:
        return f"{wrong}, {rec}, ATE after lift {fmt_num(lift, 3)} m"
    return f"{wrong}, {rec}, ATE after lift " + ("- (no lift ride)" if not floors.get("lift_rides") else "- (not measured)")


def main():
    ap = argparse.ArgumentParser(prog="fploc bench building", description=__doc__.splitlines()[0])
    ap.add_argument("--plan", action="append", help="floor plan(s) or building(s) (.pbtxt) (default: data/plans/room.json and "
                    "corridor.json with the ceiling scenarios, and the demo building with its journeys)")
    ap.add_argument("--floor", help="buildings: the floor for single-floor scenarios (auto-loop-*, building-areas-*, ...)")
    ap.add_argument("--layers", help="comma-separated plan layer globs (with --plan)")
    ap.add_argument("--scenario", action="append", help=f"scenario(s), comma-separated or repeated (default: {', '.join(SCENARIOS)})")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=0, help="simulate only this many seconds (tests)")
    ap.add_argument("--graph", default=os.path.join(ROOT, "graphs", "paper.pbtxt"))
    ap.add_argument("--plots", help="write z-against-ground-truth SVGs into this folder")
    ap.add_argument("--keep", help="keep the work folder here")
    ap.add_argument("--building-heights", action="store_true",
                    help="give the segmenter the building (segmenter.building: area heights looked up per ceiling point "
                         "with the pose feedback): the plan when it is a building, else for building-* scenarios the "
                         "simulated floor's ceilings (fploc sim --ceilings-building)")
    ap.add_argument("--imu-late-ms", type=float, default=0,
                    help="replay with every IMU event this much later than the scans in the log (live on a busy machine: "
                         "50-500 ms); the row says so (imu_late_ms)")
    ap.add_argument("--json", action="store_true", help="(JSON is always printed on stdout)")
    a = ap.parse_args()
    plans = [os.path.abspath(p) for p in (a.plan or [os.path.join(ROOT, "data", "plans", "room.json"),
                                                     os.path.join(ROOT, "data", "plans", "corridor.json"), DEMO_BUILDING])]
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
            default = BUILDING_SCENARIOS if is_building(p) and not a.floor else SCENARIOS
            for s in [x for arg in (a.scenario or default) for x in arg.split(",") if x]:
                rows.append(bench(a, work, p, layers, s))
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    # Per scenario, the floor rows beside z (stderr; the JSON has them all).
    log("scenario | z med/p99 cm | ATE xy cm | floor changes recognised after s | wrong floor (>3 s) | ATE 10 s after lift cm")
    for r in rows:
        rec = ", ".join(f"{c['how']} {fmt_num(c['recognised_after_s']) if c['recognised_after_s'] is not None else 'missed'}"
                        for c in r.get("floor_changes", [])) or "-"
        log(f"{r['plan']}:{r['scenario']} | {fmt_num(r.get('z_err_median_m'), 2, 100)}/"
            f"{fmt_num(r.get('z_err_p99_m'), 2, 100)} | {fmt_num(r.get('ate_xy_m'), 2, 100)} | {rec} | "
            f"{r.get('wrong_floor_poses', '-')} ({r.get('wrong_floor_after_3s', '-')}) | "
            f"{fmt_num(r.get('ate_after_lift_m'), 2, 100)}")
    print(json.dumps({"rows": rows, "targets": TARGETS, "seed": a.seed, "graph": os.path.relpath(a.graph, ROOT),
                      "all_meet_targets": all(r.get("meets_targets") for r in rows)}, indent=1))


if __name__ == "__main__":
    main()
