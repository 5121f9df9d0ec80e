"""Many people: the MOT evaluation against hand-made references, the simulator's detector model,
and mvtrackd on multi-person scenes (our SmartRoom and rigs built differently), floods and dropout."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mvtrack_tools.crowd import DetectorModel, crowd_scene, detect
from mvtrack_tools.flood import score, write_flood_log
from mvtrack_tools.lcmio import LogWriter, TrackLog, camera_frame, ground_truth, read_log
from mvtrack_tools.mot import as_dict, clear_mot, identity_switches, ospa, pair_frames
from mvtrack_tools.rig import random_rig, smartroom
from mvtrack_tools.simulate import T0_UTIME, build_multi, write_multi


class _T:  # a track_t stand-in
    def __init__(self, i, pos, vel=(0.0, 0.0, 0.0), status=2):
        self.id, self.position, self.velocity, self.status = i, list(pos), list(vel), status


def _logs(gt_frames, trk_frames, dt_us=40000):
    sc, tr = TrackLog(), TrackLog()
    for f, (ids, pos) in enumerate(gt_frames):
        sc.gt[T0_UTIME + f * dt_us] = (ids, np.array(pos, float).reshape(-1, 3))
    for f, tracks in enumerate(trk_frames):
        tr.tracks[T0_UTIME + f * dt_us + 2000] = tracks  # 2 ms later, as with capture jitter
    return sc, tr


@pytest.mark.tools
def test_ospa_matches_hand_computed_values():
    X = np.array([[0.0, 0, 0], [1, 0, 0]])
    assert ospa(X, X) == 0.0
    assert ospa(X[:0], X[:0]) == 0.0
    assert ospa(X, X[:0]) == pytest.approx(0.5)
    # one matched 0.1 m away, one missing: ((0.1^2 + 0.5^2) / 2)^(1/2)
    assert ospa(X, np.array([[0.1, 0, 0]])) == pytest.approx(np.sqrt((0.01 + 0.25) / 2))
    # distances beyond c are cut at c
    assert ospa(X[:1], np.array([[3.0, 0, 0]])) == pytest.approx(0.5)


@pytest.mark.tools
def test_clear_mot_motp_in_mm_switches_and_misses():
    gt = [([1, 2], [[0, 0, 1.7], [2, 0, 1.7]])] * 10
    # track 10 follows person 1 at 30 mm; person 2 is tracked by 20 then 21 (one switch); one
    # frame without any track for person 2; a false track far away in the last frame
    trk = []
    for f in range(10):
        t = [_T(10, (0.03, 0, 1.7))]
        if f != 4:
            t.append(_T(20 if f < 5 else 21, (2.0, 0.04, 1.7)))
        if f == 9:
            t.append(_T(99, (4.0, 4.0, 1.7)))
        trk.append(t)
    r = clear_mot(pair_frames(*_logs(gt, trk)))
    assert r.gt_boxes == 20
    assert r.misses == 1 and r.false_positives == 1 and r.id_switches == 1
    assert r.mota == pytest.approx(1 - 3 / 20)
    assert r.motp_mm == pytest.approx((10 * 30 + 9 * 40) / 19, rel=1e-6)


@pytest.mark.tools
def test_identity_switches_classified_by_how_they_came_about():
    p1, p2, far = (0.0, 0.0, 1.7), (2.0, 0.0, 1.7), (5.0, 0.0, 1.7)
    gt = [([1, 2], [p1, p2])] * 100
    trk = []
    for f in range(100):
        if f < 40:    # 10 follows person 1, 20 person 2 (1.6 s)
            t = [_T(10, p1), _T(20, p2)]
        elif f < 80:  # 20 takes person 1 (10 is gone); a new track 30 is born on person 2
            t = [_T(20, p1), _T(30, p2)]
        else:         # 1.64 s after it last followed person 1, identity 10 comes back on person 2
            t = [_T(20, p1), _T(10, p2)]
        trk.append(t)
    frames = pair_frames(*_logs(gt, trk))
    sw, runs = identity_switches(frames)
    got = [(s.frame, s.person, s.old_track, s.new_track, s.kind, s.was_following) for s in sw]
    assert got == [(40, 1, 10, 20, "took", 2), (40, 2, 20, 30, "born", None), (80, 2, 30, 10, "passed", 1)]
    m = clear_mot(frames)
    assert len(sw) == m.id_switches
    assert {k: v for k, v in as_dict(m).items() if k.startswith("switches_")} == {
        "switches_born": 1, "switches_took": 1, "switches_passed": 1, "switches_returned": 0, "switches_ghost": 0}
    assert runs[1] == [(10, 0, 39), (20, 40, 99)]
    assert runs[2] == [(20, 0, 39), (30, 40, 79), (10, 80, 99)]
    # person 1 is missed, born again as 11, given back their own 10; then 12, a track that has
    # followed nobody for 2.4 s, takes them
    gt = [([1], [p1])] * 80
    trk = ([[_T(10, p1), _T(12, far)]] * 20 + [[_T(12, far)]] * 10 + [[_T(11, p1), _T(12, far)]] * 20 +
           [[_T(10, p1), _T(12, far)]] * 10 + [[_T(12, p1)]] * 20)
    sw, runs = identity_switches(pair_frames(*_logs(gt, trk)))
    assert [(s.frame, s.kind) for s in sw] == [(30, "born"), (50, "returned"), (60, "ghost")]
    assert runs[1][1] == (None, 20, 29)


@pytest.mark.tools
def test_identities_command_prints_switches_and_refuses_logs_without_truth(tmp_path, capsys):
    from mvtrack_tools import identities
    import mvtrack_tools.lcmio as lcmio

    log = tmp_path / "scene.lcm"
    w = LogWriter(str(log))
    for f in range(60):
        u = T0_UTIME + f * 40000
        w.write(u, "GROUND_TRUTH", ground_truth(u, f, [1], np.array([[1.0, 1.0, 1.7]])))
        m = lcmio.mt.tracks_t()
        m.utime, m.frame = u, f
        t = lcmio.mt.track_t()
        t.id, t.status = (5 if f < 30 else 6), 2
        t.position, t.velocity = [1.0, 1.0, 1.7], [0.0, 0.0, 0.0]
        m.tracks = [t]
        m.num_tracks = 1
        w.write(u, "TRACKS", m)
    w.close()
    assert identities.main(["--scene", str(log), "--tracks", str(log)]) == 0
    out = capsys.readouterr().out
    assert "person 1: track 5 -> 6  born" in out and "1 switches: 1 born" in out
    empty = tmp_path / "empty.lcm"
    LogWriter(str(empty)).close()
    with pytest.raises(SystemExit) as e:
        identities.main(["--scene", str(empty), "--tracks", str(log)])
    assert e.value.code == 2
    assert "no GROUND_TRUTH" in capsys.readouterr().err


@pytest.mark.tools
def test_clear_mot_carries_tracks_to_gt_time_and_ignores_tentative():
    gt = [([1], [[0, 0, 1.7]])] * 3
    # the track message is 2 ms late; its velocity of 10 m/s carries it back by 20 mm
    trk = [[_T(1, (0.02, 0, 1.7), (10.0, 0, 0)), _T(2, (0.1, 0, 1.7), status=1)]] * 3
    r = clear_mot(pair_frames(*_logs(gt, trk)))
    assert r.false_positives == 0 and r.misses == 0
    assert r.motp_mm == pytest.approx(0.0, abs=1e-3)


@pytest.mark.tools
def test_detector_model_merges_misses_false_alarms_dropout():
    rig = smartroom()
    scene = crowd_scene(rig, 30.0, 5, model=DetectorModel(dropout_s=10.0))
    frames = detect(scene, np.random.default_rng(1))
    info = scene.info
    assert info["merged_blobs"] > 0 and info["missed"] > 0 and info["false_alarms"] > 0
    # dropout: camera 1 sends nothing for 4 s = 100 frames
    assert info["dropped_messages"] == 100
    assert all(frames[f][1] is None for f in range(250, 350))
    # jitter within +-3 ms
    offs = [cf.utime_offset_us for row in frames for cf in row if cf is not None]
    assert max(abs(o) for o in offs) <= 3000 and np.std(offs) > 1000
    # people never walk through each other
    for f in range(scene.n_frames):
        p = np.array([q.pos[f - q.f0, :2] for q in scene.present(f)])
        if len(p) > 1:
            d = np.linalg.norm(p[:, None] - p[None], axis=2) + np.eye(len(p)) * 9
            assert d.min() > 0.4


def _run_and_score(daemon: Path, tmp_path: Path, rig, kind: str, seed: int, **kw):
    rp = tmp_path / f"rig_{kind}_{seed}.yaml"
    rig.write(rp)
    scene, frames = build_multi(kind, rig, seed, **kw)
    log = tmp_path / f"{kind}_{seed}.lcm"
    w = LogWriter(str(log))
    write_multi(w, scene, frames, progress=False)
    w.close()
    out = tmp_path / f"{kind}_{seed}_tracks.lcm"
    r = subprocess.run([str(daemon), "--rig", str(rp), "--in", f"file://{log}?speed=0", "--out",
                        f"file://{out}?mode=w"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    tr = read_log(str(out), lambda c: c in ("TRACKS", "MVTRACK_STATUS"))
    sc = read_log(str(log), lambda c: c == "GROUND_TRUTH")
    return clear_mot(pair_frames(sc, tr, rig.frame_rate)), tr, scene


@pytest.mark.daemon
def test_daemon_interaction_scene_no_identity_switch(tmp_path, daemon_path):
    for seed in (1, 2):
        r, _, _ = _run_and_score(daemon_path, tmp_path, smartroom(), "interaction", seed)
        assert r.id_switches == 0, r
        assert r.mota > 0.97 and r.motp_mm < 40, r


@pytest.mark.daemon
def test_daemon_crowd_scene_with_dropout_keeps_publishing(tmp_path, daemon_path):
    r, tr, scene = _run_and_score(daemon_path, tmp_path, smartroom(), "crowd", 2, seconds=30.0,
                                  model=DetectorModel(dropout_s=10.0))
    # every ground-truth frame has its TRACKS message, also while camera 1 is silent
    assert r.frames_without_tracks == 0
    assert len(tr.tracks) == scene.n_frames
    # measured on this scene: MOTA 0.97; the bar leaves room for other platforms' float rounding
    assert r.mota > 0.9 and r.motp_mm < 60, r
    st = tr.status[-1]
    assert st.cameras[1].frames_missing >= 95


@pytest.mark.daemon
def test_daemon_crowd_acceptance_scene_meets_the_bar(tmp_path, daemon_path):
    """The issue's 60 s scene (5 people entering and leaving, 10 % misses, 0.3 false alarms per
    camera and frame, merged blobs, a camera absent 4 s, +-3 ms jitter), seed 1: measured MOTA
    0.969, 1 switch, 32 mm (tools/mvtrack mot); the bar is the issue's."""
    r, _, _ = _run_and_score(daemon_path, tmp_path, smartroom(), "crowd", 1)
    assert r.mota >= 0.95 and r.id_switches <= 2 and r.motp_mm <= 60, r


