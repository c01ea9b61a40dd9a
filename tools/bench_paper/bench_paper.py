#!/usr/bin/env python3
"""fploc bench paper: the paper's Tables I/II re-run on simulated sequences, through the real graph.

For every sequence: `fploc sim` writes an LCM log of OS-1 scans + IMU and the ground truth (TUM, the pose
at each scan's first column time); `fploc replay` runs graphs/paper.pbtxt (segmenter, features, matcher,
optimizer, the no-plan odometry baseline and pose loggers, one process, lock-step) on the log; `fploc eval`
scores the single-frame (SFR), windowed (WO) and odometry trajectories against the ground truth: full
6-DoF position error at each pose's own time stamp, no time offset, no alignment. The frame rate is the
number of scans over the pipeline nodes' thread CPU time (segmenter + features + matcher + optimizer;
`fploc replay --json` cpu_ms), i.e. on one core, whatever else the machine runs.

Prints one JSON document on stdout (progress on stderr):
  {"rows": [{"sequence", "speed", "length_m", "avg_speed_mps", "max_speed_mps", "frames", "ate_sfr_m",
             "rpe_sfr_m", "ate_wo_m", "rpe_wo_m", "hz", "real_time_factor", "ms_per_scan",
             "nees_sfr_median", "nees_wo_median", "false_ok_sfr", "false_ok_wo", "poor_sfr", "poor_wo", ...}],
   "baseline": [{"sequence", "speed", "ate_m", "rpe_m"}],
   "lookups": [...] (--lookups), "robustness": [...] (--robustness), "paper": {...}}
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
sys.path.insert(0, os.path.join(ROOT, "tools", "pylib"))
import fploc_tools  # noqa: E402
from fploc_tools import fmt_ms, fmt_num, log, read_tum, yaw_of  # noqa: E402


def run(cmd):
    return fploc_tools.run(cmd, "fploc bench paper")


def evaluate(gt, est, plot=None, uncertainty=None):
    return fploc_tools.fploc_eval(BIN, gt, est, "fploc bench paper", plot, uncertainty)


def uncertainty_keys(res, k):
    """NEES median, false-OK and POOR counts of trajectory k (sfr / wo) for a row (None where not measured)."""
    r = res.get(k) or {}
    sc = r.get("status_counts") or [None, None, None]
    return {f"nees_{k}_median": r.get("nees_median"), f"false_ok_{k}": r.get("false_ok_poses"), f"poor_{k}": sc[1]}


# Paper Table I (room: SFR and WO) and Table II (corridor: FP-Loc and LeGO-LOAM): ATE/RPE [m], speeds.
PAPER = {
    "room-small-loop": {"fast": dict(max=0.8719, avg=0.6236, len=25.797, rpe_sfr=0.027338, ate_sfr=0.048188, rpe_wo=0.026900, ate_wo=0.046736),
                        "medium": dict(max=0.5641, avg=0.4090, len=25.849, rpe_sfr=0.033473, ate_sfr=0.049413, rpe_wo=0.033470, ate_wo=0.046676),
                        "slow": dict(max=0.4425, avg=0.3109, len=25.714, rpe_sfr=0.033062, ate_sfr=0.053061, rpe_wo=0.033132, ate_wo=0.052476)},
    "room-large-loop": {"fast": dict(max=0.9213, avg=0.7253, len=46.725, rpe_sfr=0.031447, ate_sfr=0.059842, rpe_wo=0.031234, ate_wo=0.058678),
                        "medium": dict(max=0.6878, avg=0.5357, len=46.773, rpe_sfr=0.030335, ate_sfr=0.053048, rpe_wo=0.030256, ate_wo=0.051823),
                        "slow": dict(max=0.4742, avg=0.3552, len=46.421, rpe_sfr=0.037812, ate_sfr=0.060282, rpe_wo=0.037555, ate_wo=0.059972)},
    "room-no-loop": {"fast": dict(max=0.8458, avg=0.6926, len=25.287, rpe_sfr=0.017505, ate_sfr=0.059954, rpe_wo=0.017013, ate_wo=0.055408),
                     "medium": dict(max=0.5277, avg=0.3904, len=25.322, rpe_sfr=0.021412, ate_sfr=0.044469, rpe_wo=0.021360, ate_wo=0.043437),
                     "slow": dict(max=0.4028, avg=0.2954, len=25.208, rpe_sfr=0.020445, ate_sfr=0.049362, rpe_wo=0.020422, ate_wo=0.049270)},
    "corridor-loop": {"fast": dict(max=1.2678, avg=1.0487, len=81.448, rpe_wo=0.033826, ate_wo=0.243258, rpe_lego=0.026785, ate_lego=1.326895),
                      "medium": dict(max=0.9296, avg=0.7777, len=81.789, rpe_wo=0.031069, ate_wo=0.238171, rpe_lego=0.092715, ate_lego=1.317793),
                      "slow": dict(max=0.6603, avg=0.5547, len=82.072, rpe_wo=0.030835, ate_wo=0.248676, rpe_lego=0.075712, ate_lego=1.299051)},
}
ALL = [f"{s}-{v}" for s in PAPER for v in ("fast", "medium", "slow")]
QUICK = ["room-small-loop-fast", "corridor-loop-fast"]
PIPELINE = ("segmenter", "features", "matcher", "optimizer")
LOOKUPS = ("annf-exact", "annf-paper", "annf-paper-first", "kdtree", "brute-force")
SCAN_HZ = 10.0





def motion_stats(gt):
    """Path length, average speed over the moving time (the paper's definition) and maximum speed."""
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




class Bench:
    def __init__(self, args, work):
        self.a = args
        self.work = work
        self.logs = {}

    def simulate(self, scenario, tag="", extra=()):
        """LCM log + ground truth for a scenario (cached per tag within one run)."""
        key = (scenario, tag)
        if key in self.logs:
            return self.logs[key]
        d = os.path.join(self.work, scenario + (("-" + tag) if tag else ""))
        os.makedirs(d, exist_ok=True)
        logf, gt = os.path.join(d, "log.lcm"), os.path.join(d, "gt.tum")
        cmd = [os.path.join(BIN, "fploc-sim"), "--scenario", scenario, "--seed", str(self.a.seed), "--out", logf, "--gt", gt]
        if self.a.plan:
            cmd += ["--plan", self.a.plan] + self.a.plan_args
        if self.a.duration:
            cmd += ["--duration", str(self.a.duration)]
        cmd += list(extra)
        log(f"[{scenario}{' ' + tag if tag else ''}] simulating ...")
        _, err = run(cmd)
        info = [l for l in err.splitlines() if "clutter" in l or "dropped" in l]
        self.logs[key] = (d, logf, gt, info)
        return self.logs[key]

    def drop(self, scenario, tag):
        d, logf, _, _ = self.logs.pop((scenario, tag))
        if os.path.exists(logf):
            os.remove(logf)  # ~300 MB per minute of scans

    def replay(self, d, logf, gt, name, sets=(), init_offset=(0.0, 0.0, 0.0), search_m=0.3, plots_prefix=None):
        """graphs/paper.pbtxt on the log; returns (eval of sfr, wo, odom; replay JSON)."""
        g = read_tum(gt)
        x0, y0, yaw0 = g[0][1], g[0][2], yaw_of(g[0])
        dx, dy, dyaw = init_offset
        plan = self.a.plan or os.path.join(ROOT, "data", "plans", "corridor.json" if "corridor" in name else "room.json")
        out = {k: os.path.join(d, f"{name}-{k}.tum") for k in ("sfr", "wo", "odom", "odom_map")}
        unc = {k: os.path.join(d, f"{name}-{k}.unc") for k in ("sfr", "wo")}
        s = [f"sfr_logger.uncertainty_file={unc['sfr']}", f"wo_logger.uncertainty_file={unc['wo']}",f"matcher.plan.file={plan}", f"optimizer.plan.file={plan}",
             f"matcher.initial_pose.x={x0 + dx!r}", f"matcher.initial_pose.y={y0 + dy!r}",
             f"matcher.initial_pose.yaw={yaw0 + dyaw!r}", f"matcher.initial_search_m={search_m!r}",
             f"odometry.initial_pose.x={x0!r}", f"odometry.initial_pose.y={y0!r}", f"odometry.initial_pose.yaw={yaw0!r}",
             f"odometry_map.initial_pose.x={x0!r}", f"odometry_map.initial_pose.y={y0!r}",
             f"odometry_map.initial_pose.yaw={yaw0!r}", f"sfr_logger.file={out['sfr']}", f"wo_logger.file={out['wo']}",
             f"odom_logger.file={out['odom']}", f"odom_map_logger.file={out['odom_map']}"]
        if self.a.plan:
            for n in ("matcher", "optimizer"):
                for layer in self.a.layers:
                    s.append(f"{n}.plan.layers={layer}")
                if self.a.units:
                    s.append(f"{n}.plan.units={self.a.units}")
        cmd = [os.path.join(BIN, "fploc-replay"), "--graph", self.a.graph, "--log", logf, "--json"]
        for x in s + list(sets):
            cmd += ["--set", x]
        rep = json.loads(run(cmd)[0].strip().splitlines()[-1])
        res = {k: evaluate(gt, out[k], f"{plots_prefix}-{k}.svg" if plots_prefix else None, unc.get(k)) for k in out}
        for k in unc:
            if res.get(k) is not None:
                res[k]["status_counts"] = fploc_tools.status_counts(unc[k])
        return res, rep

    @staticmethod
    def timing(rep, scans):
        per = {}
        for n in rep["nodes"]:
            per[n["name"]] = n.get("cpu_ms", n["total_ms"])
        pipeline_ms = sum(per.get(n, 0.0) for n in PIPELINE)
        ms = {n: round(per.get(n, 0.0) / max(scans, 1), 3) for n in PIPELINE + ("odometry",)}
        hz = scans / (pipeline_ms / 1000.0) if pipeline_ms > 0 else None
        return ms, (round(hz, 1) if hz else None)

    def sequence(self, scenario):
        seq, _, speed = scenario.rpartition("-")
        d, logf, gt, _ = self.simulate(scenario)
        g = read_tum(gt)
        length, avg, vmax = motion_stats(g)
        log(f"[{scenario}] replaying {len(g)} scans through {os.path.relpath(self.a.graph, ROOT)} ...")
        res, rep = self.replay(d, logf, gt, scenario, plots_prefix=os.path.join(self.a.plots, scenario) if self.a.plots else None)
        scans = self.scans(rep)
        ms, hz = self.timing(rep, scans)
        row = {"sequence": seq, "speed": speed, "length_m": round(length, 3), "avg_speed_mps": round(avg, 4),
               "max_speed_mps": round(vmax, 4), "frames": len(g),
               "ate_sfr_m": res["sfr"]["ate_rmse_m"] if res["sfr"] else None,
               "rpe_sfr_m": res["sfr"]["rpe_mean_m"] if res["sfr"] else None,
               "ate_wo_m": res["wo"]["ate_rmse_m"] if res["wo"] else None,
               "rpe_wo_m": res["wo"]["rpe_mean_m"] if res["wo"] else None,
               "poses_sfr": res["sfr"]["poses"] if res["sfr"] else 0, "poses_wo": res["wo"]["poses"] if res["wo"] else 0,
               "hz": hz, "real_time_factor": round(hz / SCAN_HZ, 2) if hz else None, "ms_per_scan": ms,
               "node_errors": sum(n["errors"] for n in rep["nodes"])}
        row.update(uncertainty_keys(res, "sfr"))
        row.update(uncertainty_keys(res, "wo"))
        if seq in PAPER:
            row["paper"] = PAPER[seq][speed]
        base = {"sequence": seq, "speed": speed, "ate_m": res["odom"]["ate_rmse_m"] if res["odom"] else None,
                "rpe_m": res["odom"]["rpe_mean_m"] if res["odom"] else None, "odometry": "frame-to-frame",
                "ate_local_map_m": res["odom_map"]["ate_rmse_m"] if res["odom_map"] else None,
                "rpe_local_map_m": res["odom_map"]["rpe_mean_m"] if res["odom_map"] else None}
        log(f"[{scenario}] ATE sfr {fmt(row['ate_sfr_m'])} wo {fmt(row['ate_wo_m'])} odometry {fmt(base['ate_m'])} "
            f"(local map {fmt(base['ate_local_map_m'])})  NEES wo {fmt_num(row['nees_wo_median'])} false OK "
            f"{fmt_num(row['false_ok_wo'], 0)} POOR {fmt_num(row['poor_wo'], 0)}  "
            f"{fmt_num(hz, 1)} Hz (ms/scan {fmt_ms(ms)})")
        return row, base

    @staticmethod
    def scans(rep):
        for n in rep["nodes"]:
            if n["name"] == "features":
                return n["messages"]
        return 1

    def lookups(self, scenario):
        d, logf, gt, _ = self.simulate(scenario)
        out = []
        for lk in LOOKUPS:
            log(f"[{scenario}] look-up {lk} ...")
            res, rep = self.replay(d, logf, gt, f"{scenario}-{lk}", sets=[f"matcher.lookup={lk}", f"optimizer.lookup={lk}"])
            ms, hz = self.timing(rep, self.scans(rep))
            loc_ms = ms["matcher"] + ms["optimizer"]
            out.append({"lookup": lk, "sequence": scenario, "ate_sfr_m": res["sfr"]["ate_rmse_m"] if res["sfr"] else None,
                        "ate_wo_m": res["wo"]["ate_rmse_m"] if res["wo"] else None, "hz": hz,
                        "matcher_ms": ms["matcher"], "optimizer_ms": ms["optimizer"],
                        "localization_hz": round(1000.0 / loc_ms, 1) if loc_ms > 0 else None})
            log(f"  ATE sfr {fmt(out[-1]['ate_sfr_m'])} wo {fmt(out[-1]['ate_wo_m'])}, matcher {ms['matcher']} + optimizer {ms['optimizer']} ms/scan")
        return out

    def robustness(self, scenario):
        clean_d, clean_log, clean_gt, _ = self.simulate(scenario)
        cases = [("clean", None, {}),
                 ("30 % of scans dropped", ("drop30", ["--drop-scans", "0.3"]), {}),
                 ("cabinets along half of the walls", ("walls50", ["--wall-clutter", "0.5"]), {}),
                 ("initial pose 1 m / 10 deg off (x+)", None, {"init_offset": (1.0, 0.0, math.radians(10)), "search_m": 1.5}),
                 ("initial pose 1 m / 10 deg off (x-)", None, {"init_offset": (-1.0, 0.0, math.radians(10)), "search_m": 1.5}),
                 ("initial pose 1 m / 10 deg off (y+)", None, {"init_offset": (0.0, 1.0, -math.radians(10)), "search_m": 1.5}),
                 ("initial pose 1 m / 10 deg off (y-)", None, {"init_offset": (0.0, -1.0, -math.radians(10)), "search_m": 1.5})]
        out = []
        clean = None
        for name, sim, kw in cases:
            if sim:
                d, logf, gt, info = self.simulate(scenario, sim[0], sim[1])
            else:
                d, logf, gt, info = clean_d, clean_log, clean_gt, []
            log(f"[{scenario}] {name} ...")
            res, rep = self.replay(d, logf, gt, f"{scenario}-{name.split()[0]}-{len(out)}", **kw)
            row = {"case": name, "sequence": scenario, "scans": self.scans(rep),
                   "ate_sfr_m": res["sfr"]["ate_rmse_m"] if res["sfr"] else None,
                   "ate_wo_m": res["wo"]["ate_rmse_m"] if res["wo"] else None,
                   "ate_odometry_m": res["odom"]["ate_rmse_m"] if res["odom"] else None,
                   "ate_odometry_local_map_m": res["odom_map"]["ate_rmse_m"] if res["odom_map"] else None, "sim": info}
            if kw.get("init_offset"):
                # Converged: the error of the last 90 % of the poses (the first ones start 1 m off).
                row["ate_wo_after_first_s_m"] = tail_ate(gt, os.path.join(d, f"{scenario}-{name.split()[0]}-{len(out)}-wo.tum"), 1.0)
            if clean is None:
                clean = row
            row["ratio_wo_to_clean"] = round(row["ate_wo_m"] / clean["ate_wo_m"], 2) if row["ate_wo_m"] and clean["ate_wo_m"] else None
            out.append(row)
            if sim:
                self.drop(scenario, sim[0])
            log(f"  ATE sfr {fmt(row['ate_sfr_m'])} wo {fmt(row['ate_wo_m'])} ({fmt_num(row['ratio_wo_to_clean'])}x clean) {' '.join(info)}")
        return out


def tail_ate(gt_path, est_path, skip_s):
    """ATE rmse of the poses later than skip_s after the first (nearest ground-truth pose in time)."""
    gt, est = read_tum(gt_path), read_tum(est_path)
    if not est:
        return None
    t0 = est[0][0]
    truth = fploc_tools.Truth(gt)
    s, n = 0.0, 0
    for e in est:
        if e[0] - t0 < skip_s:
            continue
        g = truth.nearest(e[0], 0.02)
        if g is None:
            continue
        s += sum((e[k] - g[k]) ** 2 for k in (1, 2, 3))
        n += 1
    return math.sqrt(s / n) if n else None


def fmt(v, scale=100.0, unit=" cm", digits=2):
    t = fmt_num(v, digits, scale)
    return t if t == "-" else t + unit


def markdown(doc, argv=None):
    """The tables of docs/notes/localization.md (and docs/results/paper.md), with how they were made."""
    L = []
    if argv is not None:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
        L.append("# fploc bench paper: the paper's Tables I/II on simulated sequences, through the real graph\n")
        L.append(f"Made by `bin/fploc bench paper {' '.join(argv)}` at commit {commit or '?'} (seed {doc.get('seed', '?')}). "
                 "Each sequence: `fploc sim` -> `fploc replay --graph graphs/paper.pbtxt` -> `fploc eval` (ATE rmse / RPE mean "
                 "over 1 s of the full 6-DoF position, ground truth at each pose's own time stamp, no alignment). SFR = the "
                 "matcher's single-frame poses, WO = the windowed optimizer's final poses; paper = Tables I/II of FP-Loc "
                 "(LeGO-LOAM on the corridor: 132.7 / 131.8 / 129.9 cm). Hz = scans / CPU seconds of segmenter + features + "
                 "matcher + optimizer (one core, thread CPU time; about +-8 % between runs on a shared machine).\n")
    L.append("| sequence | speed | max / avg speed m/s | length m | RPE SFR cm | ATE SFR cm | RPE WO cm | ATE WO cm | "
             "paper ATE SFR / WO cm | odometry ATE cm: frame-to-frame / local map | Hz (1 core) | ms/scan seg / feat / match / opt |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    base = {(b["sequence"], b["speed"]): b for b in doc["baseline"]}
    for r in doc["rows"]:
        p = r.get("paper") or {}
        ms = r["ms_per_scan"]
        paper = (f"{fmt(p.get('ate_sfr'), unit='')} / {fmt(p.get('ate_wo'), unit='')}" if p else "-")
        b = base.get((r["sequence"], r["speed"]), {})
        L.append(f"| {r['sequence']} | {r['speed']} | {r['max_speed_mps']:.2f} / {r['avg_speed_mps']:.2f} | {r['length_m']:.1f} | "
                 f"{fmt(r['rpe_sfr_m'], unit='')} | {fmt(r['ate_sfr_m'], unit='')} | {fmt(r['rpe_wo_m'], unit='')} | "
                 f"{fmt(r['ate_wo_m'], unit='')} | {paper} | {fmt(b.get('ate_m'), unit='')} / {fmt(b.get('ate_local_map_m'), unit='')} | {r['hz']} | "
                 f"{ms['segmenter']:.2f} / {ms['features']:.2f} / {ms['matcher']:.2f} / {ms['optimizer']:.2f} |")
    if any(r.get("nees_wo_median") is not None for r in doc["rows"]):
        L.append("")
        L.append("Honest uncertainty (issue 12): NEES median of the published (x, y, yaw) covariance against the truth "
                 "(3 if consistent; target 1.5-6), false OK = poses with status OK more than 0.3 m off horizontally "
                 "(target 0), POOR = poses published POOR.")
        L.append("")
        L.append("| sequence | speed | NEES SFR | NEES WO | false OK SFR / WO | POOR SFR / WO |")
        L.append("|---|---|---|---|---|---|")
        for r in doc["rows"]:
            n = lambda v: "-" if v is None else f"{v:.2f}"
            L.append(f"| {r['sequence']} | {r['speed']} | {n(r.get('nees_sfr_median'))} | {n(r.get('nees_wo_median'))} | "
                     f"{fmt_num(r.get('false_ok_sfr'), 0)} / {fmt_num(r.get('false_ok_wo'), 0)} | "
                     f"{fmt_num(r.get('poor_sfr'), 0)} / {fmt_num(r.get('poor_wo'), 0)} |")
    if doc.get("lookups"):
        L.append("")
        L.append("| look-up | ATE SFR cm | ATE WO cm | matcher ms/scan | optimizer ms/scan | pipeline Hz |")
        L.append("|---|---|---|---|---|---|")
        for r in doc["lookups"]:
            L.append(f"| {r['lookup']} | {fmt(r['ate_sfr_m'], unit='')} | {fmt(r['ate_wo_m'], unit='')} | {r['matcher_ms']:.2f} | "
                     f"{r['optimizer_ms']:.2f} | {r['hz']} |")
    if doc.get("robustness"):
        L.append("")
        L.append("| case | scans | ATE SFR cm | ATE WO cm | WO / clean | ATE WO after 1 s cm | odometry ATE cm (f2f / map) |")
        L.append("|---|---|---|---|---|---|---|")
        for r in doc["robustness"]:
            L.append(f"| {r['case']} | {r['scans']} | {fmt(r['ate_sfr_m'], unit='')} | {fmt(r['ate_wo_m'], unit='')} | "
                     f"{r['ratio_wo_to_clean']} | {fmt(r.get('ate_wo_after_first_s_m'), unit='')} | "
                     f"{fmt(r['ate_odometry_m'], unit='')} / {fmt(r['ate_odometry_local_map_m'], unit='')} |")
    return "\n".join(L) + "\n"


def main():
    ap = argparse.ArgumentParser(prog="fploc bench paper", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help=f"only {', '.join(QUICK)}")
    ap.add_argument("--plan", help="any floor plan (.dxf/.csv/.json); with --scenario (e.g. auto-loop-medium)")
    ap.add_argument("--layers", action="append",
                    help="plan layer globs, comma-separated (repeatable; with --plan), e.g. 'Walls,Columns'")
    ap.add_argument("--units", help="m|cm|mm (with --plan)")
    ap.add_argument("--scenario", action="append", help="scenario name (repeatable); default: all of the paper's")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=0, help="simulate only this many seconds of each scenario (tests)")
    ap.add_argument("--graph", default=os.path.join(ROOT, "graphs", "paper.pbtxt"))
    ap.add_argument("--plots", help="write SVG plots of every trajectory against ground truth into this folder")
    ap.add_argument("--lookups", nargs="?", const="room-small-loop-medium", metavar="SCENARIO",
                    help="also run every matcher look-up on SCENARIO (default room-small-loop-medium)")
    ap.add_argument("--robustness", nargs="?", const="room-small-loop-medium", metavar="SCENARIO",
                    help="also run dropped scans, wall clutter and wrong initial poses on SCENARIO")
    ap.add_argument("--markdown", help="also write the tables as Markdown to this file")
    ap.add_argument("--keep", help="keep the work folder (trajectories) here instead of a temporary one")
    ap.add_argument("--json", action="store_true", help="(JSON is always printed on stdout)")
    a = ap.parse_args()
    if a.plan and not a.scenario:
        ap.error("--plan needs --scenario (e.g. auto-loop-medium)")
    if a.plan:
        if not os.path.exists(a.plan):
            ap.error(f"--plan {a.plan}: no such file")
        a.plan = os.path.abspath(a.plan)
    a.plan_args = []
    # One comma-separated list, as in every other command (fploc sim, fploc map) and in plan.layers.
    a.layers = [g for arg in (a.layers or []) for g in arg.split(",") if g]
    if a.layers:
        a.plan_args += ["--layers", ",".join(a.layers)]
    if a.units:
        a.plan_args += ["--units", a.units]
    a.graph = os.path.abspath(a.graph)
    scenarios = a.scenario or (QUICK if a.quick else ALL)
    if a.plots:
        os.makedirs(a.plots, exist_ok=True)
    work = a.keep or tempfile.mkdtemp(prefix="fploc-bench-paper-", dir=os.environ.get("TMPDIR", "/tmp"))
    os.makedirs(work, exist_ok=True)
    b = Bench(a, work)
    doc = {"rows": [], "baseline": []}
    try:
        for s in scenarios:
            r, base = b.sequence(s)
            doc["rows"].append(r)
            doc["baseline"].append(base)
            if s not in (a.lookups, a.robustness):
                b.drop(s, "")
        if a.lookups:
            doc["lookups"] = b.lookups(a.lookups)
        if a.robustness:
            doc["robustness"] = b.robustness(a.robustness)
    finally:
        for key in list(b.logs):
            b.drop(*key)
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    doc.update({"seed": a.seed, "graph": os.path.relpath(a.graph, ROOT),
                "evaluation": "fploc eval: translational ATE rmse / RPE mean over 1 s of the 6-DoF position, "
                              "ground truth at each pose's time stamp (scan start), no offset, no alignment",
                "paper": PAPER})
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(markdown(doc, sys.argv[1:]))
    print(json.dumps(doc, indent=1))


if __name__ == "__main__":
    main()
