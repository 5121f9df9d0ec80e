"""Calibration: a camera's lens from a board, its place in the room from world points or a board on
the floor, and the checks that catch a bad rig. Writes the rig file mvtrackd reads (OpenCV FileStorage YAML).

    tools/mvtrack calibrate intrinsics --rig RIG.yaml --camera NAME (--images GLOB | --video FILE)
                                       --board chessboard:COLSxROWS:SQUARE_M [--rational] [--plot FILE.png]
    tools/mvtrack calibrate extrinsics --rig RIG.yaml --camera NAME --points POINTS.csv
    tools/mvtrack calibrate extrinsics --rig RIG.yaml --camera NAME --image FLOOR.png
                                       --board charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT]
    tools/mvtrack calibrate check --rig RIG.yaml [--plot FILE.png] [--log LOG.lcm]

Boards: chessboard:COLSxROWS:SQUARE_M counts inner corners; charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT]
counts squares (DICT an OpenCV ArUco dictionary name, default DICT_4X4_50). A ChArUco board lying
face up on the floor defines the world frame (metres, z up, its first inner corner the origin, x
along its columns, y the other way from its rows); a chessboard is ambiguous by 180 degrees
there, so only ChArUco is accepted for extrinsics.

intrinsics: frames where the board is found are kept unless blurred (the variance of the
Laplacian over the board under a third of the median's); of those, up to --max-views are chosen
for coverage of the picture (a 4 x 4 grid) and of tilts (the board's normal in 30-degree bins); a
view the fit leaves over three times the median error (and over 1 px) is dropped and the fit redone.
OpenCV's model with 5 coefficients (8 with --rational); the highest radial terms (k3, and k4-k6
with --rational) are fitted only when the Bayesian information criterion of the residuals asks
for them (otherwise zero: they bend the model at the rim, beyond the boards). Every corner is
refined to the picture's saddle point around it (the detectors' own estimates are biased by up to
several tenths of a pixel on small, tilted or bent boards). Prints the RMS, each view's error, the
picture's cells no view covered, and how well the lens is known: the one-sigma pixel error of the
lens model (from the fit's covariance, each view's pose a nuisance) at worst where the boards were
and over the whole picture; --plot draws it over the picture with the corners used. A fitted model
that turns back inside the picture is warned of (check notes it too): the pixels beyond have no
ray, which is right only for the dark beyond a fisheye's image circle.

extrinsics: cv2.solvePnP (SQPNP) refined by Levenberg-Marquardt. Prints the reprojection error in
pixels and, for points on the floor (z = 0), the error in metres on the floor.

check: per camera its height, where it looks, whether it is under the floor or looks away from it,
and (a note, not a problem) whether its lens model turns back inside its picture;
the floor's coverage at head height (1.7 m) by two cameras or more; each pair's overlap; with
--log (DETECTIONS_ and TRACKS of a recording, or --tracks from mvtrackd's output), each pair of
cameras' mean gap between their rays at the heads of the tracks both saw: a camera whose gaps to
every other are larger than the rest's (twice, and by 1 cm) is flagged (knocked, or a wrong entry).

Every command ends with one JSON line on standard output. Bad input (no board, too few or
degenerate points, a camera under the floor, points behind it): exit 2 with one line on standard
error; the rig file is never left half written (written to a temporary file and renamed).
"""
from __future__ import annotations

import argparse
import glob
import json
import os
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import cv2
import numpy as np

from .rig import Camera, Rig, lens_reach, normalise

HEAD_M = 1.7


class CalibError(Exception):
    """Bad input: one line for the user, exit 2."""


# ---- boards -------------------------------------------------------------------------------------