@pytest.mark.daemon
def test_daemon_crowd_at_two_frames_a_second(tmp_path, daemon_path):
    """The crowd scene (smart room, seed 1, 30 s) seen at 25/12 fps: every 12th frame set of the
    25 fps log, the rig declaring that rate. Half a second between frames is the rig's pace, not an
    outage: measured MOTA 0.910, 4 switches in 63 frames (0.661 and 11 switches while every such gap
    put the tracks to sleep)."""
    import lcm
    rig = smartroom()
    scene, frames = build_multi("crowd", rig, 1, seconds=30.0)
    full = tmp_path / "crowd_25fps.lcm"
    w = LogWriter(str(full))
    write_multi(w, scene, frames, progress=False)
    w.close()
    slow = tmp_path / "crowd_2fps.lcm"
    src, dst = lcm.EventLog(str(full), "r"), lcm.EventLog(str(slow), "w", overwrite=True)
    for ev in src:
        if int(round((ev.timestamp - T0_UTIME) / 40000.0)) % 12 == 0:
            dst.write_event(ev.timestamp, ev.channel, ev.data)
    dst.close()
    rig.frame_rate = 25.0 / 12.0
    rp = tmp_path / "rig_2fps.yaml"
    rig.write(rp)
    out = tmp_path / "tracks_2fps.lcm"
    r = subprocess.run([str(daemon_path), "--rig", str(rp), "--in", f"file://{slow}?speed=0", "--out",
                        f"file://{out}?mode=w"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    res = clear_mot(pair_frames(read_log(str(slow), lambda c: c == "GROUND_TRUTH"),
                                read_log(str(out), lambda c: c == "TRACKS"), rig.frame_rate))
    assert res.mota > 0.85 and res.id_switches <= 5, res


@pytest.mark.daemon
@pytest.mark.parametrize("n_cameras,seed", [(4, 11), (6, 12), (8, 13)])
def test_daemon_multi_person_on_rigs_built_differently(tmp_path, daemon_path, n_cameras, seed):
    rig = random_rig(np.random.default_rng(seed), n_cameras)
    model = DetectorModel(sigma_px=2.0, p_miss=0.05, fa_rate=0.2, dropout_cam=None)
    r, _, _ = _run_and_score(daemon_path, tmp_path, rig, "interaction", seed, model=model)
    assert r.id_switches == 0, r
    assert r.mota > 0.95, r


@pytest.mark.daemon
@pytest.mark.parametrize("seed", [3, 6, 8, 9])
def test_daemon_false_alarm_flood_counted_tracks_kept(tmp_path, daemon_path, seed):
    rig = smartroom()
    rp = tmp_path / "rig.yaml"
    rig.write(rp)
    log = tmp_path / "flood.lcm"
    write_flood_log(log, rig, seed, 300)  # 300 false alarms per camera per frame from frame 50 on
    out = tmp_path / "flood_tracks.lcm"
    r = subprocess.run([str(daemon_path), "--rig", str(rp), "--in", f"file://{log}?speed=0", "--out",
                        f"file://{out}?mode=w"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    res = score(log, out, rig.frame_rate)
    # the two people keep their identities through the flood
    assert res["id_switches"] == 0 and res["misses"] <= 10, res
    # a track is confirmed only when its existence, against the view's clutter density, passes 0.9;
    # that density counts the detections the daemon dropped over capacity (mvt_view_t num_offered:
    # the kept ones are each track's nearest, so the density of what was kept would make a ghost's
    # random detections look likelier than clutter; tools/mvtrack flood)
    assert res["ghosts"] == 0 and res["false_positive_frames"] == 0, res
    assert res["max_tracks"] <= 32
    assert res["rejected_over_capacity"] >= 100 * 5 * (302 - 64) * 0.99
    assert "capacity" in r.stderr


@pytest.mark.daemon
@pytest.mark.parametrize("model,seed", [("rows", 4), ("camouflage", 4)])
def test_daemon_body_model_on_broken_silhouettes(tmp_path, daemon_path, model, seed):
    """The PKF tracker on rendered masks whose connected components break the bodies (rows: cut
    at the same image rows in every camera; camouflage: a shirt or trousers the colour of the
    background), the interaction scene, seeds the model was not developed on (its development used
    1-3): every person tracked, no switch, no track in a person's column below the head
    (tools/mvtrack fragments)."""
    from mvtrack_tools.fragments import column_ghosts

    rig, log, out = tmp_path / "rig.yaml", tmp_path / "scene.lcm", tmp_path / "tracks.lcm"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2] / "tools"))
    subprocess.run([sys.executable, "-m", "mvtrack_tools.simulate", "interaction", "--render", "--fragments", model,
                    "--seed", str(seed), "--rig", str(rig), "--log", str(log), "--quiet"], check=True, env=env,
                   timeout=600)
    r = subprocess.run([str(daemon_path), "--rig", str(rig), "--in", f"file://{log}?speed=0", "--out",
                        f"file://{out}?mode=w"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    frames = pair_frames(read_log(str(log), lambda c: c == "GROUND_TRUTH"), read_log(str(out), lambda c: c == "TRACKS"))
    res = clear_mot(frames)
    assert res.mota >= 0.95 and res.id_switches == 0, res
    assert column_ghosts(frames) == 0


@pytest.mark.daemon
def test_daemon_newcomer_merged_with_a_tracked_person_born_at_once(tmp_path, daemon_path):
    """The smart room's crowd, seed 7 (60 s): a person who comes in 42 s into the scene shows in
    every view that sees them first as the top of a blob merged with someone already tracked, and
    that blob's top is beyond the tracked person's gate. Such a top is someone else's: the newcomer
    must be born from it (with a second view), not left unborn while the tracked person's track
    calls the blob its displaced head. Every person is tracked within 12 frames (0.48 s) of coming
    in (without births from merged blobs that person waited 90 frames), no switch."""
    rig, log, out = tmp_path / "rig.yaml", tmp_path / "scene.lcm", tmp_path / "tracks.lcm"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2] / "tools"))
    subprocess.run([sys.executable, "-m", "mvtrack_tools.simulate", "crowd", "--seed", "7", "--rig", str(rig),
                    "--log", str(log), "--quiet"], check=True, env=env, timeout=600)
    r = subprocess.run([str(daemon_path), "--rig", str(rig), "--in", f"file://{log}?speed=0", "--out",
                        f"file://{out}?mode=w"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    frames = pair_frames(read_log(str(log), lambda c: c == "GROUND_TRUTH"), read_log(str(out), lambda c: c == "TRACKS"))
    switches, runs = identity_switches(frames)
    waits = {p: (b - a + 1 if h is None else 0) for p, ((h, a, b), *_) in runs.items()}
    assert len(waits) == 7 and max(waits.values()) <= 12, waits
    assert not switches, switches


@pytest.mark.daemon
def test_daemon_person_hidden_in_merged_blobs_kept_whatever_the_blobs_order(tmp_path, daemon_path):
    """Random rig 12 (5 cameras), crowd seed 1 (60 s): person 5, short, stands from about 16 s to
    the end beside taller people, and every view that sees them shows their head inside a blob
    another person tops; in one view two such blobs (two neighbours' overlapping boxes) hold it.
    The model keeps such a person from the blobs' extents. Which of two blobs holds a body must not
    depend on the order in which the camera lists them: with the first listed as its host, the
    person was lost after 33 s in the log's order (MOTA 0.905) and after 47 s in reverse (0.950).
    Both orders: person 5 tracked in 95 % of their frames, MOTA >= 0.98."""
    import lcm

    from mvtrack_tools.paths import import_types
    rig, log = tmp_path / "rig.yaml", tmp_path / "scene.lcm"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2] / "tools"))
    subprocess.run([sys.executable, "-m", "mvtrack_tools.simulate", "crowd", "--seed", "1", "--rig-seed", "12",
                    "--cameras", "5", "--rig", str(rig), "--log", str(log), "--quiet"], check=True, env=env,
                   timeout=600)
    mt = import_types()
    rev = tmp_path / "reversed.lcm"
    src, dst = lcm.EventLog(str(log), "r"), lcm.EventLog(str(rev), "w", overwrite=True)
    for ev in src:
        data = ev.data
        if ev.channel.startswith("DETECTIONS_"):
            m = mt.camera_frame_t.decode(data)
            m.detections = list(reversed(m.detections))
            data = m.encode()
        dst.write_event(ev.timestamp, ev.channel, data)
    dst.close()
    for scene in (log, rev):
        out = tmp_path / f"tracks_{scene.stem}.lcm"
        r = subprocess.run([str(daemon_path), "--rig", str(rig), "--in", f"file://{scene}?speed=0", "--out",
                            f"file://{out}?mode=w"], capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        frames = pair_frames(read_log(str(log), lambda c: c == "GROUND_TRUTH"),
                             read_log(str(out), lambda c: c == "TRACKS"))
        _, runs = identity_switches(frames)
        seen = sum(b - a + 1 for h, a, b in runs[5] if h is not None)
        total = sum(b - a + 1 for h, a, b in runs[5])
        res = clear_mot(frames)
        assert seen >= 0.95 * total and res.mota >= 0.98, (scene.stem, seen, total, res)


@pytest.mark.daemon
def test_daemon_person_with_legs_the_colour_of_the_background_born_at_once(tmp_path, daemon_path):
    """The interaction scene on rendered masks' connected components, camouflage model, seed 3: one
    person's trousers match the background, so four cameras show the head from the first frame and
    every blob ends above the feet. A blob's bottom taken for the feet puts the head where no other
    view sees it; the birth must try the other views first too. Both people tracked from their
    first frames: at most 10 missed person-frames (5 frames each), MOTA >= 0.99, no switch."""
    rig, log, out = tmp_path / "rig.yaml", tmp_path / "scene.lcm", tmp_path / "tracks.lcm"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2] / "tools"))
    subprocess.run([sys.executable, "-m", "mvtrack_tools.simulate", "interaction", "--render", "--fragments",
                    "camouflage", "--seed", "3", "--rig", str(rig), "--log", str(log), "--quiet"], check=True, env=env,
                   timeout=600)
    r = subprocess.run([str(daemon_path), "--rig", str(rig), "--in", f"file://{log}?speed=0", "--out",
                        f"file://{out}?mode=w"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    res = clear_mot(pair_frames(read_log(str(log), lambda c: c == "GROUND_TRUTH"),
                                read_log(str(out), lambda c: c == "TRACKS")))
    assert res.misses <= 10 and res.mota >= 0.99 and res.id_switches == 0, res
