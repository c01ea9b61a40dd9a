#!/usr/bin/env python3
"""Map refinement on one Radish log, in-process (docs/notes/real2d.md, twenty-first pass): the first part's map built
with `fploc-import-carmen --auto-split` and the bench's map options, its poses refined or not
(`--refine-map-poses N` and any other importer options after `--`), then per covered scan the floor
(`fploc-real-floor`) and grid2d's tracker (`fploc-real-track --start ref`). Scored on the covered scans of the map
built at the reference poses (the same scans for every variant), so the rows compare.

  map_refine_compare.py LOG [--passes N] [--resolution M] [--out DIR] [--no-track] [-- IMPORT_OPTIONS...]
prints one JSON line (lengths in metres): floor RMSE / median, tracker ATE / max / scans > 0.5 m and its fits' median
residual, occupied cells of both maps, the refinement's last pass."""
import argparse, json, math, os, subprocess, sys

ROOT = os.environ.get("FPLOC_ROOT", os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..")))
BIN = os.path.join(os.environ.get("FPLOC_BUILD_DIR", os.path.join(ROOT, "build")), "bin")
SHARED = os.environ.get("FPLOC_SHARED_DIR", os.path.join(ROOT, "..", "shared"))


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.stderr.write(p.stderr)
        raise SystemExit(f"map_refine_compare: {os.path.basename(cmd[0])} failed ({p.returncode})")
    return p.stdout


def build(src, d, resolution, extra):
    os.makedirs(d, exist_ok=True)
    return json.loads(run([os.path.join(BIN, "fploc-import-carmen"), src, "--map", os.path.join(d, "map"), "--auto-split",
                           "--resolution", str(resolution), "--min-hits", "1", "--occupied-ratio", "0.1",
                           "--hit-clearance", "0.1", "--json"] + extra))


def rmse(v):
    return math.sqrt(sum(e * e for e in v) / len(v)) if v else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("log")
    ap.add_argument("--passes", type=int, default=1)
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--out", default="map-refine-compare")
    ap.add_argument("--no-track", action="store_true")
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    argv = argv[:argv.index("--")] if "--" in argv else argv
    a = ap.parse_args(argv)
    a.extra = extra
    src = os.path.join(SHARED, "data", "recordings", "radish", f"{a.log}-corrected.log.gz")
    base = build(src, os.path.join(a.out, a.log, "reference"), 0.05, [])
    keep = [c >= base["coverage_ratio"] for c in base["coverage"]]
    d = os.path.join(a.out, a.log, f"p{a.passes}-r{a.resolution}" + "".join(a.extra))
    imp = build(src, d, a.resolution, ["--refine-map-poses", str(a.passes)] + a.extra)
    first, end = imp["first_scan"], imp["end_scan"]
    plan = os.path.join(d, "map", "map.yaml")
    fl = json.loads(run([os.path.join(BIN, "fploc-real-floor"), src, "--map", plan, "--first-scan", str(first),
                         "--end-scan", str(end)]))["scans"]
    fe = sorted(r["dxy_m"] for r, k in zip(fl, keep) if k)
    out = {"log": a.log, "passes": a.passes, "resolution_m": a.resolution, "import_options": a.extra,
           "covered_scans": sum(keep), "occupied_cells": imp["map"]["occupied_cells"],
           "reference_map_occupied_cells": base["map"]["occupied_cells"],
           "floor_m": rmse(fe), "floor_median_m": fe[len(fe) // 2]}
    if imp["map"].get("refine"):
        out["refine_last_pass"] = imp["map"]["refine"]["per_pass"][-1]
    if not a.no_track:
        tr = json.loads(run([os.path.join(BIN, "fploc-real-track"), src, "--map", plan, "--first-scan", str(first),
                             "--end-scan", str(end), "--start", "ref"]))["scans"]
        te = [r["err_m"] for r, k in zip(tr, keep) if k]
        rm = sorted(r["rms_m"] for r, k in zip(tr, keep) if k and r["status"] == 0)
        out.update({"track_ate_m": rmse(te), "track_max_m": max(te), "track_scans_over_0_5_m": sum(e > 0.5 for e in te),
                    "track_fit_rms_median_m": rm[len(rm) // 2] if rm else None})
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