class Board:
    def __init__(self, spec: str):
        parts = spec.split(":")
        try:
            kind = parts[0]
            cols, rows = (int(v) for v in parts[1].lower().split("x"))
            self.square = float(parts[2])
            if kind == "chessboard" and len(parts) == 3:
                self.kind, self.cols, self.rows = kind, cols, rows
            elif kind == "charuco" and len(parts) in (4, 5):
                self.kind, self.cols, self.rows = kind, cols, rows
                self.marker = float(parts[3])
                name = parts[4] if len(parts) == 5 else "DICT_4X4_50"
                self.dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name))
                self.board = cv2.aruco.CharucoBoard((cols, rows), self.square, self.marker, self.dictionary)
            else:
                raise ValueError
        except (ValueError, IndexError, AttributeError, cv2.error):
            raise CalibError(f"bad --board '{spec}': chessboard:COLSxROWS:SQUARE_M or "
                             "charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT]") from None
        if cols < 2 or rows < 2 or not (self.square > 0):
            raise CalibError(f"bad --board '{spec}': at least 2 x 2 and a positive square")

    def object_points(self) -> np.ndarray:
        """Every corner of the board in its own frame (z = 0), metres."""
        if self.kind == "chessboard":
            g = np.mgrid[0:self.cols, 0:self.rows].T.reshape(-1, 2)
            return np.hstack([g * self.square, np.zeros((len(g), 1))]).astype(np.float32)
        return self.board.getChessboardCorners().astype(np.float32)

    def detect(self, gray: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """(image points N x 2, object points N x 3) of the corners found, or None."""
        if self.kind == "chessboard":
            ok, corners = cv2.findChessboardCornersSB(gray, (self.cols, self.rows), flags=cv2.CALIB_CB_ACCURACY)
            if not ok:
                return None
            img, obj = corners.reshape(-1, 2).astype(np.float32), self.object_points()
        else:
            # a detector a call: detect runs on several threads at once (find_boards)
            corners, ids, _, _ = cv2.aruco.CharucoDetector(self.board).detectBoard(gray)
            if ids is None or len(ids) < 6:
                return None
            img, obj = corners.reshape(-1, 2).astype(np.float32), self.object_points()[ids.ravel()]
        # the window reaches a little under half-way to the next corner on a chessboard; on ChArUco a
        # little under the white margin between the corner and the nearest marker
        reach = 0.4 if self.kind == "chessboard" else min(0.4, 0.9 * (self.square - self.marker) / (2 * self.square))
        return refine_corners(gray, img, obj, self.square, reach), obj


def find_boards(board: Board, frames: list[np.ndarray]) -> list[tuple[np.ndarray, np.ndarray] | None]:
    """board.detect on every frame, the frames spread over the machine's cores: OpenCV lets go of
    Python's lock while it searches, and a frame's corners do not depend on the other frames."""
    with ThreadPoolExecutor(max_workers=max(1, min(len(frames), os.cpu_count() or 1))) as pool:
        return list(pool.map(board.detect, frames))


def refine_corners(gray: np.ndarray, img: np.ndarray, obj: np.ndarray, square: float, reach: float) -> np.ndarray:
    """Each corner moved to the saddle point of the picture around it (cv2.cornerSubPix: the point
    every image gradient in the window is orthogonal to), in a window that stays inside the four
    squares meeting there and clear of their markers (reach times the nearest neighbouring corner's
    distance, 2-6 px each way). The detectors' own estimates are biased by up to several tenths of
    a pixel where the board is small, tilted or bent by the lens; the saddle point is not, the
    picture's noise aside."""
    if len(img) < 2:
        return img
    d_img = np.linalg.norm(img[:, None, :] - img[None, :, :], axis=2)
    d_obj = np.linalg.norm(obj[:, None, :2] - obj[None, :, :2], axis=2)
    near = np.isclose(d_obj, square, rtol=0.01)  # the corner's neighbours along a row or column
    out = img.copy()
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    spacing = np.where(near, d_img, np.inf).min(axis=1)
    spacing[~np.isfinite(spacing)] = 0.0  # no neighbour found: the detector's estimate stays (below)
    half = np.clip((reach * spacing).astype(int), 2, 6)
    for r in np.unique(half):
        sel = half == r
        pts = img[sel].reshape(-1, 1, 2).copy()
        out[sel] = cv2.cornerSubPix(gray, pts, (int(r), int(r)), (-1, -1), crit).reshape(-1, 2)
    # a corner the refinement moved far (another edge in its window) keeps the detector's estimate
    far = np.linalg.norm(out - img, axis=1) > 0.25 * spacing
    out[far] = img[far]
    return out


# ---- rig file -------------------------------------------------------------------------------------

# the volume a rig file calibrate creates holds until the user sets the room's (check says so)
PLACEHOLDER_MIN, PLACEHOLDER_MAX = np.array([-5.0, -5.0, 0.0]), np.array([5.0, 5.0, 2.5])


def new_rig(cam: Camera) -> Rig:
    """The rig file calibrate creates for its first camera: the placeholder volume, 25 fps."""
    return Rig([cam], PLACEHOLDER_MIN.copy(), PLACEHOLDER_MAX.copy(), 25.0)


def load_rig(path: Path, must_exist: bool) -> Rig | None:
    if not path.exists():
        if must_exist:
            raise CalibError(f"{path}: no such rig file")
        return None
    try:
        return Rig.read(path)
    except Exception as e:  # noqa: BLE001 - any unreadable file is the user's input
        raise CalibError(f"{path}: not a rig file ({e.__class__.__name__})") from None


def save_rig(rig: Rig, path: Path) -> None:
    """Atomically: a temporary file beside it, then a rename; the old file stays whole on failure."""
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp.yaml", dir=str(path.parent.resolve()))
    os.close(fd)
    try:
        rig.write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def find_camera(rig: Rig, name: str) -> int:
    for i, c in enumerate(rig.cameras):
        if c.name == name:
            return i
    raise CalibError(f"camera '{name}' is not in the rig")


# ---- intrinsics ---------------------------------------------------------------------------------

def read_frames(images: str | None, video: str | None, every: int) -> list[np.ndarray]:
    frames = []
    if images:
        paths = sorted(glob.glob(images))
        if not paths:
            raise CalibError(f"no image matches '{images}'")
        for p in paths:
            img = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
            if img is None:
                raise CalibError(f"{p}: not an image")
            frames.append(img)
    else:
        cap = cv2.VideoCapture(video)
        if not cap.isOpened():
            raise CalibError(f"{video}: cannot open the video")
        i = 0
        while True:
            ok, img = cap.read()
            if not ok:
                break
            if i % every == 0:
                frames.append(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY))
            i += 1
        if not frames:
            raise CalibError(f"{video}: no frame")
    shapes = {f.shape for f in frames}
    if len(shapes) != 1:
        raise CalibError("the images are not all the same size")
    return frames


def sharpness(gray: np.ndarray, pts: np.ndarray) -> float:
    x0, y0 = np.maximum(pts.min(axis=0).astype(int), 0)
    x1, y1 = pts.max(axis=0).astype(int) + 1
    roi = gray[y0:y1, x0:x1]
    return float(cv2.Laplacian(roi, cv2.CV_64F).var()) if roi.size else 0.0


