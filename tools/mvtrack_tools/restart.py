"""mvtrackd killed and restarted live: do people keep their identities?

    tools/mvtrack restart [--how kill|term|nostate|nofiles] [--seconds 14] [--at 6] [--down 1]

Publishes 5 people walking the SmartRoom rig and keeping their personal space (5 cameras, 25 fps,
2 px noise, 5 % misses) live on a private LCM multicast port (ttl=0) to `mvtrackd --state DIR/state`,
stops the daemon --at seconds into the scene (--how kill: SIGKILL; term: SIGTERM; nostate: SIGKILL
and the checkpoint deleted, its identity lease FILE.ids kept; nofiles: SIGKILL, every state file
deleted: only the wall-clock identity floor is left), starts it again --down seconds later while
the cameras keep sending, and reads every TRACKS message. Prints, and writes to out/restart/HOW.json:

- kept / present: people confirmed before the stop and present after it whose track after the
  restart carries the identity they had before (matched to the truth within 0.5 m);
- reused: identities published before the stop that were given to another person after it (must
  be 0), and identities published after the restart that were published before it for anyone
  while the checkpoint was not restored;
- resume_ms: from the restarted daemon's ready line (LCM subscribed) to its first TRACKS, and from
  its exec to its first TRACKS; resume_frames_from_ready: that first TRACKS' frame counted from the
  first frame published after the ready line.
"""
from __future__ import annotations

import argparse
import json
import os
import shlex
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import lcm
import numpy as np

from .latency import blob_box, walkers
from .lcmio import camera_frame, mt
from .paths import DAEMON, REPO
from .rig import smartroom


def start_daemon(rig_path: Path, url: str, state: Path, mode: str):
    """Starts mvtrackd; returns the process and the monotonic time of its exec and ready line."""
    t_exec = time.monotonic()
    p = subprocess.Popen([str(DAEMON), "--rig", str(rig_path), "--in", url, "--mode", *shlex.split(mode), "--state", str(state)],
                         stderr=subprocess.PIPE, text=True)
    lines: list[str] = []
    ready = threading.Event()
    t_ready = [0.0]

    def read_err():
        for line in p.stderr:
            lines.append(line.rstrip("\n"))
            if " cameras, mode " in line and not ready.is_set():
                t_ready[0] = time.monotonic()
                ready.set()

    threading.Thread(target=read_err, daemon=True).start()
    ready.wait(10)
    return p, t_exec, t_ready[0], lines


def frame_messages(rig, heads: np.ndarray, f: int, u: int, rng: np.random.Generator) -> list[tuple[str, bytes]]:
    """Frame f's camera messages, cameras in a random order: the heads projected, 2 px noise, 5 %
    misses, each with its body's box."""
    out = []
    for k in rng.permutation(len(rig.cameras)):
        cam = rig.cameras[k]
        uv = cam.project(heads)
        boxes = [blob_box(cam, head) for head in heads]
        dets = [(x + rng.normal(0, 2.0), y + rng.normal(0, 2.0)) + ((b,) if b else ()) for (x, y), b in zip(uv, boxes)
                if 0 <= x < cam.width and 0 <= y < cam.height and rng.random() > 0.05]
        out.append((f"DETECTIONS_{cam.name}", camera_frame(u, f, cam, dets, 2.0).encode()))
    return out


def match(truth: np.ndarray, tracks, max_d: float = 0.5) -> dict[int, int]:
    """Confirmed or coasting track id -> index of the nearest true head within max_d (greedy)."""
    pairs = []
    for t in tracks:
        if t.status == 1:
            continue
        d = np.linalg.norm(truth - np.array(t.position), axis=1)
        pairs += [(float(d[i]), t.id, i) for i in range(len(truth)) if d[i] < max_d]
    out, used = {}, set()
    for d, tid, i in sorted(pairs):
        if tid not in out and i not in used:
            out[tid] = i
            used.add(i)
    return out


def score(before: list, after: list, people: np.ndarray, frame_of_utime: dict, f_restart: int):
    """Identities across the stop: (kept, last_before, first_after, reused_by_other, ids_before,
    ids_after) from the TRACKS messages before the stop and after the restart."""
    def matched(msgs, ids: set):
        """(frame, track id, person index) of every confirmed match; every published id into ids."""
        for m in msgs:
            f = frame_of_utime.get(m.utime)
            ids.update(t.id for t in m.tracks)
            if f is not None:
                yield from ((f, tid, i) for tid, i in match(people[f], m.tracks).items())

    # identities before the stop: id -> the person it was matched to most often
    votes: dict[int, dict[int, int]] = {}
    ids_before: set[int] = set()
    for _, tid, i in matched(before, ids_before):
        votes.setdefault(tid, {}).setdefault(i, 0)
        votes[tid][i] += 1
    owner = {tid: max(v, key=v.get) for tid, v in votes.items()}
    last_f = max((frame_of_utime.get(m.utime, -1) for m in before[-5:]), default=-1)
    last_before = {i: tid for f, tid, i in matched(before[-5:], set()) if f == last_f}
    # after the restart: the identity each person carries in the first second
    first_after: dict[int, int] = {}
    reused_by_other = set()
    ids_after: set[int] = set()
    for f, tid, i in matched(after, ids_after):
        if f <= f_restart + 25:
            first_after.setdefault(i, tid)
        if tid in owner and owner[tid] != i:
            reused_by_other.add(tid)
    kept = sum(1 for i, tid in last_before.items() if first_after.get(i) == tid)
    return kept, last_before, first_after, reused_by_other, ids_before, ids_after


