"""A rig for vtest.avi (PETS 2009 S2.L1 view 1, shipped by Debian's opencv-doc) from the people in it.

The video comes without a calibration. A single camera over a flat ground plane is fixed, up to the
choice of world axes, by its focal length, height, tilt and roll (principal point at the image
centre, no distortion). People are a calibration object: each labelled person (head and foot
visible, tests/data/vtest_labels.json) stands on the ground, and their head is `height` metres
above their foot point. Least squares on the head pixels gives height, tilt and roll; a person's
height (1.72 m, the mean adult) sets the metric scale. The focal length is not observable from
people alone here (its effect trades against the tilt to within a pixel: left free, the fit runs
to its bound), so it is fixed at 800 px, a 51 degree horizontal field of view, typical of such
surveillance lenses; how fast people grow with their foot row then fixes the tilt. The result is a CONTRACT section 2 rig with
one camera, frame_rate 10 (the video's), and a tracked volume covering the visible ground.

    tools/mvtrack python -m mvtrack_tools.vtest_rig [--labels tests/data/vtest_labels.json] --out RIG.yaml
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from .rig import Camera, Rig, intrinsics

W, H = 768, 576
PERSON_M = 1.72


FOCAL_PX = 800.0


def camera(params: np.ndarray) -> Camera:
    height, tilt_deg, roll_deg = params
    f = FOCAL_PX
    t, r = np.deg2rad(tilt_deg), np.deg2rad(roll_deg)
    # camera at (0, 0, height) looking along +y, pitched down by tilt, then rolled about its axis
    fwd = np.array([0.0, np.cos(t), -np.sin(t)])
    right = np.array([1.0, 0.0, 0.0])
    down = np.cross(fwd, right)
    R = np.stack([right, down, fwd])
    Rz = np.array([[np.cos(r), -np.sin(r), 0], [np.sin(r), np.cos(r), 0], [0, 0, 1]])
    R = Rz @ R
    import cv2

    rvec = cv2.Rodrigues(R)[0].ravel()
    tvec = -R @ np.array([0.0, 0.0, height])
    return Camera("view1", intrinsics(f, f, (W - 1) / 2, (H - 1) / 2), np.zeros(5), rvec, tvec, W, H, 3.0)


def ground(cam: Camera, uv: np.ndarray) -> np.ndarray:
    K = cam.K
    d = np.linalg.solve(K, np.array([uv[0], uv[1], 1.0]))
    dw = cam.R.T @ d
    c = cam.centre
    s = -c[2] / dw[2]
    return c + s * dw


def residuals(params: np.ndarray, pairs: list[tuple[float, float, float]]) -> np.ndarray:
    cam = camera(params)
    out = []
    for u, v_head, v_foot in pairs:
        g = ground(cam, np.array([u, v_foot]))
        if not np.all(np.isfinite(g)) or cam.depth(g)[0] <= 0:
            out += [1e3, 1e3]
            continue
        p = cam.project(g + np.array([0.0, 0.0, PERSON_M]))[0]
        out += [p[0] - u, p[1] - v_head]
    return np.asarray(out)


def fit(labels: dict) -> tuple[Camera, float, int]:
    pairs = [(u, vh, vf) for people in labels["frames"].values() for u, vh, vf in people if vf is not None]
    sol = least_squares(residuals, x0=np.array([8.0, 25.0, 0.0]), args=(pairs,),
                        bounds=([2, 2, -15], [40, 80, 15]))
    rms = float(np.sqrt(np.mean(sol.fun ** 2)))
    return camera(sol.x), rms, len(pairs)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack python -m mvtrack_tools.vtest_rig", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--labels", type=Path, default=Path(__file__).resolve().parents[2] / "tests/data/vtest_labels.json")
    ap.add_argument("--out", type=Path, required=True, help="rig file to write")
    a = ap.parse_args(argv)
    labels = json.loads(a.labels.read_text())
    cam, rms, n = fit(labels)
    # the visible ground: back-project the image's lower corners and a row below the horizon
    pts = [ground(cam, np.array(uv, float)) for uv in ((0, H - 1), (W - 1, H - 1), (0, 60), (W - 1, 60))]
    pts = np.array([p for p in pts if np.all(np.isfinite(p))])
    vmin = np.array([pts[:, 0].min() - 1, pts[:, 1].min() - 1, 0.0])
    vmax = np.array([pts[:, 0].max() + 1, pts[:, 1].max() + 1, 2.5])
    Rig([cam], vmin, vmax, 10.0).write(a.out)
    print(f"fitted from {n} people: f {cam.K[0, 0]:.0f} px, camera height {cam.centre[2]:.1f} m, "
          f"head reprojection RMS {rms:.1f} px; wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
