"""Helpers shared by fploc's Python benchmark drivers (tools/bench_paper, modules/amcl/bench): running
the built programs, reading TUM trajectories, scoring with `fploc eval`."""
import bisect
import json
import math
import os
import subprocess
import sys


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def fmt_num(v, digits=2, scale=1):
    """A number for a text summary: 1.55, not 1.5474540577388338; "-" for a value not measured (None, NaN, inf),
    never Python's None or nan. `scale` converts (100: metres to cm)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return "-" if v is None else str(v)
    return f"{v * scale:.{digits}f}" if math.isfinite(v) else "-"


def fmt_ms(ms):
    """ms per scan per node for a text summary: "segmenter 1.2, features 0.8", not a Python dict."""
    if isinstance(ms, dict):
        return ", ".join(f"{k} {fmt_num(v, 1)}" for k, v in ms.items()) or "-"
    return fmt_num(ms, 1)


def run(cmd, who):
    """Runs cmd; on failure prints the end of its stderr and exits naming `who` and the program."""
    try:
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    except FileNotFoundError:
        # A driver started from the source tree looks for the programs beside itself.
        how = f"run it as `bin/{who}`" if who.startswith("fploc bench ") else "run the built copy (build/bin)"
        raise SystemExit(f"{who}: {cmd[0]} not found: {how}, or set FPLOC_BIN to the directory of the built programs")
    if r.returncode != 0:
        log(r.stderr[-4000:])
        raise SystemExit(f"{who}: {os.path.basename(cmd[0])} failed (exit {r.returncode}): {' '.join(cmd)}")
    return r.stdout, r.stderr


def read_tum(path):
    """Rows [t, x, y, z, qx, qy, qz, qw] of a TUM file (comments and blank lines skipped)."""
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append([float(v) for v in line.split()])
    return rows


class Truth:
    """A TUM ground truth (rows of read_tum) looked up at a pose's own time stamp."""

    def __init__(self, rows):
        self.rows = rows
        self.t = [r[0] for r in rows]

    def interpolated(self, t):
        """(x, y, z) linearly interpolated at t and the nearer truth row (for the attitude), or None
        outside the truth's time span."""
        i = bisect.bisect_left(self.t, t)
        if i <= 0 or i >= len(self.rows):
            return None
        a, b = self.rows[i - 1], self.rows[i]
        f = (t - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 0.0
        return [a[k] + f * (b[k] - a[k]) for k in (1, 2, 3)], (a if f < 0.5 else b)

    def nearest(self, t, tolerance_s):
        """The truth row nearest to t, or None when it is more than tolerance_s away."""
        if not self.rows:
            return None
        i = min(max(bisect.bisect_left(self.t, t), 0), len(self.rows) - 1)
        if i > 0 and abs(self.t[i - 1] - t) < abs(self.t[i] - t):
            i -= 1
        return self.rows[i] if abs(self.t[i] - t) <= tolerance_s else None


def pct(values, q):
    """The q-quantile (0..1) of values by rank, None for none."""
    s = sorted(values)
    return s[min(len(s) - 1, int(q * len(s)))] if s else None


def roll_pitch(q):
    """Roll and pitch [rad] of a quaternion (x, y, z, w), as in a TUM row's last four columns."""
    x, y, z, w = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    return roll, pitch


def yaw_of(row):
    qx, qy, qz, qw = row[4:8]
    return math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))


def fploc_eval(bin_dir, gt, est, who, plot=None, uncertainty=None):
    """`fploc eval --json` of est against gt (dict), or None when est is missing or empty. With uncertainty
    (a fploc-pose-logger uncertainty_file of est, when it exists): also NEES and false OK (nees_median,
    false_ok_poses, ... see modules/eval/uncertainty.h)."""
    if not os.path.exists(est) or os.path.getsize(est) == 0:
        return None
    cmd = [os.path.join(bin_dir, "fploc-eval"), "--gt", gt, "--est", est, "--json"]
    if plot:
        cmd += ["--plot", plot]
    if uncertainty and os.path.exists(uncertainty) and os.path.getsize(uncertainty) > 0:
        cmd += ["--uncertainty", uncertainty]
    return json.loads(run(cmd, who)[0])


def status_counts(uncertainty):
    """Poses per status (OK, POOR, LOST) in a fploc-pose-logger uncertainty_file (None when missing)."""
    if not uncertainty or not os.path.exists(uncertainty):
        return None
    n = [0, 0, 0]
    with open(uncertainty) as f:
        for line in f:
            v = line.split()
            if v and not v[0].startswith("#") and len(v) >= 2 and v[1] in ("0", "1", "2"):
                n[int(v[1])] += 1
    return n


def replay(bin_dir, graph, log_path, sets, pipeline, who):
    """`fploc replay --graph GRAPH --log LOG --json --set ...`: returns (nodes by name, scans, ms per scan of
    each node named in `pipeline`: its thread CPU time, else its total, over the feature frames)."""
    cmd = [os.path.join(bin_dir, "fploc-replay"), "--graph", graph, "--log", log_path, "--json"]
    for s in sets:
        cmd += ["--set", s]
    rep = json.loads(run(cmd, who)[0].strip().splitlines()[-1])
    nodes = {n["name"]: n for n in rep["nodes"]}
    scans = nodes.get("features", {}).get("messages", 1) or 1
    ms = {n: round(nodes[n].get("cpu_ms", nodes[n]["total_ms"]) / scans, 3) for n in pipeline if n in nodes}
    return nodes, scans, ms


def solve3(a, b):
    """x with a x = b for a 3x3 (list of rows); None when singular."""
    m = [row[:] + [bb] for row, bb in zip(a, b)]
    for c in range(3):
        piv = max(range(c, 3), key=lambda r: abs(m[r][c]))
        if abs(m[piv][c]) < 1e-15:
            return None
        m[c], m[piv] = m[piv], m[c]
        for r in range(3):
            if r != c:
                f = m[r][c] / m[c][c]
                for k in range(c, 4):
                    m[r][k] -= f * m[c][k]
    return [m[r][3] / m[r][r] for r in range(3)]


def nees3(e, c):
    """e^T P^-1 e for e = (dx, dy, dyaw) and P from its upper triangle (xx, xy, xyaw, yy, yyaw, yawyaw), as in a
    fploc-pose-logger uncertainty_file; None when P is singular or the result negative (not positive definite)."""
    xx, xy, xa, yy, ya, aa = c
    if not all(math.isfinite(v) for v in c):
        return None
    sol = solve3([[xx, xy, xa], [xy, yy, ya], [xa, ya, aa]], list(e))
    if sol is None:
        return None
    v = sum(ei * si for ei, si in zip(e, sol))
    return v if v >= 0 else None
