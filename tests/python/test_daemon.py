"""mvtrackd on recorded logs and live LCM: accuracy, determinism, generality, hostile input, CLI."""
from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import lcm
import numpy as np
import pytest

from mvtrack_tools.evaluate import evaluate_single
from mvtrack_tools.lcmio import LogWriter, camera_frame, ground_truth, mt, read_log
from mvtrack_tools.rig import random_rig, smartroom
from mvtrack_tools.scenes import WalkModel, head_detections
from mvtrack_tools.simulate import T0_UTIME, experiment1, with_boxes, write_scene

pytestmark = pytest.mark.daemon


def run(daemon: Path, rig: Path, scene: Path, out: Path, *args: str, check: bool = True) -> subprocess.CompletedProcess:
    r = subprocess.run([str(daemon), "--rig", str(rig), "--in", f"file://{scene}?speed=0", "--out",
                        f"file://{out}?mode=w", *args], capture_output=True, text=True, timeout=300)
    if check:
        assert r.returncode == 0, r.stderr
    return r


def start_live(tmp_path: Path, daemon_path: Path, port_base: int, seconds: float, var: float, seed: int):
    """An Experiment 1 scene and mvtrackd listening live on a private multicast port (ttl=0)."""
    url = f"udpm://239.255.76.67:{port_base + os.getpid() % 200}?ttl=0"
    rig = smartroom()
    rp = tmp_path / "rig.yaml"
    rig.write(rp)
    _, states, dets = experiment1(rig, seconds, var, False, seed)
    p = subprocess.Popen([str(daemon_path), "--rig", str(rp), "--in", url], stderr=subprocess.PIPE, text=True)
    return rig, states, dets, p, lcm.LCM(url)


def publish_live(lc, rig, states, dets, frames: int, sigma_px: float, silent=lambda f, k: False, linger_s: float = 1.0):
    """Publishes every camera's detections, each with the body's box, at 25 fps (camera k silent at
    frame f when silent(f, k)), handling what comes back meanwhile, then listens linger_s more."""
    time.sleep(0.5)  # the daemon subscribes
    t0 = time.monotonic()
    for f in range(frames):
        u = T0_UTIME + f * 40000
        for k, cam in enumerate(rig.cameras):
            if not silent(f, k):
                lc.publish(f"DETECTIONS_{cam.name}",
                           camera_frame(u, f, cam, with_boxes(cam, states[f, :3], dets[f][k]), sigma_px).encode())
        while lc.handle_timeout(0) > 0:
            pass
        delay = t0 + (f + 1) * 0.04 - time.monotonic()
        if delay > 0:
            time.sleep(delay)
    end = time.monotonic() + linger_s
    while time.monotonic() < end:
        lc.handle_timeout(50)


def make_exp1(tmp_path: Path, var: float, occ: bool, seconds: float, seed: int):
    rig = smartroom()
    rp = tmp_path / "rig.yaml"
    rig.write(rp)
    _, states, dets = experiment1(rig, seconds, var, occ, seed)
    sp = tmp_path / f"scene_{seed}.lcm"
    w = LogWriter(str(sp))
    write_scene(w, rig, states, dets, var, progress=False, frame_order_seed=seed)
    w.close()
    return rig, rp, sp


def test_daemon_exp1_default_filter_near_pcrlb_and_beats_baseline(tmp_path, daemon_path):
    rig, rp, sp = make_exp1(tmp_path, 100.0, False, 40.0, seed=21)
    res = {}
    for mode in ("pkf", "kf"):
        out = tmp_path / f"{mode}.lcm"
        run(daemon_path, rp, sp, out, "--mode", mode, "--q", "0.75,0.5,0.022")
        res[mode] = evaluate_single(str(sp), str(out), rig, 100.0)
    assert res["pkf"].matched >= res["pkf"].frames - 5
    assert res["pkf"].ratio < 1.15, res["pkf"]
    assert res["pkf"].rmse_mm < res["kf"].rmse_mm


