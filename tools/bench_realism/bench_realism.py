#!/usr/bin/env python3
"""fploc bench realism: localization and plan-change detection on worlds that differ from the plan.

For every world family (modules/sim perturb.h: clean, asbuilt-2cm, asbuilt-5cm, scale-0.5pct, renovated,
glass, shelves, doors, crowd-15, mixed): `fploc sim --perturb FAMILY` writes an LCM log of the world and the
truth of the difference (LOG.world.json); `fploc replay` runs graphs/realism.pbtxt (fploc = matcher +
optimizer, AMCL + LiDAR odometry, plan_diff) on it with --record, keeping every pose_t with its status and
covariance; if a `fploc-ndt` binary and graphs/ndt.pbtxt exist, the NDT peer runs on the same log too.
"fploc": matcher + optimizer with the online drawing-scale correction (options plan_diff_scale, their plan_diff
inputs connected to FPLOC_PLAN_DIFF with plan_diff_weight 1 = no down-weighting; the plan_diff node then counts
in fploc's CPU, run on --scale-frame-hz scans per second); --no-online-scale: the plain matcher + optimizer.
"fploc+downweight": fploc with the plan diff used live, in the same single pass: the matcher and the optimizer
subscribe to FPLOC_PLAN_DIFF (their `plan_diff` input) and give the elements it marks missing or moved (and
the other face of such a wall) weight `plan_diff_weight` (0: left out).
Second passes of fploc: "fploc+scale" against the plan rescaled by its drawing-scale estimate (where that is
significant); with --methods ...,fploc+diff also "fploc+diff" against the plan the detector corrected
(missing elements dropped, moved ones shifted by the offset it measured; where it marked any).
`fploc map diff` on the recorded run gives the change detector's verdicts, scored against the truth.

Per family x method: horizontal ATE (rmse, no alignment, pose at its own time stamp against the ground
truth at the same scan), max error, LOST % (status 2), false-OK % (status OK with horizontal error > 0.3 m),
NEES median of (x, y, yaw) from the pose_t covariance (3 dof: consistent means 3), ms per scan (thread CPU
of the method's nodes, `fploc replay --json`, one core: `ms_per_scan` with the segmenter every method shares,
`ms_per_scan_localizer` without it: fploc = features + matcher + optimizer (+ plan_diff for
fploc+downweight), NDT = ndt, AMCL = features + odometry + amcl). Per family: change detection precision /
recall. --jobs N simulates and replays N families at once (CPU times are per thread, so unaffected).

Prints one JSON document on stdout (progress on stderr):
  {"rows": [{"family", "method", "ate_m", "ate_aligned_m" (after the best rigid alignment of the whole trajectory, as
             TUM / evo ATE), "ate_floor_m" (the family's floor: the rigid part of the walls' as-built offsets along the
             truth path, see gauge_floor; same for every method), "ate_bound_m" (as-built worlds: the rms expected
             error of the best per-scan estimate against the plan, `fploc eval --asbuilt-bound`, from the fploc run's
             features at the true poses; same for every method), "ate_bound_window_m" (the same when the scans within
             5 s share each scan's pose error, as with exact odometry over a 10 s window), "max_m", "lost", "false_ok", "false_ok_poses", "poor", "nees_median", "nees_poses",
             "ms_per_scan", "ms_per_scan_localizer", "scans" (what the CPU is divided by), "poses"}],
   "detection": [{"family", "removed", "removed_found", "moved", "moved_found", "added", "added_found",
                  "doors_moved", "doors_moved_found" (both pieces), "door_opened_found" (the wall piece the new
                  opening took: a missing part), "door_closed_found" (the old opening's piece that is wall now:
                  new structure), "missing_parts", "flags", "false_flags", "false_flags_per_100m", "new_on_clutter", "precision", "recall",
                  "scale_true", "scale_estimate", "scale_sigma",
                  "truth_poses" (with --diff-truth-poses: the same scores with the scans placed at the ground truth)}],
   "config": {...}}
Rates (lost, false_ok, precision, recall) are fractions 0..1.
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
from fploc_tools import log, read_tum, yaw_of  # noqa: E402
from lcm_log import decode_pose_t, events  # noqa: E402

FAMILIES = ["clean", "asbuilt-2cm", "asbuilt-5cm", "scale-0.5pct", "renovated", "glass", "shelves", "doors",
            "crowd-15", "mixed", "doors-moved"]
# method -> (pose channel in the recorded log, nodes whose CPU time is the method's)
# fploc+scale: fploc against the plan rescaled by the change detector's drawing-scale estimate (second pass,
# only where the estimate is significant). fploc+diff: fploc against the plan the detector corrected (missing
# elements dropped, moved ones shifted by their offset; second pass, where it marked any).
# fploc's relocalizer acts only while the matcher is LOST; its CPU is fploc's.
METHODS = {"fploc": ("FPLOC_POSE", ("segmenter", "features", "matcher", "relocalizer", "optimizer")),
           "fploc+downweight": ("FPLOC_POSE", ("segmenter", "features", "matcher", "relocalizer", "optimizer", "plan_diff")),
           "amcl": ("FPLOC_AMCL_POSE", ("segmenter", "features", "odometry", "amcl_lidar")),
           "ndt": ("FPLOC_POSE", ("segmenter", "ndt"))}
SHARED_NODES = ("segmenter",)  # every method's input: left out of ms_per_scan_localizer
DEFAULT_METHODS = ["fploc", "fploc+downweight", "amcl", "ndt", "fploc+scale"]
ALL_METHODS = DEFAULT_METHODS + ["fploc+diff"]


def downweight_graph(src, dst):
    """graphs/realism.pbtxt with the matcher's and the optimizer's plan_diff inputs connected to FPLOC_PLAN_DIFF
    (beside the matcher's 'refined' and the optimizer's 'frame_pose' input, in those nodes' blocks only: the
    relocalizer reads FPLOC_FRAME_POSE too)."""
    with open(src) as f:
        s = f.read()
    blocks = s.split("\nnode {")
    pd = '\n  input { port: "plan_diff" channel: "FPLOC_PLAN_DIFF" }'
    done = set()
    for i, blk in enumerate(blocks):
        for name, line in (("matcher", '  input { port: "refined" channel: "FPLOC_POSE_LATEST" }'),
                           ("optimizer", '  input { port: "frame_pose" channel: "FPLOC_FRAME_POSE" }')):
            if f'\n  name: "{name}"' in blk and blk.count(line) == 1:
                blocks[i] = blk.replace(line, line + pd)
                done.add(name)
    if done != {"matcher", "optimizer"}:
        raise SystemExit(f"fploc bench realism: {src}: cannot find the matcher's 'refined' and the optimizer's "
                         "'frame_pose' inputs to connect plan_diff beside")
    with open(dst, "w") as f:
        f.write("\nnode {".join(blocks))


FALSE_OK_M = 0.3


def run(cmd):
    return fploc_tools.run(cmd, "fploc bench realism")


# ---- LCM log and pose_t decoding (the LCM wire format: big-endian, 8-byte type hash first) ------------------
def scans_of(rep, fallback):
    """The scans a replay segmented: the segmenter's published segments (its `messages` also count the IMU samples
    it takes, ~10 per scan, which made NDT's CPU per scan read 11x too low before the fifteenth round)."""
    return next((n["messages_out"] for n in rep["nodes"] if n["name"] == "segmenter" and n.get("messages_out")), fallback)