def choose_views(views: list[dict], width: int, height: int, max_views: int) -> list[dict]:
    """Greedy: each next view adds the most picture cells (4 x 4) and tilt bins not yet covered."""
    def cells(v):
        c = set()
        for x, y in v["img"]:
            c.add((min(int(4 * x / width), 3), min(int(4 * y / height), 3)))
        return c
    for v in views:
        v["cells"] = cells(v)
        H, _ = cv2.findHomography(v["obj"][:, :2], v["img"])
        # the board's tilt: the angle of its normal estimated from the homography's columns
        h1, h2 = H[:, 0], H[:, 1]
        n = np.cross(h1 / np.linalg.norm(h1), h2 / np.linalg.norm(h2))
        v["tilt"] = (int(np.degrees(np.arctan2(n[0], n[2])) // 30), int(np.degrees(np.arctan2(n[1], n[2])) // 30))
    chosen: list[dict] = []
    got_cells: set = set()
    got_tilts: set = set()
    rest = list(views)
    while rest and len(chosen) < max_views:
        best = max(rest, key=lambda v: (len(v["cells"] - got_cells) + 2 * (v["tilt"] not in got_tilts), len(v["img"])))
        chosen.append(best)
        got_cells |= best["cells"]
        got_tilts.add(best["tilt"])
        rest.remove(best)
    return chosen


def intrinsics(a) -> dict:
    board = Board(a.board)
    rig_path = Path(a.rig)
    rig = load_rig(rig_path, must_exist=False)
    frames = read_frames(a.images, a.video, a.every)
    h, w = frames[0].shape
    found = []
    for i, (f, d) in enumerate(zip(frames, find_boards(board, frames))):
        if d is not None:
            found.append({"index": i, "img": d[0], "obj": d[1], "sharp": sharpness(f, d[0])})
    if not found:
        raise CalibError("no board found in any image")
    med = float(np.median([v["sharp"] for v in found]))
    sharp = [v for v in found if v["sharp"] >= med / 3.0]
    views = choose_views(sharp, w, h, a.max_views)
    if len(views) < 3:
        raise CalibError(f"too few views of the board: {len(views)} (3 or more, from different angles)")
    base = cv2.CALIB_RATIONAL_MODEL if a.rational else 0

    def solve_with(vs, flags):
        # views reaching the picture's rim, where a strong lens bends most, start the fit in the
        # wrong place (its first guess has no distortion): the lens is first fitted to the views
        # within 80 % of the half-diagonal, and then to all of them from there
        centre = np.array([(w - 1) / 2, (h - 1) / 2])
        inner = [v for v in vs if np.max(np.linalg.norm(v["img"] - centre, axis=1)) <= 0.8 * np.hypot(*centre)]
        K0, d0 = None, None
        if 6 <= len(inner) < len(vs):
            _, K0, d0, _, _ = cv2.calibrateCamera([v["obj"] for v in inner], [v["img"] for v in inner], (w, h), None,
                                                  None, flags=flags)
            flags |= cv2.CALIB_USE_INTRINSIC_GUESS
        rms_, K_, dist_, rvecs_, tvecs_ = cv2.calibrateCamera([v["obj"] for v in vs], [v["img"] for v in vs], (w, h),
                                                              K0, d0, flags=flags)
        errs = []
        for v, r, t in zip(vs, rvecs_, tvecs_):
            p, _ = cv2.projectPoints(v["obj"], r, t, K_, dist_)
            errs.append(float(np.sqrt(np.mean(np.sum((p.reshape(-1, 2) - v["img"]) ** 2, axis=1)))))
        fixed_terms = [4, 5, 6, 7] if flags & cv2.CALIB_FIX_K3 else []
        return rms_, K_, dist_, errs, (rvecs_, tvecs_, fixed_terms)

    def solve(vs):
        """The lens's highest radial term (k3; k4-k6 too with --rational) only where the views ask
        for it: it bends the model most at the picture's rim, beyond the boards' reach, and a term
        the data do not need extrapolates there by up to a pixel. It is kept when it lowers the
        Bayesian information criterion of the reprojection residuals (2 n ln RMS + k ln 2n over n
        corners: each coefficient must buy its ln 2n)."""
        n = sum(len(v["img"]) for v in vs)
        fixed = base | cv2.CALIB_FIX_K3 | (cv2.CALIB_FIX_K4 | cv2.CALIB_FIX_K5 | cv2.CALIB_FIX_K6 if a.rational else 0)
        r_free, r_fix = solve_with(vs, base), solve_with(vs, fixed)
        extra = 4 if a.rational else 1
        bic_free = 2 * n * np.log(r_free[0]) + extra * np.log(2 * n)
        bic_fix = 2 * n * np.log(r_fix[0])
        return r_free if bic_free < bic_fix else r_fix

    rms, K, dist, per_view, fit = solve(views)
    # a view the model cannot fit (corners found in the wrong order, a board that bent) is dropped
    # and the calibration done again without it
    med_err = float(np.median(per_view))
    bad = [i for i, e in enumerate(per_view) if e > max(1.0, 3.0 * med_err)]
    dropped = []
    if bad and len(views) - len(bad) >= 3:
        dropped = [views[i]["index"] for i in bad]
        views = [v for i, v in enumerate(views) if i not in bad]
        rms, K, dist, per_view, fit = solve(views)
    n_dist = 8 if a.rational else 5
    free = [j for j in range(n_dist) if j not in fit[2]]
    corners = np.vstack([v["img"] for v in views])
    unc = lens_uncertainty(views, K, dist.ravel()[:n_dist], fit[0], fit[1], free, w, h, corners)
    covered = set().union(*(v["cells"] for v in views))
    missing = sorted({(i, j) for i in range(4) for j in range(4)} - covered)
    cam = Camera(a.camera, K, dist.ravel()[:n_dist], np.zeros(3), np.zeros(3), w, h, 2.0)
    if rig is None:
        rig = new_rig(cam)
    else:
        try:
            i = find_camera(rig, a.camera)
            old = rig.cameras[i]
            cam.rvec, cam.tvec, cam.sigma_px = old.rvec, old.tvec, old.sigma_px
            rig.cameras[i] = cam
        except CalibError:
            rig.cameras.append(cam)
    save_rig(rig, rig_path)
    print(f"{a.camera}: {len(found)} of {len(frames)} images show the board, {len(found) - len(sharp)} blurred, "
          f"{len(views)} used; RMS {rms:.3f} px; fx {K[0, 0]:.1f} fy {K[1, 1]:.1f} cx {K[0, 2]:.1f} cy {K[1, 2]:.1f}",
          file=sys.stderr)
    if dropped:
        print("  dropped (the model fits them over three times worse than the rest): images " +
              " ".join(str(i) for i in dropped), file=sys.stderr)
    for v, e in zip(views, per_view):
        print(f"  view {v['index']}: {e:.3f} px", file=sys.stderr)
    if missing:
        print("  picture cells (column, row of a 4 x 4 grid) no view covered: " +
              " ".join(f"({i},{j})" for i, j in missing), file=sys.stderr)
    print(f"  the lens is known to {unc['covered_px']:.2f} px (one standard deviation, at worst) where the boards "
          f"were ({100 * unc['covered_share']:.0f} % of the picture), {unc['picture_px']:.2f} px over the whole "
          "picture (beyond the boards the model extrapolates); more views, and views where it is largest, lower it",
          file=sys.stderr)
    reach = lens_reach(cam)
    if reach < 1.0:
        print(f"  warning: {fold_message(reach)}", file=sys.stderr)
    if a.plot:
        plot_lens(unc, corners, w, h, a.camera, a.plot)
    return {"camera": a.camera, "rms_px": float(rms), "views": len(views), "per_view_px": per_view, "dropped": dropped,
            "camera_matrix": K.tolist(), "distortion": dist.ravel()[:n_dist].tolist(),
            "uncovered_cells": [list(c) for c in missing],
            "lens_sigma_px": {"covered": unc["covered_px"], "picture": unc["picture_px"],
                              "covered_share": unc["covered_share"]},
            "lens_reach": reach if np.isfinite(reach) else None}


def lens_uncertainty(views: list[dict], K: np.ndarray, dist: np.ndarray, rvecs, tvecs, free: list[int], w: int,
                     h: int, corners: np.ndarray, grid: tuple[int, int] = (48, 36)) -> dict:
    """How well the fit knows the lens, over the picture: the covariance of the intrinsics (focal
    lengths, principal point, the distortion terms fitted) from the fit's Jacobian, every view's pose
    a nuisance parameter, scaled by the residuals' variance; propagated to the pixel that each ray of
    a grid over the picture projects to, after the rotation that fits the grid best (a camera's
    orientation comes from its extrinsics, so an error the rotation absorbs is no error of the
    lens). Corner noise that is independent between corners is assumed: a biased corner detector
    makes the lens worse than this says. Returns the grid, each point's largest one-sigma error (px),
    and the worst of it where the views' corners were (their convex hull) and over the picture."""
    cols = [0, 1, 2, 3] + [4 + j for j in free]
    p = len(cols)
    n_par = p + 6 * len(views)
    JtJ = np.zeros((n_par, n_par))
    res2, n_obs = 0.0, 0
    for k, (v, r, t) in enumerate(zip(views, rvecs, tvecs)):
        proj, J = cv2.projectPoints(v["obj"], r, t, K, dist)
        e = proj.reshape(-1, 2) - v["img"]
        res2 += float(np.sum(e ** 2))
        n_obs += e.size
        A = np.zeros((J.shape[0], n_par))
        A[:, :p] = J[:, 6:][:, cols]
        A[:, p + 6 * k:p + 6 * k + 6] = J[:, :6]
        JtJ += A.T @ A
    s2 = res2 / max(n_obs - n_par, 1)
    dn = 1.0 / np.sqrt(np.maximum(np.diag(JtJ), 1e-300))  # scaled to unit diagonal: the terms differ by 10^6
    cov = s2 * (dn[:p, None] * np.linalg.pinv(dn[:, None] * JtJ * dn[None, :], hermitian=True)[:p, :p] * dn[None, :p])
    uu, vv = np.meshgrid(np.linspace(0, w - 1, grid[0]), np.linspace(0, h - 1, grid[1]))
    pix = np.stack([uu.ravel(), vv.ravel()], axis=1)
    hull = cv2.convexHull(corners.astype(np.float32))
    inside = np.array([cv2.pointPolygonTest(hull, (float(x), float(y)), False) >= 0 for x, y in pix])
    xn, _ = normalise(K, dist, pix)
    X = np.hstack([xn, np.ones((len(xn), 1))])
    _, Jg = cv2.projectPoints(X, np.zeros(3), np.zeros(3), K, dist)
    lam, V = np.linalg.eigh(0.5 * (cov + cov.T))
    L = V * np.sqrt(np.maximum(lam, 0.0))  # cov = L L^T

    def sigma(sel: np.ndarray) -> np.ndarray:
        rows = np.repeat(np.flatnonzero(sel) * 2, 2) + np.tile([0, 1], int(sel.sum()))
        Jt, Jr = Jg[rows][:, 6:][:, cols], Jg[rows][:, :3]
        M = Jt - Jr @ np.linalg.lstsq(Jr, Jt, rcond=None)[0]  # what no rotation absorbs
        Q = (M @ L).reshape(-1, 2, p)
        C = Q @ Q.transpose(0, 2, 1)  # each point's 2 x 2 covariance
        return np.sqrt(np.linalg.eigvalsh(C)[:, 1])

    every = sigma(np.ones(len(pix), bool))
    covered = sigma(inside) if inside.sum() >= 4 else every
    return {"grid": pix, "sigma": every, "covered_px": float(covered.max()), "picture_px": float(every.max()),
            "covered_share": float(cv2.contourArea(hull)) / (w * h)}


def plot_lens(unc: dict, corners: np.ndarray, w: int, h: int, name: str, path: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    g = unc["grid"]
    nx = len(np.unique(g[:, 0]))
    fig, ax = plt.subplots(figsize=(8, 6.2))
    im = ax.imshow(unc["sigma"].reshape(-1, nx), extent=(0, w - 1, h - 1, 0), cmap="magma", interpolation="bilinear",
                   norm=matplotlib.colors.LogNorm(vmin=max(1e-3, unc["sigma"].min()), vmax=max(unc["sigma"].max(), 1e-2)))
    fig.colorbar(im, ax=ax, label="the lens's one-sigma error (px)")
    ax.plot(corners[:, 0], corners[:, 1], ".", color="cyan", ms=1.5)
    hull = cv2.convexHull(corners.astype(np.float32)).reshape(-1, 2)
    ax.plot(np.r_[hull[:, 0], hull[0, 0]], np.r_[hull[:, 1], hull[0, 1]], color="white", lw=1)
    ax.set_xlim(0, w - 1)
    ax.set_ylim(h - 1, 0)
    ax.set_title(f"{name}: how well the lens is known (one sigma)\n{unc['covered_px']:.2f} px at worst inside the "
                 f"corners' hull (white), {unc['picture_px']:.2f} px over the picture", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


# ---- extrinsics ---------------------------------------------------------------------------------

def read_points(path: str) -> tuple[np.ndarray, np.ndarray]:
    try:
        with open(path) as f:
            header = f.readline().strip().replace(" ", "")
            if header != "u,v,x,y,z":
                raise CalibError(f"{path}: the first line must be u,v,x,y,z")
            rows = [[float(x) for x in line.split(",")] for line in f if line.strip()]
    except OSError as e:
        raise CalibError(f"{path}: {e.strerror}") from None
    except ValueError:
        raise CalibError(f"{path}: every line needs five numbers u,v,x,y,z") from None
    a = np.array(rows, float).reshape(-1, 5)
    if not np.all(np.isfinite(a)):
        raise CalibError(f"{path}: a value is not a finite number")
    return a[:, :2].astype(np.float64), a[:, 2:].astype(np.float64)


def check_points(img: np.ndarray, obj: np.ndarray, width: int, height: int) -> None:
    if len(obj) < 4:
        raise CalibError(f"too few points: {len(obj)} (4 or more)")
    c = obj - obj.mean(axis=0)
    s = np.linalg.svd(c, compute_uv=False)
    if s[1] < 1e-3 * max(s[0], 1e-9):
        raise CalibError("the world points are collinear (degenerate)")
    span = (img.max(axis=0) - img.min(axis=0)) / np.array([width, height])
    if span[0] * span[1] < 0.02:
        raise CalibError("the points cover under 2 % of the picture (all in one corner): spread them out")


def pose(img: np.ndarray, obj: np.ndarray, cam: Camera) -> tuple[np.ndarray, np.ndarray]:
    K, dist = np.asarray(cam.K, float), np.asarray(cam.dist, float)
    ok, r, t = cv2.solvePnP(obj, img, K, dist, flags=cv2.SOLVEPNP_SQPNP)
    if not ok:
        raise CalibError("no pose fits the points")
    r, t = cv2.solvePnPRefineLM(obj, img, K, dist, r, t)
    R = cv2.Rodrigues(r)[0]
    centre = -R.T @ t.ravel()
    if centre[2] <= 0:
        raise CalibError(f"the solution puts the camera under the floor (z = {centre[2]:.2f} m): check the points")
    depth = (obj @ R.T + t.ravel())[:, 2]
    if np.any(depth <= 0):
        raise CalibError("the solution puts points behind the camera: check the points")
    return r.ravel(), t.ravel()


def fit_focal(img: np.ndarray, obj: np.ndarray, cam: Camera) -> None:
    """The focal length from the points as well (a camera nobody calibrated with a board): one view,
    the principal point and the lens as the rig has them, square pixels. Sets cam.K."""
    if len(obj) < 6:
        raise CalibError(f"too few points to fit the focal length too: {len(obj)} (6 or more)")
    flags = (cv2.CALIB_USE_INTRINSIC_GUESS | cv2.CALIB_FIX_PRINCIPAL_POINT | cv2.CALIB_FIX_ASPECT_RATIO |
             cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K1 | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3)
    try:
        _, K, _, _, _ = cv2.calibrateCamera([obj.astype(np.float32)], [img.astype(np.float32)], (cam.width, cam.height),
                                            np.asarray(cam.K, float).copy(), np.asarray(cam.dist, float)[:5].copy(),
                                            flags=flags)
    except cv2.error:
        raise CalibError("the points do not fix a focal length (they need depth or a plane seen at an angle)") from None
    if not (K[0, 0] > 0 and np.isfinite(K).all()):
        raise CalibError("the points do not fix a focal length")
    cam.K = K


def floor_error(img: np.ndarray, obj: np.ndarray, cam: Camera, r: np.ndarray, t: np.ndarray) -> float | None:
    """Median distance on the floor between the floor points and their pixels cast onto z = 0, m."""
    on = np.abs(obj[:, 2]) < 1e-6
    if not on.any():
        return None
    xn = cv2.undistortPoints(img[on].reshape(-1, 1, 2), np.asarray(cam.K, float), np.asarray(cam.dist, float)).reshape(-1, 2)
    R = cv2.Rodrigues(r)[0]
    C = -R.T @ t
    d = (np.hstack([xn, np.ones((len(xn), 1))]) @ R)  # rays in the world: R^T [x y 1]
    lam = -C[2] / d[:, 2]
    hit = C + lam[:, None] * d
    return float(np.median(np.linalg.norm(hit[:, :2] - obj[on, :2], axis=1)))


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise CalibError(f"--size {text}: give the picture's size as WIDTHxHEIGHT, e.g. 1280x720") from None
    if not (16 <= w <= 16384 and 16 <= h <= 16384):
        raise CalibError(f"--size {text}: width and height must be 16..16384 pixels")
    return w, h


def new_camera(name: str, size: str) -> Camera:
    """A camera nobody calibrated: the picture's size, the principal point at its centre, no lens
    distortion, a first focal length of one picture width (a 53-degree field) for --fit-focal to fit."""
    w, h = parse_size(size)
    K = np.array([[float(w), 0.0, 0.5 * (w - 1)], [0.0, float(w), 0.5 * (h - 1)], [0.0, 0.0, 1.0]])
    return Camera(name, K, np.zeros(5), np.zeros(3), np.zeros(3), w, h, 2.0)


def extrinsics(a) -> dict:
    rig_path = Path(a.rig)
    if a.size and not (a.fit_focal and a.points):
        raise CalibError("--size makes a camera nobody calibrated: it needs --points and --fit-focal")
    rig = load_rig(rig_path, must_exist=False)
    if rig is None and not a.size:
        raise CalibError(f"{rig_path}: no such rig file (calibrate intrinsics creates it, or give --size WxH with "
                         "--points and --fit-focal for a camera without a lens calibration)")
    names = [c.name for c in rig.cameras] if rig is not None else []
    if a.camera in names:
        if a.size:
            raise CalibError(f"camera '{a.camera}' is in the rig already: leave out --size to place it")
        cam = rig.cameras[names.index(a.camera)]
    elif a.size:
        cam = new_camera(a.camera, a.size)
        if rig is None:
            rig = new_rig(cam)
        else:
            rig.cameras.append(cam)
    else:
        raise CalibError(f"camera '{a.camera}' is not in the rig: calibrate its lens first (calibrate "
                         "intrinsics), or give --size WxH with --points and --fit-focal")
    if a.points:
        img, obj = read_points(a.points)
    else:
        if not a.image or not a.board:
            raise CalibError("extrinsics needs --points CSV, or --image with --board charuco:...")
        board = Board(a.board)
        if board.kind != "charuco":
            raise CalibError("a chessboard on the floor is ambiguous by 180 degrees: use a charuco board")
        gray = cv2.imread(a.image, cv2.IMREAD_GRAYSCALE)
        if gray is None:
            raise CalibError(f"{a.image}: not an image")
        d = board.detect(gray)
        if d is None:
            raise CalibError(f"{a.image}: no board found")
        # the board's own frame has z into the board (OpenCV's): lying face up on the floor, the
        # world (z up) is that frame turned half a turn about its x axis
        img, obj = d[0].astype(np.float64), d[1].astype(np.float64) * np.array([1.0, -1.0, -1.0])
    check_points(img, obj, cam.width, cam.height)
    if a.fit_focal:
        fit_focal(img, obj, cam)
    r, t = pose(img, obj, cam)
    p, _ = cv2.projectPoints(obj, r, t, np.asarray(cam.K, float), np.asarray(cam.dist, float))
    err = np.linalg.norm(p.reshape(-1, 2) - img, axis=1)
    rms = float(np.sqrt(np.mean(err ** 2)))
    if rms > a.max_rms_px:
        raise CalibError(f"the points fit no pose of this camera (reprojection RMS {rms:.1f} px over "
                         f"{a.max_rms_px:g}): check their pairing and the camera's intrinsics")
    fe = floor_error(img, obj, cam, r, t)
    cam.rvec, cam.tvec = r, t
    save_rig(rig, rig_path)
    R = cv2.Rodrigues(r)[0]
    C = -R.T @ t
    print(f"{a.camera}: {len(obj)} points, reprojection RMS {rms:.3f} px (max {err.max():.2f} px)"
          + (f", on the floor {100 * fe:.1f} cm (median)" if fe is not None else "")
          + f"; camera at ({C[0]:.2f}, {C[1]:.2f}, {C[2]:.2f}) m", file=sys.stderr)
    return {"camera": a.camera, "rms_px": rms, "median_px": float(np.median(err)), "max_px": float(err.max()),
            "floor_error_m": fe, "position_m": C.tolist(), "points": int(len(obj)), "focal_px": float(cam.K[0][0])}


# ---- check ----------------------------------------------------------------------------------------

def sees(cam: Camera, X: np.ndarray) -> np.ndarray:
    front = cam.depth(X) > 0.1
    uv = cam.project(X)
    return front & cam.in_image(uv) & np.all(np.isfinite(uv), axis=1)


def ray(cam: Camera, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    xn = cv2.undistortPoints(np.asarray(uv, float).reshape(-1, 1, 2), np.asarray(cam.K, float),
                             np.asarray(cam.dist, float)).reshape(-1, 2)
    d = np.hstack([xn, np.ones((len(xn), 1))]) @ cam.R
    return cam.centre, d / np.linalg.norm(d, axis=1, keepdims=True)


def ray_gap(c1, d1, c2, d2) -> np.ndarray:
    """The vector from the second ray's point nearest the first to the first's nearest the second (unit
    directions): its length is the rays' distance, its mean over many heads a pair's bias."""
    w0 = c1 - c2
    b, d, e = float(d1 @ d2), float(d1 @ w0), float(d2 @ w0)
    den = 1.0 - b * b
    if den < 1e-12:
        return np.cross(np.cross(d1, w0), d1)
    s = (b * e - d) / den
    t = (e - b * d) / den
    return (c1 + s * d1) - (c2 + t * d2)


def consistency(rig: Rig, log: str, tracks_log: str | None = None) -> dict:
    """Per pair of cameras, the bias of their rays at the heads of the tracks both updated (each
    camera's detection nearest the track's head): the length of the mean gap between the rays. A
    camera whose pairs are all biased more than the others' is flagged."""
    from .lcmio import read_log
    from .paths import import_types
    import lcm

    mt = import_types()
    names = [c.name for c in rig.cameras]
    per_cam: dict[str, dict[int, list]] = {n: {} for n in names}
    for ev in lcm.EventLog(log, "r"):
        if ev.channel.startswith("DETECTIONS_"):
            m = mt.camera_frame_t.decode(ev.data)
            if m.camera in per_cam:
                per_cam[m.camera][int(m.utime)] = [(d.u, d.v) for d in m.detections]
    times = {n: np.array(sorted(v), dtype=np.int64) for n, v in per_cam.items()}
    half_us = int(0.5e6 / rig.frame_rate)
    tl = read_log(tracks_log or log, lambda c: c == "TRACKS").tracks
    pairs: dict[tuple[int, int], list[float]] = {}
    for u in sorted(tl):
        frame = {}  # each camera's message of this frame set: the one nearest in time
        for n in names:
            ts = times[n]
            if len(ts):
                j = int(np.argmin(np.abs(ts - u)))
                if abs(int(ts[j]) - u) <= half_us:
                    frame[n] = per_cam[n][int(ts[j])]
        for t in tl[u]:
            used = [k for k in range(len(names)) if (t.cameras_used >> k) & 1 and names[k] in frame]
            if len(used) < 2:
                continue
            X = np.array(t.position, float)[None]
            pick = {}
            for k in used:
                cam = rig.cameras[k]
                if not len(frame[names[k]]):
                    continue
                uv = cam.project(X)[0]
                cand = np.array(frame[names[k]], float)
                i = int(np.argmin(np.linalg.norm(cand - uv, axis=1)))
                if np.linalg.norm(cand[i] - uv) < 30:
                    pick[k] = cand[i]
            ks = sorted(pick)
            for a_ in range(len(ks)):
                for b_ in range(a_ + 1, len(ks)):
                    ca, da = ray(rig.cameras[ks[a_]], pick[ks[a_]])
                    cb, db = ray(rig.cameras[ks[b_]], pick[ks[b_]])
                    pairs.setdefault((ks[a_], ks[b_]), []).append(ray_gap(ca, da[0], cb, db[0]))
    # a pair's bias: the length of its rays' mean gap (the noise of single heads averages out; a
    # camera off by a few centimetres or a degree keeps its gap to every other camera the same way)
    med = {p: float(np.linalg.norm(np.mean(v, axis=0))) for p, v in pairs.items() if len(v) >= 30}
    per_cam = {}
    for k in range(len(names)):
        vals = [v for (a_, b_), v in med.items() if k in (a_, b_)]
        if vals:
            per_cam[k] = float(np.median(vals))
    flagged = []
    if len(per_cam) >= 3:
        base = float(np.median(list(per_cam.values())))
        for k, v in per_cam.items():
            # a knocked camera: its rays miss every other camera's by more than the rest do
            others = [w for (a_, b_), w in med.items() if k not in (a_, b_)]
            ref = float(np.median(others)) if others else base
            if v > max(2.0 * ref, ref + 0.01):
                flagged.append(names[k])
    return {"pairs": {f"{names[a_]}-{names[b_]}": v for (a_, b_), v in med.items()},
            "per_camera_m": {names[k]: v for k, v in per_cam.items()}, "inconsistent": flagged}


def fold_message(reach: float) -> str:
    """What a lens model that turns back inside its picture (rig.lens_reach under 1) means to a user."""
    return (f"its lens model turns back at {100 * reach:.1f} % of the way to the picture's corners: the pixels "
            "beyond have no ray (right for the dark beyond a fisheye's image circle; where the picture shows "
            "the room there, the fit extrapolated past the boards: add views there)")


def check(a) -> dict:
    rig = load_rig(Path(a.rig), must_exist=True)
    lo, hi = np.asarray(rig.volume_min, float), np.asarray(rig.volume_max, float)
    xs = np.linspace(lo[0], hi[0], 41)
    ys = np.linspace(lo[1], hi[1], 41)
    gx, gy = np.meshgrid(xs, ys)
    grid = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, HEAD_M)], axis=1)
    seen = np.array([sees(c, grid) for c in rig.cameras])
    n_seen = seen.sum(axis=0)
    cams, problems = [], []
    if np.allclose(lo, PLACEHOLDER_MIN) and np.allclose(hi, PLACEHOLDER_MAX):
        problems.append("the volume is calibrate's placeholder (-5..5 m, 0..2.5 m): set volume_min/volume_max to "
                        "the room's floor area and head heights; the floor shares printed are over the placeholder")
    for k, c in enumerate(rig.cameras):
        C = c.centre
        axis = c.R[2]  # the optical axis in the world
        floor_pt = None
        if axis[2] < 0:
            lam = -C[2] / axis[2]
            floor_pt = (C + lam * axis)[:2].tolist()
        overlap = [rig.cameras[j].name for j in range(len(rig.cameras)) if j != k and (seen[k] & seen[j]).any()]
        flags = []
        if C[2] <= 0:
            flags.append("under the floor")
        elif axis[2] >= 0:
            flags.append("looks away from the floor (mirrored or upside down)")
        if not overlap and len(rig.cameras) > 1:
            flags.append("no other camera overlaps it")
        if not seen[k].any():
            flags.append("sees no head-height point of the volume")
        reach = lens_reach(c)
        notes = [fold_message(reach)] if reach < 1.0 else []
        problems += [f"{c.name}: {f}" for f in flags]
        cams.append({"name": c.name, "height_m": float(C[2]), "position_m": C.tolist(),
                     "looks_down_deg": float(np.degrees(np.arcsin(np.clip(-axis[2], -1, 1)))),
                     "looks_at_floor_m": floor_pt, "overlaps": overlap, "flags": flags, "notes": notes,
                     "floor_seen_share": float(seen[k].mean())})
        print(f"{c.name}: {C[2]:.2f} m above the floor at ({C[0]:.2f}, {C[1]:.2f}), looking "
              f"{cams[-1]['looks_down_deg']:.0f} deg down" + (f" at ({floor_pt[0]:.2f}, {floor_pt[1]:.2f})" if floor_pt else "")
              + f"; sees {100 * seen[k].mean():.0f} % of the floor at {HEAD_M} m"
              + ("; " + "; ".join(flags + notes) if flags or notes else ""), file=sys.stderr)
    share2 = float((n_seen >= 2).mean())
    print(f"floor at head height seen by two cameras or more: {100 * share2:.0f} %", file=sys.stderr)
    out = {"cameras": cams, "floor_seen_by_2": share2, "problems": problems}
    if a.log:
        cons = consistency(rig, a.log, a.tracks)
        out["consistency"] = cons
        for name in cons["inconsistent"]:
            out["problems"].append(f"{name}: its rays miss the other cameras' at the same heads (knocked, or a wrong entry)")
        for k, v in cons["per_camera_m"].items():
            print(f"{k}: its rays pass {100 * v:.1f} cm from the other cameras' at the same heads, on average "
                  "(median over its pairs)", file=sys.stderr)
    for p in out["problems"]:
        print(f"PROBLEM {p}", file=sys.stderr)
    if a.plot:
        plot(rig, grid, n_seen, seen, a.plot)
    return out


def plot(rig: Rig, grid: np.ndarray, n_seen: np.ndarray, seen: np.ndarray, path: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lo, hi = np.asarray(rig.volume_min, float), np.asarray(rig.volume_max, float)
    fig, ax = plt.subplots(figsize=(7, 6))
    n = int(np.sqrt(len(grid)))
    im = ax.imshow(n_seen.reshape(n, n), origin="lower", extent=(lo[0], hi[0], lo[1], hi[1]), cmap="viridis",
                   vmin=0, vmax=max(2, len(rig.cameras)))
    fig.colorbar(im, ax=ax, label=f"cameras that see a head at {HEAD_M} m")
    ax.contour(grid[:, 0].reshape(n, n), grid[:, 1].reshape(n, n), (n_seen >= 2).reshape(n, n).astype(float),
               levels=[0.5], colors="white", linewidths=1)
    for c in rig.cameras:
        C = c.centre
        a = c.R[2]
        ax.plot(C[0], C[1], "r^", ms=9)
        ax.annotate(c.name, (C[0], C[1]), color="red", xytext=(4, 4), textcoords="offset points")
        ax.arrow(C[0], C[1], 0.8 * a[0], 0.8 * a[1], color="red", head_width=0.12, length_includes_head=True)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("floor plan: cameras, and how many see each place at head height\n"
                 "(white line: seen by two or more)")
    ax.set_aspect("equal")
    ax.set_xlim(min(lo[0], min(c.centre[0] for c in rig.cameras)) - 0.5, max(hi[0], max(c.centre[0] for c in rig.cameras)) + 0.5)
    ax.set_ylim(min(lo[1], min(c.centre[1] for c in rig.cameras)) - 0.5, max(hi[1], max(c.centre[1] for c in rig.cameras)) + 0.5)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


# ---- command line ---------------------------------------------------------------------------------

def main(argv: list[str] | None = None) -> int:
    # One thread: OpenCV's parallel sums change with the threads' timing, and a wide lens's fit
    # (8 coefficients, ill-conditioned toward the picture's corners) then lands on a different
    # solution from run to run; the same views must give the same lens.
    cv2.setNumThreads(1)
    ap = argparse.ArgumentParser(prog="mvtrack calibrate", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("intrinsics", help="a camera's lens from views of a board")
    p.add_argument("--rig", required=True)
    p.add_argument("--camera", required=True)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--images", metavar="GLOB")
    src.add_argument("--video", metavar="FILE")
    p.add_argument("--board", required=True, help="chessboard:COLSxROWS:SQUARE_M or charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT]")
    p.add_argument("--rational", action="store_true", help="8 coefficients (wide lenses)")
    p.add_argument("--max-views", type=int, default=40, help="views used at most (default 40)")
    p.add_argument("--every", type=int, default=10, help="--video: every N-th frame (default 10)")
    p.add_argument("--plot", help="a picture of how well the lens is known over the picture, with the corners (PNG)")
    p = sub.add_parser("extrinsics", help="a camera's place in the world (metres, z up, floor z = 0)")
    p.add_argument("--rig", required=True)
    p.add_argument("--camera", required=True)
    p.add_argument("--points", metavar="CSV", help="u,v,x,y,z per line: pixel (raw image) and world point")
    p.add_argument("--image", help="an image of a charuco board lying on the floor (its frame is the world's)")
    p.add_argument("--board", help="with --image: charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT]")
    p.add_argument("--fit-focal", action="store_true",
                   help="--points: fit the focal length too (a camera without a lens calibration; principal "
                        "point and distortion as the rig has them, square pixels)")
    p.add_argument("--size", metavar="WxH",
                   help="--points --fit-focal for a camera not in the rig (no lens calibration): its "
                        "picture's size; the principal point at the centre, no distortion; creates the rig "
                        "file if missing")
    p.add_argument("--max-rms-px", type=float, default=10.0,
                   help="refuse a pose whose reprojection RMS exceeds this (default 10 px)")
    p = sub.add_parser("check", help="the whole rig: heights, directions, coverage, overlaps, consistency")
    p.add_argument("--rig", required=True)
    p.add_argument("--plot", help="floor plan with the cameras and the coverage at head height (PNG)")
    p.add_argument("--log", help="a recording with DETECTIONS_ and TRACKS: each camera pair's ray distances")
    p.add_argument("--tracks", help="with --log: the TRACKS from this log instead (mvtrackd's output on --log)")
    a = ap.parse_args(argv)
    try:
        if a.cmd == "intrinsics":
            if a.max_views < 3 or a.every < 1:
                raise CalibError("--max-views must be >= 3 and --every >= 1")
            out = intrinsics(a)
        elif a.cmd == "extrinsics":
            out = extrinsics(a)
        else:
            out = check(a)
    except CalibError as e:
        print(f"mvtrack calibrate {a.cmd}: {e}", file=sys.stderr)
        return 2
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