def test_daemon_exp1_with_occlusions_keeps_the_track(tmp_path, daemon_path):
    """Occlusion bursts (each camera, 30 % of frames, 10 frames displaced): the track is kept, and
    the memory of lasting displacements (the default) lowers the error against --outlier-persist 0
    (these three seeds: 142.1 against 146.4 mm summed; the feet, which each view's blob bottom
    gives, now fix most of what a burst would slide)."""
    matched = frames = 0
    err = {"default": 0.0, "off": 0.0}
    for seed in (22, 23, 24):
        rig, rp, sp = make_exp1(tmp_path, 100.0, True, 40.0, seed=seed)
        for name, args in (("default", []), ("off", ["--outlier-persist", "0"])):
            out = tmp_path / f"pkf_{seed}_{name}.lcm"
            run(daemon_path, rp, sp, out, *args)
            r = evaluate_single(str(sp), str(out), rig, None)
            assert r.mean_mm < 120
            err[name] += r.mean_mm
            if name == "default":
                matched += r.matched
                frames += r.frames
    assert matched >= 0.97 * frames
    assert err["default"] < err["off"], err


def test_daemon_motion_options(tmp_path, daemon_path):
    """--motion-models with the default bank spelt out gives the default's TRACKS bit for bit; a
    bank that differs gives other TRACKS; --motion cv equals --q with the default q; --q with
    --motion imm, a bad bank and a bad --motion are refused with exit 2."""
    rig, rp, sp = make_exp1(tmp_path, 100.0, True, 8.0, seed=31)
    outs = {}
    for name, args in (("default", []),
                       ("spelt", ["--motion-models", "still:2.5e-5:2.5e-5:0.2;cv/still:0.3:4e-4:0.3;"
                                                   "cv:3:0.1:1.5;still/cv:2.5e-5:1:1.3"]),
                       ("other", ["--motion-models", "still:1e-4:1e-4:0.2;cv:1:0.05:0.2"]),
                       ("cv", ["--motion", "cv"]), ("q", ["--q", "0.5,0.5,0.05"])):
        out = tmp_path / f"{name}.lcm"
        run(daemon_path, rp, sp, out, *args)
        outs[name] = tracks_without_publish_time(out)
    assert outs["spelt"] == outs["default"]
    assert outs["other"] != outs["default"]
    assert outs["cv"] == outs["q"] and outs["cv"] != outs["default"]
    for bad in (["--motion", "imm", "--q", "1,1,1"], ["--motion-models", "cv:1:x"], ["--motion-models", "walk:1:1:1"],
                ["--motion-models", "cv:-1:1:1"], ["--motion-models", "cv/:1:1:1"], ["--motion-models", "cv/walk:1:1:1"],
                ["--motion-models", "cv/still/cv:1:1:1"], ["--motion", "fast"], ["--outlier-persist", "-1"],
                ["--outlier-persist", "nan"], ["--outlier-persist", "0.5s"]):
        r = run(daemon_path, rp, sp, tmp_path / "bad.lcm", *bad, check=False)
        assert r.returncode == 2, (bad, r.stderr)
        assert "mvtrackd:" in r.stderr


def tracks_without_publish_time(path: Path) -> list[bytes]:
    out = []
    for ev in lcm.EventLog(str(path), "r"):
        if ev.channel == "TRACKS":
            m = mt.tracks_t.decode(ev.data)
            m.publish_utime = 0
            out.append(m.encode())
    return out


def test_daemon_same_log_gives_bit_identical_tracks(tmp_path, daemon_path):
    _, rp, sp = make_exp1(tmp_path, 200.0, True, 10.0, seed=5)
    a, b = tmp_path / "a.lcm", tmp_path / "b.lcm"
    run(daemon_path, rp, sp, a)
    run(daemon_path, rp, sp, b)
    ta, tb = tracks_without_publish_time(a), tracks_without_publish_time(b)
    assert len(ta) == 250
    assert ta == tb
    # real-time scheduling changes when frame sets are handled, never what comes out
    if os.geteuid() == 0:
        c = tmp_path / "c.lcm"
        run(daemon_path, rp, sp, c, "--rt-priority", "5")
        assert tracks_without_publish_time(c) == ta
    for bad in ("0", "100", "x"):
        r = run(daemon_path, rp, sp, tmp_path / "d.lcm", "--rt-priority", bad, check=False)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "--rt-priority" in r.stderr, r.stderr
        assert not (tmp_path / "d.lcm").exists()


