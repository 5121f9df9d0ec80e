"""Live latency and output rate of mvtrackd at 25 fps while cameras drop out and come back.

    tools/mvtrack latency [--seconds 120] [--people 5] [--drop-every 20] [--drop-for 4]
                          [--flood-camera K --flood-factor F --flood-after-s S] [--clock K:MS] [--delay K:MS] [--view]

Starts `mvtrackd` live on a private LCM multicast port (ttl=0), publishes every camera's
detections of people walking the SmartRoom rig at the rig's frame rate (each head with its body's
box, 5 cameras, +-3 ms capture jitter, cameras sending in a shuffled order), and silences one camera at a time for --drop-for
seconds every --drop-every seconds. For every frame set it takes the wall time just after the last
camera message was published and the `publish_utime` the daemon stamped on that frame's TRACKS:
the difference is the latency (same machine, same CLOCK_REALTIME). Prints p50/p99/p99.9/max, the
TRACKS rate over 10-second windows, and writes out/latency/latency.json and latency.png.

--flood-camera K: besides its own frames, camera K's channel carries F times its frame rate of
extra messages (default F = 50) with plausible capture times (the current one) and random
detections: a detector stuck in a loop, or someone replaying at line rate; --flood-after-s S starts
it S seconds into the run. The run then also
reports the messages the daemon shed, and how well the people are tracked (share of true heads
with a confirmed track within 0.3 m, mean error), to compare with a run without the flood.

--clock K:MS: camera K stamps its frames MS ms ahead (negative: behind) of the others. --delay K:MS:
camera K's messages leave MS ms after the others' (a slower detector or network), truly stamped;
the daemon's clock estimates for those cameras (from arrival times, and the lag the tracks see)
are reported.

--view: tools/mvtrack view listens to the same traffic with its page open in headless Chromium for
the whole run, to compare with a run without it.
"""
from __future__ import annotations

import argparse
import heapq
import json
import multiprocessing as mp
import os
import signal
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import lcm
import numpy as np

from .crowd import body_box
from .lcmio import camera_frame, mt
from .paths import DAEMON, REPO
from .rig import smartroom


def walkers(rng, n, frames, dt, lo, hi, apart=False):
    """n people walking at random (velocity an Ornstein-Uhlenbeck process, turning at the walls).
    With apart, they keep their personal space as the crowd scenes' walkers do (crowd.py): pushed
    apart within 0.9 m, and no step that brings two heads closer than 0.45 m (two bodies cannot
    overlap); without it they pass through each other (the timing scenes here, where only the
    load matters)."""
    pos = np.column_stack([rng.uniform(lo[0] + 0.5, hi[0] - 0.5, n), rng.uniform(lo[1] + 0.5, hi[1] - 0.5, n)])
    for i in range(1, n if apart else 0):  # standing places at least 0.9 m apart
        for _ in range(1000):
            if np.min(np.linalg.norm(pos[:i] - pos[i], axis=1)) >= 0.9:
                break
            pos[i] = [rng.uniform(lo[0] + 0.5, hi[0] - 0.5), rng.uniform(lo[1] + 0.5, hi[1] - 0.5)]
    vel = rng.normal(0, 0.6, (n, 2))
    height = rng.uniform(1.55, 1.9, n)
    out = np.zeros((frames, n, 3))
    for f in range(frames):
        vel += -0.3 * vel * dt + 0.5 * np.sqrt(dt) * rng.normal(size=(n, 2))
        if not apart:
            pos += vel * dt
        for i in range(n if apart else 0):
            d = pos[i] - np.delete(pos, i, axis=0)
            r = np.linalg.norm(d, axis=1)
            near = (r > 1e-6) & (r < 0.9)
            vel[i] += (d[near] / r[near, None] * (1.2 * (0.9 - r[near]) / 0.9)[:, None]).sum(axis=0) * dt / 0.5
        for i in range(n if apart else 0):
            step = vel[i] * dt
            others = np.delete(pos, i, axis=0)
            r_now = np.linalg.norm(pos[i] - others, axis=1)
            r_next = np.linalg.norm(pos[i] + step - others, axis=1)
            if np.any((r_next < 0.45) & (r_next < r_now)):
                vel[i] *= 0.0
                continue
            pos[i] += step
        for a in range(2):
            low, high = pos[:, a] < lo[a] + 0.3, pos[:, a] > hi[a] - 0.3
            vel[low | high, a] *= -1
            pos[:, a] = np.clip(pos[:, a], lo[a] + 0.3, hi[a] - 0.3)
        out[f, :, :2] = pos
        out[f, :, 2] = height
    return out


