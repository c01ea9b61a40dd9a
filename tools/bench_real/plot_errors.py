#!/usr/bin/python3
"""Per-scan error plot of a fploc-real-track run (JSON): position error, yaw error, fit inlier share and status
over the scans, and the trajectories (reference green, estimate blue, POOR/LOST scans red) with the map.

  fploc-real-track LOG --map M.yaml --first-scan S > t.json
  tools/bench_real/plot_errors.py t.json --map M.yaml --out t.png [--covered cov.json]

Needs Debian's python3-matplotlib (diagnostic tool, not part of the bench's contract)."""
import argparse, json, math, os, sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt


def read_map(yaml_path):
    meta = {}
    for line in open(yaml_path):
        if ":" in line:
            k, v = line.split(":", 1)
            meta[k.strip()] = v.strip()
    img = os.path.join(os.path.dirname(yaml_path), meta["image"])
    data = open(img, "rb").read()
    # P5 header: magic, width height, maxval (comments skipped)
    toks, pos = [], 0
    while len(toks) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        toks.append(data[pos:end])
        pos = end
    w, h = int(toks[1]), int(toks[2])
    pix = data[pos + 1:pos + 1 + w * h]
    res = float(meta["resolution"])
    origin = [float(x) for x in meta["origin"].strip("[]").split(",")]
    rows = [list(pix[r * w:(r + 1) * w]) for r in range(h)]
    return rows, (origin[0], origin[0] + w * res, origin[1], origin[1] + h * res)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("track")
    ap.add_argument("--map")
    ap.add_argument("--out", required=True)
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    j = json.load(open(a.track))
    s = j["scans"]
    k = [r["scan"] for r in s]
    fig = plt.figure(figsize=(16, 9))
    ax1 = fig.add_subplot(2, 2, 1)
    ax1.plot(k, [100 * r["err_m"] for r in s], "b-", lw=0.8, label="position error [cm]")
    ax1.set_yscale("symlog", linthresh=10)
    ax1.axhline(5, color="g", lw=0.5)
    bad = [r for r in s if r["status"] != 0]
    ax1.plot([r["scan"] for r in bad], [100 * r["err_m"] for r in bad], "r.", ms=3, label="POOR/LOST")
    ax1.set_ylabel("cm (symlog)")
    ax1.legend(fontsize=8)
    rms = math.sqrt(sum(r["err_m"] ** 2 for r in s) / len(s))
    ax1.set_title(f"{a.title} {j.get('start', '')}: RMSE {100 * rms:.1f} cm over {len(s)} scans, {j['ms_per_scan']:.1f} ms/scan")
    ax2 = fig.add_subplot(2, 2, 3, sharex=ax1)
    ax2.plot(k, [r["err_yaw_deg"] for r in s], "m-", lw=0.8, label="yaw error [deg]")
    ax2.plot(k, [100 * r["inlier_ratio"] for r in s], "k-", lw=0.5, alpha=0.6, label="inliers [%]")
    ax2.plot(k, [r.get("hypotheses", 1) * 10 for r in s], "c-", lw=0.8, label="hypotheses x10")
    ax2.set_ylim(-30, 105)
    ax2.legend(fontsize=8)
    ax2.set_xlabel("scan")
    ax3 = fig.add_subplot(1, 2, 2)
    if a.map:
        rows, ext = read_map(a.map)
        ax3.imshow(rows, cmap="gray", extent=ext, vmin=0, vmax=255)
    ax3.plot([r["ref_x"] for r in s], [r["ref_y"] for r in s], "g-", lw=1.2, label="reference")
    ax3.plot([r["x"] for r in s], [r["y"] for r in s], "b-", lw=0.7, label="fploc")
    ax3.plot([r["x"] for r in bad], [r["y"] for r in bad], "r.", ms=3)
    xs = [r["ref_x"] for r in s] + [r["x"] for r in s]
    ys = [r["ref_y"] for r in s] + [r["y"] for r in s]
    ax3.set_xlim(min(xs) - 3, max(xs) + 3)
    ax3.set_ylim(min(ys) - 3, max(ys) + 3)
    ax3.set_aspect("equal")
    ax3.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=80)
    return 0


if __name__ == "__main__":
    sys.exit(main())