@pytest.mark.parametrize("n_cameras,seed", [(4, 1), (6, 2), (8, 3), (5, 4)])
def test_daemon_tracks_on_rigs_built_differently(tmp_path, daemon_path, n_cameras, seed):
    """Random rooms, camera placements, focal lengths, principal points, image sizes, roll and
    distortion of either sign: nothing of the simulator's SmartRoom."""
    rng = np.random.default_rng(100 + seed)
    rig = random_rig(rng, n_cameras)
    rp = tmp_path / "rig.yaml"
    rig.write(rp)
    model = WalkModel.for_room(rig.volume_min, rig.volume_max)
    states = model.sample(rng, 500, 0.04, rig.volume_min, rig.volume_max, margin=0.8)
    dets = head_detections(rig, states[:, :3], 4.0, rng)
    sp = tmp_path / "scene.lcm"
    w = LogWriter(str(sp))
    write_scene(w, rig, states, dets, 4.0, progress=False)
    w.close()
    out = tmp_path / "tracks.lcm"
    run(daemon_path, rp, sp, out)
    r = evaluate_single(str(sp), str(out), rig, None)
    assert r.matched >= 0.97 * r.frames, r
    assert r.rmse_mm < 40, r


def test_daemon_hostile_input_counted_and_survived(tmp_path, daemon_path):
    rig = smartroom()
    rp = tmp_path / "rig.yaml"
    rig.write(rp)
    _, states, dets = experiment1(rig, 4.0, 50.0, False, 3)
    sp = tmp_path / "scene.lcm"
    w = LogWriter(str(sp))
    write_scene(w, rig, states, dets, 50.0, progress=False)
    # hostile messages in the middle of the log
    u = T0_UTIME + 50 * 40000
    w.log.write_event(u, "DETECTIONS_cam0", b"\x00\x01garbage")                      # undecodable
    w.log.write_event(u, "DETECTIONS_cam0", os.urandom(300))                         # undecodable
    bad = camera_frame(u, 50, rig.cameras[0], [(100.0, 100.0)], 2.0)
    bad.camera = "nosuchcam"
    w.write(u, "DETECTIONS_nosuchcam", bad)                                          # unknown camera
    nan = camera_frame(u + 40000 * 3, 53, rig.cameras[1], [(float("nan"), 5.0), (float("inf"), 1.0)], 2.0)
    w.write(u, "DETECTIONS_cam1", nan)                                               # NaN / Inf detections
    wrong = camera_frame(u + 40000 * 4, 54, rig.cameras[2], [(10.0, 10.0)], 2.0)
    wrong.width = 640
    w.write(u, "DETECTIONS_cam2", wrong)                                             # size mismatch
    flood = camera_frame(u + 40000 * 6, 56, rig.cameras[3], [(float(i % 700), float(i % 500)) for i in range(3000)], 2.0)
    w.write(u, "DETECTIONS_cam3", flood)                                             # over capacity
    boxes = camera_frame(u + 40000 * 7, 57, rig.cameras[0],
                         [(300.0, 200.0, (float("nan"), 0.0, 10.0, 10.0)), (310.0, 210.0, (50.0, 50.0, 10.0, 10.0)),
                          (320.0, 220.0, (-1e30, 0.0, 1e30, 1e30)), (330.0, 230.0, (float("inf"),) * 4)], 2.0)
    w.write(u, "DETECTIONS_cam0", boxes)                                             # hostile boxes: ignored
    old = camera_frame(T0_UTIME, 0, rig.cameras[4], [(300.0, 300.0)], 2.0)
    w.write(u, "DETECTIONS_cam4", old)                                               # time going backwards
    w.close()
    out = tmp_path / "tracks.lcm"
    r = run(daemon_path, rp, sp, out)
    log = read_log(str(out))
    assert len(log.tracks) >= 99  # every frame set still processed
    st = log.status[-1]
    assert st.rejected_undecodable == 2
    assert st.rejected_unknown_camera == 1
    assert st.rejected_bad_value >= 3
    assert st.rejected_over_capacity > 0
    assert st.rejected_time_backwards + st.rejected_late >= 1
    assert "undecodable" in r.stderr
    # the person is still tracked at the end
    last = log.tracks[max(log.tracks)]
    assert any(t.status == 2 for t in last)


