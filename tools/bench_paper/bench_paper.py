#!/usr/bin/env python3
"""fploc bench paper: the paper's Tables I/II re-run on simulated sequences, through the real graph.

For every sequence: `fploc sim` writes an LCM log of OS-1 scans + IMU and the ground truth (TUM);
`fploc replay` runs graphs/paper.pbtxt (segmenter, features, matcher, optimizer, odometry baseline and
pose loggers, one process, lock-step) on the log; `fploc eval` scores the single-frame (SFR), windowed
(WO) and no-plan odometry trajectories against the ground truth. Prints one JSON document on stdout
(progress on stderr):
  {"rows": [{"sequence", "speed", "length_m", "avg_speed_mps", "max_speed_mps", "frames", "ate_sfr_m",
             "rpe_sfr_m", "ate_wo_m", "rpe_wo_m", "hz", "real_time_factor", "per_node_ms"}],
   "baseline": [{"sequence", "speed", "ate_m", "rpe_m"}], "paper": {...}}
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.environ.get("FPLOC_ROOT") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BIN = os.environ.get("FPLOC_BIN") or os.path.dirname(os.path.abspath(__file__))

# Paper Table I (room) and II (corridor): windowed-optimisation ATE/RPE [m] and the sequences' speeds.
PAPER = {
    "room-small-loop": {"fast": (0.046736, 0.026900), "medium": (0.046676, 0.033470), "slow": (0.052476, 0.033132)},
    "room-large-loop": {"fast": (0.058678, 0.031234), "medium": (0.051823, 0.030256), "slow": (0.059972, 0.037555)},
    "room-no-loop": {"fast": (0.055408, 0.017013), "medium": (0.043437, 0.021360), "slow": (0.049270, 0.020422)},
    "corridor-loop": {"fast": (0.243258, 0.033826), "medium": (0.238171, 0.031069), "slow": (0.248676, 0.030835)},
}
PAPER_LEGO_LOAM_CORRIDOR_ATE = {"fast": 1.326895, "medium": 1.317793, "slow": 1.299051}
ALL = [f"{s}-{v}" for s in PAPER for v in ("slow", "medium", "fast")]
QUICK = ["room-small-loop-fast", "corridor-loop-fast"]
PIPELINE = ("segmenter", "features", "matcher", "optimizer")


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def run(cmd, capture=True):
    r = subprocess.run(cmd, stdout=subprocess.PIPE if capture else None, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        log(r.stderr[-4000:])
        raise SystemExit(f"fploc bench paper: {os.path.basename(cmd[0])} failed (exit {r.returncode})")
    return r.stdout


def read_tum(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append([float(v) for v in line.split()])
    return rows


def motion_stats(gt):
    length, vmax, moving = 0.0, 0.0, 0.0
    for a, b in zip(gt, gt[1:]):
        d = math.dist(a[1:3], b[1:3])
        dt = b[0] - a[0]
        length += d
        if dt > 0:
            v = d / dt
            vmax = max(vmax, v)
            if v > 0.02:
                moving += dt
    return length, (length / moving if moving > 0 else 0.0), vmax


def yaw_of(row):
    qx, qy, qz, qw = row[4:8]
    return math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))


def evaluate(gt, est, plot):
    if not os.path.exists(est) or os.path.getsize(est) == 0:
        return None
    cmd = [os.path.join(BIN, "fploc-eval"), "--gt", gt, "--est", est, "--json"]
    if plot:
        cmd += ["--plot", plot]
    return json.loads(run(cmd))


def one(plan, scenario, seed, work, graph, plots):
    seq, _, speed = scenario.rpartition("-")
    d = os.path.join(work, scenario)
    os.makedirs(d, exist_ok=True)
    logf, gt = os.path.join(d, "log.lcm"), os.path.join(d, "gt.tum")
    sim = [os.path.join(BIN, "fploc-sim"), "--scenario", scenario, "--seed", str(seed), "--out", logf, "--gt", gt]
    if plan:
        sim += ["--plan", plan]
    log(f"[{scenario}] simulating ...")
    run(sim)
    g = read_tum(gt)
    length, avg, vmax = motion_stats(g)
    x0, y0, yaw0 = g[0][1], g[0][2], yaw_of(g[0])
    plan_file = plan or os.path.join(ROOT, "data", "plans", "corridor.json" if seq.startswith("corridor") else "room.json")
    out = {k: os.path.join(d, k + ".tum") for k in ("sfr", "wo", "odom")}
    sets = [f"matcher.plan.file={plan_file}", f"optimizer.plan.file={plan_file}",
            f"matcher.initial_pose.x={x0!r}", f"matcher.initial_pose.y={y0!r}", f"matcher.initial_pose.yaw={yaw0!r}",
            f"odometry.initial_pose.x={x0!r}", f"odometry.initial_pose.y={y0!r}", f"odometry.initial_pose.yaw={yaw0!r}",
            f"sfr_logger.file={out['sfr']}", f"wo_logger.file={out['wo']}", f"odom_logger.file={out['odom']}"]
    cmd = [os.path.join(BIN, "fploc-replay"), "--graph", graph, "--log", logf, "--json"]
    for s in sets:
        cmd += ["--set", s]
    log(f"[{scenario}] replaying {len(g)} frames through {os.path.relpath(graph, ROOT)} ...")
    rep = json.loads(run(cmd))
    os.remove(logf)  # hundreds of MB per sequence
    per_node = {n["name"]: n["total_ms"] for n in rep["nodes"]}
    pipeline_ms = sum(per_node.get(n, 0.0) for n in PIPELINE)
    res = {k: evaluate(gt, out[k], os.path.join(plots, f"{scenario}-{k}.svg") if plots else None) for k in out}
    row = {"sequence": seq, "speed": speed, "length_m": round(length, 3), "avg_speed_mps": round(avg, 4),
           "max_speed_mps": round(vmax, 4), "frames": len(g),
           "ate_sfr_m": res["sfr"]["ate_rmse_m"] if res["sfr"] else None,
           "rpe_sfr_m": res["sfr"]["rpe_mean_m"] if res["sfr"] else None,
           "ate_wo_m": res["wo"]["ate_rmse_m"] if res["wo"] else None,
           "rpe_wo_m": res["wo"]["rpe_mean_m"] if res["wo"] else None,
           "poses_wo": res["wo"]["poses"] if res["wo"] else 0,
           "hz": round(len(g) / (pipeline_ms / 1000.0), 1) if pipeline_ms > 0 else None,
           "real_time_factor": round(rep["real_time_factor"], 2),
           "per_node_ms": {n: round(per_node.get(n, 0.0) / max(len(g), 1), 3) for n in PIPELINE}}
    base = {"sequence": seq, "speed": speed,
            "ate_m": res["odom"]["ate_rmse_m"] if res["odom"] else None,
            "rpe_m": res["odom"]["rpe_mean_m"] if res["odom"] else None}
    if seq in PAPER:
        row["paper_ate_wo_m"], row["paper_rpe_wo_m"] = PAPER[seq][speed]
    log(f"[{scenario}] ATE sfr {row['ate_sfr_m']}  wo {row['ate_wo_m']}  odometry {base['ate_m']}  ({row['hz']} Hz)")
    return row, base


def main():
    ap = argparse.ArgumentParser(prog="fploc bench paper", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help=f"only {', '.join(QUICK)}")
    ap.add_argument("--plan", help="any floor plan (.dxf/.csv/.json); with --scenario auto-loop-<speed>")
    ap.add_argument("--scenario", action="append", help="scenario name (repeatable); default: all of the paper's")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--graph", default=os.path.join(ROOT, "graphs", "paper.pbtxt"))
    ap.add_argument("--plots", help="write SVG plots of every trajectory against ground truth into this folder")
    ap.add_argument("--keep", help="keep the work folder (trajectories) here instead of a temporary one")
    ap.add_argument("--json", action="store_true", help="(JSON is always printed on stdout)")
    a = ap.parse_args()
    scenarios = a.scenario or (QUICK if a.quick else ALL)
    if a.plan and not a.scenario:
        raise SystemExit("fploc bench paper: --plan needs --scenario (e.g. auto-loop-medium)")
    if a.plots:
        os.makedirs(a.plots, exist_ok=True)
    work = a.keep or tempfile.mkdtemp(prefix="fploc-bench-paper-")
    os.makedirs(work, exist_ok=True)
    rows, baseline = [], []
    try:
        for s in scenarios:
            r, b = one(os.path.abspath(a.plan) if a.plan else None, s, a.seed, work, a.graph, a.plots)
            rows.append(r)
            baseline.append(b)
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    doc = {"rows": rows, "baseline": baseline, "seed": a.seed, "graph": os.path.relpath(a.graph, ROOT),
           "paper": {"windowed": {k: {s: {"ate_m": v[0], "rpe_m": v[1]} for s, v in d.items()} for k, d in PAPER.items()},
                     "lego_loam_corridor_ate_m": PAPER_LEGO_LOAM_CORRIDOR_ATE}}
    print(json.dumps(doc, indent=1))


if __name__ == "__main__":
    main()
