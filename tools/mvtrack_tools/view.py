"""The room live in a browser: a local web page that shows the tracks on the floor plan and every
camera's detections with the tracks reprojected onto its picture.

    tools/mvtrack view [--in URL]... [--rig RIG.yaml] [--port 8765] [--rate 10] [--trail-s 5]

The tool listens to --in (an LCM URL; the default is the daemon's) and serves
http://127.0.0.1:PORT/ (never another address). The page reads the state over a WebSocket (/ws),
about --rate times a second; GET /state.json answers with the same state:
{"utime", "tracks": [{"id", "status", "position", "velocity", "covariance", "cameras": [...]}],
 "trails", "cameras": [{"name", "stopped", ...}], "status", "particles", "replay"}.

- The floor plan: the rig's volume, its cameras (position and the direction each looks), and the
  floor at head height (1.7 m) shaded by how many cameras see it (two or more: a head there is
  placed in 3D).
- Tracks: identity, status (tentative dashed, coasting grey), the 2-sigma ellipse of the position's
  covariance, and a trail of the last --trail-s seconds; particle clouds when the daemon publishes
  them (mvtrackd --mode pf --publish-particles N).
- One tile per camera: its foreground mask when sent, its detections (points and boxes), and every
  track's head and body (a 0.45 m wide column down to the floor) reprojected through the rig's lens
  model, so that a calibration error shows as an offset. A camera whose last frame is more than
  STOPPED_S behind the newest, or that the daemon's MVTRACK_STATUS reports inactive, is stopped
  (red).
- Health from MVTRACK_STATUS: per camera rate, age of its last frame, frames missing, times down;
  the daemon's output rate, latency and births.
- --in file://LOG.lcm replays a recorded log (tools/mvtrack record) with pause and a time slider;
  several --in file:// logs merge by capture time (a scene's detections and the daemon's offline
  output of it: mvtrackd --in file://scene.lcm?speed=0 --out file://tracks.lcm?mode=w).

The tool is a separate process, niced (+10) so that on a machine with few cores it yields to the
daemon; it costs the daemon the multicast copy of each message. Run a browser beside a live daemon
niced too.
Exit 2 with one line on bad input (a rig that cannot be read, a log that does not exist, a port
taken).
"""
from __future__ import annotations

import argparse
import asyncio
import bisect
import collections
import json
import os
import sys
import threading
import time
from pathlib import Path

import numpy as np

from .paths import import_types

DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"
HOST = "127.0.0.1"
HEAD_M = 1.7
BODY_HALF_M = 0.225
STOPPED_S = 1.0
PAGE = Path(__file__).with_name("view_page.html")


class ViewError(Exception):
    pass


def rig_summary(rig) -> dict:
    """What the page needs of the rig: the volume, the cameras, and the floor's coverage."""
    from .calibrate import sees

    lo, hi = np.asarray(rig.volume_min, float), np.asarray(rig.volume_max, float)
    n = 40
    xs = lo[0] + (np.arange(n) + 0.5) * (hi[0] - lo[0]) / n
    ys = lo[1] + (np.arange(n) + 0.5) * (hi[1] - lo[1]) / n
    gx, gy = np.meshgrid(xs, ys)
    grid = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, HEAD_M)], axis=1)
    seen = np.array([sees(c, grid) for c in rig.cameras]).sum(axis=0).reshape(n, n)
    cams = []
    for c in rig.cameras:
        C = c.centre
        axis = c.R[2]
        cams.append({"name": c.name, "position": [float(v) for v in C], "axis": [float(v) for v in axis],
                     "width": int(c.width), "height": int(c.height)})
    return {"volume_min": lo.tolist(), "volume_max": hi.tolist(), "coverage": seen.astype(int).tolist(),
            "coverage_n": n, "head_m": HEAD_M, "cameras": cams}


