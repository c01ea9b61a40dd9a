#!/usr/bin/env python3
"""A fake Ouster sensor HTTP API for tests (never on a real network: the tests run it in a private
network namespace). It keeps an active and a staged configuration, reinitialises on request and reports
INITIALIZING for --init-s seconds (-1: forever), then RUNNING / STANDBY, or ERROR with active alerts
(--error). Firmware generations: 2.1 (metadata from cmd/get_*), 2.2-2.x (cmd/ config endpoints,
/api/v1/sensor/metadata), 3.x (GET/POST /api/v1/sensor/config). --fw none: no HTTP API (404).
Endpoints and JSON shapes follow the Ouster HTTP API reference (see docs/notes/os1.md).
Every request is printed to stdout as "REQ <method> <path>" (the tests read the sequence)."""
import argparse
import json
import re
import sys
import threading
import time
import urllib.parse
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

LIDAR_MODES = {"512x10", "512x20", "1024x10", "1024x20", "2048x10", "4096x5"}
PROFILES = {"LEGACY", "RNG19_RFL8_SIG16_NIR16", "RNG19_RFL8_SIG16_NIR16_DUAL", "RNG15_RFL8_NIR8",
            "FUSA_RNG15_RFL8_NIR8_DUAL"}
TS_MODES = {"TIME_FROM_INTERNAL_OSC", "TIME_FROM_SYNC_PULSE_IN", "TIME_FROM_PTP_1588"}

ap = argparse.ArgumentParser()
ap.add_argument("--bind", default="127.0.0.1")
ap.add_argument("--port", type=int, default=80)
ap.add_argument("--fw", default="ousteros-image-prod-aries-v2.3.0+20220415163956")
ap.add_argument("--init-s", type=float, default=0.5, help="INITIALIZING after a reinit (-1: never RUNNING)")
ap.add_argument("--error", action="store_true", help="ERROR after a reinit, with active alerts")
ap.add_argument("--warn-after", type=float, default=-1, help="raise a WARNING alert this long after RUNNING")
ap.add_argument("--metadata", required=True, help="beam angles from this metadata JSON")
args = ap.parse_args()

m = re.search(r"v?(\d+)\.(\d+)\.(\d+)", args.fw)
FW = tuple(int(x) for x in m.groups()) if m else (0, 0, 0)
base = json.load(open(args.metadata))
alt = base.get("beam_altitude_angles") or base["beam_intrinsics"]["beam_altitude_angles"]
azi = base.get("beam_azimuth_angles") or base["beam_intrinsics"]["beam_azimuth_angles"]

lock = threading.Lock()
active = {"udp_dest": "", "udp_port_lidar": 7502, "udp_port_imu": 7503, "lidar_mode": "512x20",
          "timestamp_mode": "TIME_FROM_INTERNAL_OSC", "operating_mode": "NORMAL", "azimuth_window": [0, 360000],
          "multipurpose_io_mode": "OFF", "signal_multiplier": 1, "auto_start_flag": 1}
if FW >= (2, 2, 0):
    active["udp_profile_lidar"] = "LEGACY"
    active["udp_profile_imu"] = "LEGACY"
staged = dict(active)
state = {"reinit_at": time.time() - 100.0, "running_since": None, "cursor": 0, "log": [], "alerts": {}}


def raise_alert(aid, level, cat, msg, verbose=""):
    a = {"id": aid, "level": level, "category": cat, "msg": msg, "msg_verbose": verbose, "active": True,
         "realtime": str(time.time_ns()), "cursor": state["cursor"]}
    state["cursor"] += 1
    state["alerts"][aid] = a
    state["log"] = (state["log"] + [a])[-32:]


def status():
    dt = time.time() - state["reinit_at"]
    if args.init_s < 0 or dt < args.init_s:
        return "INITIALIZING"
    if args.error:
        if "0x01000001" not in state["alerts"]:
            raise_alert("0x01000001", "ERROR", "OVERTEMP", "Unit internal temperature is too high; shutting down.",
                        "internal temperature 96 C")
            raise_alert("0x0100000c", "WARNING", "STARTUP", "Unit has experienced an internal warning during startup.")
        return "ERROR"
    if active["operating_mode"] == "STANDBY":
        return "STANDBY"
    if state["running_since"] is None:
        state["running_since"] = time.time()
    if args.warn_after >= 0 and time.time() - state["running_since"] > args.warn_after and "0x01000017" not in state["alerts"]:
        raise_alert("0x01000017", "WARNING", "UDP_TRANSMISSION",
                    "Received an unknown error when trying to send lidar data UDP packet; closing socket.",
                    f"{active['udp_dest']}:{active['udp_port_lidar']}")
    return "RUNNING"


def sensor_info():
    return {"build_date": "2022-04-14T21:11:47Z", "build_rev": "v%d.%d.%d" % FW, "image_rev": args.fw,
            "initialization_id": 5431292, "prod_line": "OS-1-64", "prod_pn": "840-102145-D", "prod_sn": "991913000010",
            "status": status()}


