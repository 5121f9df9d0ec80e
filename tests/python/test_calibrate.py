"""tools/mvtrack calibrate on boards rendered through known cameras (mvtrack_tools.board_render):
the recovered cameras against the ones that rendered them, the checks that catch a bad rig, and the
error paths (exit 2, one line, the rig file unchanged)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from mvtrack_tools.board_render import pose_in_front, render
from mvtrack_tools.calibrate import Board, find_boards
from mvtrack_tools.rig import Rig, intrinsics, look_at, normalise, smartroom

REPO = Path(__file__).resolve().parents[2]

# focal length (px), distortion k1 k2 p1 p2 k3, camera height (m) and where it looks. Every lens's
# radial map still rises at the picture's corners, as a real lens's does (rig.lens_reach; the
# simulator's random lenses are drawn so too).
CAMERAS = [
    (420.0, (-0.28, 0.09, 0.0006, -0.0004, 0.0), 2.2, (2.0, 2.0, 0.0)),
    (560.0, (-0.18, 0.03, -0.0003, 0.0005, 0.0), 2.6, (2.5, 1.5, 0.0)),
    (700.0, (-0.08, 0.0, 0.0, 0.0, 0.0), 3.0, (1.5, 2.5, 0.0)),
    (900.0, (0.04, -0.02, 0.0002, 0.0002, 0.0), 3.5, (2.0, 3.0, 0.0)),
    (1200.0, (0.0, 0.0, 0.0, 0.0, 0.0), 2.8, (3.0, 2.0, 0.0)),
]
POSITIONS = [(0.2, 0.3), (4.0, 0.4), (0.3, 4.2), (4.3, 4.0), (2.2, -0.5)]
# camera 0's lens with a k3 that bends its radial map flat at the picture's corners (it turns back
# at 99.7 % of the way there, squeezing the squares about seven-fold before, where no board is
# found): the hardest lens the tool must not be thrown by
FOLDING_LENS = (-0.28, 0.09, 0.0006, -0.0004, -0.012)


def camera(i: int, dist=None):
    f, lens, h, tgt = CAMERAS[i]
    dist = lens if dist is None else dist
    K = intrinsics(f, f, 383.5 + 3 * i, 287.5 - 2 * i)
    x, y = POSITIONS[i]
    return look_at(f"cam{i}", [x, y, h], list(tgt), K, dist)


def run(*args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(REPO / "tools"))
    return subprocess.run([sys.executable, "-m", "mvtrack_tools.calibrate", *args], capture_output=True, text=True,
                          env=env)


def picture_error(true_cam, K: np.ndarray, dist: np.ndarray, hull: np.ndarray | None = None) -> float:
    """Largest pixel distance over the picture between the true lens and the recovered one: the rays
    of a 48 x 36 grid of the true camera's pixels (those inside hull, the views' corners, when given:
    a lens model says nothing where no view showed it), projected by the recovered lens turned by the
    small rotation that fits them best (a principal point error trades against the camera's pose,
    which the extrinsics then absorb). Pixels beyond the true lens's field (its polynomial folds
    before the picture's corner) are left out."""
    w, h = true_cam.width, true_cam.height
    uu, vv = np.meshgrid(np.linspace(2, w - 3, 48), np.linspace(2, h - 3, 36))
    pix = np.stack([uu.ravel(), vv.ravel()], axis=1)
    if hull is not None:
        hh = cv2.convexHull(hull.astype(np.float32))
        pix = pix[[cv2.pointPolygonTest(hh, (float(x), float(y)), False) >= 0 for x, y in pix]]
    xn, _ = normalise(true_cam.K, true_cam.dist, pix)
    # a pixel beyond the fold of the true lens's polynomial has no ray (no real lens shows it)
    back, _ = cv2.projectPoints(np.hstack([xn, np.ones((len(xn), 1))]), np.zeros(3), np.zeros(3),
                                np.asarray(true_cam.K, float), np.asarray(true_cam.dist, float))
    has_ray = np.linalg.norm(back.reshape(-1, 2) - pix, axis=1) < 1e-3
    pix, xn = pix[has_ray], xn[has_ray]
    X = np.hstack([xn, np.ones((len(xn), 1))]).astype(np.float64)
    from scipy.optimize import least_squares

    def res(r):
        p, _ = cv2.projectPoints(X, r, np.zeros(3), K, dist)
        return (p.reshape(-1, 2) - pix.reshape(-1, 2)).ravel()

    r = least_squares(res, np.zeros(3)).x
    return float(np.max(np.linalg.norm(res(r).reshape(-1, 2), axis=1)))