def body_outline(cam, p: np.ndarray) -> dict | None:
    """Track at head p in camera cam: its head's pixel and its body's column (head to floor, a body
    wide across the camera's line of sight) as four pixels, through the rig's lens model."""
    to_cam = cam.centre[:2] - p[:2]
    nrm = float(np.hypot(*to_cam))
    side = np.array([-to_cam[1], to_cam[0], 0.0]) / nrm * BODY_HALF_M if nrm > 1e-6 else np.array([BODY_HALF_M, 0, 0])
    foot = np.array([p[0], p[1], 0.0])
    pts = np.array([p, p - side, p + side, foot + side, foot - side])
    uv = cam.project(pts)
    if not np.all(np.isfinite(uv[0])):
        return None
    body = uv[1:] if np.all(np.isfinite(uv[1:])) else None
    return {"head": [round(float(uv[0, 0]), 1), round(float(uv[0, 1]), 1)],
            "body": None if body is None else [[round(float(a), 1), round(float(b), 1)] for a, b in body]}


class State:
    """What the page shows, updated from LCM messages (live or replayed); thread-safe."""

    def __init__(self, rig, trail_s: float):
        self.rig = rig
        self.trail_s = trail_s
        self.lock = threading.Lock()
        self.version = 0  # counts every change, a seek included: never goes back
        self._snap: dict | None = None
        self.reset()

    def reset(self) -> None:
        with self.lock:
            self.version += 1
            self.tracks_msg = None
            self.trails: dict[int, collections.deque] = {}
            self.frames: dict[str, object] = {}
            self.status = None
            self.particles = None
            self.newest_utime = 0

    def apply(self, channel: str, msg) -> None:
        with self.lock:
            self.version += 1
            if channel == "TRACKS":
                self.tracks_msg = msg
                self.newest_utime = max(self.newest_utime, int(msg.utime))
                for t in msg.tracks:
                    d = self.trails.setdefault(int(t.id), collections.deque())
                    d.append((int(msg.utime), float(t.position[0]), float(t.position[1])))
                horizon = int(msg.utime - self.trail_s * 1e6)
                for tid in list(self.trails):
                    d = self.trails[tid]
                    while d and d[0][0] < horizon:
                        d.popleft()
                    if not d:
                        del self.trails[tid]
            elif channel.startswith("DETECTIONS_"):
                self.frames[channel[len("DETECTIONS_"):]] = msg
                self.newest_utime = max(self.newest_utime, int(msg.utime))
            elif channel == "MVTRACK_STATUS":
                self.status = msg
            elif channel == "MVTRACK_PARTICLES":
                self.particles = msg

    def snapshot(self) -> dict:
        """The state the page shows, built once per change (every track projected into every
        camera) and shared by every client and /state.json until the next change."""
        with self.lock:
            if self._snap is not None and self._snap["version"] == self.version:
                return self._snap
        snap = self._build()
        with self.lock:
            if snap["version"] == self.version:
                self._snap = snap
        return snap

    def _build(self) -> dict:
        with self.lock:
            tm, frames, status, parts = self.tracks_msg, dict(self.frames), self.status, self.particles
            trails = {str(k): [[round(x, 3), round(y, 3)] for _, x, y in d] for k, d in self.trails.items()}
            newest = self.newest_utime
            version = self.version
        cams_status = {}
        if status is not None:
            for cs in status.cameras:
                cams_status[cs.name] = cs
        tracks = []
        if tm is not None:
            for t in tm.tracks:
                p = np.array(t.position, float)
                proj = []
                if self.rig is not None:
                    for k, c in enumerate(self.rig.cameras):
                        o = body_outline(c, p)
                        if o is not None:
                            o["camera"] = k
                            proj.append(o)
                tracks.append({"id": int(t.id), "status": int(t.status),
                               "position": [round(float(v), 4) for v in t.position],
                               "velocity": [round(float(v), 4) for v in t.velocity],
                               "covariance": [float(v) for v in t.position_covariance],
                               "cameras_used": int(t.cameras_used), "cameras": proj})
        names = [c.name for c in self.rig.cameras] if self.rig is not None else sorted(frames)
        cams = []
        for name in names:
            f = frames.get(name)
            cs = cams_status.get(name)
            age = None if f is None else (newest - int(f.utime)) * 1e-6
            stopped = f is None or age > STOPPED_S or (cs is not None and not cs.active)
            entry = {"name": name, "stopped": bool(stopped), "age_s": None if age is None else round(age, 3),
                     "utime": None if f is None else int(f.utime), "detections": [], "mask": None}
            if f is not None:
                entry["width"], entry["height"] = int(f.width), int(f.height)
                entry["detections"] = [[round(float(d.u), 1), round(float(d.v), 1)] + [round(float(b), 1) for b in d.bbox]
                                       for d in f.detections]
                if f.mask_width > 0 and f.num_runs > 0:
                    entry["mask"] = {"width": int(f.mask_width), "height": int(f.mask_height), "runs": list(f.runs)}
            if cs is not None:
                entry.update({"rate_hz": round(float(cs.rate_hz), 2), "active": bool(cs.active),
                              "frames_missing": int(cs.frames_missing), "went_down": int(cs.went_down),
                              "last_message_age_s": round(float(cs.last_message_age_s), 3),
                              "clock_offset_ms": round(float(cs.clock_offset_ms), 1) if cs.clock_known else None,
                              "clock_tracks_lag_ms": round(float(cs.clock_tracks_lag_ms), 1) if cs.clock_tracks_known
                              else None})
            cams.append(entry)
        st = None
        if status is not None:
            st = {"mode": status.mode, "output_rate_hz": round(float(status.output_rate_hz), 2),
                  "latency_ms_p50": round(float(status.latency_ms_p50), 3),
                  "latency_ms_p99": round(float(status.latency_ms_p99), 3),
                  "proc_ms_p99": round(float(status.proc_ms_p99), 3), "births": int(status.births),
                  "deletions": int(sum(getattr(status, f) for f in status.__slots__ if f.startswith("deleted_"))),
                  "rejected": int(sum(getattr(status, f) for f in status.__slots__ if f.startswith("rejected_"))),
                  "tracks_confirmed": int(status.tracks_confirmed), "frames_processed": int(status.frames_processed)}
        pl = []
        if parts is not None:
            pl = [[round(float(x), 3), round(float(y), 3), int(i)] for x, y, i in zip(parts.x, parts.y, parts.id)]
        return {"version": version, "utime": None if tm is None else int(tm.utime), "tracks": tracks,
                "trails": trails, "cameras": cams, "status": st, "particles": pl}


