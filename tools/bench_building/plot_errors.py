#!/usr/bin/python3
"""Errors of a bench building run against time, as a PNG: where a p99 comes from.

    tools/bench_building/plot_errors.py OUT.png RUN_DIR [RUN_DIR2 [RUN_DIR3]]

RUN_DIR: a folder with gt.tum and wo.tum (`fploc bench building --keep DIR` keeps one per row). Five panels,
top to bottom: z error (+-10 cm, dotted +-2 cm), roll error and pitch error (+-1 deg, dotted +-0.2 deg), the
true z and the true pitch. Runs in red, blue, green (e.g. before / after). Scored as
bench building scores (truth interpolated at each pose's time; roll/pitch from the nearer truth sample).
Needs Debian's python3-matplotlib (diagnostic tool). Also prints, per 5 s window, the largest |errors| of each run.
"""
import bisect
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "pylib"))
from fploc_tools import read_tum, roll_pitch  # noqa: E402

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def series(d):
    """(t, z err, roll err deg, pitch err deg, true z, true pitch deg) per pose."""
    gt, est = read_tum(os.path.join(d, "gt.tum")), read_tum(os.path.join(d, "wo.tum"))
    ts = [g[0] for g in gt]
    out = []
    for e in est:
        i = min(max(bisect.bisect_left(ts, e[0]), 1), len(ts) - 1)
        a, b = gt[i - 1], gt[i]
        f = (e[0] - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 0.0
        z = a[3] + f * (b[3] - a[3])
        near = a if abs(e[0] - a[0]) < abs(e[0] - b[0]) else b
        r1, p1 = roll_pitch(e[4:8])
        r0, p0 = roll_pitch(near[4:8])
        out.append((e[0] - gt[0][0], e[3] - z, math.degrees(r1 - r0), math.degrees(p1 - p0), z, math.degrees(p0)))
    return out


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    path, dirs = sys.argv[1], sys.argv[2:5]
    runs = [series(d) for d in dirs]
    panels = [(1, 100, "z error [cm]", (-10, 10), [2, -2]), (2, 1, "roll error [deg]", (-1, 1), [0.2, -0.2]),
              (3, 1, "pitch error [deg]", (-1, 1), [0.2, -0.2]), (4, 1, "true z [m]", None, []),
              (5, 1, "true pitch [deg]", None, [])]
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(12, 2.0 * len(panels)))
    colours = ["tab:red", "tab:blue", "tab:green"]
    for ax, (idx, scale, label, ylim, refs) in zip(axes, panels):
        for v in refs:
            ax.axhline(v, color="grey", linestyle=":", linewidth=0.8)
        for c, d, r in zip(colours, dirs, runs):
            ax.plot([s[0] for s in r], [s[idx] * scale for s in r], color=c, linewidth=0.8, label=os.path.basename(d.rstrip("/")))
        if ylim:
            ax.set_ylim(*ylim)
        ax.set_ylabel(label)
        ax.grid(True, axis="x", color="0.9")
    axes[0].legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    t1 = max(s[0] for r in runs for s in r)
    for d, r in zip(dirs, runs):
        print(d)
        for t in range(0, int(t1) + 1, 5):
            w = [s for s in r if t <= s[0] < t + 5]
            if w:
                print(f"{t:4d} s: |z| max {100 * max(abs(s[1]) for s in w):5.2f} cm, |roll| max {max(abs(s[2]) for s in w):.3f} deg, "
                      f"|pitch| max {max(abs(s[3]) for s in w):.3f} deg")


if __name__ == "__main__":
    main()
