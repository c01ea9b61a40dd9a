#!/usr/bin/env python3
"""The text summaries of fploc bench building (and the helpers the other bench_* drivers share) print "-" or words
for what was not measured, never Python's None, [] or nan: a user trial read "recognised after [] s, ATE after
lift None m" for a run without a floor change."""
import importlib.util
import math
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
os.environ.setdefault("FPLOC_ROOT", ROOT)
spec = importlib.util.spec_from_file_location("bench_building", os.path.join(ROOT, "tools", "bench_building", "bench_building.py"))
bb = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bb)
import fploc_tools  # noqa: E402 (tools/pylib, put on the path by bench_building)


def clean(text):
    for bad in ("None", "[]", "nan", "{", "'"):
        assert bad not in text, f"{bad!r} in {text!r}"
    return text


# The trial's run (Barcelona pavilion, auto-loop-medium, one floor): scored, no change, no lift ride.
s = clean(bb.floors_summary({"floor_scored": True, "wrong_floor_poses": 0, "wrong_floor_after_3s": 0, "floor_changes": [],
                             "lift_rides": [], "ate_after_lift_m": None}))
assert "no floor change in this run" in s, s
# A stair change recognised, a lift ride missed and its ATE not measured.
s = clean(bb.floors_summary({"floor_scored": True, "wrong_floor_poses": 4, "wrong_floor_after_3s": 1,
                             "floor_changes": [{"how": "stairs", "recognised_after_s": 1.2345},
                                               {"how": "lift", "recognised_after_s": None}],
                             "lift_rides": [{"ate_xy_m": None}], "ate_after_lift_m": None}))
assert "stairs recognised after 1.23 s" in s and "lift not recognised" in s and "ATE after lift - (not measured)" in s, s
s = clean(bb.floors_summary({"floor_scored": True, "wrong_floor_poses": 0, "wrong_floor_after_3s": 0,
                             "floor_changes": [{"how": "lift", "recognised_after_s": 0.5}], "lift_rides": [{"ate_xy_m": 0.0123}],
                             "ate_after_lift_m": 0.0123}))
assert s.endswith("ATE after lift 0.012 m"), s
assert bb.floors_summary({"floor_scored": False, "floor_note": "not scored"}) == "not scored"

for v, want in ((None, "-"), (float("nan"), "-"), (math.inf, "-"), (0.01234, "1.23"), (3, "3.00"), ("x", "x")):
    got = fploc_tools.fmt_num(v, 2, 100 if isinstance(v, float) and v == 0.01234 else 1)
    assert got == want, (v, got, want)
assert clean(fploc_tools.fmt_ms({"matcher": 1.234, "optimizer": None})) == "matcher 1.2, optimizer -"
assert fploc_tools.fmt_ms({}) == "-" and fploc_tools.fmt_ms(None) == "-"
print("bench summary formats: OK")
