#!/usr/bin/env python3
"""A stand-in for cncstreamd, for developing the web page before the daemon
serves it (stdlib only). It implements the parts of docs/api-v1.md the page
uses, with a pretend machine: positions move with jogs, a job's lines are
"answered" at a fixed rate, status is pushed over a WebSocket every 100 ms.

It is a test aid, not the product: the browser test runs against the real
cncstreamd. Usage: mock_daemon.py [--port N] [--web DIR] [--token T]
"""
import argparse
import base64
import hashlib
import json
import math
import os
import re
import secrets
import struct
import threading
import time
import zlib
from datetime import datetime, timezone
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import parse_qs, unquote, urlsplit

LOCK = threading.RLock()
ARGS = None


def now_iso():
    return datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


class Machine:
    def __init__(self, name):
        self.name = name
        self.mpos = [-200.0, -150.0, -5.0]
        self.wco = [-200.0, -150.0, -25.0]
        self.state = "Idle"
        self.alarm = False
        self.jog_dir = None   # continuous: unit vector
        self.jog_feed = 0
        self.jog_until = 0.0  # lease deadline
        self.jog_owner = None
        self.steps = []       # queued step targets (mpos)
        self.step_feed = 1000
        self.job = None
        self.holder = None
        self.seq = 0
        self.overrides = [100, 100, 100]

    def wpos(self):
        return [round(m - w, 3) for m, w in zip(self.mpos, self.wco)]

    def status(self):
        self.seq += 1
        return {"type": "status", "machine": self.name, "seq": self.seq, "state": self.state,
                "state_text": self.state, "mpos": [round(v, 3) for v in self.mpos], "wpos": self.wpos(),
                "wco": self.wco, "feed": self.jog_feed if self.state == "Jog" else (1000 if self.job and self.job.state == "running" else 0),
                "spindle": 18000 if self.job and self.job.state == "running" else 0, "overrides": self.overrides,
                "buffer": {"planner_free": 15, "rx_free": 128}, "line": None, "link": "ready",
                "alarm": self.alarm, "jogging": self.state == "Jog", "job_active": bool(self.job and self.job.state in ("running", "held")),
                "reported_us": int(time.time() * 1e6)}

    def summary(self):
        return {"name": self.name, "port": "sim", "link": "ready", "profile": "grbl-1.1", "state": self.state,
                "alarm": self.alarm, "job_active": bool(self.job and self.job.state in ("running", "held")),
                "jogging": self.state == "Jog", "control_holder": self.holder,
                "current_job": self.job.id if self.job else None}


class Job:
    seq = 0

    def __init__(self, machine, f, params):
        Job.seq += 1
        self.id = Job.seq
        self.machine = machine
        self.file = f
        self.params = params
        self.state = "generating" if f["kind"] == "stl" else "ready"
        self.message = ""
        self.created_at = now_iso()
        self.started_at = None
        self.ended_at = None
        self.gen_stage = "load"
        self.gen_fraction = 0.0
        self.gcode = None if f["kind"] == "stl" else f["data"].decode()
        self.lines = 0 if self.gcode is None else self.gcode.count("\n")
        self.answered = 0.0
        self.position = 0

    def to_json(self):
        total = self.lines
        frac = (self.answered / total) if total else 0.0
        rate = 4000.0
        return {"id": self.id, "machine": self.machine, "file": self.file["id"], "file_name": self.file["name"],
                "kind": self.file["kind"], "params": self.params, "state": self.state, "position": self.position,
                "message": self.message, "created_at": self.created_at, "started_at": self.started_at,
                "ended_at": self.ended_at,
                "generation": {"stage": self.gen_stage, "fraction": self.gen_fraction, "cached": False, "seconds": 0.5},
                "program": {"lines": total, "estimated_s": total / 50.0} if self.gcode is not None else None,
                "progress": {"lines_sent": int(self.answered), "lines_answered": int(self.answered),
                             "last_answered_line": int(self.answered), "fraction": frac,
                             "eta_s": (total - self.answered) / rate if self.state == "running" else None},
                "preview": self.preview(),
                "journal_id": None, "resumed_from": 0, "from_line": 0}

    def preview(self):
        if self.gcode is None:
            return None
        cut = [p for p in parse_moves(self.gcode) if not p[3]]
        if not cut:
            return None
        xs, ys, zs = [p[0] for p in cut], [p[1] for p in cut], [p[2] for p in cut]
        base = f"/api/v1/jobs/{self.id}"
        return {"bounds": [min(xs), min(ys), max(xs), max(ys)], "z": [min(zs), max(zs)],
                "png": base + "/clmap.png", "path": base + "/path"}


