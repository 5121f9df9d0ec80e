"""Calibration boards seen through a camera model: images to test `tools/mvtrack calibrate` on.

A board (chessboard or ChArUco, from the same spec strings as calibrate.py) is a texture on a plane
with pose (R_b, t_b): board point p (metres, z = 0 on the board) is world point R_b p + t_b. Every
picture pixel is cast back through the camera (its lens included, cv2.undistortPoints) onto the
board's plane and takes the texture there (bilinear), grey elsewhere; a slight optical blur and
sensor noise follow. So the corners land where the camera model puts them, to a small fraction of a
pixel, whatever the distortion.
"""
from __future__ import annotations

import cv2
import numpy as np

from .calibrate import Board
from .rig import Camera

PX_PER_M = 2000.0  # texture resolution


def texture(board: Board) -> tuple[np.ndarray, float, float]:
    """The board's texture (uint8), and its extent in metres along x and y."""
    if board.kind == "chessboard":
        # inner corners cols x rows: squares (cols + 1) x (rows + 1), a white margin of one square
        nx, ny = board.cols + 1, board.rows + 1
        s = int(round(board.square * PX_PER_M))
        img = np.full(((ny + 2) * s, (nx + 2) * s), 255, np.uint8)
        for j in range(ny):
            for i in range(nx):
                if (i + j) % 2 == 0:
                    img[(j + 1) * s:(j + 2) * s, (i + 1) * s:(i + 2) * s] = 0
        # board coordinates: the first inner corner is the origin; the texture starts 2 squares before
        return img, -2 * board.square, -2 * board.square
    w = int(round(board.cols * board.square * PX_PER_M))
    h = int(round(board.rows * board.square * PX_PER_M))
    img = board.board.generateImage((w, h), marginSize=0, borderBits=1)
    pad = int(round(board.square * PX_PER_M))
    img = cv2.copyMakeBorder(img, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=255)
    return img, -board.square, -board.square


def render(cam: Camera, board: Board, R_b: np.ndarray, t_b: np.ndarray, rng: np.random.Generator | None = None,
           noise: float = 1.5) -> np.ndarray:
    """The camera's grey picture of the board at pose (R_b, t_b)."""
    tex, x0, y0 = texture(board)
    h, w = cam.height, cam.width
    uu, vv = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    pix = np.stack([uu.ravel(), vv.ravel()], axis=1).reshape(-1, 1, 2)
    xn = cv2.undistortPointsIter(pix, np.asarray(cam.K, float), np.asarray(cam.dist, float), None, None,
                                 (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)).reshape(-1, 2)
    d = np.hstack([xn, np.ones((len(xn), 1))]) @ cam.R  # world rays
    C = cam.centre
    n = R_b[:, 2]  # the board's normal in the world
    denom = d @ n
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = ((t_b - C) @ n) / denom
    X = C + lam[:, None] * d
    p = (X - t_b) @ R_b  # board coordinates: R_b^T (X - t_b)
    mx = ((p[:, 0] - x0) * PX_PER_M).astype(np.float32).reshape(h, w)
    my = ((p[:, 1] - y0) * PX_PER_M).astype(np.float32).reshape(h, w)
    bad = ~(lam > 0).reshape(h, w)
    mx[bad] = -1e6
    my[bad] = -1e6
    # supersample the texture's footprint: a pixel covers many texels, so average them first
    scale = float(np.nanmedian(np.abs(np.diff(mx, axis=1))[~bad[:, 1:]])) if (~bad).any() else 1.0
    k = max(1, int(scale))
    src = cv2.blur(tex, (k, k)) if k > 1 else tex
    img = cv2.remap(src, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=128)
    img = cv2.GaussianBlur(img.astype(np.float32), (0, 0), 0.6)
    if rng is not None and noise > 0:
        img = img + rng.normal(0, noise, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def rot(rx_deg: float, ry_deg: float, rz_deg: float) -> np.ndarray:
    r = cv2.Rodrigues(np.array([np.radians(rx_deg), 0, 0]))[0]
    r = cv2.Rodrigues(np.array([0, np.radians(ry_deg), 0]))[0] @ r
    return cv2.Rodrigues(np.array([0, 0, np.radians(rz_deg)]))[0] @ r


def pose_in_front(cam: Camera, board_size_m: tuple[float, float], dist_m: float, offset: tuple[float, float],
                  tilt: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """A board pose in front of the camera: its centre dist_m deep, on the ray of the picture point
    offset (-1..1 of the half width and half height from the picture's centre, through the lens),
    tilted (degrees about the camera's axes)."""
    Rc = cam.R.T  # camera axes in the world (columns)
    uv = np.array([[[0.5 * (cam.width - 1) * (1 + offset[0]), 0.5 * (cam.height - 1) * (1 + offset[1])]]])
    xn = cv2.undistortPointsIter(uv, np.asarray(cam.K, float), np.asarray(cam.dist, float), None, None,
                                 (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-12)).reshape(2)
    centre_c = np.array([xn[0] * dist_m, xn[1] * dist_m, dist_m])
    R_bc = rot(*tilt)  # board axes in the camera frame (z along the camera axis: facing it)
    R_b = Rc @ R_bc
    c_w = cam.centre + Rc @ centre_c
    t_b = c_w - R_b @ np.array([board_size_m[0] / 2, board_size_m[1] / 2, 0.0])
    return R_b, t_b
