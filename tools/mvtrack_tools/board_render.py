"""Calibration boards seen through a camera model: images to test `tools/mvtrack calibrate` on.

A board (chessboard or ChArUco, from the same spec strings as calibrate.py) is a texture on a plane
with pose (R_b, t_b): board point p (metres, z = 0 on the board) is world point R_b p + t_b. Every
picture pixel is cast back through the camera (its lens included, rig.normalise) onto the board's
plane and takes the texture there (bilinear, 3 x 3 samples a pixel averaged), grey elsewhere,
dark beyond the lens's fold; a slight optical blur and sensor noise follow. So the corners land
where the camera model puts them, to a few hundredths of a pixel, whatever the distortion.
"""
from __future__ import annotations

import cv2
import numpy as np

from .calibrate import Board
from .rig import Camera, normalise

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


_RAYS: dict = {}


def _rays(cam: Camera, ss: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The normalised image coordinates x and y of every sub-pixel of the picture, ss x ss per pixel,
    and where no ray reaches (cached per lens: the inverse lens is the slow part)."""
    key = (tuple(np.asarray(cam.K, float).ravel()), tuple(np.asarray(cam.dist, float).ravel()), cam.width, cam.height, ss)
    if key not in _RAYS:
        if len(_RAYS) > 4:
            _RAYS.clear()
        sub = (np.arange(ss) + 0.5) / ss - 0.5
        u = (np.arange(cam.width)[:, None] + sub[None, :]).ravel()
        v = (np.arange(cam.height)[:, None] + sub[None, :]).ravel()
        uu, vv = np.meshgrid(u, v)
        xn, has_ray = normalise(cam.K, cam.dist, np.stack([uu.ravel(), vv.ravel()], axis=1))
        _RAYS[key] = (xn[:, 0].reshape(uu.shape).astype(np.float32), xn[:, 1].reshape(uu.shape).astype(np.float32),
                      ~has_ray.reshape(uu.shape))
    return _RAYS[key]


def render(cam: Camera, board: Board, R_b: np.ndarray, t_b: np.ndarray, rng: np.random.Generator | None = None,
           noise: float = 1.5, ss: int = 3) -> np.ndarray:
    """The camera's grey picture of the board at pose (R_b, t_b): each pixel the mean of ss x ss
    samples over its area (a sensor integrates light over its pixel; sampling only its centre
    aliases the squares' edges by a good part of a pixel where the board is small or tilted)."""
    tex, x0, y0 = texture(board)
    h, w = cam.height * ss, cam.width * ss
    x, y, dark = _rays(cam, ss)
    # the board's plane maps to the normalised picture by a homography: [x y 1] ~ H [bx by 1]
    R = cam.R
    H = np.column_stack([R @ R_b[:, 0], R @ R_b[:, 1], R @ t_b + np.asarray(cam.tvec, float).ravel()])
    A = np.linalg.inv(H)
    q2 = (A[2, 0] * x + A[2, 1] * y + A[2, 2]).astype(np.float32)  # 1 / depth: positive in front
    bad = ~(q2 > 0)
    q2[bad] = 1.0
    # texel i spans [i - 0.5, i + 0.5) in cv2.remap's coordinates: its edge at i - 0.5 is board
    # coordinate x0 + i / PX_PER_M
    mx = ((A[0, 0] * x + A[0, 1] * y + A[0, 2]) / q2 - x0) * PX_PER_M - 0.5
    my = ((A[1, 0] * x + A[1, 1] * y + A[1, 2]) / q2 - y0) * PX_PER_M - 0.5
    mx = mx.astype(np.float32)
    my = my.astype(np.float32)
    mx[bad] = -1e6
    my[bad] = -1e6
    # a sample covering many texels averages them first
    scale = float(np.nanmedian(np.abs(np.diff(mx, axis=1))[~bad[:, 1:]])) if (~bad).any() else 1.0
    k = max(1, int(scale)) | 1  # odd: a centred box moves no edge
    src = cv2.blur(tex, (k, k)) if k > 1 else tex
    img = cv2.remap(src, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=128)
    img = np.where(dark, 0, img).astype(np.float32).reshape(cam.height, ss, cam.width, ss).mean(axis=(1, 3))
    img = cv2.GaussianBlur(img, (0, 0), 0.6)
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
