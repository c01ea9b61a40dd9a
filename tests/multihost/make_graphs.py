#!/usr/bin/env python3
"""Writes the network test's graphs: the demo pipeline of robot r1 spread over three hosts (driver,
compute, dashboard), the same graph on one host (the baseline), robot r2's identical graph on its own
host, and a graph naming an unreachable host (for --check)."""
import sys

T, ROOT, KEY = sys.argv[1:4]
PLAN = f"{ROOT}/data/plans/room.json"
SSH = [f"IdentityFile={KEY}", "StrictHostKeyChecking=no", "UserKnownHostsFile=/dev/null"]


def host(name, addr):
    opts = " ".join(f'ssh_option: "{o}"' for o in SSH)
    return f'host {{ name: "{name}" address: "{addr}" user: "root" {opts} }}\n'


def graph(name, robot, placement, hosts, ttl, out, dashboard=True):
    on = lambda n: f'  host: "{placement[n]}"\n' if placement.get(n) else ""
    g = f'name: "{name}"\nrobot: "{robot}"\nlcm_url: "udpm://239.255.76.67:7667?recv_buf_size=4194304"\n'
    g += f'lcm_ttl: {ttl}\nshutdown_timeout_s: 2\n'
    if ttl:
        g += 'lcm_interface: "eth0"\n'
    g += "".join(hosts)
    nodes = [
        ("sim", "fploc-sim-sensor", [], ["ground_truth:FPLOC_GROUND_TRUTH"],
         f'sim {{ plan {{ file: "{PLAN}" }} scenario: "room-small-loop-medium" seed: 1 loop: true '
         f'metadata_out: "{out}-os1.json" start_delay_s: 5 }}'),
        ("os1_driver", "fploc-os1-driver", [], ["scan:OS1_SCAN"],
         f'os1_driver {{ metadata: "{out}-os1.json" lidar_port: 7502 bind_address: "127.0.0.1" }}'),
        ("imu_driver", "fploc-imu-driver", [], ["imu:OS1_IMU"],
         'imu_driver { source: "os1" imu_port: 7503 bind_address: "127.0.0.1" }'),
        ("segmenter", "fploc-segmenter", ["scan:OS1_SCAN"], ["segments:FPLOC_SEGMENTS"], "segmenter {}"),
        ("features", "fploc-features", ["segments:FPLOC_SEGMENTS"], ["features:FPLOC_FEATURES"], "features {}"),
        ("matcher", "fploc-matcher", ["features:FPLOC_FEATURES", "imu:OS1_IMU", "refined:FPLOC_POSE_LATEST"],
         ["frame_pose:FPLOC_FRAME_POSE"],
         f'matcher {{ plan {{ file: "{PLAN}" }} lookup: "annf-exact" initial_pose {{ x: 5.7976 y: 3.2267 yaw: -1.4433 }} }}'),
        ("relocalizer", "fploc-relocalizer", ["features:FPLOC_FEATURES", "frame_pose:FPLOC_FRAME_POSE"],
         ["initial_pose:FPLOC_INITIAL_POSE"], f'relocalizer {{ plan {{ file: "{PLAN}" }} }}'),
        ("optimizer", "fploc-optimizer", ["features:FPLOC_FEATURES", "frame_pose:FPLOC_FRAME_POSE"],
         ["pose:FPLOC_POSE", "latest:FPLOC_POSE_LATEST"],
         f'optimizer {{ plan {{ file: "{PLAN}" }} window: 10 alpha: 1.1 beta: 0.9 }}'),
        ("pose_logger", "fploc-pose-logger", ["pose:FPLOC_POSE"], [], f'pose_logger {{ file: "{out}-est.tum" }}'),
        ("gt_logger", "fploc-pose-logger", ["pose:", "ground_truth:FPLOC_GROUND_TRUTH"], [],
         f'pose_logger {{ file: "{out}-gt.tum" }}'),
    ]
    if dashboard:
        nodes.append(("dashboard", "fploc-dashboard",
                      ["pose:FPLOC_POSE", "frame_pose:FPLOC_FRAME_POSE", "features:FPLOC_FEATURES",
                       "ground_truth:FPLOC_GROUND_TRUTH", "telemetry:FPLOC_TELEMETRY"], [],
                      f'dashboard {{ plan {{ file: "{PLAN}" }} bind: "127.0.0.1" port: 18080 }}'))
    for n, exe, ins, outs, opts in nodes:
        g += f'node {{\n  name: "{n}"\n  executable: "{exe}"\n{on(n)}'
        for p in ins:
            port, ch = p.split(":")
            g += f'  input {{ port: "{port}" channel: "{ch}" }}\n'
        for p in outs:
            port, ch = p.split(":")
            g += f'  output {{ port: "{port}" channel: "{ch}" }}\n'
        g += f"  {opts}\n}}\n"
    return g


three = {n: "compute" for n in ["segmenter", "features", "matcher", "relocalizer", "optimizer"]}
three.update({n: "dash" for n in ["pose_logger", "gt_logger", "dashboard"]})
hosts = [host("compute", "10.213.0.2"), host("dash", "10.213.0.3")]
open(f"{T}/mh.pbtxt", "w").write(graph("multihost-r1", "r1", three, hosts, 1, f"{T}/mh"))
open(f"{T}/base.pbtxt", "w").write(graph("onehost-r1", "r1", {}, [], 0, f"{T}/base"))
open(f"{T}/r2.pbtxt", "w").write(graph("robot-r2", "r2", {}, [], 1, f"{T}/r2", dashboard=False))
bad = dict(three)
bad["dashboard"] = "gone"
open(f"{T}/bad.pbtxt", "w").write(
    graph("bad-host", "r1", bad, hosts + [host("gone", "10.213.0.9")], 1, f"{T}/bad"))
