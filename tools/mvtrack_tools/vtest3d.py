"""Real footage in 3D: vtest.avi (PETS 2009 S2.L1 view 1) through mvtrack-detect and mvtrackd with one
camera, scored on the ground plane against the public ground truth (--gt FILE: the 2D MOT 2015
annotation's gt.txt of PETS09-S2L1; by default the project's reference data beside the repository).

1. The camera: calibrated from the ground truth's own world points (mvtrack_tools.vtest_rig: each
   annotated box's bottom-centre is a person's feet on the floor at the annotated world x, y;
   tools/mvtrack calibrate extrinsics --fit-focal), in the annotation's world frame and metres,
   frame_rate 7 (the sequence's, as 2D MOT 2015 gives it).
2. mvtrack-detect on the video with that rig (masks off), then mvtrackd offline with --daemon-args.
3. CLEAR MOT on the ground plane (x, y) with a 1 m threshold (motmetrics) over the frames given,
   every annotated person counted (the benchmark's flag 0 boxes, people far away, are don't-care:
   a track on them is neither false nor required). Frames 0-399 are where the model was looked
   at; 400-794 are reported apart.

    tools/mvtrack vtest3d [--daemon-args "--mode kf"] [--out out/vtest3d] [--json]
"""
from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np

from .paths import BUILD, REPO, import_types

VTEST = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")
GT = REPO.parent / "shared" / "data" / "pets09_s2l1_gt.txt"
W, H = 768, 576
FPS = 7.0
MATCH_M = 1.0


def load_gt(path: Path) -> np.ndarray:
    """Rows: frame (0-based video frame), id, left, top, width, height, flag, world x, world y."""
    a = np.loadtxt(path, delimiter=",")
    a[:, 0] -= 1  # the annotation's frame f is the video's frame f - 1 (its README)
    return a[:, :9]


def fit_rig(out: Path, gt_path: Path = GT) -> dict:
    """The camera from the annotation's feet (mvtrack_tools.vtest_rig, through tools/mvtrack calibrate
    extrinsics --fit-focal), frame_rate 7."""
    p = subprocess.run([sys.executable, "-m", "mvtrack_tools.vtest_rig", "--gt", str(gt_path), "--out", str(out),
                        "--frame-rate", str(FPS)], capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"vtest3d: {p.stderr.strip()}")
    r = json.loads(p.stdout.strip().splitlines()[-1])
    from .rig import Rig
    cam = Rig.read(out).cameras[0]
    return {"rms_px": r["feet_rms_px"], "feet_error_px_median": r["feet_median_px"], "focal_px": r["focal_px"],
            "camera_height_m": float(cam.centre[2]), "heights_median_m": r["heights_median_m"]}


def tracks_by_frame(log: Path, t0: int) -> dict[int, list]:
    import lcm

    mt = import_types()
    out: dict[int, list] = {}
    for ev in lcm.EventLog(str(log), "r"):
        if ev.channel == "TRACKS":
            m = mt.tracks_t.decode(ev.data)
            f = int(round((m.utime - t0) * FPS / 1e6))
            out[f] = [(t.id, t.position[0], t.position[1]) for t in m.tracks if t.status in (2, 3)]
    return out


def clear_mot(gt: np.ndarray, tracks: dict[int, list], frames: range) -> dict:
    import motmetrics as mm

    acc = mm.MOTAccumulator(auto_id=True)
    for f in frames:
        g = gt[gt[:, 0] == f]
        hyp = tracks.get(f, [])
        care = g[:, 6] > 0
        gp = g[:, 7:9]
        hp = np.array([[x, y] for _, x, y in hyp], float).reshape(-1, 2)
        d = np.linalg.norm(gp[:, None, :] - hp[None, :, :], axis=2) if len(hp) else np.zeros((len(gp), 0))
        # a track within reach of a don't-care person is neither matched nor false
        dc = np.zeros(len(hp), bool)
        if len(hp) and (~care).any():
            dc = (d[~care] <= MATCH_M).any(axis=0)
        keep = ~dc
        dd = d[care][:, keep]
        acc.update([int(i) for i in g[care, 1]], [int(hyp[j][0]) for j in np.flatnonzero(keep)],
                   np.where(dd <= MATCH_M, dd, np.nan))
    mh = mm.metrics.create()
    s = mh.compute(acc, metrics=["mota", "motp", "num_switches", "idf1", "num_false_positives", "num_misses",
                                 "num_objects"], name="r")
    r = {k: float(s[k].iloc[0]) for k in s.columns}
    return {"mota": r["mota"], "motp_m": r["motp"], "switches": int(r["num_switches"]), "idf1": r["idf1"],
            "false_positives": int(r["num_false_positives"]), "misses": int(r["num_misses"]),
            "objects": int(r["num_objects"])}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack vtest3d", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gt", type=Path, default=GT, help="the annotation, MOT 2015 gt.txt form")
    ap.add_argument("--out", type=Path, default=Path("out/vtest3d"))
    ap.add_argument("--daemon-args", default="", metavar="ARGS", help="more mvtrackd options")
    ap.add_argument("--detect-args", default="", metavar="ARGS", help="more mvtrack-detect options")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    if not VTEST.exists():
        ap.error(f"{VTEST} is missing: tools/mvtrack setup installs opencv-doc")
    if not a.gt.is_file():
        ap.error(f"no annotation file {a.gt} (--gt FILE)")
    a.out.mkdir(parents=True, exist_ok=True)
    gt = load_gt(a.gt)
    rig = a.out / "rig.yaml"
    cal = fit_rig(rig, a.gt)
    det = a.out / "detections.lcm"
    t0 = 1_700_000_000_000_000
    subprocess.run([str(BUILD / "bin" / "mvtrack-detect"), "--rig", str(rig), "--video", f"view1={VTEST}",
                    "--out", f"file://{det}?mode=w", "--start-utime", str(t0), "--status-s", "0", "--quiet"]
                   + shlex.split(a.detect_args), check=True)
    trk = a.out / "tracks.lcm"
    subprocess.run([str(BUILD / "bin" / "mvtrackd"), "--rig", str(rig), "--in", f"file://{det}?speed=0",
                    "--out", f"file://{trk}?mode=w"] + shlex.split(a.daemon_args), check=True,
                   stderr=subprocess.DEVNULL)
    tracks = tracks_by_frame(trk, t0)
    n = int(gt[:, 0].max()) + 1
    res = {"calibration": cal, "all": clear_mot(gt, tracks, range(0, n)),
           "frames_0_399": clear_mot(gt, tracks, range(0, 400)), "frames_400_794": clear_mot(gt, tracks, range(400, n))}
    if a.json:
        print(json.dumps(res))
    else:
        c = res["calibration"]
        print(f"rig from the annotation's feet: RMS {c['rms_px']:.2f} px (median {c['feet_error_px_median']:.2f} px), "
              f"focal {c['focal_px']:.0f} px, camera {c['camera_height_m']:.2f} m above the floor, people "
              f"{c['heights_median_m']:.2f} m tall (median)")
        for k in ("all", "frames_0_399", "frames_400_794"):
            r = res[k]
            print(f"{k:15s} MOTA {r['mota']:.3f}  MOTP {r['motp_m']:.3f} m  IDF1 {r['idf1']:.3f}  switches "
                  f"{r['switches']}  FP {r['false_positives']}  misses {r['misses']} of {r['objects']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