def message_type(mt, channel: str):
    """The LCM type the view reads on channel, or None for a channel it does not show."""
    if channel.startswith("DETECTIONS_"):
        return mt.camera_frame_t
    return {"TRACKS": mt.tracks_t, "MVTRACK_STATUS": mt.status_t, "MVTRACK_PARTICLES": mt.particles_t}.get(channel)


class Live:
    """LCM subscriber thread feeding the state."""

    def __init__(self, url: str, state: State):
        import lcm

        self.mt = import_types()
        try:
            self.lc = lcm.LCM(url)
        except Exception as e:  # noqa: BLE001 - the user's URL
            raise ViewError(f"cannot open LCM {url}: {e}") from None
        self.state = state
        self.stop = threading.Event()
        for ch in ("TRACKS", "MVTRACK_STATUS", "MVTRACK_PARTICLES", "DETECTIONS_.*"):
            self.lc.subscribe(ch, self._on)
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _on(self, channel, data):
        try:
            msg = message_type(self.mt, channel).decode(data)
        except Exception:  # noqa: BLE001 - a bad message is skipped, the view goes on
            return
        self.state.apply(channel, msg)

    def _run(self):
        while not self.stop.is_set():
            self.lc.handle_timeout(100)

    def start(self):
        self.thread.start()

    def replay_info(self):
        return None

    def command(self, cmd: dict) -> None:
        pass


