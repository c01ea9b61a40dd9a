#!/usr/bin/env python3
"""Scores a floor change: score_floors.py EST GT.tum FLOORS.txt [LAUNCH.log]

EST: the final poses, either EST.tum as fploc-pose-logger writes it with its floor_file at EST.tum.floors
("t floor_index floor" per pose), or an LCM log with FPLOC_POSE (pose_t, with floor_index/floor);
GT.tum the ground truth; FLOORS.txt "utime floor" per ground-truth pose plus "# arrival UTIME" and
"# ride_start UTIME" (tests/floors/make_lift_log). Prints the time from the arrival to the first pose
on the new floor, the poses on the wrong floor (all, and from 3 s after the arrival), the horizontal
ATE over the 10 s after the arrival, the z error (pose_t z is absolute: the floor's elevation + the
height above it, as the ground truth) during the ride and from 3 s after the arrival, and fails (exit 1)
when a target is missed: recognised within 2 s, none wrong 3 s after the arrival, ATE <= 5 cm, z median
<= 5 cm from 3 s after the arrival, and with the IMU (not FPLOC_FLOOR_NO_IMU=1) z within 30 cm during the
ride (integrated from the IMU)."""
import bisect
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "pylib"))
from lcm_log import decode_pose_t, events  # noqa: E402


def main():
    rec, gt_path, floors_path = sys.argv[1:4]
    launch = sys.argv[4] if len(sys.argv) > 4 else None
    meta, gt_floor = {}, []
    for line in open(floors_path):
        p = line.split()
        if line.startswith("#"):
            meta[p[1]] = p[2:]
        elif p:
            gt_floor.append((int(p[0]), p[1]))
    arrival = int(meta["arrival"][0])
    ride_start = int(meta["ride_start"][0])
    upper = gt_floor[-1][1]
    lower = gt_floor[0][1]
    gt = []
    for line in open(gt_path):
        if line.strip() and not line.startswith("#"):
            t, x, y, z = map(float, line.split()[:4])
            gt.append((int(round(t * 1e6)), x, y, z))
    gt_t = [g[0] for g in gt]
    poses = {}
    if rec.endswith(".tum"):
        floor_of = {}
        for line in open(rec + ".floors"):
            if line.strip() and not line.startswith("#"):
                t, _i, name = line.split()[:3]
                floor_of[int(round(float(t) * 1e6))] = name
        for line in open(rec):
            if line.strip() and not line.startswith("#"):
                t, x, y, z = map(float, line.split()[:4])
                u = int(round(t * 1e6))
                poses[u] = {"utime": u, "x": x, "y": y, "z": z, "floor": floor_of.get(u, "")}
    else:
        for _ts, ch, buf in events(rec, with_time=True):
            if ch == "FPLOC_POSE":
                p = decode_pose_t(buf)
                poses[p["utime"]] = p
    poses = [poses[t] for t in sorted(poses)]
    if not poses:
        print("FAIL: no FPLOC_POSE recorded")
        return 1
    ok = True
    first_upper = next((p for p in poses if p["utime"] >= ride_start and p["floor"] == upper), None)
    early = [p for p in poses if p["utime"] < ride_start and p["floor"] != lower]
    wrong_all = [p for p in poses if (p["floor"] != (upper if p["utime"] >= arrival else lower))]
    wrong_late = [p for p in poses if p["utime"] >= arrival + 3_000_000 and p["floor"] != upper]
    after = [p for p in poses if arrival <= p["utime"] <= arrival + 10_000_000]
    errs = []
    for p in after:
        k = bisect.bisect_left(gt_t, p["utime"])
        k = min(max(k, 0), len(gt) - 1)
        if abs(gt[k][0] - p["utime"]) > 2000:
            continue
        errs.append(math.hypot(p["x"] - gt[k][1], p["y"] - gt[k][2]))
    ate = math.sqrt(sum(e * e for e in errs) / len(errs)) if errs else float("nan")

    def z_errs(sel):
        out = []
        for p in sel:
            k = min(max(bisect.bisect_left(gt_t, p["utime"]), 0), len(gt) - 1)
            if abs(gt[k][0] - p["utime"]) <= 2000:
                out.append(abs(p["z"] - gt[k][3]))
        return sorted(out)
    z_ride = z_errs([p for p in poses if ride_start <= p["utime"] < arrival])
    z_after = z_errs([p for p in poses if arrival + 3_000_000 <= p["utime"] <= arrival + 10_000_000])
    no_imu = os.environ.get("FPLOC_FLOOR_NO_IMU") == "1"
    rec_s = (first_upper["utime"] - arrival) * 1e-6 if first_upper else float("inf")
    print(f"poses: {len(poses)} (final), floors seen: {sorted(set(p['floor'] for p in poses))}")
    print(f"ride {ride_start} .. arrival {arrival} us; first pose on '{upper}': {rec_s:+.2f} s after the arrival")
    print(f"poses on the wrong floor: {len(wrong_all)} in all, {len(wrong_late)} from 3 s after the arrival, "
          f"{len(early)} on '{upper}' before the ride")
    print(f"horizontal ATE over the 10 s after the arrival: {100 * ate:.2f} cm ({len(errs)} poses, max "
          f"{100 * max(errs) if errs else float('nan'):.2f} cm)")
    zmed = z_after[len(z_after) // 2] if z_after else float("nan")
    zride = z_ride[-1] if z_ride else float("nan")
    print(f"z error (absolute z): during the ride max {100 * zride:.1f} cm ({len(z_ride)} poses{', no IMU' if no_imu else ''}); "
          f"3-10 s after the arrival median {100 * zmed:.2f} cm, max {100 * (z_after[-1] if z_after else float('nan')):.2f} cm")
    if not (zmed <= 0.05):
        print("FAIL: z median above 5 cm from 3 s after the arrival (absolute z)"); ok = False
    if not no_imu and not (zride <= 0.3):
        print("FAIL: z more than 30 cm off during the ride (IMU vertical motion)"); ok = False
    if not (rec_s <= 2.0):
        print("FAIL: the new floor was not recognised within 2 s of the arrival"); ok = False
    if wrong_late:
        print(f"FAIL: {len(wrong_late)} poses on the wrong floor 3 s after the arrival"); ok = False
    if early:
        print(f"FAIL: {len(early)} poses on '{upper}' before the ride"); ok = False
    if not (ate <= 0.05) or len(errs) < 50:
        print("FAIL: ATE over the 10 s after the ride above 5 cm (or too few poses)"); ok = False
    if launch:
        said = [l.strip() for l in open(launch, errors="replace") if "lift '" in l and "->" in l]
        if not said:
            print("FAIL: the matcher did not say why it switched floor"); ok = False
        else:
            print("matcher: " + said[0][:300])
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