def poses_of(log_path, channel):
    """The method's pose per scan: the final estimate when the method marks one, else its last pose."""
    by_t, finals = {}, {}
    for _ts, ch, buf in events(log_path, with_time=True):
        if ch != channel:
            continue
        p = decode_pose_t(buf)
        by_t[p["utime"]] = p
        if p["final"]:
            finals[p["utime"]] = p
    use = finals if len(finals) >= 0.5 * max(len(by_t), 1) else by_t
    return [use[t] for t in sorted(use)]


def quat_yaw(q):
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def score_poses(poses, gt_rows):
    """Horizontal ATE, max, LOST, false OK, NEES (x, y, yaw) of pose_t records against the TUM truth."""
    truth = fploc_tools.Truth(gt_rows)
    errs, nees, lost, false_ok, poor, n = [], [], 0, 0, 0, 0
    pairs = []
    for p in poses:
        g = truth.nearest(p["utime"] * 1e-6, 0.005)
        if g is None:
            continue
        n += 1
        ex, ey = p["p"][0] - g[1], p["p"][1] - g[2]
        e = math.hypot(ex, ey)
        eyaw = (quat_yaw(p["q"]) - yaw_of(g) + math.pi) % (2 * math.pi) - math.pi
        if p["status"] == 2:
            lost += 1
        if p["status"] == 1:
            poor += 1
        if p["status"] == 0 and e > FALSE_OK_M:
            false_ok += 1
        errs.append(e)
        pairs.append((p["p"][0], p["p"][1], g[1], g[2]))
        c = p["cov"]
        idx = (0, 1, 5)
        S = [[c[i * 6 + j] for j in idx] for i in idx]
        if all(math.isfinite(x) for row in S for x in row):
            sol = fploc_tools.solve3(S, [ex, ey, eyaw])
            if sol is not None:
                v = ex * sol[0] + ey * sol[1] + eyaw * sol[2]
                if v >= 0:
                    nees.append(v)
    if not n:
        return None
    nees.sort()
    return {"poses": n, "ate_m": math.sqrt(sum(e * e for e in errs) / n), "max_m": max(errs),
            "lost": lost / n, "false_ok": false_ok / n, "false_ok_poses": false_ok, "poor": poor / n,
            "nees_median": nees[len(nees) // 2] if nees else None, "nees_poses": len(nees),
            "ate_aligned_m": aligned_ate(pairs)}


def aligned_ate(pairs):
    """Horizontal ATE after the best rigid alignment (rotation + translation, no scale) of the estimated positions
    onto the truth, as TUM's / evo's ATE aligns (Horn / Umeyama; in 2D the angle is closed form). pairs: (ex, ey, gx, gy)."""
    n = len(pairs)
    if not n:
        return None
    mex = sum(p[0] for p in pairs) / n
    mey = sum(p[1] for p in pairs) / n
    mgx = sum(p[2] for p in pairs) / n
    mgy = sum(p[3] for p in pairs) / n
    sc = ss = 0.0
    for ex, ey, gx, gy in pairs:
        ax, ay, bx, by = ex - mex, ey - mey, gx - mgx, gy - mgy
        sc += ax * bx + ay * by
        ss += ax * by - ay * bx
    th = math.atan2(ss, sc)
    c, s = math.cos(th), math.sin(th)
    e2 = 0.0
    for ex, ey, gx, gy in pairs:
        ax, ay = ex - mex, ey - mey
        dx = c * ax - s * ay + mgx - gx
        dy = s * ax + c * ay + mgy - gy
        e2 += dx * dx + dy * dy
    return math.sqrt(e2 / n)


def gauge_floor(plan_path, truth, gt_rows):
    """The ATE floor of a world whose walls stand off their drawn place (as-built offsets): the rigid motion
    (dx, dy, dyaw) of the whole building that best explains the walls' own offsets (length-weighted least squares
    over every unchanged segment, its offset and rotation sampled at 10 points along it) cannot be told from the
    robot's own pose error by anything measured against the plan alone; its rms displacement along the truth
    path is what a localizer that knew every wall's offset up to that motion would still be off. None without
    as-built offsets (0 on the plan itself)."""
    with open(plan_path) as f:
        plan = json.load(f)["elements"]
    segs = [e for e in plan if e.get("type") == "segment"]
    if not segs or not truth or len(truth.get("elements", [])) != len(plan):
        return None
    cx = sum(e["a"][0] for e in segs) / len(segs)
    cy = sum(e["a"][1] for e in segs) / len(segs)
    A = [[0.0] * 3 for _ in range(3)]
    b = [0.0] * 3
    any_offset = False
    for e, te in zip(plan, truth["elements"]):
        if e.get("type") != "segment" or te.get("change") != "unchanged" or te.get("kind") != "segment":
            continue
        (ax, ay), (bx, by) = e["a"], e["b"]
        L = math.hypot(bx - ax, by - ay)
        if L < 1e-9:
            continue
        nx, ny = -(by - ay) / L, (bx - ax) / L
        rot = math.radians(te.get("rotation_deg", 0.0))
        any_offset |= abs(te.get("offset_m", 0.0)) > 0 or abs(rot) > 0
        for k in range(10):
            sfrac = 0.05 + 0.1 * k
            px, py = ax + sfrac * (bx - ax), ay + sfrac * (by - ay)
            off = te.get("offset_m", 0.0) + (sfrac - 0.5) * L * math.tan(rot)
            row = [nx, ny, -nx * (py - cy) + ny * (px - cx)]
            w = L / 10
            for i in range(3):
                b[i] += w * row[i] * off
                for j in range(3):
                    A[i][j] += w * row[i] * row[j]
    if not any_offset:
        return 0.0
    x = fploc_tools.solve3(A, b)
    if x is None:
        return None
    e2 = 0.0
    for r in gt_rows:
        rx, ry = r[1] - cx, r[2] - cy
        dx, dy = x[0] - x[2] * ry, x[1] + x[2] * rx
        e2 += dx * dx + dy * dy
    return math.sqrt(e2 / max(1, len(gt_rows)))


BOUND_WINDOW_S = 10.0  # ate_bound_window_m: the bound with exact odometry over this window


def asbuilt_bound(plan_path, truth, gt_path, rec):
    """As-built worlds (truth's asbuilt_sigma_m > 0): the rms, over the run's scans, of the expected horizontal error of
    the best estimate of each scan's pose from its features against the plan when every plan vertex stands N(0, sigma^2)
    off (`fploc eval --asbuilt-bound`, modules/eval/asbuilt_bound.h). Scan by scan no localizer that knows only the plan
    does better on average; and the same over a BOUND_WINDOW_S window. None for other worlds."""
    sigma = (truth or {}).get("asbuilt_sigma_m", 0.0)
    if not sigma or not os.path.exists(rec):
        return None
    out = run([os.path.join(BIN, "fploc-eval"), "--gt", gt_path, "--est", gt_path, "--plan", plan_path,
               "--asbuilt-bound", repr(sigma), "--features", rec, "--bound-window", str(BOUND_WINDOW_S), "--json"])[0]
    return json.loads(out.strip().splitlines()[-1])["asbuilt_bound"]


# ---- change detection against the truth ------------------------------------------------------------------
def seg_dist(p, a, b):
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    t = 0 if L2 == 0 else max(0, min(1, ((p[0] - ax) * dx + (p[1] - ay) * dy) / L2))
    return math.hypot(p[0] - ax - t * dx, p[1] - ay - t * dy)


def on_furniture(p, furn, tol=0.15):
    for f in furn:
        c, yaw, (hx, hy) = f["c"], f["yaw"], f["half"]
        rx, ry = p[0] - c[0], p[1] - c[1]
        lx = math.cos(yaw) * rx + math.sin(yaw) * ry
        ly = -math.sin(yaw) * rx + math.cos(yaw) * ry
        if abs(lx) <= hx + tol and abs(ly) <= hy + tol:
            return True
    return False


def score_detection(diff, truth, moved_min=0.10, added_min=1.0):
    el = {e["id"]: e for e in diff["elements"]}
    removed = moved = found_r = found_m = 0
    false_flags, flags, tp_flags = 0, 0, 0
    offset_err = []
    for t in truth["elements"]:
        d = el.get(t["id"])
        status = d["status"] if d else "seen"
        in_view = d is not None and (d["frames_expected"] > 0 or d["frames_with_points"] > 0)
        if status in ("missing", "moved"):
            flags += 1
        if t["change"] in ("removed", "glass"):
            if in_view:
                removed += 1
                found_r += status == "missing"
            tp_flags += status in ("missing", "moved")
        elif t["change"] == "moved" and abs(t["offset_m"]) >= moved_min:
            if in_view:
                moved += 1
                if status == "moved":
                    found_m += 1
                    offset_err.append(abs(d["offset_m"] - t["offset_m"]))
            tp_flags += status in ("missing", "moved")
        elif t["change"] == "door-moved":
            tp_flags += status in ("missing", "moved")  # a face or jamb of a moved doorway: it did change
        elif status in ("missing", "moved"):
            # As built, a wall may really stand some cm off: a "moved" verdict within 3 cm of the truth is right.
            if status == "moved" and abs(d["offset_m"] - t["offset_m"]) <= 0.03 and abs(t["offset_m"]) >= 0.05:
                tp_flags += 1
            else:
                false_flags += 1
    furn = truth.get("furniture", [])
    added_truth = [a for a in truth["added"] if a["kind"] == "partition" and a["length_m"] >= added_min]
    others = [a for a in truth["added"] if a not in added_truth]
    found_a = 0
    matched = set()
    for a in added_truth:
        for i, n in enumerate(diff["new"]):
            mid = [(n["a"][0] + n["b"][0]) / 2, (n["a"][1] + n["b"][1]) / 2]
            if seg_dist(mid, a["a"], a["b"]) < 0.15 and seg_dist(n["a"], a["a"], a["b"]) < 0.15 and seg_dist(n["b"], a["a"], a["b"]) < 0.15:
                matched.add(i)
        if any(seg_dist([(diff["new"][i]["a"][0] + diff["new"][i]["b"][0]) / 2, (diff["new"][i]["a"][1] + diff["new"][i]["b"][1]) / 2], a["a"], a["b"]) < 0.15
               for i in matched):
            covered = sum(diff["new"][i]["length_m"] for i in matched
                          if seg_dist(diff["new"][i]["a"], a["a"], a["b"]) < 0.15)
            if covered >= 0.5 * a["length_m"]:
                found_a += 1
    new_on_clutter = 0
    for i, n in enumerate(diff["new"]):
        flags += 1
        if i in matched:
            tp_flags += 1
            continue
        mid = [(n["a"][0] + n["b"][0]) / 2, (n["a"][1] + n["b"][1]) / 2]
        if any(seg_dist(mid, a["a"], a["b"]) < 0.15 for a in others) or any(seg_dist(mid, a["a"], a["b"]) < 0.15 for a in added_truth):
            tp_flags += 1  # a door leaf, a short partition, or a second piece of a found one: there is something new
        elif on_furniture(mid, furn):
            new_on_clutter += 1
            flags -= 1  # static clutter: unmapped and real, but not the building; counted apart
        else:
            false_flags += 1
    # Doors moved: the piece of wall the new opening took (a missing part) and the piece of the old opening
    # that is wall now (new structure continuing a wall), each found when >= half of it is reported within 15 cm.
    def covered(a, b, segs, tol=0.15):
        n = 40
        hit = 0
        for k in range(n + 1):
            x = [a[0] + (b[0] - a[0]) * k / n, a[1] + (b[1] - a[1]) * k / n]
            if any(seg_dist(x, s["a"], s["b"]) < tol for s in segs):
                hit += 1
        return math.hypot(b[0] - a[0], b[1] - a[1]) * hit / (n + 1)
    parts = diff.get("missing_parts", [])
    dm = truth.get("doors_moved", [])
    opened_found = closed_found = doors_found = 0
    for t in dm:
        L = abs(t["shift_m"])
        o = covered(t["opened"][0], t["opened"][1], parts) >= 0.5 * L
        c = covered(t["closed"][0], t["closed"][1], diff["new"]) >= 0.5 * L
        opened_found += o
        closed_found += c
        doors_found += o and c
    for p in parts:
        flags += 1
        mid = [(p["a"][0] + p["b"][0]) / 2, (p["a"][1] + p["b"][1]) / 2]
        if any(seg_dist(mid, t["opened"][0], t["opened"][1]) < 0.15 for t in dm):
            tp_flags += 1
        else:
            false_flags += 1
    for i, n in enumerate(diff["new"]):
        # New structure on a closed piece of an old doorway was counted false above: it is right.
        mid = [(n["a"][0] + n["b"][0]) / 2, (n["a"][1] + n["b"][1]) / 2]
        if i not in matched and any(seg_dist(mid, t["closed"][0], t["closed"][1]) < 0.15 for t in dm) and \
                not any(seg_dist(mid, a["a"], a["b"]) < 0.15 for a in others + added_truth) and not on_furniture(mid, furn):
            false_flags -= 1
            tp_flags += 1
    wall_m = truth.get("plan_wall_length_m") or 1
    truth_n = removed + moved + len(added_truth) + 2 * len(dm)
    return {"removed": removed, "removed_found": found_r, "moved": moved, "moved_found": found_m,
            "moved_offset_err_max_m": max(offset_err) if offset_err else None,
            "added": len(added_truth), "added_found": found_a, "flags": flags, "false_flags": false_flags,
            "false_flags_per_100m": false_flags / (wall_m / 100.0), "new_on_clutter": new_on_clutter,
            "doors_moved": len(dm), "doors_moved_found": doors_found, "door_opened_found": opened_found,
            "door_closed_found": closed_found, "missing_parts": len(parts),
            "precision": tp_flags / flags if flags else None,
            "recall": (found_r + found_m + found_a + opened_found + closed_found) / truth_n if truth_n else None}


def scale_plan_json(src, dst, s):
    """A JSON plan scaled by s about its bounding-box centre (segments, circles and arcs)."""
    with open(src) as f:
        j = json.load(f)
    xs, ys = [], []
    for e in j["elements"]:
        for k in ("a", "b", "c"):
            if k in e:
                xs.append(e[k][0]); ys.append(e[k][1])
    cx, cy = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
    for e in j["elements"]:
        for k in ("a", "b", "c"):
            if k in e:
                e[k] = [cx + s * (e[k][0] - cx), cy + s * (e[k][1] - cy)]
        if "r" in e:
            e["r"] = e["r"] * s
    with open(dst, "w") as f:
        json.dump(j, f)


def twin_of(els, i):
    """The other face of a wall drawn with two lines: a parallel segment within 0.4 m overlapping it."""
    e = els[i]
    if e.get("type") != "segment":
        return None
    ax, ay = e["a"]; bx, by = e["b"]
    L = math.hypot(bx - ax, by - ay)
    if L < 1e-9:
        return None
    ux, uy = (bx - ax) / L, (by - ay) / L
    best, best_d = None, 0.4
    for j, f in enumerate(els):
        if j == i or f.get("type") != "segment":
            continue
        fx0, fy0 = f["a"]; fx1, fy1 = f["b"]
        fl = math.hypot(fx1 - fx0, fy1 - fy0)
        if fl < 1e-9 or abs(ux * (fy1 - fy0) / fl - uy * (fx1 - fx0) / fl) > 0.05:
            continue
        mx, my = (fx0 + fx1) / 2 - ax, (fy0 + fy1) / 2 - ay
        d = abs(ux * my - uy * mx)
        if d < 0.02 or d >= best_d:
            continue
        s0, s1 = sorted((ux * (fx0 - ax) + uy * (fy0 - ay), ux * (fx1 - ax) + uy * (fy1 - ay)))
        if min(s1, L) - max(s0, 0.0) < 0.5 * min(L, s1 - s0):
            continue
        best, best_d = j, d
    return best


def corrected_plan_json(src, dst, diff):
    """The plan as the diff saw the building: elements marked missing dropped, moved ones shifted by their
    offset along the normal (a wall drawn with two lines loses / moves its other face with it)."""
    with open(src) as f:
        j = json.load(f)
    els = j["elements"]
    drop, shift = set(), {}
    for e in diff["elements"]:
        i = e["id"]
        if e["status"] not in ("missing", "moved"):
            continue
        group = [i]
        t = twin_of(els, i)
        if t is not None:
            group.append(t)
        for k in group:
            if e["status"] == "missing":
                drop.add(k)
            elif els[i].get("type") == "segment":
                (ax, ay), (bx, by) = els[i]["a"], els[i]["b"]
                L = math.hypot(bx - ax, by - ay)
                shift[k] = (-(by - ay) / L * e["offset_m"], (bx - ax) / L * e["offset_m"])
            elif "r" in els[k]:
                els[k]["r"] = max(0.01, els[k]["r"] + e["offset_m"])
    for k, (dx, dy) in shift.items():
        if k in drop:
            continue
        for key in ("a", "b", "c"):
            if key in els[k]:
                els[k][key] = [els[k][key][0] + dx, els[k][key][1] + dy]
    j["elements"] = [e for i, e in enumerate(els) if i not in drop]
    with open(dst, "w") as f:
        json.dump(j, f)


class Bench:
    def __init__(self, a, work):
        self.a = a
        self.work = work
        self.ndt_graph = os.path.join(ROOT, "graphs", "ndt.pbtxt")
        self.have_ndt = os.path.exists(os.path.join(BIN, "fploc-ndt")) and os.path.exists(self.ndt_graph)
        self.methods = [m for m in a.methods.split(",") if m]
        self.floors = {}  # family -> gauge_floor (families run in threads: one key each)
        self.bounds = {}  # family -> as-built bound (ditto)

    def family(self, fam):
        d = os.path.join(self.work, fam)
        os.makedirs(d, exist_ok=True)
        logf, gt = os.path.join(d, "sim.lcm"), os.path.join(d, "gt.tum")
        cmd = [os.path.join(BIN, "fploc-sim"), "--scenario", self.a.scenario, "--seed", str(self.a.seed),
               "--out", logf, "--gt", gt]
        if fam != "clean":
            cmd += ["--perturb", fam]
        if self.a.duration:
            cmd += ["--duration", str(self.a.duration)]
        log(f"[{fam}] simulating {self.a.scenario} seed {self.a.seed} ...")
        run(cmd)
        truth = None
        tp = os.path.join(d, "sim.world.json")
        if os.path.exists(tp):
            with open(tp) as f:
                truth = json.load(f)
        g = read_tum(gt)
        x0, y0, yaw0 = g[0][1], g[0][2], yaw_of(g[0])
        plan = os.path.join(ROOT, "data", "plans", "corridor.json" if self.a.scenario.startswith("corridor") else "room.json")
        rec = os.path.join(d, "run.lcm")
        graph = os.path.join(ROOT, "graphs", "realism.pbtxt")
        sets = [f"{n}.plan.file={plan}" for n in ("matcher", "relocalizer", "optimizer", "amcl_lidar", "plan_diff")]
        for n in ("matcher", "odometry", "amcl_lidar"):
            sets += [f"{n}.initial_pose.x={x0!r}", f"{n}.initial_pose.y={y0!r}", f"{n}.initial_pose.yaw={yaw0!r}"]
        sets += [f"wo_logger.file={os.path.join(d, 'wo.tum')}", f"amcl_lidar_logger.file={os.path.join(d, 'amcl.tum')}"]
        main_sets = list(sets)
        if self.a.online_scale:
            # The online scale correction (matcher/plan_scale.h): the plan diff's estimate used live, no down-weighting.
            graph = os.path.join(d, "realism-scale.pbtxt")
            downweight_graph(os.path.join(ROOT, "graphs", "realism.pbtxt"), graph)
            main_sets += [f"{n}.{k}" for n in ("matcher", "optimizer") for k in ("plan_diff_weight=1", "plan_diff_scale=true")]
            main_sets += [f"plan_diff.frame_hz={self.a.scale_frame_hz}"]
        cmd = [os.path.join(BIN, "fploc-replay"), "--graph", graph, "--log", logf, "--record", rec, "--json"]
        if self.a.diff_heights:  # the segmenter's 3D points too: the diff tells new walls from furniture by height
            cmd += ["--record-channels", "FPLOC_.*"]
        for s in main_sets:
            cmd += ["--set", s]
        log(f"[{fam}] replaying fploc + AMCL + plan diff ...")
        rep = json.loads(run(cmd)[0].strip().splitlines()[-1])
        rows = []
        self.floors[fam] = gauge_floor(plan, truth, g) if truth is not None else None
        self.bounds[fam] = asbuilt_bound(plan, truth, gt, rec)
        for m in ("fploc", "amcl"):
            if m not in self.methods:
                continue
            ch, nodes = METHODS[m]
            if m == "fploc" and self.a.online_scale:
                nodes = nodes + ("plan_diff",)
            rows.append(self.row(fam, m, poses_of(rec, ch), g, rep, nodes))
        if "fploc+downweight" in self.methods:
            gdw = os.path.join(d, "realism-downweight.pbtxt")
            downweight_graph(os.path.join(ROOT, "graphs", "realism.pbtxt"), gdw)
            recd = os.path.join(d, "run-downweight.lcm")
            cmdd = [os.path.join(BIN, "fploc-replay"), "--graph", gdw, "--log", logf, "--record", recd,
                    "--record-channels", "FPLOC_POSE", "--json"]
            scale_sets = [f"{n}.plan_diff_scale=true" for n in ("matcher", "optimizer")] if self.a.online_scale else []
            for x in sets + scale_sets + [f"matcher.plan_diff_weight={self.a.downweight}", f"optimizer.plan_diff_weight={self.a.downweight}",
                             f"plan_diff.out_json={os.path.join(d, 'diff-downweight.json')}"]:
                cmdd += ["--set", x]
            log(f"[{fam}] replaying fploc with the plan diff's down-weighting (weight {self.a.downweight}) ...")
            repd = json.loads(run(cmdd)[0].strip().splitlines()[-1])
            rows.append(self.row(fam, "fploc+downweight", poses_of(recd, "FPLOC_POSE"), g, repd,
                                 METHODS["fploc+downweight"][1]))
            os.remove(recd)
        if self.have_ndt and "ndt" in self.methods:
            nrec = os.path.join(d, "ndt.lcm")
            cmd = [os.path.join(BIN, "fploc-replay"), "--graph", self.ndt_graph, "--log", logf, "--record", nrec, "--json",
                   "--set", f"ndt.plan.file={plan}", "--set", f"ndt.initial_pose.x={x0!r}", "--set", f"ndt.initial_pose.y={y0!r}",
                   "--set", f"ndt.initial_pose.yaw={yaw0!r}", "--set", f"pose_logger.file={os.path.join(d, 'ndt.tum')}",
                   "--set", f"pose_logger.uncertainty_file={os.path.join(d, 'ndt.unc')}"]
            log(f"[{fam}] replaying NDT ...")
            try:
                nrep = json.loads(run(cmd)[0].strip().splitlines()[-1])
                rows.append(self.row(fam, "ndt", poses_of(nrec, METHODS["ndt"][0]), g, nrep, METHODS["ndt"][1]))
            except SystemExit:
                log(f"[{fam}] NDT run failed (left out)")
        det = None
        if truth is not None:
            dj = os.path.join(d, "diff.json")
            # The run's plan, not the graph's (room.json): on the corridor scenario the detector compared the run
            # with the room's plan (55-68 false flags per 100 m and a wrong scale for fploc+scale).
            run([os.path.join(BIN, "fploc-map-diff"), "--graph", os.path.join(ROOT, "graphs", "realism.pbtxt"), "--log", rec,
                 "--out", dj, "--out", os.path.join(d, "diff.dxf"), "--all", "--set", f"plan_diff.plan.file={plan}"])
            with open(dj) as f:
                diff = json.load(f)
            det = {"family": fam, **score_detection(diff, truth),
                   "scale_true": truth.get("scale", 0.0), "scale_estimate": diff.get("scale", {}).get("error"),
                   "scale_sigma": diff.get("scale", {}).get("sigma")}
            est, sig = det["scale_estimate"], det["scale_sigma"] or 0.0
            if "fploc+scale" in self.methods and est is not None and abs(est) > max(0.001, 3 * sig):
                # The scale estimate on: a second pass of fploc against the plan scaled by (1 + estimate)
                # about its bounding-box centre.
                sp = os.path.join(d, "plan-scaled.json")
                scale_plan_json(plan, sp, 1.0 + est)
                rec2 = os.path.join(d, "run-scaled.lcm")
                cmd2 = [os.path.join(BIN, "fploc-replay"), "--graph", os.path.join(ROOT, "graphs", "realism.pbtxt"), "--log", logf,
                        "--record", rec2, "--record-channels", "FPLOC_POSE", "--json"]
                for x in sets + [f"matcher.plan.file={sp}", f"relocalizer.plan.file={sp}", f"optimizer.plan.file={sp}"]:
                    cmd2 += ["--set", x]
                log(f"[{fam}] scale estimate {100 * est:.3f} %: replaying fploc against the rescaled plan ...")
                rep2 = json.loads(run(cmd2)[0].strip().splitlines()[-1])
                rows.append(self.row(fam, "fploc+scale", poses_of(rec2, "FPLOC_POSE"), g, rep2, METHODS["fploc"][1]))
                os.remove(rec2)
            flagged = [e["id"] for e in diff["elements"] if e["status"] in ("missing", "moved")]
            if flagged and "fploc+diff" in self.methods:
                # The diff's verdicts used: a second pass of fploc against the plan the diff corrected
                # (missing elements dropped, moved ones shifted), as a later run would use a survey run's diff.
                dp = os.path.join(d, "plan-diffed.json")
                corrected_plan_json(plan, dp, diff)
                rec3 = os.path.join(d, "run-diffed.lcm")
                cmd3 = [os.path.join(BIN, "fploc-replay"), "--graph", os.path.join(ROOT, "graphs", "realism.pbtxt"), "--log", logf,
                        "--record", rec3, "--record-channels", "FPLOC_POSE", "--json"]
                for x in sets + [f"matcher.plan.file={dp}", f"relocalizer.plan.file={dp}", f"optimizer.plan.file={dp}"]:
                    cmd3 += ["--set", x]
                log(f"[{fam}] {len(flagged)} elements missing/moved: replaying fploc against the plan the diff corrected ...")
                rep3 = json.loads(run(cmd3)[0].strip().splitlines()[-1])
                rows.append(self.row(fam, "fploc+diff", poses_of(rec3, "FPLOC_POSE"), g, rep3, METHODS["fploc"][1]))
                os.remove(rec3)
            log(f"[{fam}] detection: removed {det['removed_found']}/{det['removed']}, moved {det['moved_found']}/{det['moved']}, "
                f"added {det['added_found']}/{det['added']}, false flags {det['false_flags']} "
                f"({det['false_flags_per_100m']:.2f} per 100 m), new on clutter {det['new_on_clutter']}")
            if self.a.diff_truth_poses:
                # Diagnostic: the same scans placed with the ground truth instead of fploc's poses (what the detector
                # finds with good poses; the difference to the row above is the localizer's part).
                djt = os.path.join(d, "diff-truth-poses.json")
                run([os.path.join(BIN, "fploc-map-diff"), "--graph", os.path.join(ROOT, "graphs", "realism.pbtxt"), "--log", rec,
                     "--out", djt, "--all", "--set", f"plan_diff.plan.file={plan}", "--poses", gt])
                with open(djt) as f:
                    t = score_detection(json.load(f), truth)
                det["truth_poses"] = t
                log(f"[{fam}] detection with the truth's poses: removed {t['removed_found']}/{t['removed']}, moved "
                    f"{t['moved_found']}/{t['moved']}, added {t['added_found']}/{t['added']}, false flags {t['false_flags']} "
                    f"({t['false_flags_per_100m']:.2f} per 100 m), new on clutter {t['new_on_clutter']}")
        if not self.a.keep:
            for f in (logf, rec, os.path.join(d, "ndt.lcm")):
                if os.path.exists(f) and not (fam == "renovated" and f == rec):
                    os.remove(f)
        return rows, det

    def floor_of(self, fam):
        return self.floors.get(fam)

    def bound_of(self, fam, key="rms_m"):
        b = self.bounds.get(fam)
        return b.get(key) if b else None

    def row(self, fam, method, poses, g, rep, nodes):
        s = score_poses(poses, g) or {"poses": 0}
        scans = scans_of(rep, len(g))  # this replay's own
        cpu = sum(n.get("cpu_ms", n["total_ms"]) for n in rep["nodes"] if n["name"] in nodes)
        own = sum(n.get("cpu_ms", n["total_ms"]) for n in rep["nodes"] if n["name"] in nodes and n["name"] not in SHARED_NODES)
        r = {"family": fam, "method": method, **s, "scans": scans, "ms_per_scan": round(cpu / max(scans, 1), 3),
             "ms_per_scan_localizer": round(own / max(scans, 1), 3), "ate_floor_m": self.floor_of(fam),
             "ate_bound_m": self.bound_of(fam), "ate_bound_window_m": self.bound_of(fam, "window_rms_m")}
        log(f"[{fam}] {method}: ATE {fmt(r.get('ate_m'))} (aligned {fmt(r.get('ate_aligned_m'))}, floor {fmt(r.get('ate_floor_m'))}, "
            f"as-built bound {fmt(r.get('ate_bound_m'))}) max {fmt(r.get('max_m'))} LOST {pct(r.get('lost'))} "
            f"false-OK {pct(r.get('false_ok'))} POOR {pct(r.get('poor'))} NEES {fmt(r.get('nees_median'), 2)} {r['ms_per_scan']} ms/scan "
            f"({r['ms_per_scan_localizer']} without the segmenter)")
        return r


def fmt(v, nd=4):
    return fploc_tools.fmt_num(v, nd)


def pct(v):
    t = fploc_tools.fmt_num(v, 1, 100)
    return t if t == "-" else t + " %"


def svg_bars(rows, path, key="ate_m", title="horizontal ATE [cm]", scale=100.0):
    fams = []
    for r in rows:
        if r["family"] not in fams:
            fams.append(r["family"])
    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    colors = {"fploc": "#1f77b4", "amcl": "#d62728", "ndt": "#2ca02c", "fploc+scale": "#9467bd", "fploc+diff": "#17becf",
              "fploc+downweight": "#ff7f0e"}
    vals = {(r["family"], r["method"]): (r.get(key) or 0) * scale for r in rows}
    vmax = max(list(vals.values()) + [1e-9])
    # Log-free linear scale, capped so small values stay visible: bars above the cap are clipped and labelled.
    cap = min(vmax, 20.0) if vmax > 0 else 1.0
    W, H, left, bottom = 120 + 70 * len(fams) * max(1, len(methods)) // 2, 360, 60, 80
    bw = 55.0 / max(1, len(methods))
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="11">',
           f'<text x="{W / 2}" y="16" text-anchor="middle" font-size="13">{title}</text>']
    ph = H - bottom - 30
    for k in range(5):
        v = cap * k / 4
        y = H - bottom - ph * k / 4
        out.append(f'<line x1="{left}" x2="{W - 10}" y1="{y}" y2="{y}" stroke="#ddd"/>'
                   f'<text x="{left - 5}" y="{y + 4}" text-anchor="end">{v:.1f}</text>')
    for i, f in enumerate(fams):
        x0 = left + 10 + i * 70 * max(1, len(methods)) / 2
        for j, m in enumerate(methods):
            v = vals.get((f, m))
            if v is None:
                continue
            h = ph * min(v, cap) / cap
            x = x0 + j * bw
            out.append(f'<rect x="{x:.1f}" y="{H - bottom - h:.1f}" width="{bw - 2:.1f}" height="{h:.1f}" fill="{colors.get(m, "#777")}"/>')
            if v > cap:
                out.append(f'<text x="{x + bw / 2:.1f}" y="{H - bottom - h - 3:.1f}" text-anchor="middle" font-size="9">{v:.0f}</text>')
        out.append(f'<text x="{x0 + 20}" y="{H - bottom + 14}" transform="rotate(30 {x0 + 20} {H - bottom + 14})">{f}</text>')
    for j, m in enumerate(methods):
        out.append(f'<rect x="{left + 10 + 90 * j}" y="26" width="10" height="10" fill="{colors.get(m, "#777")}"/>'
                   f'<text x="{left + 24 + 90 * j}" y="35">{m}</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out))


def markdown(res, cmdline):
    L = ["# Realism bench: worlds that differ from the plan", "",
         f"Generated by `{cmdline}` ({res['config']['scenario']}, seed {res['config']['seed']}"
         + (f", first {res['config']['duration']} s" if res['config']['duration'] else "") + ").", "",
         "Localization (horizontal, every pose of the method against the truth of the same scan, no alignment; "
         "false OK = status OK with error > 0.3 m; NEES = median of (x, y, yaw) NEES from pose_t's covariance, "
         "3 for a consistent covariance; POOR = share of poses published POOR; ms/scan = thread CPU of the method's "
         "nodes on one core, with and without the segmenter every method shares). ATE aligned = the same after the best "
         "rigid alignment (rotation + translation) of the whole estimated trajectory onto the truth, as TUM's / evo's ATE "
         "(what is left once a constant offset of the whole run is removed); floor = the rms, along the truth path, of the "
         "rigid motion of the whole building that best explains the walls' as-built offsets (sim.world.json): against "
         "the plan alone a localizer cannot tell it from its own error, so the unaligned ATE of any method is about "
         "this far from 0 at best (0 where the walls stand where drawn); as-built bound = the rms over the scans of "
         "the expected error of the best per-scan estimate when every plan vertex stands N(0, sigma^2) off, from the "
         "scan's features at its true pose (`fploc eval --asbuilt-bound`): scan by scan no localizer that knows only "
         "the plan does better on average (as-built worlds only):", "",
         "| world | method | ATE [cm] | ATE aligned [cm] | floor [cm] | as-built bound [cm] | max [cm] | LOST | POOR | false OK | NEES | ms/scan | ms/scan w/o segmenter |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in res["rows"]:
        cm = lambda v, nd=2: fmt(100 * v if v is not None else None, nd)  # noqa: E731
        L.append(f"| {r['family']} | {r['method']} | {fmt(100 * r['ate_m'] if r.get('ate_m') is not None else None, 2)} | "
                 f"{cm(r.get('ate_aligned_m'))} | {cm(r.get('ate_floor_m'))} | {cm(r.get('ate_bound_m'))} | "
                 f"{fmt(100 * r['max_m'] if r.get('max_m') is not None else None, 1)} | {pct(r.get('lost'))} | "
                 f"{pct(r.get('poor'))} | {pct(r.get('false_ok'))} | {fmt(r.get('nees_median'), 1)} | {r['ms_per_scan']} | "
                 f"{r.get('ms_per_scan_localizer', '-')} |")
    L += ["", "Plan-change detection (`fploc map diff` on the fploc run; truth from `fploc sim`'s LOG.world.json). "
          "Removed = removed walls/pillars and glass in view of the path; moved = walls moved >= 10 cm in view; "
          "added = partitions >= 1 m (found when >= half their length is reported within 15 cm); new structure on the "
          "simulator's furniture is counted apart (unmapped and real, but not the building):", "",
          "| world | removed found | moved found | added found | doors moved found (opened / closed piece) | flags | false flags | per 100 m of walls | new on furniture | precision | recall | scale true / estimated [%] |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for d in res["detection"]:
        L.append(f"| {d['family']} | {d['removed_found']}/{d['removed']} | {d['moved_found']}/{d['moved']} | "
                 f"{d['added_found']}/{d['added']} | {d.get('doors_moved_found', 0)}/{d.get('doors_moved', 0)} "
                 f"({d.get('door_opened_found', 0)} / {d.get('door_closed_found', 0)}) | {d['flags']} | {d['false_flags']} | {d['false_flags_per_100m']:.2f} | "
                 f"{d['new_on_clutter']} | {fmt(d['precision'], 2)} | {fmt(d['recall'], 2)} | "
                 f"{100 * d['scale_true']:.2f} / {fmt(100 * d['scale_estimate'] if d['scale_estimate'] is not None else None, 3)} "
                 f"± {fmt(100 * d['scale_sigma'] if d['scale_sigma'] is not None else None, 3)} |")
    L += ["", "![ATE](realism-ate.svg)", ""]
    return "\n".join(L) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", action="store_true", help="print the JSON document on stdout (always printed)")
    ap.add_argument("--families", default=",".join(FAMILIES), help="comma-separated world families")
    ap.add_argument("--scenario", default="room-small-loop-medium")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=0, help="simulate only the first S seconds (0 = whole scenario)")
    ap.add_argument("--markdown", help="write the tables (Markdown) here, the plot beside it")
    ap.add_argument("--work", help="keep the intermediate files in this folder")
    ap.add_argument("--keep", action="store_true", help="keep the LCM logs")
    ap.add_argument("--methods", default=",".join(DEFAULT_METHODS),
                    help=f"comma-separated, of {', '.join(ALL_METHODS)} (ndt only where fploc-ndt is built)")
    ap.add_argument("--downweight", type=float, default=0.0,
                    help="plan_diff_weight of fploc+downweight: weight of elements the diff flags (0 = left out)")
    ap.add_argument("--jobs", type=int, default=1, help="families simulated and replayed at once")
    ap.add_argument("--no-online-scale", dest="online_scale", action="store_false",
                    help="fploc and fploc+downweight without the online drawing-scale correction (plan_diff_scale)")
    ap.add_argument("--scale-frame-hz", type=float, default=2.0,
                    help="scans per second the live plan diff of the fploc row uses for its scale estimate (2)")
    ap.add_argument("--diff-heights", action="store_true",
                    help="record FPLOC_SEGMENTS with the fploc run (~0.5 MB per scan) so the plan diff checks the height "
                         "of new structure (plan_diff.new_min_height_m); without it new runs are not told by height")
    ap.add_argument("--diff-truth-poses", action="store_true",
                    help="also run the change detector with the ground-truth poses (detection[].truth_poses)")
    a = ap.parse_args()
    fams = [f for f in a.families.split(",") if f]
    for f in fams:
        if f not in FAMILIES:
            sys.exit(f"fploc bench realism: unknown family '{f}' (families: {', '.join(FAMILIES)})")
    for m in a.methods.split(","):
        if m and m not in ALL_METHODS:
            sys.exit(f"fploc bench realism: unknown method '{m}' (methods: {', '.join(ALL_METHODS)})")
    work = a.work or tempfile.mkdtemp(prefix="fploc-realism-")
    os.makedirs(work, exist_ok=True)
    b = Bench(a, work)
    log(f"fploc bench realism: {len(fams)} families, methods {', '.join(m for m in b.methods if m != 'ndt' or b.have_ndt)}"
        f"{'' if b.have_ndt or 'ndt' not in b.methods else ' (no fploc-ndt: NDT left out)'}; work in {work}")
    res = {"rows": [], "detection": [], "config": {"scenario": a.scenario, "seed": a.seed, "duration": a.duration,
                                                   "families": fams, "ndt": b.have_ndt, "false_ok_m": FALSE_OK_M,
                                                   "methods": b.methods, "downweight": a.downweight,
                                                   "online_scale": a.online_scale, "scale_frame_hz": a.scale_frame_hz}}
    try:
        from concurrent.futures import ThreadPoolExecutor
        with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
            for rows, det in ex.map(b.family, fams):  # results in family order
                res["rows"] += rows
                if det:
                    res["detection"].append(det)
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(markdown(res, "bin/fploc bench realism " + " ".join(sys.argv[1:])))
        svg_bars(res["rows"], os.path.join(os.path.dirname(os.path.abspath(a.markdown)), "realism-ate.svg"))
    print(json.dumps(res))


if __name__ == "__main__":
    main()