MACHINES = {}
FILES = {}
JOBS = {}
CLIENTS = []      # WsClient
WS_TOKENS = {}    # one-shot -> expiry


def stl_bounds(data):
    if len(data) >= 84:
        n = struct.unpack_from("<I", data, 80)[0]
        if 84 + 50 * n == len(data):
            lo, hi = [math.inf] * 3, [-math.inf] * 3
            for i in range(n):
                vals = struct.unpack_from("<12f", data, 84 + 50 * i)
                for k in range(3):
                    v = vals[3 + k::3]
                    lo[k] = min(lo[k], *v)
                    hi[k] = max(hi[k], *v)
            return n, lo, hi
    text = data.decode("ascii", "replace")
    if text.lstrip().startswith("solid") and "facet" in text:
        import re
        pts = [tuple(map(float, m)) for m in re.findall(r"vertex\s+(\S+)\s+(\S+)\s+(\S+)", text)]
        if pts:
            return len(pts) // 3, [min(p[k] for p in pts) for k in range(3)], [max(p[k] for p in pts) for k in range(3)]
    return None


def fake_program(f, params):
    """A zig-zag over the part's box with a dome for Z: enough to draw a preview."""
    lo, hi = f["lo"], f["hi"]
    sx, sy, sz = hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]
    so = float(params.get("stepover", 0.4))
    out = ["G21 G90 G94 G17", "M3 S18000", "G4 P2", "G0 Z5"]
    rows = max(2, int(sy / so))
    y = 0.0
    for r in range(rows + 1):
        y = min(sy, r * so)
        xs = [i * sx / 60 for i in range(61)]
        if r % 2:
            xs.reverse()
        out.append(f"G0 X{xs[0]:.3f} Y{y:.3f}" if r == 0 else f"G1 Y{y:.3f} F1000")
        if r == 0:
            out.append("G1 Z0 F300")
        for x in xs:
            u, v = x / sx - 0.5, y / sy - 0.5
            z = -sz * (u * u + v * v) * 2
            out.append(f"G1 X{x:.3f} Z{z:.3f}")
    out += ["G0 Z5", "M5", "M2"]
    return "\n".join(out) + "\n"


def parse_moves(text):
    """(x, y, z, rapid) where the program starts and after every motion line."""
    x = y = z = 0.0
    mode = 0
    pts = [(x, y, z, True)]
    for raw in text.splitlines():
        line = re.sub(r"\(.*?\)|;.*$", "", raw).upper()
        moved = False
        for w, v in re.findall(r"([GXYZ])\s*(-?\d*\.?\d+)", line):
            v = float(v)
            if w == "G":
                mode = int(v) if v in (0, 1, 2, 3) else mode
            elif w == "X":
                x, moved = v, True
            elif w == "Y":
                y, moved = v, True
            else:
                z, moved = v, True
        if moved:
            pts.append((x, y, z, mode == 0))
    return pts


VIRIDIS = [(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)]


def viridis(t):
    t = min(1.0, max(0.0, t)) * (len(VIRIDIS) - 1)
    i = min(len(VIRIDIS) - 2, int(t))
    f = t - i
    return bytes(round(a + (b - a) * f) for a, b in zip(VIRIDIS[i], VIRIDIS[i + 1]))


