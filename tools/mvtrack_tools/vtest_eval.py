"""The detector on real footage: vtest.avi (PETS 2009 S2.L1 view 1, Debian's opencv-doc) against
heads labelled by hand (tests/data/vtest_labels.json).

Runs build/bin/mvtrack-detect on the video with the rig fitted to it (tests/data/vtest_rig.yaml,
see vtest_rig.py), matches each labelled frame's detections to the labelled heads (Hungarian, a
head is found when a detection's point is within --radius px), and prints recall, false blobs per
frame and the head-point error. --image writes one frame with its detections and the labels.

    tools/mvtrack python -m mvtrack_tools.vtest_eval [--bg mog2|knn] [--image out/vtest.png] [--json]
"""
from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

from .paths import BUILD, REPO, import_types

VTEST = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")
LABELS = REPO / "tests/data/vtest_labels.json"
RIG = REPO / "tests/data/vtest_rig.yaml"


def detections(log: Path) -> dict[int, list]:
    import lcm

    mt = import_types()
    out: dict[int, list] = {}
    for ev in lcm.EventLog(str(log), "r"):
        if ev.channel.startswith("DETECTIONS_"):
            m = mt.camera_frame_t.decode(ev.data)
            out[int(m.frame)] = list(m.detections)
    return out


def score(dets: dict[int, list], labels: dict, radius: float) -> dict:
    found = total = false = 0
    errs: list[float] = []
    per_frame = {}
    for key, people in labels["frames"].items():
        heads = np.array([[u, v] for u, v, _ in people], float)
        d = dets.get(int(key), [])
        pts = np.array([[x.u, x.v] for x in d], float).reshape(-1, 2)
        cost = np.linalg.norm(heads[:, None, :] - pts[None, :, :], axis=2) if len(pts) else np.zeros((len(heads), 0))
        hit = 0
        if cost.size:
            r, c = linear_sum_assignment(np.where(cost <= radius, cost, 1e6))
            ok = cost[r, c] <= radius
            hit = int(ok.sum())
            errs += list(cost[r, c][ok])
        found += hit
        total += len(heads)
        false += len(pts) - hit
        per_frame[key] = {"people": len(heads), "found": hit, "false_blobs": len(pts) - hit}
    return {"recall": found / max(total, 1), "found": found, "people": total,
            "false_blobs_per_frame": false / max(len(labels["frames"]), 1),
            "head_error_px_median": float(np.median(errs)) if errs else float("nan"), "frames": per_frame}


def draw(path: Path, frame_index: int, dets: list, people: list) -> None:
    import cv2

    cap = cv2.VideoCapture(str(VTEST))
    cap.set(cv2.CAP_PROP_POS_FRAMES, frame_index)
    ok, img = cap.read()
    if not ok:
        return
    for d in dets:
        x0, y0, x1, y1 = (int(round(v)) for v in d.bbox)
        cv2.rectangle(img, (x0, y0), (x1, y1), (0, 255, 255), 1)
        cv2.drawMarker(img, (int(round(d.u)), int(round(d.v))), (0, 0, 255), cv2.MARKER_CROSS, 12, 2)
    for u, v, _ in people:
        cv2.circle(img, (int(round(u)), int(round(v))), 15, (0, 255, 0), 1)
    cv2.putText(img, f"vtest.avi frame {frame_index}: detections (red cross: head, yellow: box), "
                     "labelled heads (green: 15 px)", (8, 566), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1)
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), img)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack python -m mvtrack_tools.vtest_eval", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bg", choices=["mog2", "knn"], default="mog2")
    ap.add_argument("--radius", type=float, default=15.0, help="head match radius, px (default 15)")
    ap.add_argument("--image", type=Path, help="write a labelled frame with its detections here")
    ap.add_argument("--frame", type=int, default=700, help="the frame for --image (default 700)")
    ap.add_argument("--json", action="store_true", help="print the result as JSON")
    ap.add_argument("--detect-args", default="", metavar="ARGS",
                    help="more mvtrack-detect options, e.g. \"--history-s 600\"")
    a = ap.parse_args(argv)
    if not VTEST.exists():
        ap.error(f"{VTEST} is missing: tools/mvtrack setup installs opencv-doc")
    labels = json.loads(LABELS.read_text())
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "det.lcm"
        subprocess.run([str(BUILD / "bin" / "mvtrack-detect"), "--rig", str(RIG), "--video", f"view1={VTEST}",
                        "--out", f"file://{log}?mode=w", "--bg", a.bg, "--status-s", "0", "--quiet"]
                       + shlex.split(a.detect_args), check=True)
        dets = detections(log)
    r = score(dets, labels, a.radius)
    r["bg"] = a.bg
    if a.image:
        draw(a.image, a.frame, dets.get(a.frame, []), labels["frames"].get(str(a.frame), []))
    if a.json:
        print(json.dumps(r))
    else:
        print(f"vtest.avi, {a.bg}: found {r['found']}/{r['people']} labelled people ({100 * r['recall']:.0f} %) "
              f"within {a.radius:g} px, {r['false_blobs_per_frame']:.2f} false blobs per labelled frame, "
              f"head error median {r['head_error_px_median']:.1f} px")
        for k, f in r["frames"].items():
            print(f"  frame {k}: {f['found']}/{f['people']} found, {f['false_blobs']} false")
    return 0


if __name__ == "__main__":
    sys.exit(main())