def corners_of(board: Board, folder: Path) -> np.ndarray:
    frames = [cv2.imread(str(f), cv2.IMREAD_GRAYSCALE) for f in sorted(folder.glob("*.png"))]
    return np.vstack([d[0] for d in find_boards(board, frames) if d is not None])


def board_views(cam, board: Board, size_m, out: Path, rng) -> None:
    """32 views: the board a third of the picture wide in every part of it up to the corners (where
    the lens bends most), and half the picture wide tilted every way, up to 45 degrees (a tilt
    separates the focal length from the board's distance)."""
    small = size_m[0] * float(cam.K[0, 0]) / (0.28 * cam.width)
    big = size_m[0] * float(cam.K[0, 0]) / (0.55 * cam.width)
    poses = [(small, (x, y), (10 * np.sign(-y), 10 * np.sign(x), 0)) for x in (-0.72, 0.0, 0.72) for y in (-0.66, 0.0, 0.66)]
    poses += [(small, (x, y), (0, 0, 0)) for x, y in ((-0.4, -0.66), (0.4, 0.66), (-0.72, 0.35), (0.72, -0.35))]
    poses += [(big, (0, 0), (0, 0, 0)), (big, (-0.3, -0.3), (25, -20, 5)), (big, (0.3, -0.3), (-25, -20, -5)),
              (big, (-0.3, 0.3), (25, 20, 0)), (big, (0.3, 0.3), (-25, 20, 10)), (big, (0, -0.3), (35, 0, 0)),
              (big, (0, 0.3), (-35, 0, 0)), (big, (-0.3, 0), (0, 35, 0)), (big, (0.3, 0), (0, -35, 0)),
              (big, (0, 0), (20, 20, 45)), (small, (0.62, -0.58), (0, 0, 30))]
    poses += [(big, (0, 0), t) for t in ((45, 0, 0), (-45, 0, 0), (0, 45, 0), (0, -45, 0), (35, 35, 20),
                                         (-35, 35, -20), (35, -35, 10), (-35, -35, -10))]
    for i, (dist, off, tilt) in enumerate(poses):
        R_b, t_b = pose_in_front(cam, size_m, dist * (0.95 + 0.1 * rng.random()), off, tilt)
        cv2.imwrite(str(out / f"view{i:02d}.png"), render(cam, board, R_b, t_b, rng))


SEEDS = [int(v) for v in os.environ.get("MVTRACK_CALIB_SEEDS", "5").split(",")]


