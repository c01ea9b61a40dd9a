#!/usr/bin/env python3
"""fploc bench real: fploc (2D LiDAR mode) and AMCL on the real Radish CARMEN logs, non-circular protocol.

Per log: the map is built from the scans and reference (corrected FLASER) poses of the first part of the log
(`fploc import-carmen --map`, a map_server occupancy grid: fploc-grid2d matches scans to its raster, the matcher,
optimizer and AMCL load it as a plan, vectorised on load). Where the first part ends (--split auto, the default):
the smallest split S in 0.20, 0.25 .. 0.80 of the scans whose scans cover >= 75 % of the remaining scans (a scan
is covered when >= 50 % of its returns lie within 10 cm of a return of [0, S) at the reference poses), else
the candidate with the largest covered share: the same rule and values for every log (modules/carmen/coverage.h).
The rest is imported as an LCM log (laser_scan_t + wheel odometry) and run through graphs/lidar2d.pbtxt with
`fploc replay` (grid2d, matcher + optimizer and AMCL in the same run, on the same scans, odometry and map),
started from the reference pose (row "ref") and from a pose 1 m / 10 deg off (row "off"), and scored against
the reference poses (time association, no alignment). Scored: the scans the map covers (>= 50 % of the returns
within 10 cm of an occupied cell at the reference pose); the others are reported separately ("uncovered", and
"all"). LOST %: share of scans whose position error exceeds --lost-m (0.5 m). What each method said of itself
(fploc-pose-logger's uncertainty_file): false OK = poses published OK with a horizontal error > 0.3 m (count and
%), POOR % and the median x/y/yaw NEES of its covariance (3 when consistent). ms per scan: the nodes' thread
CPU time (grid2d; laser2d + matcher + optimizer for the plan path; AMCL's own) over the scans, from replay's
--json. "floor": the RMSE over the covered scans of the map fit started at each scan's own reference pose
(fploc-real-floor): how far the map and the reference poses of the rest disagree; "floor.cauchy" the same with
the fit's Cauchy loss instead of Huber (lower on every log: part of the Huber floor is the loss's bias).
"reference_noise": how noisy the reference poses are themselves, by the three-cornered hat of the reference, fploc's
estimate (its poses published OK) and the wheel odometry (`fploc eval --hat`, modules/eval/reference_noise.h): each
one's noise from the increments between consecutive scans (and 2 scans apart: white noise gives the same). Against a reference with
per-pose noise sigma even a perfect localizer scores an ATE of ~sigma, so each method's "ate_less_reference_noise_m"
(sqrt(ATE^2 - sigma^2), an estimate of its own error) and "nees_median_with_reference_noise" (the reference's
variance added to the published covariance) are given beside ATE and NEES. Plots
per row, framed on the tracks with 3 m around them, a legend and a scale bar in metres: ROW.png (reference green,
fploc blue, AMCL orange) and ROW-fploc.png (without AMCL).

  fploc bench real [--json] [--markdown FILE] [--logs intel,aces] [--split auto|F] [--end 0.6] [--out DIR] [--rows ref,off]
  fploc bench real --from-json RUN.json --markdown FILE     (the tables of an earlier run's JSON, nothing rerun)
  fploc bench real --rows global [--global-every 50 --global-starts 5 --global-scans 300]   (global localization:
      no start pose, started at several covered scans of each log; JSON "global_rows", see global_starts())
"""
import argparse, json, math, os, subprocess, sys