class Replay:
    """Recorded logs, played against the wall clock, with pause and seek. Events are ordered by
    capture time (a message's utime: a log the daemon wrote offline stamps its events with the wall
    clock of the run); MVTRACK_STATUS, stamped with the wall clock, stays after the message before it
    in its own log. Several logs merge: a scene's detections and the daemon's tracks of it. Camera
    messages (masks and colour make a log of a minute hundreds of megabytes) are indexed, and read
    from the file when the replay reaches them."""

    def __init__(self, paths: list[Path], state: State):
        import struct

        import lcm

        self.mt = mt = import_types()
        events: list[tuple[int, int, str, object]] = []  # (capture time, order, channel, message or (log, pos))
        self.logs = []
        for path in paths:
            if not path.exists():
                raise ViewError(f"{path}: no such log")
            t_prev = None
            try:
                log = lcm.EventLog(str(path), "r")
                self.logs.append(log)
                while True:
                    pos = log.tell()
                    ev = log.read_next_event()
                    if ev is None:
                        break
                    ch = ev.channel
                    if ch.startswith("DETECTIONS_"):
                        if len(ev.data) < 16:
                            continue
                        at = struct.unpack(">q", ev.data[8:16])[0]  # after the 8-byte fingerprint: utime
                        events.append((at, len(events), ch, (len(self.logs) - 1, pos)))
                        t_prev = at
                        continue
                    t = message_type(mt, ch)
                    if t is None:
                        continue
                    try:
                        msg = t.decode(ev.data)
                    except Exception:  # noqa: BLE001 - skipped, as live
                        continue
                    if ch == "MVTRACK_STATUS":
                        if t_prev is None:
                            continue
                        at = t_prev
                    else:
                        at = int(msg.utime)
                        t_prev = at
                    events.append((at, len(events), ch, msg))
            except Exception as e:  # noqa: BLE001 - not an LCM log
                raise ViewError(f"{path}: not an LCM log ({e.__class__.__name__})") from None
        if not events:
            raise ViewError("no TRACKS, DETECTIONS_* or MVTRACK_PARTICLES message in " + ", ".join(map(str, paths)))
        events.sort(key=lambda e: (e[0], e[1]))
        self.events = [(t, ch, m) for t, _, ch, m in events]
        self.times = [e[0] for e in self.events]
        self.t0, self.t1 = self.times[0], self.times[-1]
        self.state = state
        self.lock = threading.Lock()
        self.pos_us = self.t0
        self.idx = 0
        self.paused = False
        self.speed = 1.0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _message(self, ch: str, m):
        if not ch.startswith("DETECTIONS_"):
            return m
        k, pos = m
        log = self.logs[k]
        log.seek(pos)
        ev = log.read_next_event()
        try:
            return message_type(self.mt, ch).decode(ev.data)
        except Exception:  # noqa: BLE001 - skipped, as live
            return None

    def _apply(self, i: int) -> None:
        _, ch, m = self.events[i]
        msg = self._message(ch, m)
        if msg is not None:
            self.state.apply(ch, msg)

    def _seek(self, t_us: int) -> None:
        """Rebuilds the state at t_us: the trail's horizon of tracks before it, each camera's last
        message."""
        t_us = int(min(max(t_us, self.t0), self.t1))
        self.state.reset()
        start = bisect.bisect_left(self.times, t_us - int((self.state.trail_s + 2.0) * 1e6))
        end = bisect.bisect_right(self.times, t_us)
        last_frame: dict[str, int] = {}
        for i in range(start, end):
            ch = self.events[i][1]
            if ch.startswith("DETECTIONS_"):
                last_frame[ch] = i
            else:
                self._apply(i)
        for i in sorted(last_frame.values()):
            self._apply(i)
        self.pos_us, self.idx = t_us, end

    def _run(self):
        last = time.monotonic()
        while not self.stop.is_set():
            time.sleep(0.02)
            now = time.monotonic()
            with self.lock:
                if not self.paused:
                    self.pos_us = min(self.t1, self.pos_us + int((now - last) * 1e6 * self.speed))
                    while self.idx < len(self.events) and self.times[self.idx] <= self.pos_us:
                        self._apply(self.idx)
                        self.idx += 1
                    if self.pos_us >= self.t1:
                        self.paused = True
            last = now

    def start(self):
        self.thread.start()

    def replay_info(self):
        with self.lock:
            return {"t0": self.t0, "t1": self.t1, "t": self.pos_us, "paused": self.paused, "speed": self.speed}

    def command(self, cmd: dict) -> None:
        with self.lock:
            c = cmd.get("cmd")
            if c == "pause":
                self.paused = True
            elif c == "play":
                if self.pos_us >= self.t1:
                    self._seek(self.t0)
                self.paused = False
            elif c == "seek" and isinstance(cmd.get("t"), (int, float)):
                self._seek(int(cmd["t"]))
            elif c == "speed" and isinstance(cmd.get("speed"), (int, float)) and 0.05 <= cmd["speed"] <= 20:
                self.speed = float(cmd["speed"])


