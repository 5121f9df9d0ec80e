"""Tests of the Python tools against independent references (OpenCV, FilterPy, numpy)."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from mvtrack_tools import motion
from mvtrack_tools.evaluate import learn_q, pcrlb_known, pcrlb_position_mse
from mvtrack_tools.paths import import_types
from mvtrack_tools.rig import Rig, random_rig, smartroom
from mvtrack_tools.scenes import AxisModel, Occlusions, WalkModel


def test_rig_write_read_round_trip_is_contract_yaml(tmp_path):
    rig = smartroom()
    p = tmp_path / "rig.yaml"
    rig.write(p)
    text = p.read_text()
    assert text.startswith("%YAML:1.0")
    for key in ("cameras:", "camera_matrix: !!opencv-matrix", "distortion_coefficients", "rvec", "tvec",
                "volume_min", "volume_max", "frame_rate", "image_width", "image_height"):
        assert key in text
    back = Rig.read(p)
    assert [c.name for c in back.cameras] == [c.name for c in rig.cameras]
    X = np.array([[2.0, 3.0, 1.7], [4.5, 1.0, 1.2]])
    for a, b in zip(rig.cameras, back.cameras):
        np.testing.assert_allclose(a.project(X), b.project(X), atol=1e-9)
    np.testing.assert_allclose(back.volume_max, rig.volume_max)
    assert back.occluders == []
    rig.occluders = [{"name": "shelf", "min": np.array([0.5, 0.5, 0.0]), "max": np.array([1.0, 1.5, 2.0])}]
    rig.write(p)
    back = Rig.read(p)
    assert [o["name"] for o in back.occluders] == ["shelf"]
    np.testing.assert_allclose(back.occluders[0]["max"], [1.0, 1.5, 2.0])


def test_camera_project_jacobian_matches_finite_differences():
    cam = smartroom().cameras[1]
    X = np.array([2.5, 2.2, 1.6])
    J = cam.project_jacobian(X)
    h = 1e-6
    for c in range(3):
        d = np.zeros(3)
        d[c] = h
        fd = (cam.project(X + d) - cam.project(X - d))[0] / (2 * h)
        np.testing.assert_allclose(J[:, c], fd, rtol=1e-5, atol=1e-3)


INTERFACE_FIELDS = {
    "detection_t": ["u", "v", "sigma_px", "bbox", "score", "hue", "saturation"],
    "camera_frame_t": ["utime", "frame", "camera", "width", "height", "num_detections", "detections", "mask_width",
                       "mask_height", "num_runs", "runs", "num_hs", "hue", "saturation"],
    "track_t": ["id", "status", "position", "velocity", "position_covariance", "cameras_used", "extent_min",
                "extent_max", "hue", "saturation"],
    "tracks_t": ["utime", "frame", "publish_utime", "num_tracks", "tracks"],
    "ground_truth_t": ["utime", "frame", "num_targets", "id", "position"],
}


@pytest.mark.parametrize("name", sorted(INTERFACE_FIELDS))
def test_lcm_types_fields_in_contract_order(name):
    mt = import_types()
    cls = getattr(mt, name)
    assert list(cls.__slots__) == INTERFACE_FIELDS[name]


def test_lcm_track_status_constants_match_contract():
    mt = import_types()
    assert (mt.track_t.TENTATIVE, mt.track_t.CONFIRMED, mt.track_t.COASTING) == (1, 2, 3)


def test_walk_model_discretisation_keeps_stationary_covariance():
    ax = AxisModel(0.6, 0.6, 0.3, 2.0)
    F, Q = ax.discrete(0.04)
    P = ax.stationary_cov()
    # the continuous stationary covariance is a fixed point of the exact discretisation
    np.testing.assert_allclose(F @ P @ F.T + Q, P, rtol=1e-9, atol=1e-12)


def test_learn_q_recovers_white_acceleration_density():
    rng = np.random.default_rng(0)
    q, dt, n = 0.7, 0.04, 20000
    F = np.array([[1, dt], [0, 1]])
    Q = q * np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]])
    L = np.linalg.cholesky(Q)
    s = np.zeros((n, 2))
    for k in range(1, n):
        s[k] = F @ s[k - 1] + L @ rng.standard_normal(2)
    pos = np.stack([s[:, 0], s[:, 0], s[:, 0]], axis=1)
    est = learn_q(pos, dt)
    assert abs(est[0] - q) / q < 0.05


def test_pcrlb_equals_filterpy_kalman_covariance_on_linearised_model():
    """For a linear-Gaussian model the PCRLB recursion is the Kalman covariance recursion."""
    rig = smartroom()
    model = WalkModel.for_room(rig.volume_min, rig.volume_max)
    rng = np.random.default_rng(3)
    states = model.sample(rng, 60, 0.04, rig.volume_min, rig.volume_max)
    pos = states[:, :3]
    var = 50.0
    bound = pcrlb_position_mse(rig, model, pos, var)
    F, Q, _ = model.transition(0.04)
    kf = KalmanFilter(dim_x=6, dim_z=2)
    kf.F, kf.Q, kf.P = F, Q, model.stationary_cov()
    for f in range(len(pos)):
        if f > 0:
            kf.predict()
        for cam in rig.cameras:
            uv = cam.project(pos[f])
            if cam.depth(pos[f])[0] > 0.2 and cam.in_image(uv)[0]:
                H = np.zeros((2, 6))
                H[:, :3] = cam.project_jacobian(pos[f])
                kf.update(uv[0], R=var * np.eye(2), H=H)
        assert np.trace(kf.P[:3, :3]) == pytest.approx(bound[f], rel=1e-6)


def test_mixed_motion_bound_equals_filterpy_with_the_schedule():
    """The mixed-motion scene is linear-Gaussian given its schedule: the schedule-conditioned
    PCRLB (evaluate.pcrlb_known) is FilterPy's Kalman covariance with each frame's own F and Q.
    The paths have standing, walking, turning and stopping over 60 s, stay in the room and below
    2 m/s, and some sit down (the head goes below 1.45 m) and stand up."""
    rig = smartroom()
    dt = 0.04
    for seed in (1, 2, 3):
        states, Fs, Qs, kinds, P0 = motion.sample_mixed(np.random.default_rng(seed), 1500, dt, rig.volume_min,
                                                        rig.volume_max)
        assert {"stand", "walk", "turn", "stop"} <= set(kinds)
        assert np.all(states[:, :2] >= rig.volume_min[:2] + 0.4) and np.all(states[:, :2] <= rig.volume_max[:2] - 0.4)
        assert np.all(np.hypot(states[:, 3], states[:, 4]) < 2.0)
    sat = 0
    for seed in range(4, 12):
        states, Fs, Qs, kinds, P0 = motion.sample_mixed(np.random.default_rng(seed), 1500, dt, rig.volume_min,
                                                        rig.volume_max)
        assert np.all((states[:, 2] > 0.9) & (states[:, 2] < 2.1))  # a head's height, seated or standing
        sat += "sit" in kinds and states[:, 2].min() < 1.45 and states[:, 2].max() > 1.6
    assert sat >= 2  # some sat down (a sit cut by the end of the scene may not reach the seat)
    pos = states[:200, :3]
    seen = np.ones((len(pos), len(rig.cameras)), dtype=bool)
    for k, cam in enumerate(rig.cameras):
        seen[:, k] = (cam.depth(pos) > 0.2) & cam.in_image(cam.project(pos))
    bound = pcrlb_known(rig, pos, Fs, Qs, P0, 50.0, seen)
    kf = KalmanFilter(dim_x=6, dim_z=2)
    kf.P = P0.copy()
    for f in range(len(pos)):
        if f > 0:
            kf.predict(F=Fs[f], Q=Qs[f])
        for k, cam in enumerate(rig.cameras):
            if seen[f, k]:
                H = np.zeros((2, 6))
                H[:, :3] = cam.project_jacobian(pos[f])
                kf.update(cam.project(pos[f])[0], R=50.0 * np.eye(2), H=H)
        assert np.trace(kf.P[:3, :3]) == pytest.approx(bound[f], rel=1e-6)


def test_motion_tool_imm_steadier_than_single_model(tmp_path, daemon_path):
    """tools/mvtrack motion end to end on one room: the table and results are written, every
    ratio to the bound is >= 0.9 (nothing beats the bound by more than sampling noise), and a
    person standing still jitters less than half as much with the IMM as with the single model."""
    from mvtrack_tools import motion_eval
    out = tmp_path / "m"
    assert motion_eval.main(["--rooms", "1", "--seeds", "1", "--levels", "100", "--seconds", "12", "--kinds",
                             "mixed", "--no-occlusion", "--variants", "imm", "cv", "--out", str(out), "--quiet"]) == 0
    res = json.loads((out / "results.json").read_text())
    assert (out / "table.md").exists()
    assert {r["variant"] for r in res["rows"]} == {"imm", "cv"}
    assert all(r["ratio"] >= 0.9 for r in res["rows"])
    jit = {s["variant"]: s["jitter_mm"] for s in res["stand"]}
    assert jit["imm"] < 0.5 * jit["cv"], jit


def test_occlusions_cover_requested_fraction_in_bursts():
    occ, off = Occlusions().masks(np.random.default_rng(5), 200000, 2)
    assert abs(occ.mean() - 0.3) < 0.02
    starts = np.flatnonzero(np.diff(occ[:, 0].astype(int)) == 1)
    assert len(starts) > 100
    amp = np.linalg.norm(off[occ], axis=1)
    assert amp.min() >= 40 and amp.max() <= 150


def test_random_rig_sees_room_centre_from_every_camera():
    rng = np.random.default_rng(9)
    for n in (4, 6, 8):
        rig = random_rig(rng, n)
        centre = (rig.volume_min + rig.volume_max) / 2
        centre[2] = 1.7
        for cam in rig.cameras:
            assert cam.in_image(cam.project(centre))[0]


def test_camera_field_ends_at_the_distortion_fold():
    """k1 < 0: r (1 + k1 r^2) peaks at r_f = 1 / sqrt(-3 k1). cv2.projectPoints folds a point at
    r = 1.5 back into the picture; Camera.project gives NaN there (the core refuses it too:
    tests/test_camera.c)."""
    from mvtrack_tools.rig import intrinsics, look_at
    cam = look_at("fold", [0, 0, 2], [3, 0, 2], intrinsics(400, 400, 400, 300), [-0.3, 0, 0, 0, 0], 800, 600)
    rf = 1 / np.sqrt(0.9)
    assert (rf - 1 / 256) ** 2 <= cam.field_r2 <= (rf + 1 / 256) ** 2
    inside, folded = np.array([3.0, -0.9 * 3, 2.0]), np.array([3.0, -1.5 * 3, 2.0])
    assert np.all(np.isfinite(cam.project(inside)))
    assert np.all(np.isnan(cam.project(folded)))
    raw, _ = cv2.projectPoints(folded.reshape(1, 1, 3), cam.rvec, cam.tvec, cam.K, cam.dist)
    assert cam.in_image(raw.reshape(1, 2))[0]  # where the polynomial alone would put it
    assert np.isinf(look_at("pin", [0, 0, 2], [3, 0, 2], intrinsics(400, 400, 400, 300), [0] * 5).field_r2)


def test_random_rig_lenses_do_not_fold_inside_the_picture():
    """Every random camera's model still rises beyond its image corners (a calibration's validity):
    undistorting a corner and projecting it back lands on the corner."""
    for seed in range(1, 30):
        for cam in random_rig(np.random.default_rng(seed), 5).cameras:
            corners = np.array([[0, 0], [cam.width - 1, 0], [0, cam.height - 1], [cam.width - 1, cam.height - 1]],
                               np.float64)
            xn = cv2.undistortPointsIter(corners.reshape(-1, 1, 2), cam.K, cam.dist, None, None,
                                         (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12))
            xn = xn.reshape(-1, 2)
            assert np.all(np.sum(xn ** 2, axis=1) < cam.field_r2)
            X = cam.centre + (np.c_[xn, np.ones(4)] @ cam.R) * 2.0
            np.testing.assert_allclose(cam.project(X), corners, atol=0.05)


def test_covered_only_makes_people_seen_by_one_camera_dont_care():
    """A person in fewer than two cameras' pictures and any track within 0.5 m of them leave the
    scoring; everything else is scored as before."""
    from mvtrack_tools.mot import FrameSet, clear_mot, covered_only, views_per_person
    rig = smartroom()
    inside = np.array([3.0, 2.5, 1.7])            # room centre: every camera
    outside = np.array([3.0, 2.5, 8.0])           # above the cameras: none sees it
    frames = [FrameSet(i, [1, 2], np.array([inside, outside]), [7, 8, 9],
                       np.array([inside + 0.05, outside + 0.1, [1.0, 1.0, 1.7]]), True) for i in range(10)]
    views = views_per_person(rig, frames)
    assert views[0][0] == len(rig.cameras) and views[0][1] == 0
    cov = covered_only(frames, views)
    assert cov[0].gt_ids == [1] and cov[0].hyp_ids == [7, 9]
    full, part = clear_mot(frames), clear_mot(cov)
    assert full.false_positives == 10 and full.misses == 0  # the track near the unseen person matches it
    assert part.misses == 0 and part.false_positives == 10  # the stray track at (1, 1) is still false


def test_learn_q_command_pools_people_and_skips_gaps(tmp_path, capsys):
    """tools/mvtrack learn-q on a log: two people walking with white acceleration q = (0.7, 0.3,
    0.05), each with a gap in their truth (second differences across it are not taken): the
    printed --q is within 6 % per axis; a log without truth is refused with exit 2."""
    from mvtrack_tools.lcmio import LogWriter, ground_truth
    from mvtrack_tools.learnq import main as learnq_main
    rng = np.random.default_rng(4)
    q, dt, n = np.array([0.7, 0.3, 0.05]), 0.04, 6000
    F = np.array([[1, dt], [0, 1]])
    tracks = []
    for person in range(2):
        s = np.zeros((n, 3, 2))
        for ax in range(3):
            L = np.linalg.cholesky(q[ax] * np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]]))
            for k in range(1, n):
                s[k, ax] = F @ s[k - 1, ax] + L @ rng.standard_normal(2)
        tracks.append(s[:, :, 0] + [2.0 * person, 1.0, 1.7])
    log = tmp_path / "truth.lcm"
    w = LogWriter(str(log))
    for f in range(n):
        present = [p for p in range(2) if not (1000 + 500 * p <= f < 1100 + 500 * p)]  # gaps
        u = 1_700_000_000_000_000 + f * 40000
        w.write(u, "GROUND_TRUTH", ground_truth(u, f, [p + 1 for p in present], np.array([tracks[p][f] for p in present])))
    w.close()
    assert learnq_main([str(log)]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    est = np.array([float(v) for v in line.split("--q ")[1].split(",")])
    np.testing.assert_allclose(est, q, rtol=0.06)
    empty = tmp_path / "empty.lcm"
    LogWriter(str(empty)).close()
    assert learnq_main([str(empty)]) == 2


def test_oracles_reach_the_bound_they_should():
    """motion --oracles: the EKF told the mixed scene's schedule sits on the schedule-conditioned
    PCRLB (it is the bound's own filter, run on noisy detections), the IMM of the generator's
    segment models that is not told the schedule is above it, and on Experiment 1's walk the EKF
    of the walk's own model is at the bound, the same walk without its pull to the room's centre
    above it."""
    from mvtrack_tools import oracle
    from mvtrack_tools.motion_eval import draw
    from mvtrack_tools.scenes import head_detections
    rig = smartroom()
    var = 100.0
    ratios = {}
    for kind in ("mixed", "exp1"):
        states, Fs, Qs, P0, rng, bs = draw(kind, rig, 30.0, 2)
        dets = head_detections(rig, states[:, :3], var, rng, None)
        seen = np.array([[bool(dets[f][k]) for k in range(len(rig.cameras))] for f in range(len(states))])
        bound = pcrlb_known(rig, states[:, :3], Fs, Qs, P0, var, seen)
        refs = (oracle.mixed_references(rig, dets, var, states, Fs, Qs, bs, P0) if kind == "mixed" else
                oracle.exp1_references(rig, dets, var, states, learn_q(states[:, :3], 0.04)))
        for name, est in refs.items():
            e2 = np.sum((est - states[:, :3]) ** 2, axis=1)
            ratios[name] = float(np.sqrt(e2[5:].mean() / bound[5:].mean()))
    assert 0.85 < ratios["kf-schedule"] < 1.1, ratios
    assert 0.85 < ratios["ekf-true"] < 1.1, ratios
    assert ratios["ekf-true"] < ratios["ekf-no-centre"] < 1.2, ratios  # the centre is information
    assert ratios["imm-generator"] > ratios["kf-schedule"], ratios
    assert ratios["imm-generator"] < 1.5, ratios


def _residual_logs(tmp_path, offset_cam4=(0.0, -25.0), with_tracks=True):
    """A person walking through the smart room for 4 s: cameras 0-3 detect the projected head with
    1.5 px noise, camera 4 with a fixed offset; GROUND_TRUTH and (optionally) a confirmed track on
    the person in a TRACKS message 10 ms late (its position then: carried back by its velocity)."""
    from mvtrack_tools.lcmio import LogWriter, camera_frame, ground_truth, mt

    rig = smartroom()
    rig.write(tmp_path / "rig.yaml")
    rng = np.random.default_rng(4)
    w = LogWriter(str(tmp_path / "log.lcm"))
    t0 = 1_700_000_000_000_000
    for f in range(100):
        u = t0 + f * 40000
        X = np.array([[1.5 + 0.03 * f, 2.5, 1.7]])
        for k, cam in enumerate(rig.cameras):
            uv = cam.project(X)[0] + (np.asarray(offset_cam4) if k == 4 else rng.normal(0, 1.5, 2))
            w.write(u, f"DETECTIONS_{cam.name}", camera_frame(u, f, cam, [(uv[0], uv[1])], 2.0))
        w.write(u, "GROUND_TRUTH", ground_truth(u, f, [1], X))
        if with_tracks:
            m = mt.tracks_t()
            m.utime, m.frame = u + 10000, f
            t = mt.track_t()
            t.id, t.status = 7, 2
            t.position, t.velocity = [1.5 + 0.03 * f + 0.0075, 2.5, 1.7], [0.75, 0.0, 0.0]
            m.tracks, m.num_tracks = [t], 1
            w.write(u, "TRACKS", m)
    w.close()
    return rig, tmp_path / "log.lcm"


def test_residuals_flag_a_camera_whose_points_are_not_heads(tmp_path, capsys):
    from mvtrack_tools import residuals
    from mvtrack_tools.lcmio import read_log

    rig, log = _residual_logs(tmp_path)
    for truth in (True, False):
        res, arrays = residuals.residuals(rig, str(log), read_log(str(log)), truth)
        by = {c.camera: c for c in res}
        assert by["cam4"].paired == by["cam4"].heads == 100 and by["cam4"].flagged
        assert by["cam4"].median_px == pytest.approx(25.0, abs=0.01)
        assert by["cam4"].mean_dv_px == pytest.approx(-25.0, abs=0.01) and abs(by["cam4"].mean_du_px) < 0.01
        for k in range(4):
            c = by[f"cam{k}"]
            assert not c.flagged and c.paired == c.heads > 90
            assert 1.0 < c.median_px < 2.5 and c.beyond_10px == 0.0  # 1.5 px noise: median 1.77 px
    # a camera within the noise of the others is not flagged
    rig, log = _residual_logs(tmp_path, offset_cam4=(1.0, -1.0))
    res, _ = residuals.residuals(rig, str(log), read_log(str(log)), True)
    assert not any(c.flagged for c in res)
    # the command: table, plot, and clear errors for bad input
    assert residuals.main(["--rig", str(tmp_path / "rig.yaml"), "--detections", str(log), "--truth",
                           "--plot", str(tmp_path / "r.png")]) == 0
    assert (tmp_path / "r.png").stat().st_size > 1000
    assert "cam4" in capsys.readouterr().out
    rig, log = _residual_logs(tmp_path, with_tracks=False)
    for args, msg in ((["--detections", str(log)], "holds no TRACKS"),
                      (["--detections", str(log), "--truth", "--radius", "0"], "--radius must be > 0"),
                      (["--detections", str(tmp_path / "missing.lcm"), "--truth"], "cannot read")):
        with pytest.raises(SystemExit) as e:
            residuals.main(["--rig", str(tmp_path / "rig.yaml")] + args)
        assert e.value.code == 2
        assert msg in capsys.readouterr().err


def test_report_quick_fails_below_a_floor(tmp_path, daemon_path, monkeypatch, capsys):
    """`tools/mvtrack report --quick` exits 1 and names the figure when one is below its floor (here
    a floor no tracker can meet: MOTA above 1), writing its tables all the same."""
    import json
    from mvtrack_tools import report
    monkeypatch.setitem(report.FLOORS, "mot.mota_min", 1.01)
    rc = report.main(["--quick", "--only", "mot", "--out", str(tmp_path), "--quiet"])
    out = capsys.readouterr().out
    assert rc == 1, out
    assert "BELOW FLOOR: mot:" in out and "report: FAIL" in out
    fig = json.loads((tmp_path / "figures.json").read_text())
    assert fig["below"] and fig["figures"]["mot"]["mota_min"] > 0.9, fig
    assert "| crowd | 1 |" in (tmp_path / "results.md").read_text()