@pytest.mark.parametrize("seed", SEEDS)
def test_intrinsics_five_cameras_recovered(tmp_path, seed):
    """Focal length within 0.5 %, principal point within 2 px, the lens within 0.3 px of the true one
    where the boards were and over the whole picture; and the uncertainty intrinsics reports is
    honest: the true error stays within four of its standard deviations where the boards were and
    over the whole picture.
    MVTRACK_CALIB_SEEDS=5,1,2,3 runs more sensor-noise seeds."""
    rng = np.random.default_rng(seed)
    board = Board("chessboard:9x6:0.05")
    rows = []
    for i in range(len(CAMERAS)):
        cam = camera(i)
        d = tmp_path / f"c{i}"
        d.mkdir()
        board_views(cam, board, (0.5, 0.35), d, rng)
        rig = tmp_path / "rig.yaml"
        r = run("intrinsics", "--rig", str(rig), "--camera", cam.name, "--images", str(d / "*.png"),
                "--board", "chessboard:9x6:0.05")
        assert r.returncode == 0, r.stderr
        out = json.loads(r.stdout.strip().splitlines()[-1])
        K = np.array(out["camera_matrix"])
        dist = np.array(out["distortion"])
        f_err = abs(K[0, 0] / cam.K[0, 0] - 1)
        pp_err = float(np.hypot(K[0, 2] - cam.K[0, 2], K[1, 2] - cam.K[1, 2]))
        hull = corners_of(board, d)
        pic = picture_error(cam, K, dist, hull)
        whole = picture_error(cam, K, dist)
        sig = out["lens_sigma_px"]
        share = float(cv2.contourArea(cv2.convexHull(hull.astype(np.float32)))) / (cam.width * cam.height)
        rows.append((cam.name, out["rms_px"], f_err, pp_err, pic, sig["covered"], share, whole, sig["picture"]))
        assert out["lens_reach"] is None or out["lens_reach"] > 1.0, out["lens_reach"]
        assert "turns back" not in r.stderr
        written = Rig.read(rig)
        assert any(c.name == cam.name for c in written.cameras)
    print(f"\nintrinsics, seed {seed} (camera, RMS px, focal error, principal point error px, largest error over "
          "the views' hull px, its reported sigma, the hull's share of the picture, largest error over the "
          "whole picture px, its reported sigma):")
    for row in rows:
        print("  %s  %.3f  %.4f  %.2f  %.3f  %.3f  %.2f  %.3f  %.3f" % row)
    for name, rms, f_err, pp_err, pic, sig_c, share, whole, sig_p in rows:
        assert f_err < 0.005, (name, f_err)
        assert pp_err < 2.0, (name, pp_err)
        assert pic < 0.3 and whole < 0.3, (name, pic, whole)
        assert pic < 4 * sig_c and whole < 4 * sig_p, (name, pic, sig_c, whole, sig_p)
    assert len(Rig.read(tmp_path / "rig.yaml").cameras) == len(CAMERAS)


def test_intrinsics_boards_into_a_strong_lens_corners(tmp_path):
    """Boards waved into the corners of the strongest barrel lens, where its squares are squeezed
    most, widen the part of the picture the lens is known over and do not throw the fit into a
    wrong lens (the first guess has no distortion): within 0.3 px over the boards' hull."""
    rng = np.random.default_rng(7)
    cam = camera(0, FOLDING_LENS)
    board = Board("chessboard:9x6:0.05")
    board_views(cam, board, (0.5, 0.35), tmp_path, rng)
    near = 0.5 * float(cam.K[0, 0]) / (0.22 * cam.width)
    for x in (-1, 1):
        for y in (-1, 1):
            for k, (ox, oy) in enumerate(((0.86, 0.86), (0.86, 0.69), (0.69, 0.86))):
                R_b, t_b = pose_in_front(cam, (0.5, 0.35), near, (ox * x, oy * y), (12 * y, -12 * x, 0))
                cv2.imwrite(str(tmp_path / f"corner{x + 1}{y + 1}{k}.png"), render(cam, board, R_b, t_b, rng))
    rig = tmp_path / "rig.yaml"
    r = run("intrinsics", "--rig", str(rig), "--camera", cam.name, "--images", str(tmp_path / "*.png"), "--board",
            "chessboard:9x6:0.05", "--max-views", "60")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    hull = corners_of(board, tmp_path)
    share = float(cv2.contourArea(cv2.convexHull(hull.astype(np.float32)))) / (cam.width * cam.height)
    pic = picture_error(cam, np.array(out["camera_matrix"]), np.array(out["distortion"]), hull)
    print(f"\nboards into the corners: {out['views']} views, RMS {out['rms_px']:.3f} px, hull {100 * share:.0f} % of "
          f"the picture, largest error there {pic:.3f} px; the fitted lens turns back at {out['lens_reach']} of the "
          "way to the corners")
    assert share > 0.8
    assert pic < 0.3