def metadata():
    cols = int(active["lidar_mode"].split("x")[0])
    fmt = {"columns_per_frame": cols, "columns_per_packet": 16, "pixels_per_column": len(alt),
           "column_window": [0, cols - 1]}
    if "udp_profile_lidar" in active:
        fmt["udp_profile_lidar"] = active["udp_profile_lidar"]
    return {"sensor_info": sensor_info(),
            "beam_intrinsics": {"beam_altitude_angles": alt, "beam_azimuth_angles": azi,
                                "lidar_origin_to_beam_origin_mm": 12.163},
            "imu_intrinsics": {"imu_to_sensor_transform": [1, 0, 0, 6.253, 0, 1, 0, -11.775, 0, 0, 1, 7.645, 0, 0, 0, 1]},
            "lidar_intrinsics": {"lidar_to_sensor_transform": [-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1]},
            "lidar_data_format": fmt, "calibration_status": {"reflectivity": {"valid": True}},
            "config_params": dict(active)}


def check(cfg):
    """The sensor's own validation: an error string or None."""
    for k, v in cfg.items():
        if k == "lidar_mode" and v not in LIDAR_MODES:
            return f"invalid lidar_mode {v}"
        if k == "udp_profile_lidar" and v not in PROFILES:
            return f"invalid udp_profile_lidar {v}"
        if k == "timestamp_mode" and v not in TS_MODES:
            return f"invalid timestamp_mode {v}"
        if k == "operating_mode" and v not in ("NORMAL", "STANDBY"):
            return f"invalid operating_mode {v}"
        if k not in active and not (k == "udp_ip"):
            return f"unknown parameter {k}"
    return None


def reinit():
    active.clear()
    active.update(staged)
    state["reinit_at"] = time.time()
    state["running_since"] = None


class H(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"

    def log_message(self, *a):
        pass

    def reply(self, code, body, ctype="application/json"):
        data = body.encode() if isinstance(body, str) else json.dumps(body).encode()
        self.send_response(code)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)

    def do_GET(self):
        print("REQ GET", self.path, flush=True)
        url = urllib.parse.urlsplit(self.path)
        p, q = url.path, url.query
        with lock:
            if args.fw == "none":
                return self.reply(404, "Not Found", "text/plain")
            if p == "/api/v1/system/firmware":
                return self.reply(200, {"fw": args.fw})
            if p == "/api/v1/sensor/alerts":
                cur = int(urllib.parse.parse_qs(q).get("cursor", ["0"])[0])
                return self.reply(200, {"active": list(state["alerts"].values()),
                                        "log": [a for a in state["log"] if a["cursor"] >= cur],
                                        "next_cursor": state["cursor"]})
            if p == "/api/v1/sensor/metadata/sensor_info" and FW >= (2, 2, 0):
                return self.reply(200, sensor_info())
            if p == "/api/v1/sensor/metadata" and FW >= (2, 2, 0):
                if status() != "RUNNING":
                    return self.reply(503, "sensor not running", "text/plain")
                return self.reply(200, metadata())
            if p == "/api/v1/sensor/config" and FW >= (3, 0, 0):
                return self.reply(200, active)
            if p.startswith("/api/v1/sensor/cmd/"):
                return self.cmd(p[len("/api/v1/sensor/cmd/"):], q)
        self.reply(404, "Not Found", "text/plain")

    def cmd(self, name, q):
        md = metadata()
        ok_auto = '"set_config_param"' if FW < (2, 3, 0) else "{}"
        if name == "get_config_param":
            which = urllib.parse.unquote_plus(q.split("=", 1)[1]) if "=" in q else ""
            return self.reply(200, active if which == "active" else staged)
        if name == "set_config_param":
            raw = urllib.parse.unquote_plus(q.split("=", 1)[1])  # ". {json}" (the '+' is a space)
            key, _, value = raw.partition(" ")
            try:
                cfg = json.loads(value) if key == "." else {key: value}
            except ValueError:
                return self.reply(400, "error: bad JSON", "text/plain")
            err = check(cfg)
            if err:
                return self.reply(400, "error: " + err, "text/plain")
            staged.update(cfg)
            return self.reply(200, '"set_config_param"')
        if name == "set_udp_dest_auto":
            staged["udp_dest"] = self.client_address[0]
            return self.reply(200, ok_auto)
        if name == "reinitialize":
            reinit()
            return self.reply(200, "{}")
        if name == "save_config_params":
            return self.reply(200, "{}")
        if name == "get_sensor_info":
            return self.reply(200, sensor_info())
        for key in ("beam_intrinsics", "imu_intrinsics", "lidar_intrinsics", "lidar_data_format"):
            if name == "get_" + key:
                return self.reply(200, md[key])
        self.reply(404, "Not Found", "text/plain")

    def do_POST(self):
        print("REQ POST", self.path, flush=True)
        n = int(self.headers.get("Content-Length", "0"))
        body = self.rfile.read(n)
        url = urllib.parse.urlsplit(self.path)
        qs = urllib.parse.parse_qs(url.query)
        with lock:
            if args.fw == "none" or url.path != "/api/v1/sensor/config" or FW < (3, 0, 0):
                return self.reply(404, "Not Found", "text/plain")
            try:
                cfg = json.loads(body)
            except ValueError:
                return self.reply(400, {"error": "bad JSON"})
            if cfg.get("udp_dest") == "@auto":
                cfg["udp_dest"] = self.client_address[0]
            err = check(cfg)
            if err:
                return self.reply(400, {"error": err})
            staged.update(cfg)
            if qs.get("reinit", ["true"])[0].lower() == "true":
                reinit()
            self.send_response(204)
            self.send_header("Content-Length", "0")
            self.end_headers()


srv = ThreadingHTTPServer((args.bind, args.port), H)
print(f"fake sensor fw {args.fw} on {args.bind}:{args.port}", flush=True)
try:
    srv.serve_forever()
except KeyboardInterrupt:
    pass