def run(how: str, seconds: float, at: float, down: float, mode: str, out: Path, seed: int, port: int) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    url = f"udpm://239.255.76.67:{port}?ttl=0&recv_buf_size=4194304"
    rig = smartroom()
    rig_path = out / "rig.yaml"
    rig.write(rig_path)
    state = out / f"state-{how}"
    for suffix in ("", ".ids", ".tmp", ".ids.tmp"):
        Path(str(state) + suffix).unlink(missing_ok=True)
    period = 1.0 / rig.frame_rate
    frames = int(seconds / period)
    rng = np.random.default_rng(seed)
    people = walkers(rng, 5, frames, period, rig.volume_min, rig.volume_max, apart=True)

    sub = lcm.LCM(url)
    got: list[tuple[float, object]] = []  # (receive time, tracks_t)
    stop = threading.Event()
    sub.subscribe("TRACKS", lambda c, d: got.append((time.monotonic(), mt.tracks_t.decode(d))))
    rx = threading.Thread(target=lambda: [sub.handle_timeout(20) for _ in iter(stop.is_set, True)], daemon=True)
    rx.start()
    d1, _, _, err1 = start_daemon(rig_path, url, state, mode)
    pub = lcm.LCM(url)
    time.sleep(0.3)
    t0 = time.monotonic()
    u0 = int(time.time() * 1e6)
    f_stop, f_restart = int(at / period), int((at + down) / period)
    d2, t_exec, t_ready, err2 = None, 0.0, 0.0, []
    frame_of_utime: dict[int, int] = {}
    try:
        for f in range(frames):
            if f == f_stop:
                d1.send_signal(signal.SIGTERM if how == "term" else signal.SIGKILL)
                d1.wait(10)
                if how == "nostate":
                    state.unlink(missing_ok=True)
                if how == "nofiles":
                    for suffix in ("", ".ids"):
                        Path(str(state) + suffix).unlink(missing_ok=True)
            if f == f_restart:
                d2, t_exec, t_ready, err2 = start_daemon(rig_path, url, state, mode)
            u = u0 + int(round(f * period * 1e6))
            frame_of_utime[u] = f
            for channel, data in frame_messages(rig, people[f], f, u, rng):
                pub.publish(channel, data)
            delay = t0 + (f + 1) * period - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        time.sleep(0.3)
    finally:
        for p in (d1, d2):
            if p is not None and p.poll() is None:
                p.send_signal(signal.SIGTERM)
                p.wait(10)
        stop.set()
        rx.join(timeout=2)

    before = [(t, m) for t, m in got if t < t0 + f_stop * period]
    after = [(t, m) for t, m in got if d2 is not None and t >= t_exec]
    kept, last_before, _, reused_by_other, ids_before, ids_after = score(
        [m for _, m in before], [m for _, m in after], people, frame_of_utime, f_restart)
    res = {
        "how": how, "mode": mode, "down_s": down,
        "present": len(last_before),
        "kept": kept,
        "identities_before": len(ids_before),
        "reused_by_another_person": sorted(reused_by_other),
        "new_ids_that_existed_before": [],  # restored runs: reused_by_another_person is the check
        "resume_ms_from_ready": (after[0][0] - t_ready) * 1e3 if after and t_ready else None,
        # frames: the first output's frame after the first frame published once it was ready (a
        # slow or loaded machine stretches the milliseconds, not this)
        "resume_frames_from_ready": frame_of_utime.get(after[0][1].utime, -1) - f_restart if after and t_ready else None,
        "resume_ms_from_exec": (after[0][0] - t_exec) * 1e3 if after else None,
        "tracks_after": len(after),
        "restore_line": next((ln for ln in err2 if "state" in ln and ("restored" in ln or "refused" in ln
                                                                        or "no checkpoint" in ln)), None),
        "first_id_after": min(ids_after) if ids_after else None,
    }
    if how in ("nostate", "nofiles"):
        # nothing restored: every identity after the restart must be new
        res["new_ids_that_existed_before"] = sorted(ids_after & ids_before)
    (out / f"{how}.json").write_text(json.dumps(res, indent=2))
    return res