def test_intrinsics_charuco_rational_wide_lens(tmp_path):
    rng = np.random.default_rng(9)
    K = intrinsics(380.0, 380.0, 380.0, 290.0)
    cam = look_at("wide", [0, 0, 2], [1, 1, 0], K, (0.3, -0.05, 0.0, 0.0, 0.0, 0.6, -0.1, 0.0))
    board = Board("charuco:10x7:0.05:0.037")
    board_views(cam, board, (0.5, 0.35), tmp_path, rng)
    rig = tmp_path / "rig.yaml"
    png = tmp_path / "lens.png"
    r = run("intrinsics", "--rig", str(rig), "--camera", "wide", "--images", str(tmp_path / "*.png"), "--board",
            "charuco:10x7:0.05:0.037", "--rational", "--plot", str(png))
    assert r.returncode == 0, r.stderr
    assert "the lens is known to" in r.stderr
    assert cv2.imread(str(png)) is not None
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert len(out["distortion"]) == 8
    K2 = np.array(out["camera_matrix"])
    pic = picture_error(cam, K2, np.array(out["distortion"]), corners_of(board, tmp_path))
    print(f"\ncharuco, rational: RMS {out['rms_px']:.3f} px, focal error {abs(K2[0, 0] / 380 - 1):.4f}, picture {pic:.3f} px")
    assert abs(K2[0, 0] / 380.0 - 1) < 0.005
    assert pic < 0.3


def write_true_rig(path: Path, cams) -> None:
    """A rig with the cameras' true intrinsics and no pose yet (as intrinsics leaves it)."""
    out = []
    for c in cams:
        c2 = look_at(c.name, [0, 0, 1], [0, 1, 1], c.K, c.dist)
        c2.rvec, c2.tvec = np.zeros(3), np.zeros(3)
        out.append(c2)
    Rig(out, np.array([0.0, 0.0, 0.0]), np.array([5.0, 5.0, 2.5]), 25.0).write(path)


def pose_errors(rig_path: Path, cam) -> tuple[float, float]:
    c = next(x for x in Rig.read(rig_path).cameras if x.name == cam.name)
    dpos = float(np.linalg.norm(c.centre - cam.centre))
    dR = cv2.Rodrigues(c.R @ cam.R.T)[0]
    return dpos, float(np.degrees(np.linalg.norm(dR)))


def test_extrinsics_from_floor_board_and_from_points(tmp_path):
    rng = np.random.default_rng(3)
    board = Board("charuco:7x5:0.25:0.19")
    cams = [camera(i) for i in range(len(CAMERAS))]
    rig = tmp_path / "rig.yaml"
    write_true_rig(rig, cams)
    first = Rig.read(rig)  # the room's furniture, declared before calibrating, stays
    first.occluders = [{"name": "shelf", "min": [0.5, 0.5, 0.0], "max": [1.0, 1.5, 2.0]}]
    first.write(rig)
    rows = []
    for i, cam in enumerate(cams):
        # each camera looks at the board, which lies on the floor and is the world frame (board
        # point p is world point p)
        a = np.radians(72 * i + 20)
        centre = np.array([0.75, -0.5, 0.0])  # the board's middle
        reach = 1.2 + 0.002 * float(cam.K[0, 0])  # a longer lens stands farther back
        cam = look_at(cam.name, [centre[0] + reach * np.cos(a), centre[1] + reach * np.sin(a), CAMERAS[i][2]],
                      list(centre), cam.K, cam.dist)
        img = render(cam, board, np.diag([1.0, -1.0, -1.0]), np.zeros(3), rng)
        png = tmp_path / f"{cam.name}_floor.png"
        cv2.imwrite(str(png), img)
        r = run("extrinsics", "--rig", str(rig), "--camera", cam.name, "--image", str(png), "--board",
                "charuco:7x5:0.25:0.19")
        assert r.returncode == 0, r.stderr
        dpos_b, dang_b = pose_errors(rig, cam)
        # world points: a 3 x 3 grid on the floor and four 1.5 m up, 0.3 px of detection noise
        pts = [(x, y, 0.0) for x in (-0.5, 0.6, 1.7) for y in (-1.4, -0.45, 0.5)] + \
              [(0.0, 0.0, 1.0), (1.2, 0.0, 1.0), (0.0, -1.2, 1.0), (1.2, -1.2, 1.0)]
        X = np.array(pts)
        uv = cam.project(X) + rng.normal(0, 0.3, (len(X), 2))
        ok = cam.in_image(uv) & (cam.depth(X) > 0)
        csv = tmp_path / f"{cam.name}.csv"
        csv.write_text("u,v,x,y,z\n" + "".join(f"{u},{v},{x},{y},{z}\n" for (u, v), (x, y, z) in zip(uv[ok], X[ok])))
        r = run("extrinsics", "--rig", str(rig), "--camera", cam.name, "--points", str(csv))
        assert r.returncode == 0, r.stderr
        dpos_p, dang_p = pose_errors(rig, cam)
        rows.append((cam.name, dpos_b, dang_b, dpos_p, dang_p, int(ok.sum())))
    print("\nextrinsics (camera, board: position error m, angle deg; points: m, deg, points):")
    for row in rows:
        print("  %s  %.4f %.3f  %.4f %.3f  %d" % row)
    for name, dpb, dab, dpp, dap, _ in rows:
        assert dpb < 0.02 and dab < 0.3, name
        assert dpp < 0.02 and dap < 0.3, name
    assert [o["name"] for o in Rig.read(rig).occluders] == ["shelf"]