def test_daemon_help_and_bad_arguments(tmp_path, daemon_path):
    h = subprocess.run([str(daemon_path), "--help"], capture_output=True, text=True)
    assert h.returncode == 0
    for word in ("--rig", "--in", "--out", "--mode", "pkf", "kf", "pkf-paper", "ttl=0"):
        assert word in h.stdout
    r = subprocess.run([str(daemon_path)], capture_output=True, text=True)
    assert r.returncode == 2 and "--rig is required" in r.stderr
    r = subprocess.run([str(daemon_path), "--rig", str(tmp_path / "none.yaml")], capture_output=True, text=True)
    assert r.returncode == 2 and "cannot open" in r.stderr
    broken = tmp_path / "broken.yaml"
    smartroom().write(broken)
    broken.write_text(broken.read_text().replace("camera_matrix", "camera_matrx", 1))
    r = subprocess.run([str(daemon_path), "--rig", str(broken)], capture_output=True, text=True)
    assert r.returncode == 2 and "missing camera_matrix" in r.stderr
    good = tmp_path / "good.yaml"
    smartroom().write(good)
    r = subprocess.run([str(daemon_path), "--rig", str(good), "--mode", "nope"], capture_output=True, text=True)
    assert r.returncode == 2 and "unknown --mode" in r.stderr
    # static occluders: read from the rig (an OpenCV matrix or a plain list), an empty box refused
    room = smartroom()
    room.occluders = [{"name": "desk", "min": [1.0, 2.0, 0.0], "max": [3.0, 2.6, 0.9]}]
    with_desk = tmp_path / "desk.yaml"
    room.write(with_desk)
    text = with_desk.read_text().replace("occluders:", "occluders:\n   - { name: pillar, min: [4.0, 1.0, 0.0], "
                                         "max: [4.3, 1.3, 2.5] }", 1)
    with_desk.write_text(text)
    empty = tmp_path / "empty.lcm"  # one event on a channel the daemon ignores
    log = lcm.EventLog(str(empty), "w", overwrite=True)
    log.write_event(1000000, "NOTHING", b"")
    log.close()
    r = subprocess.run([str(daemon_path), "--rig", str(with_desk), "--in", f"file://{empty}?speed=0", "--out",
                        f"file://{tmp_path / 'o.lcm'}?mode=w"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 0 and "2 static occluders" in r.stderr, r.stderr
    with_desk.write_text(text.replace("max: [4.3, 1.3, 2.5]", "max: [3.9, 1.3, 2.5]"))
    r = subprocess.run([str(daemon_path), "--rig", str(with_desk)], capture_output=True, text=True)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "occluders[0]: max must exceed min" in r.stderr


def test_daemon_live_udpm_tracks_and_stops_on_sigterm(tmp_path, daemon_path):
    """Live over LCM multicast (ttl=0, a private port): publish 3 s at 25 fps, then SIGTERM."""
    rig, states, dets, p, lc = start_live(tmp_path, daemon_path, 7700, 3.0, 50.0, 8)
    got = []
    lc.subscribe("TRACKS", lambda c, d: got.append(mt.tracks_t.decode(d)))
    try:
        publish_live(lc, rig, states, dets, len(states), 7.0)
    finally:
        p.send_signal(signal.SIGTERM)
        _, err = p.communicate(timeout=10)
    assert p.returncode == 0, err
    assert len(got) >= 0.95 * len(states)
    final = got[-1]
    assert any(t.status == 2 for t in final.tracks)
    assert all(m.publish_utime > 0 for m in got)


def test_daemon_time_faults_counted_tracks_survive(tmp_path, daemon_path):
    """Every time fault in docs/interfaces.md section 3 and the trust model: the capture clock of every camera
    set back an hour, one camera's clock far ahead, a camera restarting its frame counter, utimes
    outside 0..2^60, duplicates, a truncated message and hostile counts. The person stays tracked,
    every frame set after the faults is processed, each fault is counted."""
    rig = smartroom()
    rp = tmp_path / "rig.yaml"
    rig.write(rp)
    _, states, dets = experiment1(rig, 8.0, 25.0, False, 5)
    sp = tmp_path / "scene.lcm"
    w = LogWriter(str(sp))
    jump_at, jump_us = 100, -3600 * 1_000_000
    for f in range(len(states)):
        u = T0_UTIME + f * 40000 + (jump_us if f >= jump_at else 0)
        for k, cam in enumerate(rig.cameras):
            counter = f if not (k == 1 and f >= 150) else f - 150  # cam1's detector restarts at 150
            m = camera_frame(u, counter, cam, [(a, b) for a, b, _ in dets[f][k]], 5.0)
            if k == 3 and 60 <= f < 70:
                m.utime = u + 500 * 1_000_000                      # cam3's clock 500 s ahead, 10 frames
            w.write(u, f"DETECTIONS_{cam.name}", m)
            if f == 80 and k == 0:
                w.write(u, "DETECTIONS_cam0", m)                   # duplicate
                for bad_u in (-1, 2**62):
                    b = camera_frame(bad_u, f, cam, [], 5.0)
                    w.write(u, "DETECTIONS_cam0", b)               # utime out of range
                data = m.encode()
                w.log.write_event(u, "DETECTIONS_cam0", data[: len(data) // 2])  # truncated
                hostile = bytearray(data)
                hostile[24:28] = (0x7FFFFFFF).to_bytes(4, "big")  # camera name length 2^31 - 1
                w.log.write_event(u, "DETECTIONS_cam0", bytes(hostile))
    w.close()
    out = tmp_path / "tracks.lcm"
    r = run(daemon_path, rp, sp, out)
    log = read_log(str(out))
    st = log.status[-1]
    assert st.clock_jumps == 1, r.stderr
    assert st.rejected_time_ahead == 10
    assert [c.counter_restarts for c in st.cameras] == [0, 1, 0, 0, 0]
    assert st.rejected_duplicate >= 1
    assert st.rejected_bad_value >= 2
    assert st.rejected_undecodable == 2
    # TRACKS carry the cameras' own clock: after the jump, times an hour earlier, frame after frame
    times = sorted(log.tracks)
    after = [t for t in times if t < T0_UTIME]
    assert len(after) >= len(states) - jump_at - 2
    assert np.all(np.diff(after) > 0)
    # the track kept its identity across the jump and the faults
    ids_before = {t.id for t in log.tracks[max(t for t in times if t >= T0_UTIME)] if t.status == 2}
    ids_end = {t.id for t in log.tracks[max(after)] if t.status == 2}
    assert ids_before and ids_before == ids_end


def test_daemon_live_camera_drop_output_keeps_rate(tmp_path, daemon_path):
    """Live: camera 2 stops for 2 s and comes back; a TRACKS message for every frame set, the camera
    reported down and back in MVTRACK_STATUS, frames during the drop without it in cameras_used."""
    rig, states, dets, p, lc = start_live(tmp_path, daemon_path, 7500, 5.0, 25.0, 9)
    got, status = [], []
    lc.subscribe("TRACKS", lambda c, d: got.append(mt.tracks_t.decode(d)))
    lc.subscribe("MVTRACK_STATUS", lambda c, d: status.append(mt.status_t.decode(d)))
    try:
        publish_live(lc, rig, states, dets, len(states), 5.0, silent=lambda f, k: k == 2 and 50 <= f < 100, linger_s=1.3)
    finally:
        p.send_signal(signal.SIGTERM)
        _, err = p.communicate(timeout=10)
    assert p.returncode == 0, err
    assert len(got) >= len(states) - 3
    cam2 = status[-1].cameras[2]
    assert cam2.went_down == 1 and cam2.came_back == 1 and cam2.active
    during = [m for m in got if T0_UTIME + 55 * 40000 <= m.utime < T0_UTIME + 98 * 40000]
    assert during and all(not (t.cameras_used >> 2) & 1 for m in during for t in m.tracks)
    assert "camera cam2 absent" in err and "camera cam2 is back" in err


def test_daemon_one_view_start_found_again_where_the_views_agree(tmp_path, daemon_path):
    """Five people walking the smart room (tools/mvtrack latency's walkers, seed 1); the first frame
    set holds camera 1 alone and camera 0 never reports. Camera 1's boxes are made up, 120 px tall
    under the head, so their bottoms read as feet farther away than the people are: person 1 is born
    along camera 1's ray 0.8 m beyond them, pinned there by those feet. From the next frame cameras
    2-4 agree on where that head is, and camera 1's head, which places the track, agrees with them:
    once the track's place has rested on one view for 1 s (twice a displacement's mean duration)
    it starts again at their point with its identity. Measured: person 1 untracked 22 frames, every
    head from frame 25 on within 0.3 m of a confirmed track (0.909 when the track stays where its
    first view put it: person 1 untracked 102 frames)."""
    from mvtrack_tools.latency import walkers
    rig = smartroom()
    rp = tmp_path / "rig.yaml"
    rig.write(rp)
    rng = np.random.default_rng(1)
    people = walkers(rng, 5, 200, 0.04, rig.volume_min, rig.volume_max)
    w = LogWriter(str(tmp_path / "scene.lcm"))
    for f in range(200):
        u = T0_UTIME + f * 40000
        msgs = []
        for k in rng.permutation(5):
            cam = rig.cameras[k]
            uv = cam.project(people[f])
            dets = [(x + rng.normal(0, 2.0), y + rng.normal(0, 2.0)) for x, y in uv
                    if 0 <= x < cam.width and 0 <= y < cam.height and rng.random() > 0.05]
            jitter = int(rng.integers(-3000, 3001))
            if k != 0 and (f > 0 or k == 1):
                msgs.append((u + jitter, f"DETECTIONS_{cam.name}", camera_frame(u + jitter, f, cam, dets, 2.0)))
        for uu, ch, m in sorted(msgs, key=lambda x: x[0]):
            w.write(uu, ch, m)
    w.close()
    run(daemon_path, rp, tmp_path / "scene.lcm", tmp_path / "tracks.lcm")
    tr = read_log(str(tmp_path / "tracks.lcm"), lambda c: c == "TRACKS").tracks
    hit = n = 0
    for f, u in enumerate(sorted(tr)[25:200], start=25):
        pos = np.array([t.position for t in tr[u] if t.status != 1]).reshape(-1, 3)
        for head in people[f]:
            n += 1
            hit += bool(len(pos)) and float(np.linalg.norm(pos - head, axis=1).min()) < 0.3
    assert n == 875 and hit / n > 0.99, (hit, n)


def test_daemon_live_flooding_camera_shed_output_kept(tmp_path, daemon_path):
    """Live, 5 cameras, 5 people; from 1 s on, camera 0's channel also carries 50x its frame rate of
    extra messages with plausible times (tools/mvtrack latency --flood-camera 0 --flood-after-s 1).
    The flood is shed before decoding and counted; TRACKS stays at 25 Hz and the people stay tracked
    by the other cameras. The flood starts once the room is tracked: begun with the first frame, on
    a loaded machine, it starves the start-up into one-camera frame sets, which is another test's
    scene (test_daemon_one_view_start_found_again_where_the_views_agree)."""
    import json
    from mvtrack_tools import latency
    latency.main(["--seconds", "8", "--drop-every", "0", "--flood-camera", "0", "--flood-after-s", "1",
                  "--out", str(tmp_path),
                  "--port", str(7700 + os.getpid() % 200)])
    r = json.loads((tmp_path / "latency.json").read_text())
    assert r["flood_rate_hz"] > 40 * 25, r           # the flood happened (>= 40x; 50x asked)
    assert r["shed_by_daemon"][0] >= 0.9 * r["flood_messages_sent"], r
    assert r["shed_by_daemon"][1:] == [0, 0, 0, 0], r
    assert abs(r["rate_hz_mean"] - 25.0) < 0.5, r
    assert r["heads_tracked_within_0.3m"] > 0.95, r


@pytest.mark.parametrize("skew_ms", [60, -200])
def test_daemon_live_camera_clock_off_measured_and_corrected(tmp_path, daemon_path, skew_ms):
    """Live, 5 cameras, 5 people; camera 2 stamps its frames skew_ms ahead of (negative: behind) the
    others. The daemon measures the offset from when frames arrive, reports it in MVTRACK_STATUS,
    and assembles the camera's frames on the corrected time: from 10 s on the people are tracked
    as without the skew (tools/mvtrack latency --clock 2:MS; measured: MOTA 0.968 with 60 ms and without,
    mean error 14.1 mm both; without the correction 60 ms ahead gave MOTA 0.882, 111 mm)."""
    import json
    from mvtrack_tools import latency
    latency.main(["--seconds", "13", "--drop-every", "0", "--clock", f"2:{skew_ms}", "--score-from-s", "10",
                  "--out", str(tmp_path), "--port", str(7500 + os.getpid() % 200)])
    r = json.loads((tmp_path / "latency.json").read_text())
    c = r["clock"][0]
    assert c["reported_at_score_from_s"]["known"], r
    assert abs(c["reported_at_score_from_s"]["offset_ms"] - skew_ms) < 5.0, r
    assert r["heads_tracked_within_0.3m"] > 0.95 and r["mean_error_mm"] < 30.0, r


def test_daemon_live_slow_camera_seen_late_by_the_tracks(tmp_path, daemon_path):
    """Live, 5 cameras, 5 people; camera 2's messages leave 60 ms after the others' (a slower
    detector), stamped with the true capture time. Arrival times call it 60 ms behind and re-time
    it; the tracks see its walking people late against the other cameras (measured 45-56 ms at
    15-30 s: frame sets it lands in late hold the others' views late too), the on-time cameras show
    no lag (within 2 ms), and the people stay tracked."""
    import json
    from mvtrack_tools import latency
    latency.main(["--seconds", "24", "--drop-every", "0", "--delay", "2:60", "--clock", "0:0", "--score-from-s", "15",
                  "--out", str(tmp_path), "--port", str(7300 + os.getpid() % 200)])
    r = json.loads((tmp_path / "latency.json").read_text())
    cam = {c["camera"]: c["reported_last"] for c in r["clock"]}
    assert cam["cam2"]["tracks_known"] and cam["cam0"]["tracks_known"], r
    assert abs(cam["cam2"]["offset_ms"] + 60.0) < 5.0, r
    assert 30.0 < cam["cam2"]["tracks_lag_ms"] < 75.0, r
    assert abs(cam["cam0"]["tracks_lag_ms"]) < 5.0, r
    assert "walking people in its frames are" in (tmp_path / "daemon.stderr").read_text()
    assert r["heads_tracked_within_0.3m"] > 0.95, r


def test_readme_subscribers_print_the_daemons_tracks(tmp_path, daemon_path):
    """The README's subscribers (docs/subscribe_tracks.c, built as build/bin/subscribe_tracks, and
    docs/subscribe_tracks.py) print one line per confirmed or coasting track of every TRACKS
    message, here of the daemon's offline output of a simulated walk."""
    import sys
    from mvtrack_tools.paths import BUILD, REPO
    rig = smartroom()
    rig.write(tmp_path / "rig.yaml")
    _, states, dets = experiment1(rig, 4.0, 100.0, False, 3)
    w = LogWriter(str(tmp_path / "scene.lcm"))
    write_scene(w, rig, states, dets, 100.0, progress=False)
    w.close()
    r = subprocess.run([str(daemon_path), "--rig", str(tmp_path / "rig.yaml"), "--in",
                        f"file://{tmp_path / 'scene.lcm'}?speed=0", "--out", f"file://{tmp_path / 'tracks.lcm'}?mode=w"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    tr = read_log(str(tmp_path / "tracks.lcm"), lambda c: c == "TRACKS").tracks
    want = [f"{u} id {t.id} at {t.position[0]:.2f} {t.position[1]:.2f} {t.position[2]:.2f} m"
            for u in sorted(tr) for t in tr[u] if t.status != 1]
    assert len(want) > 50
    url = f"file://{tmp_path / 'tracks.lcm'}?speed=0"
    c = subprocess.run([str(BUILD / "bin" / "subscribe_tracks"), url], capture_output=True, text=True, timeout=60)
    assert c.stdout.splitlines() == want
    env = dict(os.environ, PYTHONPATH=str(BUILD / "lcmtypes" / "python"))
    p = subprocess.Popen([sys.executable, str(REPO / "docs" / "subscribe_tracks.py"), url], stdout=subprocess.PIPE,
                         text=True, env=env)
    try:
        got = [p.stdout.readline().rstrip("\n") for _ in want]  # it waits for more at the log's end
    finally:
        p.kill()
        p.wait()
    assert got == want
