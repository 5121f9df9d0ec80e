"""The real camera of vtest.avi (PETS 2009 S2.L1 view 1, Debian's opencv-doc), calibrated from the
public ground truth's world points (--gt FILE, the 2D MOT 2015 gt.txt of PETS09-S2L1: each annotated person's box
bottom-centre is their feet, on the floor at the annotated world x, y).

The video comes without a calibration. Every annotated box the benchmark counts (flag 1) whose
bottom the picture does not cut gives one pair (feet pixel, world point on the floor); `tools/mvtrack
calibrate extrinsics --points --fit-focal` fits the focal length and the pose to them (principal point
at the picture's centre, square pixels, no distortion). The rig is in the annotation's world frame
and metres, its volume the annotated people's floor area widened by 2 m, frame_rate 7 (the
sequence's, as 2D MOT 2015 gives it). As a physical check the rig's people heights are printed:
each box's top-centre ray against the vertical over its feet.

    tools/mvtrack python -m mvtrack_tools.vtest_rig [--gt gt.txt] --out RIG.yaml
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from .rig import Camera, Rig, intrinsics

W, H = 768, 576
FPS = 7.0
REPO = Path(__file__).resolve().parents[2]
GT = REPO.parent / "shared" / "data" / "pets09_s2l1_gt.txt"


def heights(cam: Camera, gt: np.ndarray) -> np.ndarray:
    """Each counted, uncut box's height: its top-centre's ray at the vertical over its feet."""
    import cv2

    ok = (gt[:, 6] > 0) & (gt[:, 3] + gt[:, 5] < H - 2) & (gt[:, 3] > 2)
    out = []
    K, R, C = np.asarray(cam.K, float), cam.R, cam.centre
    for r in gt[ok]:
        xn = cv2.undistortPoints(np.array([[[r[2] + r[4] / 2, r[3]]]]), K, np.asarray(cam.dist, float)).reshape(2)
        d = R.T @ np.array([xn[0], xn[1], 1.0])
        F = np.array([r[7], r[8], 0.0])
        lam = ((F[:2] - C[:2]) @ d[:2]) / (d[:2] @ d[:2])
        out.append((C + lam * d)[2])
    return np.array(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack python -m mvtrack_tools.vtest_rig", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gt", type=Path, default=GT)
    ap.add_argument("--out", type=Path, required=True, help="rig file to write")
    ap.add_argument("--frame-rate", type=float, default=FPS,
                    help="the rig's frame_rate (default 7, the sequence's)")
    a = ap.parse_args(argv)
    gt = np.loadtxt(a.gt, delimiter=",")
    ok = (gt[:, 6] > 0) & (gt[:, 3] + gt[:, 5] < H - 2)
    rows = gt[ok]
    lo = np.array([gt[:, 7].min() - 2.0, gt[:, 8].min() - 2.0, 0.0])
    hi = np.array([gt[:, 7].max() + 2.0, gt[:, 8].max() + 2.0, 2.5])
    start = Camera("view1", intrinsics(800.0, 800.0, (W - 1) / 2, (H - 1) / 2), np.zeros(5), np.zeros(3), np.zeros(3),
                   W, H, 3.0)
    with tempfile.TemporaryDirectory() as tmp:
        rig = Path(tmp) / "rig.yaml"
        Rig([start], lo, hi, a.frame_rate).write(rig)
        csv = Path(tmp) / "feet.csv"
        csv.write_text("u,v,x,y,z\n" + "".join(f"{r[2] + r[4] / 2},{r[3] + r[5]},{r[7]},{r[8]},0\n" for r in rows))
        p = subprocess.run([sys.executable, "-m", "mvtrack_tools.calibrate", "extrinsics", "--rig", str(rig),
                            "--camera", "view1", "--points", str(csv), "--fit-focal"], capture_output=True, text=True)
        if p.returncode != 0:
            print(p.stderr.strip(), file=sys.stderr)
            return 2
        fit = json.loads(p.stdout.strip().splitlines()[-1])
        result = Rig.read(rig)
        result.write(a.out)
    h = heights(result.cameras[0], gt)
    share = float(np.mean((h >= 1.5) & (h <= 2.0)))
    print(f"vtest.avi from {fit['points']} feet: focal {fit['focal_px']:.0f} px, feet reprojected with a median "
          f"of {fit['median_px']:.2f} px (RMS {fit['rms_px']:.2f} px), camera {result.cameras[0].centre[2]:.2f} m up; "
          f"heights of {len(h)} people: median {np.median(h):.2f} m, {100 * share:.0f} % within 1.5-2.0 m; "
          f"wrote {a.out}", file=sys.stderr)
    print(json.dumps({"feet_median_px": fit["median_px"], "feet_rms_px": fit["rms_px"], "focal_px": fit["focal_px"],
                      "heights_median_m": float(np.median(h)), "heights_1p5_2p0_share": share,
                      "frame_rate": a.frame_rate}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