def make_app(state: State, source, rig_info: dict | None, rate_hz: float):
    from aiohttp import WSMsgType, web

    page = PAGE.read_text()

    def full_state() -> dict:
        return dict(state.snapshot(), replay=source.replay_info())

    async def index(_):
        return web.Response(text=page, content_type="text/html")

    async def state_json(_):
        return web.json_response(full_state())

    async def rig_json(_):
        return web.json_response(rig_info)

    async def ws_handler(request):
        ws = web.WebSocketResponse(heartbeat=10.0)
        await ws.prepare(request)

        async def pusher():
            sent = None
            while not ws.closed:
                replay = source.replay_info()
                key = (state.version, json.dumps(replay))
                if key != sent:  # nothing is built or sent while nothing changed
                    await ws.send_str(json.dumps(dict(state.snapshot(), replay=replay)))
                    sent = key
                await asyncio.sleep(1.0 / rate_hz)

        task = asyncio.ensure_future(pusher())
        try:
            async for m in ws:
                if m.type == WSMsgType.TEXT:
                    try:
                        source.command(json.loads(m.data))
                    except (ValueError, TypeError):
                        pass
        finally:
            task.cancel()
        return ws

    app = web.Application()
    app.router.add_get("/", index)
    app.router.add_get("/state.json", state_json)
    app.router.add_get("/rig.json", rig_json)
    app.router.add_get("/ws", ws_handler)
    app.router.add_get("/favicon.ico", lambda _: web.Response(status=204))
    return app


def headless_chromium(width: int = 1600, height: int = 1000):
    """Debian's Chromium through its chromedriver (apt: chromium, chromium-driver), headless; for the
    browser test and the README's screenshot. Nothing is downloaded: both paths are given."""
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    o = Options()
    o.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                f"--window-size={width},{height}"):
        o.add_argument(arg)
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=o)


def screenshot(url: str, source, at_s: float, out: Path) -> None:
    """The page in headless Chromium, the replay paused at_s seconds in, saved to out."""
    source.command({"cmd": "pause"})
    source.command({"cmd": "seek", "t": source.t0 + at_s * 1e6})
    driver = headless_chromium()
    try:
        driver.get(url)
        for _ in range(200):
            st = driver.execute_script(PAGE_STATE_JS)
            if st["version"] is not None and st["replayPaused"]:
                break
            time.sleep(0.1)
        time.sleep(1.0)
        out.parent.mkdir(parents=True, exist_ok=True)
        driver.save_screenshot(str(out))
    finally:
        driver.quit()
    print(f"mvtrack view: wrote {out}", file=sys.stderr)


