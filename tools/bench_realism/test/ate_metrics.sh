#!/usr/bin/env bash
# The bench's added metrics on known inputs: the aligned ATE (best rigid alignment of the whole trajectory, as
# TUM / evo ATE) removes a rigid motion of the whole run and nothing else; the as-built floor of a world whose
# walls are all shifted by one vector is that vector, of one whose walls stand where drawn 0.
set -euo pipefail
ROOT="${FPLOC_ROOT:?}"
python3 - "$ROOT" <<'PY'
import json, math, sys
root = sys.argv[1]
sys.path.insert(0, root + "/tools/bench_realism")
sys.path.insert(0, root + "/tools/pylib")
import bench_realism as br
# A loop; the estimate = the truth rotated by 2 deg about (3, 1) and shifted (4 cm, -3 cm), plus a 1 cm wobble.
gt = [(5 + 3 * math.cos(0.1 * i), 4 + 2 * math.sin(0.1 * i)) for i in range(200)]
th, c, s = math.radians(2), math.cos(math.radians(2)), math.sin(math.radians(2))
def moved(x, y):
    return (3 + c * (x - 3) - s * (y - 1) + 0.04, 1 + s * (x - 3) + c * (y - 1) - 0.03)
pairs = [(*moved(x, y), x, y) for x, y in gt]
assert br.aligned_ate(pairs) < 1e-9, br.aligned_ate(pairs)
wob = [(ex + 0.01 * (-1) ** i, ey, gx, gy) for i, (ex, ey, gx, gy) in enumerate(pairs)]
a = br.aligned_ate(wob)
assert abs(a - 0.01) < 1e-3, a
# Floor: every wall shifted by d = (3 cm, -4 cm): each segment's offset along its left normal is n . d.
plan_path = root + "/data/plans/room.json"
plan = json.load(open(plan_path))["elements"]
d = (0.03, -0.04)
els = []
for e in plan:
    if e.get("type") == "segment":
        (ax, ay), (bx, by) = e["a"], e["b"]
        L = math.hypot(bx - ax, by - ay)
        n = (-(by - ay) / L, (bx - ax) / L) if L > 0 else (0, 0)
        els.append({"change": "unchanged", "kind": "segment", "offset_m": n[0] * d[0] + n[1] * d[1], "rotation_deg": 0.0})
    else:
        els.append({"change": "unchanged", "kind": e.get("type"), "offset_m": 0.0, "rotation_deg": 0.0})
rows = [(0.1 * i, x, y) for i, (x, y) in enumerate(gt)]
f = br.gauge_floor(plan_path, {"elements": els}, rows)
assert abs(f - 0.05) < 1e-6, f
for e in els:
    e["offset_m"] = 0.0
assert br.gauge_floor(plan_path, {"elements": els}, rows) == 0.0
print("ate metrics: ok", a, f)
PY
