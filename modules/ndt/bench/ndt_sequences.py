#!/usr/bin/env python3
"""The NDT peer beside fploc on the paper's simulated sequences, in one replay per sequence.

For every sequence: `fploc sim` writes the LCM log and the ground truth; `fploc replay` runs
modules/ndt/bench/ndt_bench.pbtxt (one segmenter feeding fploc's features -> matcher -> optimizer and
fploc-ndt, both logged with status and covariance); `fploc eval --uncertainty` scores both (ATE, NEES,
false OK). CPU: the replay's handler time per scan of each node (one process, same messages, same run):
fploc = features + matcher + optimizer, NDT = ndt (the segmenter, shared, is excluded from both).

  python3 modules/ndt/bench/ndt_sequences.py [--scenario NAME ...] [--seed 1] [--duration S] [--keep DIR]
         [--plots DIR] [--markdown FILE]

Prints one JSON document on stdout ({"rows": [...]}).
"""
import argparse
import json
import os
import shutil
import sys
import tempfile

ROOT = os.environ.get("FPLOC_ROOT") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
BUILD = os.environ.get("FPLOC_BUILD_DIR") or os.path.join(ROOT, "build")
BIN = os.path.join(BUILD, "bin")
sys.path.insert(0, os.path.join(ROOT, "tools", "pylib"))
import fploc_tools  # noqa: E402
from fploc_tools import log, read_tum, yaw_of  # noqa: E402

QUICK = ["room-small-loop-medium", "room-no-loop-fast", "corridor-loop-medium"]
METHODS = {"fploc": "wo", "ndt": "ndt"}


def run(cmd):
    return fploc_tools.run(cmd, "ndt_sequences")


def evaluate(gt, est, unc, plan, plot):
    if not os.path.exists(est) or os.path.getsize(est) == 0:
        return None
    cmd = [os.path.join(BIN, "fploc-eval"), "--gt", gt, "--est", est, "--json", "--uncertainty", unc]
    if plot:
        cmd += ["--plot", plot, "--plan", plan]
    return json.loads(run(cmd)[0])


def one(a, scenario, work):
    d = os.path.join(work, scenario)
    os.makedirs(d, exist_ok=True)
    logf, gt = os.path.join(d, "log.lcm"), os.path.join(d, "gt.tum")
    sim = [os.path.join(BIN, "fploc-sim"), "--scenario", scenario, "--seed", str(a.seed), "--out", logf, "--gt", gt]
    if a.duration:
        sim += ["--duration", str(a.duration)]
    log(f"[{scenario}] simulating ...")
    run(sim)
    g = read_tum(gt)
    x0, y0, yaw0 = g[0][1], g[0][2], yaw_of(g[0])
    plan = os.path.join(ROOT, "data", "plans", "corridor.json" if scenario.startswith("corridor") else "room.json")
    sets = [f"matcher.plan.file={plan}", f"optimizer.plan.file={plan}", f"ndt.plan.file={plan}"]
    for n in ("matcher", "ndt"):
        sets += [f"{n}.initial_pose.x={x0!r}", f"{n}.initial_pose.y={y0!r}", f"{n}.initial_pose.yaw={yaw0!r}"]
    for k in METHODS.values():
        sets += [f"{k}_logger.file={os.path.join(d, k + '.tum')}", f"{k}_logger.uncertainty_file={os.path.join(d, k + '.unc')}"]
    sets.append(f"ndt.stats_file={os.path.join(d, 'ndt.stats.json')}")
    cmd = [os.path.join(BIN, "fploc-replay"), "--graph", a.graph, "--log", logf, "--json"]
    for s in sets:
        cmd += ["--set", s]
    log(f"[{scenario}] replaying {len(g)} frames ...")
    rep = json.loads(run(cmd)[0])
    os.remove(logf)
    nodes = {n["name"]: n for n in rep["nodes"]}
    ms = {n: v["total_ms"] / max(len(g), 1) for n, v in nodes.items()}
    row = {"sequence": scenario, "frames": len(g), "node_ms_per_scan": {n: round(v, 3) for n, v in ms.items()},
           "node_errors": {n: v["errors"] for n, v in nodes.items() if v["errors"]}}
    for m, k in METHODS.items():
        plot = os.path.join(a.plots, f"{scenario}-{m}.svg") if a.plots else None
        row[m] = evaluate(gt, os.path.join(d, k + ".tum"), os.path.join(d, k + ".unc"), plan, plot)
    row["fploc_ms_per_scan"] = round(ms.get("features", 0) + ms.get("matcher", 0) + ms.get("optimizer", 0), 3)
    row["ndt_ms_per_scan"] = round(ms.get("ndt", 0), 3)
    p = os.path.join(d, "ndt.stats.json")
    if os.path.exists(p):
        with open(p) as f:
            row["ndt_stats"] = json.load(f)
    def c(m):
        r = row[m]
        return f"ATE {100 * r['ate_rmse_m']:.2f} cm, max {100 * r['ate_max_m']:.1f} cm, NEES med {r['nees_median']:.3g}, " \
               f"false OK {r['false_ok_poses']}" if r else "no poses"
    log(f"[{scenario}] fploc: {c('fploc')}, {row['fploc_ms_per_scan']} ms/scan | ndt: {c('ndt')}, {row['ndt_ms_per_scan']} ms/scan")
    return row