# What the page shows, read in one script run (the page redraws between WebDriver calls).
PAGE_STATE_JS = """
return {
  version: document.body.dataset.version || null,
  labels: Array.from(document.querySelectorAll('#plan text.track-label[data-id]')).map(e => +e.dataset.id),
  stoppedTiles: Array.from(document.querySelectorAll('.tile.stopped')).map(e => e.dataset.camera),
  tiles: Array.from(document.querySelectorAll('.tile')).map(e => e.dataset.camera),
  stoppedRows: Array.from(document.querySelectorAll('#health tr.stopped')).map(e => e.dataset.camera),
  clock: document.getElementById('clock').textContent,
  replayPaused: document.getElementById('play').textContent === 'play'
};
"""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack view", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--in", dest="url", action="append", metavar="URL",
                    help=f"LCM URL to listen to (default {DEFAULT_URL}); file://LOG.lcm replays a recorded log, "
                         "and several logs given with --in each are merged by capture time (a scene's detections "
                         "and the daemon's offline output of it)")
    ap.add_argument("--rig", type=Path, help="rig file: the floor plan, and the camera tiles' reprojection")
    ap.add_argument("--port", type=int, default=8765, help="port on 127.0.0.1 (default %(default)s)")
    ap.add_argument("--rate", type=float, default=10.0, help="page updates per second, 1..30 (default %(default)s)")
    ap.add_argument("--trail-s", type=float, default=5.0, help="seconds of trail behind each track (default %(default)s)")
    ap.add_argument("--screenshot", type=Path, metavar="PNG",
                    help="replay only: open the page in headless Chromium, paused --at seconds into the logs, "
                         "save a screenshot and exit")
    ap.add_argument("--at", type=float, default=0.0, help="--screenshot: seconds from the logs' start")
    a = ap.parse_args(argv)
    try:
        os.nice(10)  # beside a live daemon on few cores, the view yields: the tracks come first
    except OSError:
        pass
    try:
        if not 1.0 <= a.rate <= 30.0:
            raise ViewError(f"--rate {a.rate}: must be 1..30")
        if not 0.0 <= a.trail_s <= 120.0:
            raise ViewError(f"--trail-s {a.trail_s}: must be 0..120")
        if not 1 <= a.port <= 65535:
            raise ViewError(f"--port {a.port}: must be 1..65535")
        rig = None
        rig_info = None
        if a.rig is not None:
            from .calibrate import CalibError, load_rig
            try:
                rig = load_rig(a.rig, must_exist=True)
            except CalibError as e:
                raise ViewError(str(e)) from None
            rig_info = rig_summary(rig)
        state = State(rig, a.trail_s)
        urls = a.url or [DEFAULT_URL]
        if a.screenshot is not None and not all(u.startswith("file://") for u in urls):
            raise ViewError("--screenshot needs logs (--in file://LOG.lcm)")
        if all(u.startswith("file://") for u in urls):
            source = Replay([Path(u[len("file://"):].split("?", 1)[0]) for u in urls], state)
        elif len(urls) > 1:
            raise ViewError("several --in: only logs (file://) can be merged")
        else:
            if "udpm://" in urls[0] and "ttl=0" not in urls[0]:
                raise ViewError(f"--in {urls[0]}: a multicast URL must carry ttl=0")
            source = Live(urls[0], state)
        from aiohttp import web

        app = make_app(state, source, rig_info, a.rate)
        runner = web.AppRunner(app)

        async def serve():
            await runner.setup()
            site = web.TCPSite(runner, HOST, a.port)
            try:
                await site.start()
            except OSError as e:
                raise ViewError(f"cannot listen on {HOST}:{a.port}: {e.strerror}") from None
            source.start()
            print(f"mvtrack view: http://{HOST}:{a.port}/ ({', '.join(urls)})", file=sys.stderr, flush=True)
            if a.screenshot is not None:
                await asyncio.get_running_loop().run_in_executor(None, screenshot, f"http://{HOST}:{a.port}/",
                                                                 source, a.at, a.screenshot)
                await runner.cleanup()
                return
            while True:
                await asyncio.sleep(3600)

        asyncio.run(serve())
    except ViewError as e:
        print(f"mvtrack view: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