def offline(seed: int, gap_s: float, at: float, seconds: float, out: Path, mode: str = "pkf") -> dict:
    """The same scene as a log, cut at `at` with gap_s of it removed, the daemon run on each half
    with --state: deterministic, for comparing versions over many seeds and gaps."""
    from .lcmio import read_log, split_log
    out.mkdir(parents=True, exist_ok=True)
    rig = smartroom()
    rig_path = out / "rig.yaml"
    rig.write(rig_path)
    period = 1.0 / rig.frame_rate
    frames = int(seconds / period)
    rng = np.random.default_rng(seed)
    people = walkers(rng, 5, frames, period, rig.volume_min, rig.volume_max, apart=True)
    u0 = 1_700_000_000_000_000
    log = out / f"scene-{seed}.lcm"
    w = lcm.EventLog(str(log), "w", overwrite=True)
    frame_of_utime = {}
    for f in range(frames):
        u = u0 + int(round(f * period * 1e6))
        frame_of_utime[u] = f
        for channel, data in frame_messages(rig, people[f], f, u, rng):
            w.write_event(u, channel, data)
    w.close()
    f_stop = int(at / period)
    f_restart = f_stop + int(round(gap_s / period))
    a, b = out / f"a-{seed}.lcm", out / f"b-{seed}.lcm"
    split_log(log, a, b, u0 + int(round((f_stop - 0.5) * period * 1e6)), int(round(gap_s * 1e6)))
    state = out / f"state-{seed}"
    for suffix in ("", ".ids"):
        Path(f"{state}{suffix}").unlink(missing_ok=True)
    msgs = []
    for half in (a, b):
        o = half.with_suffix(".out.lcm")
        subprocess.run([str(DAEMON), "--rig", str(rig_path), "--in", f"file://{half}?speed=0", "--out",
                        f"file://{o}?mode=w", "--mode", *shlex.split(mode), "--state", str(state)], check=True,
                       capture_output=True)
        tl = read_log(str(o), lambda c: c == "TRACKS").tracks
        msgs.append([_Tracks(u, tl[u]) for u in sorted(tl)])
    kept, last_before, _, reused, _, _ = score(msgs[0], msgs[1], people, frame_of_utime, f_restart)
    return {"seed": seed, "gap_s": gap_s, "present": len(last_before), "kept": kept, "reused": sorted(reused)}


class _Tracks:
    def __init__(self, utime, tracks):
        self.utime, self.tracks = utime, tracks


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tools/mvtrack restart", description=__doc__.split("\n\n")[0])
    ap.add_argument("--how", choices=["kill", "term", "nostate", "nofiles", "all"], default="all")
    ap.add_argument("--seconds", type=float, default=14.0, help="scene length, s (default 14)")
    ap.add_argument("--at", type=float, default=6.0, help="stop the daemon this far into the scene, s (default 6)")
    ap.add_argument("--down", type=float, default=1.0, help="restart it this long after, s (default 1)")
    ap.add_argument("--mode", default="pkf", help="daemon --mode, and more daemon options after it if wanted "
                    "(default pkf; e.g. 'pkf --outlier-persist 1')")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--port", type=int, default=7300 + os.getpid() % 200, help="private multicast port")
    ap.add_argument("--out", type=Path, default=REPO / "out" / "restart")
    ap.add_argument("--offline", type=int, metavar="SEEDS",
                    help="instead of live: the scene as a log cut in two, --down s removed, over SEEDS seeds "
                         "(deterministic: compares versions)")
    a = ap.parse_args(argv)
    if not DAEMON.exists():
        ap.error(f"{DAEMON} not built (tools/mvtrack build)")
    if a.offline:
        tot_p = tot_k = tot_r = 0
        for seed in range(1, a.offline + 1):
            r = offline(seed, a.down, a.at, a.seconds, a.out / "offline", a.mode)
            print(json.dumps(r))
            tot_p, tot_k, tot_r = tot_p + r["present"], tot_k + r["kept"], tot_r + len(r["reused"])
        print(f"restart --offline: {tot_k} of {tot_p} people kept their identity over {a.down:g} s, "
              f"{tot_r} identities given to another person", file=sys.stderr)
        return 0 if tot_k == tot_p and tot_r == 0 else 1
    hows = ["kill", "term", "nostate", "nofiles"] if a.how == "all" else [a.how]
    ok = True
    for how in hows:
        r = run(how, a.seconds, a.at, a.down, a.mode, a.out, a.seed, a.port)
        print(json.dumps(r))
        restored = how in ("kill", "term")
        ok &= not r["reused_by_another_person"] and not r["new_ids_that_existed_before"]
        ok &= r["tracks_after"] > 0 and (not restored or r["kept"] == r["present"])
    print("restart: " + ("identities kept and never reused" if ok else "FAILED"), file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