def blob_box(cam, head: np.ndarray) -> tuple[float, ...]:
    """A walker's blob box: the body under the head, cut by the picture. Its bottom is where the
    feet are (a made-up box would tell the tracker of feet that are not there); () when the body
    has no image."""
    b = body_box(cam, head)
    return () if b is None else (max(0.0, b[0]), max(0.0, b[1]), min(cam.width - 1.0, b[2]), min(cam.height - 1.0, b[3]))


def flood_process(url: str, cam, rate_hz: float, seed: int, stop, sent) -> None:
    """rate_hz extra messages on cam's channel, in bursts every 4 ms, until stop is set: 64
    messages of 3 random detections encoded once, each sent with the current capture time patched
    into its utime field (a plausible time, so the assembler would take it)."""
    rng = np.random.default_rng(seed + 99)
    msgs = [bytearray(camera_frame(0, 0, cam, [(rng.uniform(0, cam.width), rng.uniform(0, cam.height))
                                                for _ in range(3)], 2.0).encode()) for _ in range(64)]
    lc = lcm.LCM(url)
    channel = f"DETECTIONS_{cam.name}"
    per_burst = max(1, int(round(rate_hz * 0.004)))
    t_next = time.monotonic()
    n = 0
    while not stop.is_set():
        u = int(time.time() * 1e6)
        for _ in range(per_burst):
            m = msgs[n % 64]
            struct.pack_into(">q", m, 8, u)  # after the 8-byte fingerprint
            lc.publish(channel, bytes(m))
            n += 1
        sent.value = n
        t_next += 0.004
        delay = t_next - time.monotonic()
        if delay > 0:
            time.sleep(delay)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tools/mvtrack latency", description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="length of the live run (default 120)")
    ap.add_argument("--people", type=int, default=5, help="people walking (default 5)")
    ap.add_argument("--drop-every", type=float, default=20.0, help="a camera goes silent this often, s (default 20)")
    ap.add_argument("--drop-for", type=float, default=4.0, help="... for this long, s (default 4)")
    ap.add_argument("--mode", default="pkf", help="daemon --mode (default pkf)")
    ap.add_argument("--rt-priority", type=int, metavar="PRIO", help="daemon --rt-priority PRIO (SCHED_FIFO; needs root)")
    ap.add_argument("--port", type=int, default=7600 + os.getpid() % 300, help="private multicast port")
    ap.add_argument("--out", type=Path, default=REPO / "out" / "latency")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--flood-camera", type=int, default=-1, help="camera index whose channel floods (default none)")
    ap.add_argument("--flood-factor", type=float, default=50.0, help="flood rate / frame rate (default 50)")
    ap.add_argument("--flood-after-s", type=float, default=0.0,
                    help="the flood starts this long after the first frame (default 0: with it)")
    ap.add_argument("--clock", action="append", default=[], metavar="K:MS",
                    help="camera K stamps its frames MS milliseconds ahead (negative: behind) of the others; "
                         "the tracking quality is then scored from --score-from-s on")
    ap.add_argument("--delay", action="append", default=[], metavar="K:MS",
                    help="camera K's messages leave MS milliseconds after the others' (its detector or network is "
                         "slower), stamped with the true capture time")
    ap.add_argument("--score-from-s", type=float, default=1.0,
                    help="tracking quality over the run from this second on (default 1: tracks are being confirmed)")
    ap.add_argument("--view", action="store_true",
                    help="with tools/mvtrack view listening and its page open in headless Chromium all along")
    ap.add_argument("--view-rate", type=float, default=10.0, help="--view: the page's updates per second (default 10)")
    a = ap.parse_args(argv)
    def per_camera(opts, name, low):
        out: dict[int, int] = {}
        for c in opts:
            try:
                k, ms = c.split(":")
                out[int(k)] = int(round(float(ms) * 1e3))
            except ValueError:
                ap.error(f"{name} {c}: expected K:MS")
            if not (0 <= int(k) < 5) or out[int(k)] < low:
                ap.error(f"{name} {c}: K is a camera 0..4" + (", MS >= 0" if low == 0 else ""))
        return out
    if not 0.0 <= a.flood_after_s < a.seconds:
        ap.error("--flood-after-s must lie in [0, --seconds)")
    skew_us = per_camera(a.clock, "--clock", -10 ** 9)
    delay_us = per_camera(a.delay, "--delay", 0)
    if not DAEMON.exists():
        ap.error(f"{DAEMON} not built (tools/mvtrack build)")
    a.out.mkdir(parents=True, exist_ok=True)
    url = f"udpm://239.255.76.67:{a.port}?ttl=0&recv_buf_size=4194304"
    rig = smartroom()
    rig_path = a.out / "rig.yaml"
    rig.write(rig_path)
    period = 1.0 / rig.frame_rate
    frames = int(a.seconds / period)
    rng = np.random.default_rng(a.seed)
    people = walkers(rng, a.people, frames, period, rig.volume_min, rig.volume_max)

    daemon = subprocess.Popen([str(DAEMON), "--rig", str(rig_path), "--in", url, "--mode", a.mode] +
                              (["--rt-priority", str(a.rt_priority)] if a.rt_priority else []),
                              stderr=subprocess.PIPE, text=True)
    pub = lcm.LCM(url)
    sub = lcm.LCM(url)
    tracks: dict[int, tuple[int, float]] = {}   # frame utime -> (publish_utime, receive time)
    positions: dict[int, list] = {}             # frame utime -> confirmed tracks' positions
    statuses = []
    stop = threading.Event()

    ids: dict[int, list] = {}                   # frame utime -> confirmed tracks' identities
    status_times: list[float] = []

    def on_tracks(_c, data):
        m = mt.tracks_t.decode(data)
        tracks[m.utime] = (m.publish_utime, time.time())
        positions[m.utime] = [t.position for t in m.tracks if t.status != 1]
        ids[m.utime] = [t.id for t in m.tracks if t.status != 1]

    def on_status(_c, data):
        try:
            statuses.append(mt.status_t.decode(data))
        except ValueError:  # another build's status type (its fingerprint): not read
            return
        status_times.append(time.monotonic())

    sub.subscribe("TRACKS", on_tracks)
    sub.subscribe("MVTRACK_STATUS", on_status)

    def receive():
        while not stop.is_set():
            sub.handle_timeout(50)

    rx = threading.Thread(target=receive, daemon=True)
    rx.start()
    flood_sent = mp.Value("q", 0)
    stop_flood = mp.Event()

    flooder = None
    if a.flood_camera >= 0:
        cam = rig.cameras[a.flood_camera]
        flooder = mp.Process(target=flood_process, args=(url, cam, a.flood_factor * rig.frame_rate, a.seed, stop_flood,
                                                        flood_sent), daemon=True)
    viewer, browser = None, None
    if a.view:
        from .view import headless_chromium

        vport = 8700 + os.getpid() % 300
        viewer = subprocess.Popen([sys.executable, "-m", "mvtrack_tools.view", "--in", url, "--rig", str(rig_path),
                                   "--port", str(vport), "--rate", str(a.view_rate)], stderr=subprocess.DEVNULL,
                                  env=dict(os.environ, PYTHONPATH=str(REPO / "tools")))
        time.sleep(2.0)
        browser = headless_chromium()
        browser.get(f"http://127.0.0.1:{vport}/")
        time.sleep(1.0)
        # the browser niced as the view is, its page's renderer included (a viewer on the daemon's
        # machine should yield to it)
        pids = subprocess.run(["pgrep", "-f", "chromium|chromedriver"], capture_output=True, text=True).stdout.split()
        for pid in pids:
            try:
                tids = os.listdir(f"/proc/{pid}/task")
            except OSError:
                continue
            for tid in tids:
                try:
                    os.setpriority(os.PRIO_PROCESS, int(tid), 10)  # per thread: Linux nices one task
                except OSError:
                    pass
    time.sleep(0.7)  # the daemon subscribes
    sent_last: dict[int, float] = {}
    frame_utime: list[int] = []
    dropped: list[int] = []
    t0 = time.monotonic()
    u0 = int(time.time() * 1e6)
    ncam = len(rig.cameras)
    t_flood = time.time()
    flood_from = int(round(a.flood_after_s * rig.frame_rate))
    # --delay: a heap of (wall time due, order sent, channel, data); latency counts from the frame's
    # last message sent on time
    pending: list[tuple[float, int, str, bytes]] = []

    def publish_due(until: float) -> None:
        """Publishes the delayed messages due by wall time until (monotonic), sleeping between them."""
        while pending and pending[0][0] <= until:
            due, _, ch, data = heapq.heappop(pending)
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            pub.publish(ch, data)

    try:
        for f in range(frames):
            if flooder is not None and f == flood_from:
                t_flood = time.time()
                flooder.start()  # a process of its own: the measuring publisher keeps its interpreter
            t = f * period
            k_drop = -1
            if a.drop_every > 0 and (t % a.drop_every) >= a.drop_every - a.drop_for:
                k_drop = int(t // a.drop_every) % ncam
            dropped.append(k_drop)
            u = u0 + int(round(t * 1e6))
            frame_utime.append(u)
            msgs = []
            for k in rng.permutation(ncam):
                if k == k_drop:
                    continue
                cam = rig.cameras[k]
                uv = cam.project(people[f])
                boxes = [blob_box(cam, head) for head in people[f]]
                dets = [(x + rng.normal(0, 2.0), y + rng.normal(0, 2.0)) + ((b,) if b else ())
                        for (x, y), b in zip(uv, boxes)
                        if 0 <= x < cam.width and 0 <= y < cam.height and rng.random() > 0.05]
                jitter = int(rng.integers(-3000, 3001))
                msgs.append((int(k), f"DETECTIONS_{cam.name}",
                             camera_frame(u + jitter + skew_us.get(int(k), 0), f, cam, dets, 2.0).encode()))
            for k, ch, data in msgs:
                if delay_us.get(k, 0) > 0:
                    heapq.heappush(pending, (time.monotonic() + delay_us[k] * 1e-6, f * ncam + k, ch, data))
                else:
                    pub.publish(ch, data)
            sent_last[u] = time.time()
            publish_due(t0 + (f + 1) * period)
            delay = t0 + (f + 1) * period - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            if f % 250 == 0:
                print(f"\rlatency: {f / frames * 100:5.1f} % of {a.seconds:.0f} s live", end="", file=sys.stderr)
        publish_due(float("inf"))
        time.sleep(0.5)
    finally:
        stop.set()
        stop_flood.set()
        if flooder is not None and flooder.pid is not None:
            flooder.join(5)
        t_flood_end = time.time()
        daemon.send_signal(signal.SIGTERM)
        _, err = daemon.communicate(timeout=10)
        rx.join(timeout=2)
        if browser is not None:
            browser.quit()
        if viewer is not None:
            viewer.terminate()
            viewer.wait(timeout=10)
    print("", file=sys.stderr)
    (a.out / "daemon.stderr").write_text(err)
    if daemon.returncode != 0:
        print(err, file=sys.stderr)
        return 1

    # TRACKS.utime is the latest capture time in the set (jittered; a camera stamping ahead, --clock,
    # whose time the daemon does not correct, moves it by its skew, and one re-timed by its arrivals,
    # --delay, by its delay): match each frame by nearest
    tk = np.array(sorted(tracks))
    lat, matched_frames, rx_times, matched_tracks = [], [], [], []
    fu = np.array(frame_utime)
    for u_t in tk:
        for skew in [0] + sorted(set(skew_us.values()) | set(delay_us.values())):
            i = int(np.argmin(np.abs(fu + skew - u_t)))
            if abs(fu[i] + skew - u_t) <= 10000:
                pub_u, rx_t = tracks[u_t]
                lat.append(pub_u / 1e6 - sent_last[fu[i]])
                matched_frames.append(i)
                matched_tracks.append(u_t)
                rx_times.append(rx_t)
                break
    lat_ms = np.array(lat) * 1e3
    # tracking quality: true heads with a confirmed track within 0.3 m, and their error; CLEAR MOT
    from .mot import FrameSet, clear_mot

    first = int(round(a.score_from_s * rig.frame_rate))
    hit, errs, fsets = 0, [], []
    for u_t, i in zip(matched_tracks, matched_frames):
        if i < first:
            continue  # tracks are being confirmed (or a clock learnt)
        pos = np.array(positions.get(u_t, [])).reshape(-1, 3)
        fsets.append(FrameSet(int(fu[i]), list(range(len(people[i]))), np.asarray(people[i]), list(ids.get(u_t, [])),
                              pos, True))
        for head in people[i]:
            d = np.linalg.norm(pos - head, axis=1) if len(pos) else np.array([np.inf])
            if d.min() < 0.3:
                hit += 1
                errs.append(float(d.min()))
    n_heads = sum(len(people[i]) for i in matched_frames if i >= first)
    mot = clear_mot(fsets) if fsets else None
    clock = []
    for k in sorted(set(skew_us) | set(delay_us)):
        us = skew_us.get(k, 0)

        def reported(st, k=k):
            c = st.cameras[k]
            return {"offset_ms": round(float(c.clock_offset_ms), 2), "known": bool(c.clock_known),
                    "tracks_lag_ms": round(float(c.clock_tracks_lag_ms), 2), "tracks_known": bool(c.clock_tracks_known),
                    "refused": int(c.clock_refused)}
        # what the daemon said when scoring starts (--score-from-s)
        at = next((st for st, t in zip(statuses, status_times) if t - t0 >= a.score_from_s), None)
        clock.append({"camera": rig.cameras[k].name, "set_ms": us / 1e3, "delay_ms": delay_us.get(k, 0) / 1e3,
                      "reported_at_score_from_s": reported(at) if at is not None else None,
                      "reported_last": reported(statuses[-1]) if statuses else None})
    rx_times = np.array(sorted(rx_times))
    # output rate over 10 s windows, inside the run (first and last second left out)
    edges = np.arange(rx_times[0] + 1.0, rx_times[-1] - 1.0 - 10.0 + 1e-9, 10.0)
    rates = [float(np.sum((rx_times >= e) & (rx_times < e + 10.0)) / 10.0) for e in edges]
    during_drop = np.array([dropped[i] >= 0 for i in matched_frames])
    res = {
        "frames_sent": frames,
        "tracks_received": len(tracks),
        "frames_matched": len(lat),
        "latency_ms_p50": float(np.percentile(lat_ms, 50)),
        "latency_ms_p99": float(np.percentile(lat_ms, 99)),
        "latency_ms_p999": float(np.percentile(lat_ms, 99.9)),
        "latency_ms_max": float(lat_ms.max()),
        "latency_ms_p99_while_a_camera_is_down": float(np.percentile(lat_ms[during_drop], 99)) if during_drop.any() else None,
        "frames_over_2ms": int(np.sum(lat_ms > 2.0)),
        "rate_hz_10s_windows_min": min(rates) if rates else None,
        "rate_hz_10s_windows_max": max(rates) if rates else None,
        "rate_hz_mean": float((len(rx_times) - 1) / (rx_times[-1] - rx_times[0])),
        "camera_drops": int(sum(1 for i in range(1, len(dropped)) if dropped[i] >= 0 and dropped[i - 1] < 0)),
        "daemon_status_latency_ms_p99_last": statuses[-1].latency_ms_p99 if statuses else None,
        "daemon_status_went_down": [int(c.went_down) for c in statuses[-1].cameras] if statuses else None,
        "daemon_status_came_back": [int(c.came_back) for c in statuses[-1].cameras] if statuses else None,
        "seconds": a.seconds, "people": a.people, "mode": a.mode, "rt_priority": a.rt_priority, "view_open": bool(a.view),
        "view_rate_hz": a.view_rate if a.view else None,
        "score_from_s": a.score_from_s,
        "mota": None if mot is None else mot.mota, "id_switches": None if mot is None else mot.id_switches,
        "clock": clock,
        "heads_tracked_within_0.3m": hit / max(n_heads, 1),
        "mean_error_mm": 1e3 * float(np.mean(errs)) if errs else None,
        "flood_camera": a.flood_camera,
        "flood_messages_sent": flood_sent.value,
        "flood_rate_hz": flood_sent.value / max(t_flood_end - t_flood, 1e-9) if a.flood_camera >= 0 else 0.0,
        "shed_by_daemon": [int(c.shed) for c in statuses[-1].cameras] if statuses else None,
    }
    (a.out / "latency.json").write_text(json.dumps(res, indent=2))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
        tt = np.array(matched_frames) * period
        ax[0].semilogy(tt, np.maximum(lat_ms, 1e-3), ".", ms=2)
        ax[0].axhline(2.0, color="r", lw=0.8, label="2 ms")
        ax[0].set_ylabel("last camera message -> TRACKS, ms")
        ax[0].legend(loc="upper right")
        ax[1].plot(np.arange(len(dropped)) * period, dropped, drawstyle="steps-post")
        ax[1].set_ylabel("silent camera (-1: none)")
        ax[1].set_xlabel("time, s")
        fig.suptitle(f"mvtrackd live, {a.people} people, 5 cameras at 25 fps: p50 {res['latency_ms_p50']:.3f} ms, "
                     f"p99 {res['latency_ms_p99']:.3f} ms")
        fig.tight_layout()
        fig.savefig(a.out / "latency.png", dpi=110)
    except Exception as e:  # plots are a convenience, the JSON is the result
        print(f"latency: no plot ({e})", file=sys.stderr)
    for k, v in res.items():
        print(f"{k}: {v}")
    bound_ms = 2.0 if a.flood_camera < 0 else 5.0
    if rates:
        rate_ok, rate_rule = min(rates) >= 24.5 and max(rates) <= 25.5, "every 10 s window 25 +- 0.5 Hz"
    else:  # no 10 s window inside a run this short: its mean rate
        rate_ok, rate_rule = abs(res["rate_hz_mean"] - 25.0) <= 0.5, "the run's mean rate 25 +- 0.5 Hz (no 10 s window in it)"
    ok = res["latency_ms_p99"] <= bound_ms and rate_ok
    print("latency: " + ("PASS" if ok else "FAIL") + f" (p99 <= {bound_ms:g} ms, {rate_rule})")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