def test_extrinsics_creates_a_camera_nobody_calibrated(tmp_path):
    """--size with --points and --fit-focal: a camera not in the rig (no rig file at all) is created
    with the principal point at the picture's centre, no distortion and the focal length fitted.
    Camera 4 (1200 px, no distortion, its principal point 12 px / 8 px off the centre), 17 points,
    0.3 px noise: focal within 2 %, position within 5 cm, direction within 1 degree (the principal
    point taken at the centre, 12 px off, is 0.6 degrees of it; measured 1205 px, 1.8 cm, 0.72 degrees). Without
    --fit-focal, or for a camera already in the rig, exit 2 and the rig file as it was."""
    rng = np.random.default_rng(5)
    cam = camera(4)
    pts = [(x, y, 0.0) for x in (2.5, 3.0, 3.5) for y in (1.4, 2.0, 2.6)] + \
          [(2.6, 1.6, 1.0), (3.4, 1.6, 1.0), (2.6, 2.4, 0.6), (3.4, 2.4, 0.6), (3.0, 2.0, 1.2)]
    X = np.array(pts)
    uv = cam.project(X) + rng.normal(0, 0.3, (len(X), 2))
    ok = cam.in_image(uv) & (cam.depth(X) > 0)
    assert ok.sum() >= 10
    csv = tmp_path / "cam4.csv"
    csv.write_text("u,v,x,y,z\n" + "".join(f"{u},{v},{x},{y},{z}\n" for (u, v), (x, y, z) in zip(uv[ok], X[ok])))
    rig = tmp_path / "rig.yaml"
    r = run("extrinsics", "--rig", str(rig), "--camera", "cam4", "--points", str(csv), "--size", "768x576")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and not rig.exists(), r.stderr
    r = run("extrinsics", "--rig", str(rig), "--camera", "cam4", "--points", str(csv), "--fit-focal")
    assert r.returncode == 2 and "--size" in r.stderr and not rig.exists(), r.stderr
    r = run("extrinsics", "--rig", str(rig), "--camera", "cam4", "--points", str(csv), "--fit-focal",
            "--size", "768x576")
    assert r.returncode == 0, r.stderr
    got = Rig.read(rig).cameras[0]
    dpos, dang = pose_errors(rig, cam)
    print(f"\nnew camera: focal {got.K[0, 0]:.1f} px (true {cam.K[0, 0]:.0f}), position {dpos:.3f} m, "
          f"angle {dang:.2f} deg")
    assert got.width == 768 and got.height == 576 and abs(got.K[0, 2] - 383.5) < 1e-6
    assert abs(got.K[0, 0] / cam.K[0, 0] - 1.0) < 0.02 and dpos < 0.05 and dang < 1.0
    before = rig.read_bytes()
    r = run("extrinsics", "--rig", str(rig), "--camera", "cam4", "--points", str(csv), "--fit-focal",
            "--size", "768x576")
    assert r.returncode == 2 and "already" in r.stderr and rig.read_bytes() == before, r.stderr
    r = run("check", "--rig", str(rig))
    assert r.returncode == 0 and "PROBLEM the volume is calibrate's placeholder" in r.stderr, r.stderr
    assert any("placeholder" in p for p in json.loads(r.stdout.strip().splitlines()[-1])["problems"])