ROOT = os.environ.get("FPLOC_ROOT", os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..")))
BUILD = os.environ.get("FPLOC_BUILD_DIR", os.path.join(ROOT, "build"))
SHARED = os.environ.get("FPLOC_SHARED_DIR", os.path.join(ROOT, "..", "shared"))
BIN = os.path.join(BUILD, "bin")
sys.path.insert(0, os.path.join(ROOT, "tools", "pylib"))
import fploc_tools  # noqa: E402
LOGS = ["intel", "aces", "fhw", "csail", "freiburg-079"]
FALSE_OK_M = 0.3  # a pose published OK with a larger horizontal error is a false OK (as in fploc bench realism)


def run(cmd, **kw):
    p = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if p.returncode != 0:
        sys.stderr.write(p.stderr)
        raise SystemExit(f"fploc bench real: {os.path.basename(cmd[0])} failed ({p.returncode})")
    return p


def read_tum(path):
    out = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            t = line.split()
            out[round(float(t[0]), 4)] = (float(t[1]), float(t[2]), 2 * math.atan2(float(t[6]), float(t[7])))
    return out


def read_status(path):
    """Status (0 OK, 1 POOR, 2 LOST) and x/y/yaw covariance per pose time: fploc-pose-logger's uncertainty_file
    ("t status xx xy xyaw yy yyaw yawyaw", modules/eval/uncertainty.h). {} when the file is absent."""
    out = {}
    if not path or not os.path.exists(path):
        return out
    with open(path) as f:
        for line in f:
            v = line.split()
            if not v or v[0].startswith("#") or len(v) < 8:
                continue
            out[round(float(v[0]), 4)] = (int(v[1]), [float(x) for x in v[2:8]])
    return out


def reference_noise(ref, est, status, odom, ok_path):
    """The three-cornered hat of the reference, an estimate and the wheel odometry (fploc eval --hat), at lags 1 and
    2, over the increments whose two poses the estimate published OK (its POOR/LOST stretches, errors of the estimate
    up to metres, would only add noise to the split): {"pose_sigma_xy_m", "pose_sigma_yaw_rad"} of the reference at
    lag 1 (per pose, if white; a negative value means the assumptions fail there), the same at lag 2, and the
    estimate's and odometry's at lag 1."""
    st = read_status(status)
    with open(est) as f, open(ok_path, "w") as g:
        for line in f:
            v = line.split()
            if v and not v[0].startswith("#") and st.get(round(float(v[0]), 4), (1,))[0] == 0:
                g.write(line)
    out = {}
    for lag in (1, 2):
        h = json.loads(run([os.path.join(BIN, "fploc-eval"), "--gt", ref, "--est", ok_path, "--hat", odom, "--hat-lag",
                            str(lag), "--max-dt", "0.001", "--json"]).stdout)["hat"]
        if lag == 1:
            out = {"pose_sigma_xy_m": h["gt"]["pose_sigma_xy_m"], "pose_sigma_yaw_rad": h["gt"]["pose_sigma_yaw_rad"],
                   "increments": h["increments"], "estimate": ok_path, "estimate_pose_sigma_xy_m": h["est"]["pose_sigma_xy_m"],
                   "odometry_pose_sigma_xy_m": h["third"]["pose_sigma_xy_m"]}
        else:
            out["lag2"] = {"pose_sigma_xy_m": h["gt"]["pose_sigma_xy_m"], "pose_sigma_yaw_rad": h["gt"]["pose_sigma_yaw_rad"]}
    return out


def score(gt_path, est_path, lost_m, keep=None, status_path=None, ref_noise=None):
    """ATE (RMSE of the position error, no alignment: both in the map frame, the reference pose associated by time
    with fploc eval's association), max, LOST % (position error > lost_m; a scan without an estimate counts as
    LOST and as its own entry in "missing"). keep: the reference times to score (None: all); the others are
    reported as "uncovered" with their own ATE. ref_noise (reference_noise()): also the ATE less the reference's
    noise and the NEES with the reference's variance added to the covariance."""
    gt, est, st = read_tum(gt_path), read_tum(est_path), read_status(status_path)
    def part(times):
        errs = [math.hypot(est[k][0] - gt[k][0], est[k][1] - gt[k][1]) if k in est else float("inf") for k in times]
        fin = [e for e in errs if math.isfinite(e)]
        out = {"scans": len(times), "ate_m": math.sqrt(sum(e * e for e in fin) / len(fin)) if fin else float("nan"),
               "max_m": max(fin) if fin else float("nan"), "missing": len(errs) - len(fin),
               "lost_pct": 100.0 * sum(e > lost_m for e in errs) / max(1, len(errs))}
        # A negative sigma (the hat's assumptions fail) gives no figure: the keys are null. A negative yaw sigma alone
        # counts as no yaw noise.
        rn = ref_noise if ref_noise and ref_noise["pose_sigma_xy_m"] > 0 else None
        if ref_noise is not None:
            out["ate_less_reference_noise_m"] = (math.sqrt(max(0.0, out["ate_m"] ** 2 - rn["pose_sigma_xy_m"] ** 2))
                                                 if rn and fin else None)
        if st:  # what the method said of itself: false OK (status OK, error > FALSE_OK_M), POOR/LOST shares, NEES
            said = [(k, e) for k, e in zip(times, errs) if k in st and math.isfinite(e)]
            nees, nees_rn = [], []
            for k, e in said:
                dyaw = (est[k][2] - gt[k][2] + math.pi) % (2 * math.pi) - math.pi
                err = (est[k][0] - gt[k][0], est[k][1] - gt[k][1], dyaw)
                v = fploc_tools.nees3(err, st[k][1])
                if v is not None:
                    nees.append(v)
                if rn:  # the reference's per-axis variance (half the horizontal) and yaw variance added
                    c, a2 = list(st[k][1]), rn["pose_sigma_xy_m"] ** 2 / 2
                    c[0] += a2
                    c[3] += a2
                    c[5] += max(0.0, rn["pose_sigma_yaw_rad"]) ** 2
                    v = fploc_tools.nees3(err, c)
                    if v is not None:
                        nees_rn.append(v)
            nees.sort()
            nees_rn.sort()
            if ref_noise is not None:
                out["nees_median_with_reference_noise"] = nees_rn[len(nees_rn) // 2] if nees_rn else None
            n = max(1, len(said))
            out.update({"status_poses": len(said),
                        "false_ok_poses": sum(st[k][0] == 0 and e > FALSE_OK_M for k, e in said),
                        "false_ok_pct": 100.0 * sum(st[k][0] == 0 and e > FALSE_OK_M for k, e in said) / n,
                        "poor_pct": 100.0 * sum(st[k][0] == 1 for k, _ in said) / n,
                        "said_lost_pct": 100.0 * sum(st[k][0] == 2 for k, _ in said) / n,
                        "nees_median": nees[len(nees) // 2] if nees else None})
        return out
    times = sorted(gt)
    covered = [k for k in times if keep is None or k in keep]
    out = part(covered)
    # fploc eval on the same pairs (cross-check of the association and the RMSE).
    j = json.loads(run([os.path.join(BIN, "fploc-eval"), "--gt", gt_path, "--est", est_path, "--json"]).stdout)
    out["all"] = {**part(times), "fploc_eval_ate_m": j["ate_rmse_m"], "fploc_eval_poses": j["poses"]}
    out["uncovered"] = part([k for k in times if keep is not None and k not in keep])
    return out


def global_starts(src, plan, imp, a, d):
    """--rows global: global localization (no start pose: fploc-grid2d's GridLocalizer::start_global, the whole map
    searched) started at every --global-every-th covered scan of the localized part (at most --global-starts), each
    run in-process by fploc-real-track (the node's computation without LCM: a replay per start would run the whole
    graph each time) over --global-scans scans. Per start: the scans and the reference's metres until the first OK
    pose, whether that pose is within FALSE_OK_M / 5 deg of the reference (locked), the OK poses farther than
    FALSE_OK_M off (wrong OK) over the whole run, and the ATE over the covered scans from the lock on, beside the
    ATE of the tracker started at the first scan's reference pose (fploc-real-track --start ref, one run) over the
    same scans."""
    first, end = imp["first_scan"], imp["end_scan"]
    covered = [first + i for i, c in enumerate(imp["coverage"]) if c >= imp["coverage_ratio"]]
    starts = covered[::a.global_every][:a.global_starts]
    track = os.path.join(BIN, "fploc-real-track")
    last = min(end, max(starts) + a.global_scans) if starts else first
    ref_rows = json.loads(run([track, src, "--map", plan, "--first-scan", str(first), "--end-scan", str(last),
                               "--start", "ref"]).stdout)["scans"]
    ref_err = {r["scan"]: r["err_m"] for r in ref_rows}
    cov = set(covered)
    out = []
    for s0 in starts:
        e0 = min(end, s0 + a.global_scans)
        j = json.loads(run([track, src, "--map", plan, "--first-scan", str(s0), "--end-scan", str(e0), "--start", "global"]).stdout)
        rows = j["scans"]
        with open(os.path.join(d, f"global-{s0}.json"), "w") as f:
            json.dump(j, f)
        lock = next((i for i, r in enumerate(rows) if r["status"] == 0), None)
        travel = 0.0
        for i in range(1, (lock if lock is not None else len(rows) - 1) + 1):
            travel += math.hypot(rows[i]["ref_x"] - rows[i - 1]["ref_x"], rows[i]["ref_y"] - rows[i - 1]["ref_y"])
        wrong = [r["scan"] for r in rows if r["status"] == 0 and r["err_m"] > FALSE_OK_M]
        after = [r for r in rows[lock:] if r["scan"] in cov] if lock is not None else []
        rmse = lambda v: math.sqrt(sum(e * e for e in v) / len(v)) if v else None
        pre = rows[:lock] if lock is not None else rows
        out.append({"first_scan": s0, "end_scan": e0, "scans": len(rows), "locked": lock is not None,
                    "lock_scan": rows[lock]["scan"] if lock is not None else None,
                    "scans_to_lock": lock + 1 if lock is not None else None, "metres_to_lock": travel,
                    "lock_err_m": rows[lock]["err_m"] if lock is not None else None,
                    "lock_err_deg": abs(rows[lock]["err_yaw_deg"]) if lock is not None else None,
                    "locked_correctly": lock is not None and rows[lock]["err_m"] <= FALSE_OK_M and abs(rows[lock]["err_yaw_deg"]) <= 5,
                    "wrong_ok_poses": len(wrong), "wrong_ok_scans": wrong[:20],
                    "ok_pct": 100.0 * sum(r["status"] == 0 for r in rows) / max(1, len(rows)),
                    "ate_after_lock_m": rmse([r["err_m"] for r in after]),
                    "ref_ate_same_scans_m": rmse([ref_err[r["scan"]] for r in after if r["scan"] in ref_err]),
                    "covered_scans_after_lock": len(after),
                    "ms_per_scan_before_lock": sum(r["ms"] for r in pre) / max(1, len(pre)),
                    "ms_per_scan": j["ms_per_scan"], "max_hypotheses": max((r["hypotheses"] for r in rows), default=0)})
    locked = [o for o in out if o["locked"]]
    med = lambda v: sorted(v)[len(v) // 2] if v else None
    pooled = lambda k, n: (math.sqrt(sum(o[k] ** 2 * o[n] for o in locked if o[k] is not None) /
                                     max(1, sum(o[n] for o in locked if o[k] is not None)))
                           if any(o[k] is not None for o in locked) else None)
    summary = {"starts": len(out), "locked": len(locked), "locked_correctly": sum(o["locked_correctly"] for o in out),
               "locked_correctly_pct": 100.0 * sum(o["locked_correctly"] for o in out) / max(1, len(out)),
               "scans_to_lock_median": med([o["scans_to_lock"] for o in locked]),
               "scans_to_lock_max": max((o["scans_to_lock"] for o in locked), default=None),
               "metres_to_lock_median": med([o["metres_to_lock"] for o in locked]),
               "metres_to_lock_max": max((o["metres_to_lock"] for o in locked), default=None),
               "wrong_ok_poses": sum(o["wrong_ok_poses"] for o in out),
               "ate_after_lock_m": pooled("ate_after_lock_m", "covered_scans_after_lock"),
               "ref_ate_same_scans_m": pooled("ref_ate_same_scans_m", "covered_scans_after_lock"),
               "ms_per_scan_before_lock": sum(o["ms_per_scan_before_lock"] for o in out) / max(1, len(out))}
    return {"log": os.path.basename(src).replace("-corrected.log.gz", ""), "start": "global",
            "global_every": a.global_every, "global_scans": a.global_scans, "summary": summary, "starts": out}


def global_markdown(rows):
    out = ["", "Global localization (`--rows global`: no start pose, the whole map searched; fploc-real-track per start): "
           "starts = every Nth covered scan; locked = the first OK pose within 0.3 m / 5 deg of the reference; scans and "
           "metres (the reference's path) until the first OK pose; wrong OK = OK poses more than 0.3 m off; ATE after the "
           "lock over the covered scans, and the tracker started at the reference pose over the same scans.", "",
           "| log | starts | locked correctly | scans to lock (median / max) | metres to lock (median / max) | wrong OK | "
           "ATE after lock | ref-start ATE, same scans | ms per scan before lock |", "|" + "---|" * 9]
    for r in rows:
        g = r["summary"]
        n = lambda v, f="{:.0f}": "-" if v is None else f.format(v)
        out.append(f"| {r['log']} | {g['starts']} | {g['locked_correctly']} / {g['starts']} | {n(g['scans_to_lock_median'])} / "
                   f"{n(g['scans_to_lock_max'])} | {n(g['metres_to_lock_median'], '{:.1f}')} / {n(g['metres_to_lock_max'], '{:.1f}')} | "
                   f"{g['wrong_ok_poses']} | {cm(g['ate_after_lock_m'])} | {cm(g['ref_ate_same_scans_m'])} | "
                   f"{g['ms_per_scan_before_lock']:.0f} |")
    return "\n".join(out) + "\n"


def cm(v, digits=1):
    return "-" if v is None or not math.isfinite(v) else f"{v * 100:.{digits}f}"


def markdown(doc, cmdline):
    """The run as Markdown: per row fploc (the scored estimator) against AMCL, the floor and the reference's noise,
    what fploc said of itself, and the plots (paths as the run wrote them)."""
    p = doc["protocol"]
    out = [f"# Radish logs: fploc (2D mode) and AMCL, map from the first part of each log\n",
           f"Generated by `{cmdline}`. Protocol: split {p['split']}, map resolution {p['resolution_m']} m, scored: "
           f"{p['scored']}; LOST = error > {p['lost_m']} m; graph `{os.path.basename(p['graph'])}`. ATE = RMSE of the "
           "horizontal error against the reference (FLASER) poses, no alignment, in cm. ms = thread CPU per scan. "
           "Floor = each scan's map fit started at its reference pose (Huber / Cauchy). Reference noise = the "
           "reference's own per-pose noise (three-cornered hat of reference, fploc and the wheels; `fploc eval "
           "--hat`); \"fploc less it\" = sqrt(ATE^2 - noise^2).\n",
           "| log | start | covered scans | fploc ATE | max | LOST | POOR | false OK | ms | AMCL ATE | AMCL max | AMCL LOST | AMCL ms "
           "| fploc <= AMCL / 2 | floor | reference noise | fploc less it |",
           "|" + "---|" * 17]
    for r in doc["rows"]:
        f, a, fl, n = r["fploc"], r["amcl"], r["floor"], r.get("reference_noise") or {}
        out.append(f"| {r['log']} | {r['start']} | {r['covered_scans']} | {cm(f['ate_m'])} | {cm(f['max_m'], 0)} | "
                   f"{f['lost_pct']:.1f} % | {fploc_tools.fmt_num(f.get('poor_pct'), 1)} % | {f.get('false_ok_poses', '-')} | "
                   f"{f['ms_per_scan']:.1f} | {cm(a['ate_m'])} | {cm(a['max_m'], 0)} | {a['lost_pct']:.1f} % | "
                   f"{a['ms_per_scan']:.2f} | {'yes' if r['fploc_half_of_amcl'] else 'no'} | "
                   f"{cm(fl['ate_m'])} / {cm(fl.get('cauchy', {}).get('ate_m'))} | {cm(n.get('pose_sigma_xy_m'))} | "
                   f"{cm(f.get('ate_less_reference_noise_m'))} |")
    out += ["", "What each estimator said of itself (covered scans): NEES = median x/y/yaw NEES of its covariance (3 when "
            "consistent), and with the reference's noise added to it; false OK = published OK more than 0.3 m off.", "",
            "| log | start | fploc NEES | with the reference's noise | fploc false OK | plan path (matcher + optimizer) ATE | "
            "plan path max | plan path POOR | plan path LOST | plan path false OK | plan path NEES | with the reference's noise | "
            "plan path ms | AMCL NEES |", "|" + "---|" * 14]
    for r in doc["rows"]:
        f, a, pl = r["fploc"], r["amcl"], r["fploc_plan"]
        nees = lambda m, k="nees_median": "-" if m.get(k) is None else f"{m[k]:.1f}"
        out.append(f"| {r['log']} | {r['start']} | {nees(f)} | {nees(f, 'nees_median_with_reference_noise')} | "
                   f"{f.get('false_ok_poses', '-')} | {cm(pl['ate_m'])} | {pl['max_m'] * 100:.0f} | "
                   f"{fploc_tools.fmt_num(pl.get('poor_pct'), 1)} % | {pl['lost_pct']:.1f} % | {pl.get('false_ok_poses', '-')} | "
                   f"{nees(pl)} | {nees(pl, 'nees_median_with_reference_noise')} | {pl['ms_per_scan']:.1f} | {nees(a)} |")
    # Paths under the run's --out directory (a reader of the table has no copy of the runner's /tmp).
    rel = lambda f: os.path.join(os.path.basename(os.path.dirname(f)), os.path.basename(f))
    out += ["", "Plots, under the run's `--out` directory (reference green, fploc blue, AMCL orange; `-fploc.png` without AMCL):", ""]
    out += [f"- {r['log']} {r['start']}: `{rel(r['plot'])}`, `{rel(r['plot_fploc'])}`" for r in doc["rows"]]
    if doc.get("global_rows"):
        out.append(global_markdown(doc["global_rows"]))
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description="fploc vs AMCL on the Radish logs (non-circular: map from the first part)")
    ap.add_argument("--json", action="store_true", help="the report as JSON on stdout")
    ap.add_argument("--logs", default=",".join(LOGS),
                    help="comma-separated Radish logs (NAME-corrected.log.gz under the shared data) (default: %(default)s)")
    ap.add_argument("--split", default="auto",
                    help="auto (default): the coverage rule of modules/carmen/coverage.h (the smallest split in 0.20, "
                         "0.25 .. 0.80 whose map covers >= 75 %% of the remaining scans, else the best of them), or a fraction: "
                         "map from scans [0, split), localize [split, end) (default: %(default)s)")
    ap.add_argument("--end", type=float, default=1.0, help="localize up to this fraction of the log's scans (a short test run; above the split) (default: %(default)s)")
    ap.add_argument("--resolution", type=float, default=0.05, help="map cell size [m] (default: %(default)s)")
    ap.add_argument("--rows", default="ref,off",
                    help="starts to run: ref (the reference pose of the first scan), off (1 m / 10 deg off it), global (no "
                         "start pose: global localization started at several scans, as the global-* options below say; JSON global_rows) "
                         "(default: %(default)s)")
    ap.add_argument("--global-every", type=int, default=50, help="global: a start at every this-many-th covered scan (default: %(default)s)")
    ap.add_argument("--global-starts", type=int, default=5, help="global: at most this many starts per log (default: %(default)s)")
    ap.add_argument("--global-scans", type=int, default=300, help="global: scans run from each start (default: %(default)s)")
    # The map of the first part: a cell is occupied with >= min_hits hits and hits >= occupied_ratio of hits +
    # pass-throughs, and a beam marks nothing within hit_clearance of its hit free. The bench uses fploc
    # import-carmen's defaults (modules/carmen carmen.h GridConfig: 1 / 0.1 / 0.1 m); these options override them.
    # With 2 / 0.25 / 0 beams grazing a wall erased it: only 33-60 % of a scan's returns lay within 10 cm of an
    # occupied cell at its own reference pose (fhw); with 1 / 0.1 / 0.1 m, 97 %.
    ap.add_argument("--min-hits", type=int, help="map: occupied needs this many hits (default: fploc import-carmen's, see its --help)")
    ap.add_argument("--occupied-ratio", type=float,
                    help="map: occupied when hits >= this share of hits + pass-throughs (default: fploc import-carmen's)")
    ap.add_argument("--hit-clearance", type=float,
                    help="map: a beam marks no cell within this [m] of its hit free (default: fploc import-carmen's)")
    # Refining the mapping scans' poses before rasterising (each scan aligned to the others' mean lines with a prior on
    # its reference pose, modules/laser2d/map_refine.h): 0 = off. Not the default: on the five logs it moved the
    # floor by -0.3..+0.5 cm and the tracker's ATE both ways (docs/notes/real2d.md, twenty-first pass).
    ap.add_argument("--refine-map-poses", type=int, default=0,
                    help="refine the mapping scans' poses by this many passes before the map is rasterised (0: off) (default: %(default)s)")
    ap.add_argument("--lost-m", type=float, default=0.5, help="a scan whose position error exceeds this [m] counts as LOST (default: %(default)s)")
    ap.add_argument("--out", default="bench-real", help="directory for the per-log maps, logs, tracks and plots (default: %(default)s)")
    ap.add_argument("--graph", default=os.path.join(ROOT, "graphs", "lidar2d.pbtxt"),
                    help="the graph replayed on each log (default: %(default)s)")
    ap.add_argument("--fploc", default="grid", choices=["grid", "wo"],
                    help="fploc's estimate: grid (fploc-grid2d on the map's raster) or wo (matcher + optimizer on its "
                         "vectorised plan); the other is reported too (fploc_grid, fploc_plan) (default: %(default)s)")
    ap.add_argument("--markdown", help="write the tables (Markdown) here")
    ap.add_argument("--from-json", help="an earlier run's --json output: write its --markdown, run nothing")
    a = ap.parse_args()
    if a.from_json:
        if not a.markdown:
            raise SystemExit("fploc bench real: --from-json needs --markdown FILE")
        with open(a.from_json) as f:
            doc = json.load(f)
        if doc.get("bench") != "real" or "rows" not in doc:
            raise SystemExit(f"fploc bench real: {a.from_json}: not the JSON of fploc bench real --json")
        with open(a.markdown, "w") as f:
            f.write(markdown(doc, f"fploc bench real (tables of {os.path.basename(a.from_json)})"))
        return 0
    radish = os.path.join(SHARED, "data", "recordings", "radish")
    if not os.path.isdir(radish):
        print(f"fploc bench real: {radish} absent (shared data); nothing to do", file=sys.stderr)
        return 0
    os.makedirs(a.out, exist_ok=True)
    # The map options given here; the others are import-carmen's defaults (its --json reports what it used).
    map_opts = []
    for opt, v in (("--min-hits", a.min_hits), ("--occupied-ratio", a.occupied_ratio), ("--hit-clearance", a.hit_clearance)):
        if v is not None:
            map_opts += [opt, str(v)]
    map_used = None
    rows, grows = [], []
    row_kinds = a.rows.split(",")
    bad = [r for r in row_kinds if r not in ("ref", "off", "global")]
    if bad:
        raise SystemExit(f"fploc bench real: --rows: unknown row kind '{bad[0]}' (use ref, off, global)")
    for name in a.logs.split(","):
        src = os.path.join(radish, f"{name}-corrected.log.gz")
        d = os.path.join(a.out, name)
        os.makedirs(d, exist_ok=True)
        lcm, ref, mapdir = os.path.join(d, "rest.lcm"), os.path.join(d, "ref.tum"), os.path.join(d, "map")
        odom = os.path.join(d, "odom.tum")
        split = ["--auto-split"] if a.split == "auto" else ["--begin", a.split, "--map-begin", "0", "--map-end", a.split]
        imp = json.loads(run([os.path.join(BIN, "fploc-import-carmen"), src, "--out", lcm, "--tum", ref, "--odom-tum", odom, "--end", str(a.end),
                              "--map", mapdir] + split + [
                              "--resolution", str(a.resolution), "--json"] + map_opts +
                             (["--refine-map-poses", str(a.refine_map_poses)] if a.refine_map_poses > 0 else [])).stdout)
        plan = os.path.join(mapdir, "map.yaml")
        map_used = {k: imp["map"][k] for k in ("min_hits", "occupied_ratio", "hit_clearance_m")}
        reft = read_tum(ref)
        t0 = min(reft.items())[1]
        # Scans the map covers (>= coverage_ratio of the returns within 10 cm of an occupied cell at the reference
        # pose) are scored; the others are reported separately ("uncovered").
        keep = {k for k, c in zip(sorted(reft), imp["coverage"]) if c >= imp["coverage_ratio"]}
        # The floor: every scan's map fit started at its own reference pose (fploc-real-floor); its offset from
        # the reference is how much the map (first part's scans at their reference poses) and the reference poses
        # of the rest disagree. RMSE over the covered scans, as fploc's ATE.
        def floor_of(loss):
            fl = json.loads(run([os.path.join(BIN, "fploc-real-floor"), src, "--map", plan, "--first-scan", str(imp["first_scan"]),
                                 "--end-scan", str(imp["end_scan"]), "--fit-loss", loss]).stdout)["scans"]
            fe = [r["dxy_m"] for k, r in zip(sorted(reft), fl) if k in keep]
            return {"ate_m": math.sqrt(sum(e * e for e in fe) / len(fe)) if fe else float("nan"),
                    "median_m": sorted(fe)[len(fe) // 2] if fe else float("nan"), "max_m": max(fe) if fe else float("nan")}
        floor = floor_of("huber")
        # The same with the fit's Cauchy loss (GridLocalizerConfig::fit_loss): Huber's constant pull of returns on
        # structure the map lacks biases the fit, so the Huber floor is partly the objective's, not the map's.
        floor["cauchy"] = floor_of("cauchy")
        if "global" in row_kinds:
            g = global_starts(src, plan, imp, a, d)
            grows.append(g)
            gs = g["summary"]
            print(f"{name:13s} global starts {gs['starts']} locked correctly {gs['locked_correctly']} scans to lock median "
                  f"{gs['scans_to_lock_median']} max {gs['scans_to_lock_max']} wrong OK {gs['wrong_ok_poses']} ATE after lock "
                  f"{cm(gs['ate_after_lock_m'])} cm (ref start {cm(gs['ref_ate_same_scans_m'])} cm) "
                  f"{gs['ms_per_scan_before_lock']:.0f} ms/scan before lock", file=sys.stderr)
        for row in [r for r in row_kinds if r != "global"]:
            x, y, yaw = t0
            if row == "off":  # 1 m off (along the heading's left diagonal) and 10 degrees
                x += math.cos(yaw + math.pi / 4)
                y += math.sin(yaw + math.pi / 4)
                yaw += math.radians(10)
            sets = []
            for n in ("matcher", "optimizer", "amcl", "grid2d"):
                sets += ["--set", f"{n}.plan.file={os.path.abspath(plan)}"]
            for n in ("matcher", "amcl", "grid2d"):
                sets += ["--set", f"{n}.initial_pose.x={x}", "--set", f"{n}.initial_pose.y={y}", "--set", f"{n}.initial_pose.yaw={yaw}"]
            est = {k: os.path.abspath(os.path.join(d, f"{row}-{k}.tum")) for k in ("wo", "sfr", "amcl", "grid")}
            unc = {k: os.path.abspath(os.path.join(d, f"{row}-{k}.status")) for k in ("wo", "amcl", "grid")}
            sets += ["--set", f"wo_logger.file={est['wo']}", "--set", f"sfr_logger.file={est['sfr']}",
                     "--set", f"amcl_logger.file={est['amcl']}", "--set", f"grid_logger.file={est['grid']}"]
            for k in unc:
                sets += ["--set", f"{k}_logger.uncertainty_file={unc[k]}"]
            rep = json.loads(run([os.path.join(BIN, "fploc-replay"), "--graph", a.graph, "--log", lcm, "--json"] + sets).stdout)
            cpu = {n["name"]: n.get("cpu_ms", 0.0) for n in rep["nodes"]}
            scans = imp["end_scan"] - imp["first_scan"]
            plan_ms = (cpu.get("laser2d", 0) + cpu.get("matcher", 0) + cpu.get("optimizer", 0)) / max(1, scans)
            grid_ms = cpu.get("grid2d", 0) / max(1, scans)
            amcl_ms = cpu.get("amcl", 0) / max(1, scans)
            # The reference's own noise, from fploc's estimate (the one scored as "fploc") and the wheels.
            rnoise = reference_noise(ref, est[a.fploc], unc[a.fploc], odom, os.path.join(d, f"{row}-{a.fploc}-ok.tum"))
            g, p, am = (score(ref, est[k], a.lost_m, keep, unc[k], rnoise) for k in ("grid", "wo", "amcl"))
            f, fploc_ms = (g, grid_ms) if a.fploc == "grid" else (p, plan_ms)
            png = os.path.join(d, f"{row}.png")
            # Framed on the tracks (3 m around them), a legend and a scale bar in metres (fploc occupancy --label).
            frame = ["--scale", "2", "--crop-margin", "3", "--crop-to", "tracks"]
            run([os.path.join(BIN, "fploc-occupancy"), plan, "--png", png] + frame + ["--tum", ref, "--label", "reference",
                 "--tum", est[a.fploc], "--label", f"fploc ({a.fploc})", "--tum", est["amcl"], "--label", "AMCL"])
            # AMCL's jumps hide fploc's track in the picture of all three: fploc alone (blue) on the reference (green).
            png_f = os.path.join(d, f"{row}-fploc.png")
            run([os.path.join(BIN, "fploc-occupancy"), plan, "--png", png_f] + frame + ["--tum", ref, "--label", "reference",
                 "--tum", est[a.fploc], "--label", f"fploc ({a.fploc})"])
            r = {"log": name, "start": row, "scans": scans, "map_scans": imp["map"]["end_scan"],
                 "split": imp["split"] if "split" in imp else {"fraction": float(a.split)}, "covered_scans": len(keep),
                 "floor": floor, "reference_noise": rnoise, "map_refine": imp["map"].get("refine"),
                 "fploc": {**f, "ms_per_scan": fploc_ms, "estimator": a.fploc}, "amcl": {**am, "ms_per_scan": amcl_ms},
                 "fploc_grid": {**g, "ms_per_scan": grid_ms}, "fploc_plan": {**p, "ms_per_scan": plan_ms},
                 "fploc_half_of_amcl": f["ate_m"] <= 0.5 * am["ate_m"], "plot": png, "plot_fploc": png_f}
            rows.append(r)
            print(f"{name:13s} {row:3s} split {r['split']['fraction']:.2f} scans {scans:5d} covered {len(keep):5d}  fploc ATE {f['ate_m']*100:8.1f} cm max {f['max_m']*100:8.1f} cm "
                  f"LOST {f['lost_pct']:5.1f} % false OK {f.get('false_ok_poses', '-')} POOR {fploc_tools.fmt_num(f.get('poor_pct'), 1):>4s} % {fploc_ms:6.2f} ms | AMCL ATE {am['ate_m']*100:8.1f} cm max {am['max_m']*100:8.1f} cm "
                  f"LOST {am['lost_pct']:5.1f} % {amcl_ms:6.2f} ms | other fploc ({'wo' if a.fploc == 'grid' else 'grid'}) "
                  f"ATE {(p if a.fploc == 'grid' else g)['ate_m']*100:8.1f} cm | all scans: fploc {f['all']['ate_m']*100:.1f} cm "
                  f"LOST {f['all']['lost_pct']:.1f} %, AMCL {am['all']['ate_m']*100:.1f} cm | floor {floor['ate_m']*100:.1f} cm (Cauchy fit {floor['cauchy']['ate_m']*100:.1f} cm) | reference noise {rnoise['pose_sigma_xy_m']*100:.1f} cm "
                  f"(lag 2: {rnoise['lag2']['pose_sigma_xy_m']*100:.1f}), fploc less it {cm(f['ate_less_reference_noise_m'])} cm", file=sys.stderr)
    doc = {"bench": "real", "protocol": {"split": a.split, "scored": "scans covered by the map", "end": a.end, "resolution_m": a.resolution,
                                         "map": {**(map_used or {"min_hits": a.min_hits, "occupied_ratio": a.occupied_ratio,
                                                                  "hit_clearance_m": a.hit_clearance}),
                                                 "refine_map_poses": a.refine_map_poses},
                                         "lost_m": a.lost_m, "graph": a.graph}, "rows": rows}
    if grows:
        doc["global_rows"] = grows
    if a.json:
        print(json.dumps(doc, indent=1))
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(markdown(doc, "bin/fploc bench real " + " ".join(sys.argv[1:])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