def preview_png(job, long_side):
    """The cutting points splatted onto a coarse grid (the deepest wins), the gaps
    between rows grown from their neighbours, coloured as the daemon colours them."""
    pv = job.preview()
    x0, y0, x1, y1 = pv["bounds"]
    z0, z1 = pv["z"]
    sx, sy = (x1 - x0) or 1.0, (y1 - y0) or 1.0
    w = long_side if sx >= sy else max(1, round(long_side * sx / sy))
    h = long_side if sy >= sx else max(1, round(long_side * sy / sx))
    gw, gh = max(1, w * 64 // long_side), max(1, h * 64 // long_side)
    cell = [[None] * gw for _ in range(gh)]
    for x, y, z, rapid in parse_moves(job.gcode):
        if rapid:
            continue
        cx, cy = min(gw - 1, int((x - x0) / sx * gw)), min(gh - 1, int((y1 - y) / sy * gh))
        if cell[cy][cx] is None or z < cell[cy][cx]:
            cell[cy][cx] = z
    for _ in range(16):
        prev = [row[:] for row in cell]
        for cy in range(gh):
            for cx in range(gw):
                if prev[cy][cx] is None:
                    near = [prev[ny][nx] for nx, ny in ((cx - 1, cy), (cx + 1, cy), (cx, cy - 1), (cx, cy + 1))
                            if 0 <= nx < gw and 0 <= ny < gh and prev[ny][nx] is not None]
                    if near:
                        cell[cy][cx] = sum(near) / len(near)
    colour = [[b"\x0b\x0d\x10" if z is None else viridis((z - z0) / ((z1 - z0) or 1)) for z in row] for row in cell]
    raw = b"".join(b"\0" + b"".join(colour[py * gh // h][px * gw // w] for px in range(w)) for py in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def preview_path(job, max_points):
    """Every point (a stride past max_points), cuts and rapids apart, flat [x, y, z, ...]."""
    pts = parse_moves(job.gcode)
    stride = max(1, -(-len(pts) // max(2, max_points // 2)))
    keep = [p for i, p in enumerate(pts) if i % stride == 0 or i == len(pts) - 1]
    out = {"cuts": [], "rapids": []}
    run = None
    for a, b in zip(keep, keep[1:]):
        kind = "rapids" if b[3] else "cuts"
        if kind != run:
            out[kind].append(list(a[:3]))
            run = kind
        out[kind][-1] += list(b[:3])
    n = sum(len(l) // 3 for k in out for l in out[k])
    return {"points": n, "total_points": len(pts), **out}


# ------------------------------------------------------------------ WebSocket
class WsClient:
    def __init__(self, handler, client_id):
        self.h = handler
        self.client_id = client_id
        self.lock = threading.Lock()
        self.subs = set()
        self.alive = True

    def send(self, obj):
        data = json.dumps(obj).encode()
        hdr = bytes([0x81])
        n = len(data)
        if n < 126:
            hdr += bytes([n])
        elif n < 65536:
            hdr += bytes([126]) + struct.pack(">H", n)
        else:
            hdr += bytes([127]) + struct.pack(">Q", n)
        with self.lock:
            try:
                self.h.wfile.write(hdr + data)
                self.h.wfile.flush()
            except OSError:
                self.alive = False

    def wants(self, machine):
        return "*" in self.subs or machine in self.subs


def broadcast(obj, machine=None):
    for c in list(CLIENTS):
        if c.alive and (machine is None or c.wants(machine)):
            c.send(obj)


def read_frame(rfile):
    h = rfile.read(2)
    if len(h) < 2:
        return None, None
    op = h[0] & 0x0F
    n = h[1] & 0x7F
    if n == 126:
        n = struct.unpack(">H", rfile.read(2))[0]
    elif n == 127:
        n = struct.unpack(">Q", rfile.read(8))[0]
    mask = rfile.read(4) if h[1] & 0x80 else b"\0\0\0\0"
    data = bytearray(rfile.read(n))
    for i in range(len(data)):
        data[i] ^= mask[i % 4]
    return op, bytes(data)


# ------------------------------------------------------------------ simulation
def tick_loop():
    last = time.monotonic()
    next_status = 0.0
    while True:
        time.sleep(0.02)
        t = time.monotonic()
        dt, last = t - last, t
        events = []
        with LOCK:
            for m in MACHINES.values():
                if m.jog_dir is not None:
                    if t > m.jog_until:   # the dead man: no renew within the lease
                        m.jog_dir = None
                        events.append(({"type": "event", "machine": m.name, "kind": "warning", "code": 0, "line": 0,
                                        "text": "continuous jog lease expired: jog cancelled", "info": None}, m.name))
                    else:
                        for k in range(3):
                            m.mpos[k] += m.jog_dir[k] * m.jog_feed / 60 * dt
                if m.steps:
                    tgt = m.steps[0]
                    d = [tgt[k] - m.mpos[k] for k in range(3)]
                    dist = math.sqrt(sum(v * v for v in d))
                    adv = m.step_feed / 60 * dt
                    if dist <= adv:
                        m.mpos = list(tgt)
                        m.steps.pop(0)
                    else:
                        m.mpos = [m.mpos[k] + d[k] / dist * adv for k in range(3)]
                j = m.job
                if j and j.state == "running":
                    rate = 0.2 if m.name == "bench" else 4000   # bench: real time, a G-code line takes seconds
                    j.answered = min(j.lines, j.answered + rate * dt * m.overrides[0] / 100)
                    if j.answered >= j.lines:
                        j.state = "done"
                        j.ended_at = now_iso()
                        m.job = None
                        events.append(({"type": "queue", "machine": m.name, "jobs": []}, m.name))
                    events.append(({"type": "job", "job": j.id, "machine": m.name, "state": j.state,
                                    "progress": j.to_json()["progress"], "eta_s": j.to_json()["progress"]["eta_s"],
                                    "message": j.message}, m.name))
                if m.alarm:
                    m.state = "Alarm"
                elif m.job and m.job.state == "held":
                    m.state = "Hold:0"
                elif m.job and m.job.state == "running":
                    m.state = "Run"
                elif m.jog_dir is not None or m.steps:
                    m.state = "Jog"
                else:
                    m.state = "Idle"
            for j in JOBS.values():
                if j.state == "generating":
                    j.gen_fraction = min(1.0, j.gen_fraction + dt / 1.0)
                    j.gen_stage = "tool path" if j.gen_fraction < 0.8 else "G-code"
                    if j.gen_fraction >= 1.0:
                        j.gcode = fake_program(j.file, j.params)
                        j.lines = j.gcode.count("\n")
                        j.state = "ready"
                        j.gen_stage = "done"
                        events.append(({"type": "queue", "machine": j.machine, "jobs": []}, j.machine))
                    events.append(({"type": "job", "job": j.id, "machine": j.machine, "state": j.state,
                                    "generation": j.to_json()["generation"], "message": ""}, j.machine))
            status = [] if t < next_status else [(m.status(), m.name) for m in MACHINES.values()]
            if status:
                next_status = t + 0.1
        for obj, mn in events + status:
            broadcast(obj, mn)


# ------------------------------------------------------------------ HTTP
class ApiErr(Exception):
    def __init__(self, status, code, message):
        super().__init__(message)
        self.status, self.code, self.message = status, code, message


class Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"

    def log_message(self, fmt, *a):
        if os.environ.get("MOCK_VERBOSE"):
            super().log_message(fmt, *a)

    # -- plumbing
    def reply(self, status, body=None, ctype="application/json", extra=None):
        data = b"" if body is None else (body if isinstance(body, bytes) else json.dumps(body).encode())
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(data)))
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Cache-Control", "no-store")
        for k, v in (extra or {}).items():
            self.send_header(k, v)
        self.end_headers()
        self.wfile.write(data)

    def body(self):
        n = int(self.headers.get("Content-Length") or 0)
        return self.rfile.read(n) if n else b""

    def json_body(self):
        b = self.body()
        try:
            return json.loads(b) if b else {}
        except ValueError as e:
            raise ApiErr(400, "bad_request", f"malformed JSON: {e}")

    def authorised(self):
        if not ARGS.token:
            return True
        return self.headers.get("Authorization", "") == "Bearer " + ARGS.token

    def check_origin(self):
        o = self.headers.get("Origin")
        if o is not None and o != "http://" + self.headers.get("Host", ""):
            raise ApiErr(403, "forbidden_origin", f"origin {o} is not allowed")

    def need_control(self, m):
        cid = self.headers.get("X-Client-Id")
        if not cid:
            raise ApiErr(428, "client_id_required", "X-Client-Id is required")
        if m.holder is None:
            raise ApiErr(409, "control_required", f"nobody controls {m.name}: acquire control first")
        if m.holder != cid:
            raise ApiErr(409, "control_held", f"{m.holder} controls {m.name}")

    def do_GET(self):
        self.route("GET")

    def do_POST(self):
        self.route("POST")

    def do_DELETE(self):
        self.route("DELETE")

    def route(self, method):
        u = urlsplit(self.path)
        path = unquote(u.path)
        q = {k: v[0] for k, v in parse_qs(u.query).items()}
        try:
            if method == "GET" and (path == "/" or path.startswith("/static/")):
                return self.static("index.html" if path == "/" else path[len("/static/"):])
            if path == "/api/v1/ws":
                return self.websocket(q)
            if path == "/api/v1/health":
                return self.reply(200, {"ok": True, "version": "mock"})
            if not self.authorised():
                raise ApiErr(401, "unauthorized", "token required")
            if method != "GET":
                self.check_origin()
            with LOCK:
                return self.api(method, path, q)
        except ApiErr as e:
            extra = {"WWW-Authenticate": "Bearer"} if e.status == 401 else None
            if method != "GET":
                self.close_connection = True   # the body may not have been read
            self.reply(e.status, {"error": {"status": e.status, "code": e.code, "message": e.message}}, extra=extra)

    def static(self, rel):
        if ".." in rel.split("/") or "\\" in rel or rel.startswith("/"):
            raise ApiErr(404, "not_found", "no such file")
        p = os.path.join(ARGS.web, rel)
        if not os.path.isfile(p):
            raise ApiErr(404, "not_found", "no such file")
        ext = os.path.splitext(p)[1]
        ctype = {".html": "text/html; charset=utf-8", ".js": "text/javascript", ".css": "text/css",
                 ".svg": "image/svg+xml", ".png": "image/png"}.get(ext, "application/octet-stream")
        with open(p, "rb") as f:
            self.reply(200, f.read(), ctype)

    def machine(self, name):
        m = MACHINES.get(name)
        if not m:
            raise ApiErr(404, "not_found", f"no machine {name}")
        return m

    def job(self, jid):
        j = JOBS.get(int(jid)) if jid.isdigit() else None
        if not j:
            raise ApiErr(404, "not_found", f"no job {jid}")
        return j

    def api(self, method, path, q):
        parts = path.strip("/").split("/")[2:]  # after api/v1
        if parts == ["ws-token"] and method == "POST":
            self.body()
            t = secrets.token_hex(16)
            WS_TOKENS[t] = time.time() + 30
            return self.reply(200, {"token": t, "expires_in_s": 30})
        if parts == ["machines"]:
            return self.reply(200, {"machines": [m.summary() for m in MACHINES.values()]})
        if parts == ["tools"] and method == "GET":
            return self.reply(200, {"tools": []})  # an empty library (the real daemon's is tested in test_tools_page.py)
        if parts[0] == "machines" and len(parts) >= 2:
            m = self.machine(parts[1])
            rest = parts[2:]
            if not rest:
                d = m.summary()
                st = m.status()
                d.update({"banner": "Grbl 1.1h ['$' for help]", "status": {k: st[k] for k in ("state", "state_text", "mpos", "wpos", "wco", "feed", "spindle", "overrides", "line")},
                          "buffer": {"planner_free": 15, "rx_free": 128, "in_flight": 0, "capacity": 128},
                          "progress": {"state": "none"},
                          "alarm_info": {"code": 2, "name": "Soft limit", "text": "A move would have gone past a soft limit; the machine position is kept.",
                                         "action": "Unlock ($X) and jog back inside the travel.", "reset_required": False, "position_lost": False} if m.alarm else None})
                return self.reply(200, d)
            if rest == ["control"]:
                cid = self.headers.get("X-Client-Id")
                if method == "POST":
                    b = self.json_body()
                    if m.holder and m.holder != cid and not b.get("force"):
                        raise ApiErr(409, "control_held", f"{m.holder} controls {m.name}")
                    m.holder = cid
                elif method == "DELETE":
                    if m.holder == cid:
                        m.holder = None
                broadcast({"type": "control", "machine": m.name, "holder": m.holder}, m.name)
                return self.reply(200, {"holder": m.holder, "you": m.holder == cid})
            if rest == ["jog"] and method == "POST":
                b = self.json_body()
                self.need_control(m)
                if m.alarm or (m.job and m.job.state in ("running", "held")):
                    raise ApiErr(409, "refused", "a job is running" if m.job else "the machine is in alarm")
                if len(m.steps) >= 2:
                    raise ApiErr(409, "refused", "two steps are queued already")
                d = b["dir"]
                n = math.sqrt(sum(v * v for v in d))
                base = m.steps[-1] if m.steps else m.mpos
                m.steps.append([base[k] + d[k] / n * float(b["distance"]) for k in range(3)])
                m.step_feed = min(500.0, float(b.get("feed", 1000)))   # the simulator's $110-$112
                return self.reply(202, {"accepted": True})
            if rest == ["jog", "cancel"] and method == "POST":
                self.body()
                m.jog_dir = None
                m.steps = []
                return self.reply(202, {"accepted": True})
            if rest[0] == "actions" and method == "POST":
                b = self.json_body()
                self.need_control(m)
                a = rest[1]
                if a == "zero_axes":
                    for ax in b.get("axes", ""):
                        k = "XYZ".index(ax)
                        m.wco[k] = m.mpos[k]
                elif a == "unlock":
                    m.alarm = False
                elif a == "reset":
                    if m.steps or m.jog_dir is not None:   # GRBL: a reset in motion is alarm 3
                        m.steps, m.jog_dir, m.alarm = [], None, True
                        broadcast({"type": "event", "machine": m.name, "kind": "alarm", "code": 3, "line": 0, "text": "ALARM:3",
                                   "info": {"name": "Abort during cycle", "text": "Reset while in motion. Machine position is likely lost due to the sudden halt.",
                                            "action": "Re-home with $H (or unlock with $X and re-zero) before cutting again.",
                                            "reset_required": False, "position_lost": True}}, m.name)
                elif a == "go_to_work_zero":
                    m.steps.append(list(m.wco))
                return self.reply(202, {"accepted": True})
            if rest == ["realtime"] and method == "POST":
                b = self.json_body()
                self.need_control(m)
                c = b.get("command", "")
                if c.startswith("feed_ov_"):
                    m.overrides[0] = 100 if c.endswith("reset") else max(10, min(200, m.overrides[0] + (10 if "plus" in c else -10)))
                elif c.startswith("spindle_ov_"):
                    m.overrides[2] = 100 if c.endswith("reset") else max(10, min(200, m.overrides[2] + (10 if "plus" in c else -10)))
                elif c.startswith("rapid_ov_"):
                    m.overrides[1] = {"reset": 100, "medium": 50, "low": 25}[c.rsplit("_", 1)[1]]
                return self.reply(202, {"accepted": True})
            if rest == ["console"] and method == "POST":
                b = self.json_body()
                self.need_control(m)
                line = b.get("line", "")
                broadcast({"type": "console", "machine": m.name, "dir": "out", "text": line}, m.name)
                if line.strip().upper() == "ALARM":   # a way to show the alarm banner
                    m.alarm = True
                    broadcast({"type": "event", "machine": m.name, "kind": "alarm", "code": 2, "line": 0, "text": "ALARM:2",
                               "info": {"name": "Soft limit", "text": "A move would have gone past a soft limit; the machine position is kept.",
                                        "action": "Unlock ($X) and jog back inside the travel.", "reset_required": False, "position_lost": False}}, m.name)
                elif line.strip().upper().startswith("G99"):
                    broadcast({"type": "console", "machine": m.name, "dir": "in", "text": "error:20"}, m.name)
                    broadcast({"type": "event", "machine": m.name, "kind": "error", "code": 20, "line": 0, "text": "error:20",
                               "info": {"name": "Unsupported command", "text": "Unsupported or invalid G-code command found in the block.",
                                        "action": "Remove or replace the command: this controller does not implement it.",
                                        "reset_required": False, "position_lost": False}}, m.name)
                else:
                    broadcast({"type": "console", "machine": m.name, "dir": "in", "text": "ok"}, m.name)
                return self.reply(202, {"accepted": True})
            if rest in (["hold"], ["stop"]) and method == "POST":
                self.body()
                if m.job and rest == ["hold"]:
                    m.job.state = "held"
                if m.job and rest == ["stop"]:
                    m.job.state, m.job.ended_at, m.job = "stopped", now_iso(), None
                return self.reply(202, {"accepted": True})
        if parts == ["files"] and method == "POST":
            if self.headers.get("Content-Length") is None:
                raise ApiErr(411, "length_required", "Content-Length required")
            data = self.body()
            fid = hashlib.sha256(data).hexdigest()
            b = stl_bounds(data)
            f = {"id": fid, "name": q.get("name", "file").replace("/", "_"), "size": len(data), "uploaded_at": now_iso(), "data": data}
            if b:
                f.update(kind="stl", facets=b[0], lo=b[1], hi=b[2])
            else:
                try:
                    data.decode("ascii")
                except UnicodeDecodeError:
                    raise ApiErr(415, "unsupported_media", "neither STL nor G-code text")
                f.update(kind="gcode", lines=data.count(b"\n"))
            FILES[fid] = f
            return self.reply(201, {k: v for k, v in f.items() if k not in ("data", "lo", "hi")})
        if parts == ["jobs"] and method == "POST":
            b = self.json_body()
            m = self.machine(b.get("machine", ""))
            f = FILES.get(b.get("file", ""))
            if not f:
                raise ApiErr(404, "not_found", "no such file")
            p = b.get("params") or {}
            if f["kind"] == "stl":
                for k in ("stepover", "feed", "plunge_feed"):
                    if not isinstance(p.get(k), (int, float)) or p[k] <= 0:
                        raise ApiErr(400, "bad_request", f"{k}: must be > 0")
            j = Job(m.name, f, p)
            j.position = sum(1 for o in JOBS.values() if o.machine == m.name and o.state in ("queued", "generating", "ready"))
            JOBS[j.id] = j
            broadcast({"type": "queue", "machine": m.name, "jobs": []}, m.name)
            return self.reply(201, j.to_json())
        if parts == ["jobs"]:
            js = sorted(JOBS.values(), key=lambda j: -j.id)
            if "machine" in q:
                js = [j for j in js if j.machine == q["machine"]]
            return self.reply(200, {"jobs": [j.to_json() for j in js]})
        if parts[0] == "jobs" and len(parts) >= 2:
            j = self.job(parts[1])
            m = MACHINES[j.machine]
            rest = parts[2:]
            if not rest:
                return self.reply(200, j.to_json())
            if rest == ["gcode"]:
                if j.gcode is None:
                    raise ApiErr(409, "bad_state", "not generated yet")
                return self.reply(200, j.gcode.encode(), "text/plain")
            if rest in (["clmap.png"], ["path"]):
                if j.gcode is None:
                    raise ApiErr(409, "bad_state", f"job {j.id} has no program yet ({j.state})")
                if j.preview() is None:
                    raise ApiErr(404, "not_found", "the program has no cutting move")
                if rest == ["path"]:
                    return self.reply(200, preview_path(j, int(q.get("max_points", 20000))))
                return self.reply(200, preview_png(j, int(q.get("max", 1024))), "image/png")
            self.body()
            act = rest[0]
            if act == "start":
                self.need_control(m)
                if j.state != "ready":
                    raise ApiErr(409, "bad_state", f"job {j.id} is {j.state}")
                if m.job or m.alarm:
                    raise ApiErr(409, "refused", "another job is running" if m.job else "the machine is in alarm")
                j.state, j.started_at, m.job = "running", now_iso(), j
            elif act == "hold" and j.state == "running":
                j.state = "held"
            elif act == "resume" and j.state == "held":
                self.need_control(m)
                j.state = "running"
            elif act == "stop" and j.state in ("running", "held"):
                j.state, j.ended_at, m.job = "stopped", now_iso(), None
            elif act == "cancel" and j.state in ("queued", "generating", "ready"):
                self.need_control(m)
                j.state, j.ended_at = "cancelled", now_iso()
            elif act == "move":
                pass
            else:
                raise ApiErr(409, "bad_state", f"job {j.id} is {j.state}")
            broadcast({"type": "job", "job": j.id, "machine": j.machine, "state": j.state, "progress": j.to_json()["progress"], "message": j.message}, j.machine)
            broadcast({"type": "queue", "machine": j.machine, "jobs": []}, j.machine)
            return self.reply(202, j.to_json())
        raise ApiErr(404, "not_found", f"no route {method} {path}")

    def websocket(self, q):
        if ARGS.token:
            t = q.get("token", "")
            if WS_TOKENS.pop(t, 0) < time.time():
                raise ApiErr(401, "unauthorized", "one-shot token missing or used")
        self.check_origin()
        key = self.headers.get("Sec-WebSocket-Key", "")
        accept = base64.b64encode(hashlib.sha1((key + "258EAFA5-E914-47DA-95CA-C5AB0DC85B11").encode()).digest()).decode()
        self.send_response(101)
        self.send_header("Upgrade", "websocket")
        self.send_header("Connection", "Upgrade")
        self.send_header("Sec-WebSocket-Accept", accept)
        self.end_headers()
        self.wfile.flush()
        c = WsClient(self, q.get("client_id", "anon"))
        c.send({"type": "hello", "client_id": c.client_id, "machines": list(MACHINES), "version": "mock"})
        CLIENTS.append(c)
        try:
            while c.alive:
                op, data = read_frame(self.rfile)
                if op is None or op == 8:
                    break
                if op == 9:
                    continue
                if op != 1:
                    continue
                self.ws_message(c, json.loads(data))
        except (OSError, ValueError):
            pass
        finally:
            c.alive = False
            CLIENTS.remove(c)
            with LOCK:
                for m in MACHINES.values():
                    if m.jog_owner == c.client_id:   # a dropped socket cancels its jog
                        m.jog_dir = None
                    if m.holder == c.client_id and not any(o.client_id == c.client_id for o in CLIENTS):
                        m.holder = None
            self.close_connection = True

    def ws_message(self, c, msg):
        t = msg.get("type")
        mid = msg.get("id")
        with LOCK:
            if t == "subscribe":
                c.subs = set(msg.get("machines", []))
                return c.send({"type": "ack", "id": mid})
            if t == "ping":
                return c.send({"type": "pong", "id": mid})
            m = MACHINES.get(msg.get("machine", ""))
            if not m:
                return c.send({"type": "error", "id": mid, "code": "not_found", "message": "no such machine"})
            if t == "jog_start":
                if m.holder is None:
                    return c.send({"type": "error", "id": mid, "code": "control_required", "message": "acquire control first"})
                if m.holder != c.client_id:
                    return c.send({"type": "error", "id": mid, "code": "control_held", "message": f"{m.holder} controls {m.name}"})
                if m.alarm or m.job:
                    return c.send({"type": "error", "id": mid, "code": "refused", "message": "refused in this state"})
                d = msg["dir"]
                n = math.sqrt(sum(v * v for v in d))
                m.jog_dir = [v / n for v in d]
                m.jog_feed = min(500.0, float(msg.get("feed", 1000)))
                m.jog_until = time.monotonic() + 0.3
                m.jog_owner = c.client_id
            elif t == "jog_renew":
                if m.jog_dir is None:
                    return c.send({"type": "error", "id": mid, "code": "refused", "message": "no continuous jog is running"})
                m.jog_until = time.monotonic() + 0.3
            elif t == "jog_release":
                m.jog_dir = None
            if mid is not None:
                c.send({"type": "ack", "id": mid})


def main():
    global ARGS
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, default=0)
    ap.add_argument("--web", default=os.path.join(os.path.dirname(__file__), "..", "..", "web"))
    ap.add_argument("--token", default="")
    ap.add_argument("--machines", default="sim")
    ARGS = ap.parse_args()
    for n in ARGS.machines.split(","):
        MACHINES[n] = Machine(n)
    srv = ThreadingHTTPServer(("127.0.0.1", ARGS.port), Handler)
    srv.daemon_threads = True
    threading.Thread(target=tick_loop, daemon=True).start()
    print(f"listening on http://127.0.0.1:{srv.server_address[1]}/", flush=True)
    srv.serve_forever()


if __name__ == "__main__":
    main()
