#!/usr/bin/env python3
"""AMCL baseline on the paper's simulated sequences, through the real graph (graphs/amcl.pbtxt).

For every sequence: `fploc sim` writes the LCM log (OS-1 scans, IMU, ground truth) and the ground truth
TUM; `fploc replay` runs graphs/amcl.pbtxt (segmenter, features, LiDAR odometry, AMCL with LiDAR odometry,
AMCL with simulated wheel odometry, matcher, optimizer, pose loggers) on it, one process, lock-step;
`fploc eval` scores every trajectory against the ground truth (no alignment: all are in the plan frame).
The log is deleted after each sequence (hundreds of MB).

  python3 modules/amcl/bench/amcl_sequences.py [--scenario NAME ...] [--seed 1] [--keep DIR]
         [--plan FILE --layers L --scenario auto-loop-medium] [--global] [--set NODE.field=value ...]
         [--keep-log] [--log LOG.lcm --gt GT.tum --tag NAME]   (reuse one simulated log for variants)

Prints one JSON document on stdout ({"rows": [...]}) and, with --markdown, a table on stderr.
ATE = `fploc eval` ate_rmse_m (3D: x, y from the localizer, z from the segmenter for all of them);
ate_xy = horizontal rmse over the same associated poses (what AMCL and the matcher estimate);
ate_xy_mid = horizontal rmse against the ground truth interpolated at the middle of the scan (+50 ms).
RPE = rpe_mean_m (1 s). CPU: AMCL = thread CPU per scan measured inside the node (stats file); the other
nodes = the replay's handler time per scan (total over all their messages / scans; wall clock of the one
replay thread, so it includes what the neighbours on a shared machine take from it).
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.environ.get("FPLOC_ROOT") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
BUILD = os.environ.get("FPLOC_BUILD_DIR") or os.path.join(ROOT, "build")
BIN = os.path.join(BUILD, "bin")
sys.path.insert(0, os.path.join(ROOT, "tools", "pylib"))
import fploc_tools  # noqa: E402
from fploc_tools import log, read_tum, yaw_of  # noqa: E402
SEQUENCES = [f"{s}-{v}" for s in ("room-small-loop", "room-large-loop", "room-no-loop", "corridor-loop")
             for v in ("slow", "medium", "fast")]
TRAJ = ("amcl_lidar", "amcl_wheel", "wheel_odom", "sfr", "wo", "odom")






def ate_xy(gt, est, max_dt=0.02):
    """Horizontal ATE rmse/max with the same nearest-time association as fploc eval (|dt| <= max_dt)."""
    if not est:
        return None, None
    g = sorted(gt)
    j, sq, mx, n = 0, 0.0, 0.0, 0
    for e in est:
        while j + 1 < len(g) and abs(g[j + 1][0] - e[0]) <= abs(g[j][0] - e[0]):
            j += 1
        if abs(g[j][0] - e[0]) > max_dt:
            continue
        d2 = (g[j][1] - e[1]) ** 2 + (g[j][2] - e[2]) ** 2
        sq += d2
        mx = max(mx, math.sqrt(d2))
        n += 1
    return (math.sqrt(sq / n) if n else None), (mx if n else None)


def ate_xy_mid(gt, est, offset=0.05):
    """Horizontal ATE rmse against the ground truth interpolated at est time + offset (the middle of the
    100 ms scan, where a registration of the scan's points effectively is; the trajectories are stamped
    with the scan start like the ground truth)."""
    g = sorted(gt)
    ts = [r[0] for r in g]
    sq, n = 0.0, 0
    import bisect
    for e in est:
        t = e[0] + offset
        i = bisect.bisect_right(ts, t)
        if i == 0 or i >= len(ts):
            continue
        a, b = g[i - 1], g[i]
        if b[0] - a[0] > 0.2:
            continue
        u = (t - a[0]) / (b[0] - a[0])
        x, y = a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2])
        sq += (x - e[1]) ** 2 + (y - e[2]) ** 2
        n += 1
    return math.sqrt(sq / n) if n else None


def settled(gt, est, bound=0.4, max_dt=0.02):
    """Index and time (s from the start) from which the horizontal error stays below `bound` to the end;
    and the first index below it."""
    g = {round(r[0], 3): r for r in gt}
    err = [math.dist(e[1:3], g[round(e[0], 3)][1:3]) for e in est if round(e[0], 3) in g]
    k = len(err)
    while k > 0 and err[k - 1] < bound:
        k -= 1
    first = next((i for i, x in enumerate(err) if x < bound), None)
    t0 = gt[0][0]
    return {"settled_index": k, "settled_s": (est[k][0] - t0) if k < len(est) else None,
            "first_below_index": first, "scans": len(err)}


def run(cmd):
    return fploc_tools.run(cmd, "amcl_sequences")


def length_m(gt):
    return sum(math.dist(a[1:3], b[1:3]) for a, b in zip(gt, gt[1:]))


def evaluate(gt_path, est_path):
    j = fploc_tools.fploc_eval(BIN, gt_path, est_path, "amcl_sequences")
    if j is None:
        return None
    g, e = read_tum(gt_path), read_tum(est_path)
    xy, xy_max = ate_xy(g, e)
    return {"ate_m": j["ate_rmse_m"], "ate_max_m": j.get("ate_max_m"), "rpe_m": j["rpe_mean_m"],
            "rpe_rot_deg": j.get("rpe_rot_mean_deg"), "ate_xy_m": xy, "ate_xy_max_m": xy_max,
            "ate_xy_mid_m": ate_xy_mid(g, e), "poses": j["poses"], **settled(g, e)}


def one(args, scenario, work):
    d = os.path.join(work, scenario + args.tag)
    os.makedirs(d, exist_ok=True)
    logf, gt = os.path.join(d, "log.lcm"), os.path.join(d, "gt.tum")
    if args.log:  # an existing simulator log (and its ground truth): no simulation, the log is kept
        logf, gt = os.path.abspath(args.log), os.path.abspath(args.gt)
    sim = [os.path.join(BIN, "fploc-sim"), "--scenario", scenario, "--seed", str(args.seed), "--out", logf, "--gt", gt]
    if args.plan:
        sim += ["--plan", args.plan]
        if args.layers:
            sim += ["--layers", args.layers]
    if args.duration:
        sim += ["--duration", str(args.duration)]
    if not args.log:
        log(f"[{scenario}] simulating ...")
        run(sim)
    g = read_tum(gt)
    x0, y0, yaw0 = g[0][1], g[0][2], yaw_of(g[0])
    if args.plan:
        plan = args.plan
    else:
        plan = os.path.join(ROOT, "data", "plans", "corridor.json" if scenario.startswith("corridor") else "room.json")
    out = {k: os.path.join(d, k + ".tum") for k in TRAJ}
    stats = {k: os.path.join(d, k + ".stats.json") for k in ("amcl_lidar", "amcl_wheel")}
    sets = [f"matcher.plan.file={plan}", f"optimizer.plan.file={plan}",
            f"amcl_lidar.plan.file={plan}", f"amcl_wheel.plan.file={plan}",
            f"amcl_lidar.stats_file={stats['amcl_lidar']}", f"amcl_wheel.stats_file={stats['amcl_wheel']}"]
    if args.layers:
        for n in ("matcher", "optimizer", "amcl_lidar", "amcl_wheel"):
            sets += [f"{n}.plan.layers={v}" for v in args.layers.split(",")]
    for n in ("matcher", "odometry", "amcl_lidar", "amcl_wheel"):
        sets += [f"{n}.initial_pose.x={x0!r}", f"{n}.initial_pose.y={y0!r}", f"{n}.initial_pose.yaw={yaw0!r}"]
    if args.global_loc:
        sets += ["amcl_lidar.global_localization=true", "amcl_wheel.global_localization=true"]
    for k in TRAJ:
        sets.append(f"{k}_logger.file={out[k]}")
    sets += args.set or []
    cmd = [os.path.join(BIN, "fploc-replay"), "--graph", args.graph, "--log", logf, "--json"]
    for s in sets:
        cmd += ["--set", s]
    log(f"[{scenario}] replaying {len(g)} frames through {os.path.relpath(args.graph, ROOT)} ...")
    rep_out, rep_err = run(cmd)
    rep = json.loads(rep_out)
    if not args.keep_log and not args.log:
        os.remove(logf)
    nodes = {n["name"]: n for n in rep["nodes"]}
    row = {"sequence": scenario, "frames": len(g), "length_m": round(length_m(g), 2),
           "real_time_factor": round(rep["real_time_factor"], 2)}
    for k in TRAJ:
        row[k] = evaluate(gt, out[k])
    for k, p in stats.items():
        if os.path.exists(p):
            with open(p) as f:
                row[k + "_stats"] = json.load(f)
    # Handler wall time per scan (total over all of a node's messages / scans: the matcher also gets the IMU).
    row["node_ms_per_scan"] = {n: round(v["total_ms"] / max(len(g), 1), 3) for n, v in nodes.items()}
    row["node_errors"] = {n: v["errors"] for n, v in nodes.items() if v["errors"]}
    row["node_last_error"] = {n: v["last_error"] for n, v in nodes.items() if v["errors"]}
    def f(k):
        r = row[k]
        return f"{100 * r['ate_xy_m']:.1f}" if r and r["ate_xy_m"] is not None else "-"
    log(f"[{scenario}] ATE xy cm: amcl_lidar {f('amcl_lidar')}  amcl_wheel {f('amcl_wheel')}  "
        f"wheel odom {f('wheel_odom')}  sfr {f('sfr')}  wo {f('wo')}  lidar odom {f('odom')}")
    return row


def markdown(rows):
    def c(r, k, key="ate_xy_m"):
        v = r.get(k)
        return f"{100 * v[key]:.1f}" if v and v.get(key) is not None else "–"
    def three(r, k):
        return f"{c(r, k)} / {c(r, k, 'ate_xy_mid_m')} / {c(r, k, 'rpe_m')}"
    lines = ["| sequence | m | AMCL + LiDAR odo: ATE xy / ATE xy mid / RPE (cm) | AMCL + wheel odo: ATE xy / mid / RPE | "
             "fploc WO: ATE xy / mid / RPE | fploc SFR ATE xy | LiDAR odo ATE xy | wheel odo ATE xy | "
             "AMCL CPU µs/scan (LiDAR / wheel) | AMCL CPU µs/update | particles/update | LiDAR odometry ms/scan | "
             "matcher + optimizer ms/scan |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        sl, sw = r.get("amcl_lidar_stats", {}), r.get("amcl_wheel_stats", {})
        nm = r.get("node_ms_per_scan", {})
        lines.append(
            f"| {r['sequence']} | {r['length_m']} | {three(r, 'amcl_lidar')} | {three(r, 'amcl_wheel')} | {three(r, 'wo')} | "
            f"{c(r, 'sfr')} | {c(r, 'odom')} | {c(r, 'wheel_odom')} | "
            f"{sl.get('cpu_us_per_scan_mean', 0):.0f} / {sw.get('cpu_us_per_scan_mean', 0):.0f} | "
            f"{sl.get('cpu_us_per_update_mean', 0):.0f} | {sl.get('mean_particles_per_update', 0):.0f} | "
            f"{nm.get('odometry', 0):.2f} | {nm.get('matcher', 0) + nm.get('optimizer', 0):.2f} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", action="append", help="repeatable; default: the 12 paper sequences")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--plan")
    ap.add_argument("--layers")
    ap.add_argument("--duration", type=float)
    ap.add_argument("--graph", default=os.path.join(ROOT, "graphs", "amcl.pbtxt"))
    ap.add_argument("--global", dest="global_loc", action="store_true", help="AMCL without initial pose")
    ap.add_argument("--set", action="append", help="extra replay --set NODE.field=value")
    ap.add_argument("--keep", help="keep trajectories here")
    ap.add_argument("--keep-log", action="store_true")
    ap.add_argument("--log", help="use this simulator log instead of simulating (with --gt and one --scenario)")
    ap.add_argument("--gt", help="ground truth TUM of --log")
    ap.add_argument("--tag", default="", help="suffix of the work sub-folder (several runs on one log)")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--rescore", help="re-evaluate the trajectories kept in this folder (no simulation/replay)")
    a = ap.parse_args()
    if a.log and (not a.gt or not a.scenario or len(a.scenario) != 1):
        raise SystemExit("--log needs --gt and exactly one --scenario")
    if a.plan:
        a.plan = os.path.abspath(a.plan)
        if not a.scenario:
            raise SystemExit("--plan needs --scenario (e.g. auto-loop-medium)")
    a.graph = os.path.abspath(a.graph)
    if a.rescore:  # re-evaluate the trajectories kept by an earlier run (--keep DIR)
        with open(os.path.join(a.rescore, f"rows{a.tag}.json")) as f:
            rows = json.load(f)["rows"]
        for r in rows:
            d = os.path.join(a.rescore, r["sequence"] + a.tag)
            for k in TRAJ:
                r[k] = evaluate(os.path.join(d, "gt.tum"), os.path.join(d, k + ".tum"))
        print(json.dumps({"rows": rows, "rescored": a.rescore}, indent=1))
        if a.markdown:
            log(markdown(rows))
        return
    work = a.keep or tempfile.mkdtemp(prefix="fploc-amcl-", dir="/tmp")
    os.makedirs(work, exist_ok=True)
    rows = []
    try:
        for s in a.scenario or SEQUENCES:
            rows.append(one(a, s, work))
            with open(os.path.join(work, f"rows{a.tag}.json"), "w") as f:
                print(json.dumps({"rows": rows}, indent=1), file=f)
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    print(json.dumps({"rows": rows, "seed": a.seed, "graph": os.path.relpath(a.graph, ROOT)}, indent=1))
    if a.markdown:
        log(markdown(rows))


if __name__ == "__main__":
    main()