def markdown(rows):
    L = ["| sequence | fploc ATE cm | NDT ATE cm | fploc max cm | NDT max cm | fploc NEES median (3-DoF) | "
         "NDT NEES median | fploc false OK | NDT false OK | NDT POOR/LOST scans | fploc ms/scan | NDT ms/scan |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    def v(r, m, k, scale=1.0, fmt="{:.2f}"):
        x = r.get(m) or {}
        return fmt.format(scale * x[k]) if x.get(k) is not None else "–"
    for r in rows:
        st = r.get("ndt_stats", {})
        L.append(f"| {r['sequence']} | {v(r, 'fploc', 'ate_rmse_m', 100)} | {v(r, 'ndt', 'ate_rmse_m', 100)} | "
                 f"{v(r, 'fploc', 'ate_max_m', 100, '{:.1f}')} | {v(r, 'ndt', 'ate_max_m', 100, '{:.1f}')} | "
                 f"{v(r, 'fploc', 'nees_median', 1, '{:.3g}')} | {v(r, 'ndt', 'nees_median', 1, '{:.3g}')} | "
                 f"{v(r, 'fploc', 'false_ok_poses', 1, '{:.0f}')} | {v(r, 'ndt', 'false_ok_poses', 1, '{:.0f}')} | "
                 f"{st.get('poor', '–')}/{st.get('lost', '–')} | {r['fploc_ms_per_scan']:.2f} | {r['ndt_ms_per_scan']:.2f} |")
    return "\n".join(L) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", action="append", help=f"repeatable; default: {', '.join(QUICK)}")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=0)
    ap.add_argument("--graph", default=os.path.join(ROOT, "modules", "ndt", "bench", "ndt_bench.pbtxt"))
    ap.add_argument("--keep", help="keep trajectories here")
    ap.add_argument("--plots", help="SVG plots (plan, error colouring) into this folder")
    ap.add_argument("--markdown", help="also write the table to this file")
    a = ap.parse_args()
    a.graph = os.path.abspath(a.graph)
    if a.plots:
        a.plots = os.path.abspath(a.plots)
        os.makedirs(a.plots, exist_ok=True)
    work = os.path.abspath(a.keep) if a.keep else tempfile.mkdtemp(prefix="fploc-ndt-bench-")
    os.makedirs(work, exist_ok=True)
    try:
        rows = [one(a, s, work) for s in (a.scenario or QUICK)]
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(markdown(rows))
    log(markdown(rows))
    print(json.dumps({"rows": rows}))


if __name__ == "__main__":
    main()