def test_check_flags_under_floor_mirrored_and_alone(tmp_path):
    room = smartroom()
    rig = tmp_path / "rig.yaml"
    room.write(rig)
    r = run("check", "--rig", str(rig), "--plot", str(tmp_path / "check.png"))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["problems"] == [] and out["floor_seen_by_2"] > 0.8
    assert all(1.5 < c["height_m"] < 4 for c in out["cameras"])
    assert (tmp_path / "check.png").stat().st_size > 10000
    K = room.cameras[0].K
    under = look_at("under", [2.0, 2.0, -0.5], [2.5, 2.5, -1.0], K, (0, 0, 0, 0, 0))
    up = look_at("up", [1.0, 1.0, 2.5], [1.5, 1.5, 4.0], K, (0, 0, 0, 0, 0))
    alone = look_at("alone", [-3.0, -3.0, 2.5], [-6.0, -6.0, 0.0], K, (0, 0, 0, 0, 0))
    for bad, words in ((under, "under the floor"), (up, "looks away from the floor"), (alone, "no other camera overlaps")):
        rig2 = tmp_path / f"{bad.name}.yaml"
        Rig(room.cameras + [bad], room.volume_min, room.volume_max, room.frame_rate).write(rig2)
        r = run("check", "--rig", str(rig2))
        assert r.returncode == 0, r.stderr
        problems = json.loads(r.stdout.strip().splitlines()[-1])["problems"]
        assert any(p.startswith(bad.name) and words in p for p in problems), problems
    # a lens whose model turns back inside its picture is noted (the smart room's overhead camera's
    # turns back at 84 % of the way to its corners, the dark beyond a fisheye's image circle), not a problem
    notes = {c["name"]: c["notes"] for c in out["cameras"]}
    assert [n for n, v in notes.items() if v] == ["cam4"] and "turns back at 84" in notes["cam4"][0], notes


@pytest.mark.daemon
def test_check_log_finds_a_knocked_camera(tmp_path, daemon_path):
    env = dict(os.environ, PYTHONPATH=str(REPO / "tools"))
    rig = tmp_path / "rig.yaml"
    log = tmp_path / "crowd.lcm"
    subprocess.run([sys.executable, "-m", "mvtrack_tools.simulate", "crowd", "--seconds", "20", "--seed", "3", "--rig",
                    str(rig), "--log", str(log), "--quiet", "--dropout-cam", "-1"], check=True, env=env)
    good = Rig.read(rig)
    results = {}
    for name, change in (("none", None), ("5cm", ("t", 0.05)), ("2deg", ("r", 2.0))):
        cams = [look_at(c.name, [0, 0, 1], [0, 1, 1], c.K, c.dist) for c in good.cameras]
        for c, g in zip(cams, good.cameras):
            c.rvec, c.tvec, c.sigma_px = np.array(g.rvec, float), np.array(g.tvec, float), g.sigma_px
        if change is not None:
            c = cams[2]
            if change[0] == "t":  # the camera moved 5 cm sideways in its own frame
                c.tvec = c.tvec + np.array([change[1], 0.0, 0.0])
            else:  # turned 2 degrees about its vertical
                dR = cv2.Rodrigues(np.array([0.0, np.radians(change[1]), 0.0]))[0]
                c.rvec = cv2.Rodrigues(dR @ cv2.Rodrigues(c.rvec)[0])[0].ravel()
                c.tvec = dR @ c.tvec
        bad = tmp_path / f"rig_{name}.yaml"
        Rig(cams, good.volume_min, good.volume_max, good.frame_rate).write(bad)
        trk = tmp_path / f"tracks_{name}.lcm"
        subprocess.run([str(daemon_path), "--rig", str(bad), "--in", f"file://{log}?speed=0", "--out",
                        f"file://{trk}?mode=w"], check=True, capture_output=True)
        r = run("check", "--rig", str(bad), "--log", str(log), "--tracks", str(trk))
        assert r.returncode == 0, r.stderr
        results[name] = json.loads(r.stdout.strip().splitlines()[-1])["consistency"]
    print("\nconsistency, per camera median of its pairs' mean ray gap (m):")
    for name, cons in results.items():
        print(f"  {name}: " + ", ".join(f"{k} {v:.3f}" for k, v in cons["per_camera_m"].items()) +
              f"; flagged {cons['inconsistent']}")
    assert results["none"]["inconsistent"] == []
    assert results["5cm"]["inconsistent"] == [good.cameras[2].name]
    assert results["2deg"]["inconsistent"] == [good.cameras[2].name]


