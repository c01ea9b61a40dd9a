#!/usr/bin/env python3
"""fploc bench sensors: the whole pipeline on other spinning LiDARs' beam patterns (issue 13 item 2).

For every (beam pattern, scenario): `fploc sim --beams B` writes an LCM log (scans + IMU) and the ground
truth; `fploc replay` runs graphs/paper.pbtxt on it (segmenter, features, matcher, optimizer in one process,
lock-step) against the scenario's demo plan (data/plans/room.json or corridor.json); the windowed
optimizer's poses (WO) are scored against the ground truth at each pose's own time (linear interpolation,
no alignment): horizontal ATE (rmse of the x/y error), |z error| median and p99, LOST count (the matcher's
LOST transitions, reported as node errors), ms per scan per node (thread CPU time) and features per scan.

Beam patterns (modules/sim beam_patterns.h): os1-64 (the paper's sensor, reference row), os1-32 and os1-128
(real units' metadata from ../shared/data/ouster when present), vlp16 (16 beams, +-15 deg, generated).
Targets: horizontal ATE <= 1 cm (OS-1-32/64/128) and <= 3 cm (16 beams), no LOST.

Prints one JSON document on stdout ({"rows": [...], "targets": {...}}); progress on stderr.
"""
import argparse
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
from fploc_tools import fmt_ms, fmt_num, log, pct, read_tum, yaw_of  # noqa: E402

BEAMS = ["vlp16", "os1-32", "os1-64", "os1-128"]
SCENARIOS = ["room-small-loop-medium", "corridor-loop-medium"]
PIPELINE = ("segmenter", "features", "matcher", "optimizer")


def target_ate(beams):
    return 0.03 if beams == "vlp16" else 0.01


def run(cmd):
    return fploc_tools.run(cmd, "fploc bench sensors")


def score(gt, est):
    truth = fploc_tools.Truth(gt)
    exy, ez = [], []
    for e in est:
        at = truth.interpolated(e[0])
        if at is None:
            continue
        p = at[0]
        exy.append((e[1] - p[0]) ** 2 + (e[2] - p[1]) ** 2)
        ez.append(abs(e[3] - p[2]))
    if not ez:
        return None
    return {"poses": len(ez), "ate_xy_m": round(math.sqrt(sum(exy) / len(exy)), 5),
            "max_xy_err_m": round(math.sqrt(max(exy)), 5),
            "z_err_median_m": round(pct(ez, 0.5), 5), "z_err_p99_m": round(pct(ez, 0.99), 5)}


def bench(a, work, beams, scenario):
    name = f"{beams}:{scenario}"
    d = os.path.join(work, name.replace(":", "-"))
    os.makedirs(d, exist_ok=True)
    logf, gt_path = os.path.join(d, "log.lcm"), os.path.join(d, "gt.tum")
    cmd = [os.path.join(BIN, "fploc-sim"), "--scenario", scenario, "--seed", str(a.seed), "--beams", beams,
           "--out", logf, "--gt", gt_path]
    if a.duration:
        cmd += ["--duration", str(a.duration)]
    log(f"[{name}] simulating ...")
    _, err = run(cmd)
    source = next((l.split("beams: ", 1)[1].strip() for l in err.splitlines() if "beams: " in l), "")
    plan = os.path.join(ROOT, "data", "plans", "corridor.json" if "corridor" in scenario else "room.json")
    gt = read_tum(gt_path)
    x0, y0, yaw0 = gt[0][1], gt[0][2], yaw_of(gt[0])
    wo = os.path.join(d, "wo.tum")
    sets = [f"matcher.plan.file={plan}", f"optimizer.plan.file={plan}", f"matcher.initial_pose.x={x0!r}",
            f"matcher.initial_pose.y={y0!r}", f"matcher.initial_pose.yaw={yaw0!r}", "matcher.initial_search_m=0.3",
            f"wo_logger.file={wo}", f"sfr_logger.file={os.path.join(d, 'sfr.tum')}",
            f"odom_logger.file={os.path.join(d, 'odom.tum')}", f"odom_map_logger.file={os.path.join(d, 'odom_map.tum')}",
            f"odometry.initial_pose.x={x0!r}", f"odometry.initial_pose.y={y0!r}", f"odometry.initial_pose.yaw={yaw0!r}",
            f"odometry_map.initial_pose.x={x0!r}", f"odometry_map.initial_pose.y={y0!r}",
            f"odometry_map.initial_pose.yaw={yaw0!r}"]
    log(f"[{name}] replaying {len(gt)} scans ...")
    nodes, scans, ms = fploc_tools.replay(BIN, a.graph, logf, sets, PIPELINE, "fploc bench sensors")
    os.remove(logf)
    row = {"beams": beams, "beam_source": source, "scenario": scenario, "scans": scans,
           "lost": nodes.get("matcher", {}).get("errors", 0), "ms_per_scan": ms,
           "ms_per_scan_pipeline": round(sum(ms.values()), 3)}
    m = score(gt, read_tum(wo) if os.path.exists(wo) else [])
    row.update(m or {"poses": 0})
    row["target_ate_xy_m"] = target_ate(beams)
    row["meets_targets"] = bool(m) and m["ate_xy_m"] <= target_ate(beams) and row["lost"] == 0
    log(f"[{name}] ATE xy {fmt_num(row.get('ate_xy_m'), 2, 100)} cm, z p99 "
        f"{fmt_num(row.get('z_err_p99_m'), 2, 100)} cm, LOST {row['lost']}, ms/scan {fmt_ms(ms)}")
    return row


def main():
    ap = argparse.ArgumentParser(prog="fploc bench sensors", description=__doc__.splitlines()[0])
    ap.add_argument("--beams", action="append", help=f"beam pattern(s), comma-separated or repeated (default: {', '.join(BEAMS)})")
    ap.add_argument("--scenario", action="append", help=f"scenario(s), comma-separated or repeated (default: {', '.join(SCENARIOS)})")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=0, help="simulate only this many seconds (tests)")
    ap.add_argument("--graph", default=os.path.join(ROOT, "graphs", "paper.pbtxt"))
    ap.add_argument("--keep", help="keep the work folder here")
    ap.add_argument("--json", action="store_true", help="(JSON is always printed on stdout)")
    a = ap.parse_args()
    a.graph = os.path.abspath(a.graph)
    work = a.keep or tempfile.mkdtemp(prefix="fploc-bench-sensors-", dir=os.environ.get("TMPDIR", "/tmp"))
    os.makedirs(work, exist_ok=True)
    rows = []
    try:
        for s in [x for arg in (a.scenario or SCENARIOS) for x in arg.split(",") if x]:
            for b in [x for arg in (a.beams or BEAMS) for x in arg.split(",") if x]:
                rows.append(bench(a, work, b, s))
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    print(json.dumps({"rows": rows, "targets": {"ate_xy_m": {b: target_ate(b) for b in BEAMS}, "lost": 0},
                      "seed": a.seed, "graph": os.path.relpath(a.graph, ROOT),
                      "all_meet_targets": all(r.get("meets_targets") for r in rows)}, indent=1))


if __name__ == "__main__":
    main()