def test_errors_exit_2_and_leave_the_rig(tmp_path):
    room = smartroom()
    rig = tmp_path / "rig.yaml"
    room.write(rig)
    before = rig.read_bytes()
    blank = tmp_path / "blank"
    blank.mkdir()
    for i in range(3):
        cv2.imwrite(str(blank / f"b{i}.png"), np.full((576, 768), 128, np.uint8))
    cam = room.cameras[0]
    two = tmp_path / "two"
    two.mkdir()
    rng = np.random.default_rng(2)
    board = Board("chessboard:9x6:0.05")
    for i, tilt in enumerate(((0, 0, 0), (20, 10, 0))):
        R_b, t_b = pose_in_front(cam, (0.5, 0.35), 1.2, (0.0, 0.0), tilt)
        cv2.imwrite(str(two / f"v{i}.png"), render(cam, board, R_b, t_b, rng))
    line = lambda pts: "u,v,x,y,z\n" + "".join(f"{u},{v},{x},{y},{z}\n" for u, v, x, y, z in pts)  # noqa: E731
    collinear = tmp_path / "collinear.csv"
    X = np.array([[x, 1.0, 0.0] for x in np.linspace(0.5, 4.5, 6)])
    collinear.write_text(line([(u, v, *p) for (u, v), p in zip(cam.project(X), X)]))
    corner = tmp_path / "corner.csv"
    corner.write_text(line([(10 + i, 10 + (i % 2), x, y, 0.0) for i, (x, y) in enumerate([(0, 0), (1, 0), (0, 1), (1, 1), (2, 2)])]))
    header = tmp_path / "header.csv"
    header.write_text("x,y,z,u,v\n1,2,3,4,5\n")
    # points a camera under the floor sees: the solution puts it there
    below = look_at("below", [2.0, 2.0, -2.5], [2.5, 2.5, 0.5], cam.K, cam.dist)
    Xs = np.array([[x, y, z] for x in (1.0, 3.0) for y in (1.0, 3.0) for z in (0.0, 1.5)])
    under = tmp_path / "under.csv"
    under.write_text(line([(u, v, x, y, z) for (u, v), (x, y, z) in zip(below.project(Xs), Xs)]))
    mispaired = tmp_path / "mispaired.csv"
    uvs = cam.project(Xs)
    mispaired.write_text(line([(u, v, x, y, z) for (u, v), (x, y, z) in zip(uvs[::-1], Xs)]))
    cases = [
        (["intrinsics", "--rig", str(rig), "--camera", "cam0", "--images", str(blank / "*.png"), "--board",
          "chessboard:9x6:0.05"], "no board found"),
        (["intrinsics", "--rig", str(rig), "--camera", "cam0", "--images", str(tmp_path / "none*.png"), "--board",
          "chessboard:9x6:0.05"], "no image matches"),
        (["intrinsics", "--rig", str(rig), "--camera", "cam0", "--images", str(two / "*.png"), "--board",
          "chessboard:9x6:0.05"], "too few views"),
        (["intrinsics", "--rig", str(rig), "--camera", "cam0", "--images", str(blank / "*.png"), "--board",
          "chessboard:9:0.05"], "bad --board"),
        (["extrinsics", "--rig", str(rig), "--camera", "cam0", "--points", str(collinear)], "collinear"),
        (["extrinsics", "--rig", str(rig), "--camera", "cam0", "--points", str(corner)], "one corner"),
        (["extrinsics", "--rig", str(rig), "--camera", "cam0", "--points", str(header)], "u,v,x,y,z"),
        (["extrinsics", "--rig", str(rig), "--camera", "cam0", "--points", str(under)], "under the floor"),
        (["extrinsics", "--rig", str(rig), "--camera", "cam0", "--points", str(mispaired)], "fit no pose"),
        (["extrinsics", "--rig", str(rig), "--camera", "nobody", "--points", str(collinear)], "not in the rig"),
        (["check", "--rig", str(tmp_path / "missing.yaml")], "no such rig file"),
    ]
    for args, words in cases:
        r = run(*args)
        assert r.returncode == 2, (args, r.stderr)
        assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, (args, r.stderr)
        assert r.stdout == ""
        assert rig.read_bytes() == before, args
