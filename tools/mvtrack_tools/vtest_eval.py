"""The detector on real footage: vtest.avi (PETS 2009 S2.L1 view 1, Debian's opencv-doc) against
the public ground truth of every frame, beside the textbook OpenCV detectors.

Runs build/bin/mvtrack-detect on the video with the rig fitted to it (tests/data/vtest_rig.yaml,
see vtest_rig.py; masks and colour on, one core) and, with --peers, the textbook pipelines of
vtest_peers.py on the same frames. Every detector is scored the same way, frame by frame:

- truth gt (default): the 2D MOT 2015 annotation of the sequence as head points per frame (--gt
  FILE, the JSON form {"frames": {"F": [[id, u, v, left, top, width, height, flag], ...]}}; by
  default the project's reference data beside the repository, data/vtest_gt.json);
  a head is a box's top-centre. Boxes the benchmark flags 0 are don't-care: their heads are not
  required and a detection inside one (15 px margin) is not false. Frames 20-794 are scored
  (frames 0-19: the background's start-up), split into 20-399 (where the detector is developed)
  and 400-794 (the check, looked at only to report). A detection whose box stands on the upper
  lawn or the far path at the top left (its bottom above that lawn's near edge), or by the
  parked cars at the top right beyond the van, is neither found nor false: the annotation covers
  no one there (the data's README; no annotated head ever lies there, and the person who walks
  to the light blue car and opens its boot, frames 700-794, is not annotated). A head whose
  top-centre lies on the sign by the lamp post (its rectangle, measured on the picture) is behind
  it, in no pixel: don't-care as well.
- truth hand: the project's own 32 hand-labelled heads in 5 frames (tests/data/vtest_labels.json).

Each labelled head is matched to at most one detection within --radius px (Hungarian on the
distance); recall is found / required heads, false blobs are the unmatched detections per frame,
head error the median matched distance, time the median per frame (decoding excluded). Each
missed head is counted by why (the project detector's, printed; every detector's in --json):
merged (a blob's box holds it and the blob's point is another required head: two people in one
blob reporting one head), off centre (a box holds it and its point lies on the top edge of the
annotated box, within --radius px of its height and inside its width, but more than --radius px
from the centre: a stride or an arm widens the annotated box to one side of the head, so its
top-centre is not the head), aside or below (a box holds it, its point elsewhere more than
--radius px to the side or above, or below), no blob (no box holds it). The project detector's
misses are also counted by what its own mask shows at the head (--json, misses_by_mask): outline
(foreground at the head, mostly background for a head's height above it: a top a reading of the
mask's outline could find), interior (foreground above it too: the head lies inside a region, where
a binary mask has no edge), no head (the head's window is mostly background: the segmentation lost
it); the windows are 3 mask pixels wide, a head's height (an eighth of the annotated box, at least
a mask pixel) tall, just above and just below the annotated top.

    tools/mvtrack vtest [--truth gt|hand] [--peers [mog2 knn hog]] [--plot out/vtest.png]
                        [--image out/vtest_frame.png --frame 700] [--json] [--detect-args ARGS]
"""
from __future__ import annotations

import argparse
import json
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

from .paths import BUILD, REPO, import_types
from .progress import bar
from .render import decode_runs

VTEST = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")
LABELS = REPO / "tests/data/vtest_labels.json"
GT_JSON = REPO.parent / "shared" / "data" / "vtest_gt.json"
RIG = REPO / "tests/data/vtest_rig.yaml"
WIDTH = 768  # vtest.avi's picture, px
FIRST = 20     # frames 0..FIRST-1: the background's start-up, not scored
SPLIT = 400    # frames FIRST..SPLIT-1 develop, SPLIT..end check
PEERS = ("mog2", "knn", "hog")


SIGN = (413.0, 203.0, 444.0, 243.0)  # the sign by the lamp post: x0, y0, x1, y1 px


def behind_sign(u: float, v: float) -> bool:
    """A head top on the sign is behind it: no pixel of the picture shows that head."""
    return SIGN[0] <= u <= SIGN[2] and SIGN[1] <= v <= SIGN[3]


def unannotated(u: float, bottom: float) -> bool:
    """A detection standing where the annotation covers no one: the upper lawn or the far path
    (top left; the lawn's near edge runs from (0, 145) to (420, 130)), or by the parked cars
    beyond the van (top right)."""
    return (u < 430.0 and bottom < 145.0 - 15.0 * u / 420.0) or (u >= 720.0 and bottom < 110.0)


def load_truth(kind: str, gt_path: Path = GT_JSON) -> dict[int, list]:
    """frame -> [(u, v, box or None, required)]"""
    if kind == "hand":
        d = json.loads(LABELS.read_text())
        return {int(k): [(u, v, None, True) for u, v, _ in people] for k, people in d["frames"].items()}
    d = json.loads(Path(gt_path).read_text())
    return {int(k): [(u, v, (left, top, left + w, top + h), bool(c) and not behind_sign(u, v))
                     for _, u, v, left, top, w, h, c in people]
            for k, people in d["frames"].items()}


def mvtrack_detections(detect_args: list[str]) -> tuple[dict[int, list], float, dict[int, np.ndarray]]:
    """mvtrack-detect on vtest.avi: frame -> [(u, v, box)], its median ms per frame, and frame ->
    its foreground mask (the message's runs, at the mask's resolution)."""
    import lcm

    mt = import_types()
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "det.lcm"
        p = subprocess.run([str(BUILD / "bin" / "mvtrack-detect"), "--rig", str(RIG), "--video", f"view1={VTEST}",
                            "--out", f"file://{log}?mode=w", "--masks", "--status-s", "0", "--threads", "1"]
                           + detect_args, capture_output=True, text=True)
        if p.returncode != 0:
            raise SystemExit(f"mvtrack-detect failed: {p.stderr.strip().splitlines()[-1] if p.stderr.strip() else p.returncode}")
        m = re.search(r"detect p50 ([0-9.]+) ms", p.stderr)
        out: dict[int, list] = {}
        masks: dict[int, np.ndarray] = {}
        for ev in lcm.EventLog(str(log), "r"):
            if ev.channel.startswith("DETECTIONS_"):
                msg = mt.camera_frame_t.decode(ev.data)
                out[int(msg.frame)] = [(d.u, d.v, tuple(d.bbox)) for d in msg.detections]
                if msg.num_runs:
                    masks[int(msg.frame)] = decode_runs(np.asarray(msg.runs, int), msg.mask_width, msg.mask_height)
    return out, float(m.group(1)) if m else float("nan"), masks


def peer_detections(kind: str, progress: bool) -> tuple[dict[int, list], float]:
    """A textbook peer on vtest.avi, one core: frame -> [(u, v, box)], median ms per frame."""
    import cv2

    from . import vtest_peers

    cv2.setNumThreads(1)
    det = vtest_peers.make(kind)
    cap = cv2.VideoCapture(str(VTEST))
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    out: dict[int, list] = {}
    ms = []
    for f in bar(range(n), enabled=progress, desc=kind, unit="frame"):
        ok, img = cap.read()
        if not ok:
            break
        t0 = time.perf_counter()
        out[f] = det(img)
        ms.append(1e3 * (time.perf_counter() - t0))
    return out, float(np.median(ms)) if ms else float("nan")


MISS_KINDS = ("merged", "off_centre", "aside", "below", "no_blob")


def miss_kind(u: float, v: float, dets: list, pts: np.ndarray, req_pts: np.ndarray, me: int, radius: float,
              box: tuple | None = None) -> str:
    """Why required head `me` at (u, v) was missed: merged (a blob's box holds it and the blob's point
    is another required head's), off_centre (a box holds it, its point on the top edge of the
    annotated `box`: within `radius` of its height and inside its width), below (a box holds it, its
    point more than `radius` below the head and further below than aside), aside (a box holds it,
    its point elsewhere more than `radius` away), no_blob (no box holds it)."""
    holders = [i for i, d in enumerate(dets) if d[2][0] <= u <= d[2][2] and d[2][1] - radius <= v <= d[2][3]]
    if not holders:
        return "no_blob"
    others = np.delete(req_pts, me, axis=0)
    for i in holders:
        if len(others) and (np.hypot(*(others - pts[i]).T) <= radius).any():
            return "merged"
    i = min(holders, key=lambda i: float(np.hypot(pts[i, 0] - u, pts[i, 1] - v)))
    if box is not None and box[0] <= pts[i, 0] <= box[2] and abs(pts[i, 1] - v) <= radius:
        return "off_centre"
    return "below" if pts[i, 1] - v > radius and abs(pts[i, 0] - u) <= pts[i, 1] - v else "aside"


MASK_KINDS = ("outline", "interior", "no_head")


def mask_evidence(mask: np.ndarray, width: int, u: float, v: float, box: tuple | None) -> str:
    """What the mask (of a picture `width` px wide) shows at a head top (u, v): outline, interior or
    no_head (see the module's text)."""
    s = width / mask.shape[1]
    span = max(1, int(round(((box[3] - box[1]) / 8.0 if box is not None else s) / s)))
    col = int(np.clip(u // s, 0, mask.shape[1] - 1))
    row = int(np.clip(v // s, 0, mask.shape[0] - 1))
    cols = slice(max(0, col - 1), col + 2)
    at = mask[row:row + span, cols]
    above = mask[max(0, row - span):row, cols]
    if not at.size or at.mean() < 0.5:
        return "no_head"
    return "interior" if above.size and above.mean() >= 0.5 else "outline"


def score_frame(dets: list, heads: list, radius: float, gt: bool,
                mask: np.ndarray | None = None) -> tuple[int, int, int, list[float], dict, dict | None]:
    """(required heads, found, false blobs, matched errors, misses by kind, misses by what the mask
    shows or None without a mask) of one frame"""
    req = [(u, v) for u, v, _, r in heads if r]
    req_box = [b for _, _, b, r in heads if r]
    req_pts = np.array(req, float).reshape(-1, 2)
    pts = np.array([[d[0], d[1]] for d in dets], float).reshape(-1, 2)
    used = np.zeros(len(pts), bool)
    errs: list[float] = []
    found = np.zeros(len(req), bool)
    if req and len(pts):
        cost = np.linalg.norm(req_pts[:, None, :] - pts[None, :, :], axis=2)
        r, c = linear_sum_assignment(np.where(cost <= radius, cost, 1e6))
        ok = cost[r, c] <= radius
        used[c[ok]] = True
        found[r[ok]] = True
        errs = list(cost[r, c][ok])
    misses = dict.fromkeys(MISS_KINDS, 0)
    by_mask = dict.fromkeys(MASK_KINDS, 0) if mask is not None else None
    for k in np.flatnonzero(~found):
        misses[miss_kind(req[k][0], req[k][1], dets, pts, req_pts, int(k), radius, req_box[k])] += 1
        if by_mask is not None:
            by_mask[mask_evidence(mask, WIDTH, req[k][0], req[k][1], req_box[k])] += 1
    false = 0
    for i, d in enumerate(dets):
        if used[i]:
            continue
        u, v, box = d
        if gt and unannotated(u, box[3]):
            continue
        if any(b is not None and not r and b[0] - radius <= u <= b[2] + radius and b[1] - radius <= v <= b[3] + radius
               for _, _, b, r in heads):
            continue
        false += 1
    return len(req), len(errs), false, errs, misses, by_mask


def score(dets: dict[int, list], truth: dict[int, list], frames: list[int], radius: float, gt: bool,
          masks: dict[int, np.ndarray] | None = None) -> dict:
    per = {}
    for f in frames:
        per[f] = score_frame(dets.get(f, []), truth.get(f, []), radius, gt, masks.get(f) if masks else None)
    return per


def summary(per: dict, frames: list[int]) -> dict:
    req = sum(per[f][0] for f in frames)
    found = sum(per[f][1] for f in frames)
    false = sum(per[f][2] for f in frames)
    errs = [e for f in frames for e in per[f][3]]
    return {"frames": len(frames), "people": req, "found": found, "recall": found / max(req, 1),
            "false_blobs_per_frame": false / max(len(frames), 1),
            "head_error_px_median": float(np.median(errs)) if errs else float("nan"),
            "misses": {k: sum(per[f][4][k] for f in frames) for k in MISS_KINDS},
            **({"misses_by_mask": {k: sum(per[f][5][k] for f in frames) for k in MASK_KINDS}}
               if frames and all(per[f][5] is not None for f in frames) else {})}


def plot(path: Path, runs: dict[str, dict], frames: list[int]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    win = 25
    k = np.ones(win) / win
    for name, r in runs.items():
        per = r["per_frame"]
        req = np.array([per[f][0] for f in frames], float)
        found = np.array([per[f][1] for f in frames], float)
        false = np.array([per[f][2] for f in frames], float)
        rec = np.convolve(found, k, "same") / np.maximum(np.convolve(req, k, "same"), 1e-9)
        a1.plot(frames, rec, label=name, lw=1.5 if name == "mvtrack-detect" else 1.0)
        a2.plot(frames, np.convolve(false, k, "same"), label=name, lw=1.5 if name == "mvtrack-detect" else 1.0)
    for a in (a1, a2):
        a.axvline(SPLIT, color="grey", ls=":", lw=1)
        a.grid(alpha=0.3)
    a1.set_ylabel(f"recall (heads within radius,\n{win}-frame mean)")
    a1.set_ylim(0, 1.02)
    a2.set_ylabel(f"false blobs per frame\n({win}-frame mean)")
    a2.set_xlabel(f"vtest.avi frame (develop {FIRST}-{SPLIT - 1} | check {SPLIT}-{frames[-1]})")
    a1.legend(loc="lower right", fontsize=8)
    a1.set_title("vtest.avi against the PETS 2009 S2.L1 ground truth")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def draw(path: Path, frame_index: int, dets: list, heads: list) -> None:
    import cv2

    cap = cv2.VideoCapture(str(VTEST))
    cap.set(cv2.CAP_PROP_POS_FRAMES, frame_index)
    ok, img = cap.read()
    if not ok:
        return
    for u, v, box in dets:
        x0, y0, x1, y1 = (int(round(c)) for c in box)
        cv2.rectangle(img, (x0, y0), (x1, y1), (0, 255, 255), 1)
        cv2.drawMarker(img, (int(round(u)), int(round(v))), (0, 0, 255), cv2.MARKER_CROSS, 12, 2)
    for u, v, _, req in heads:
        cv2.circle(img, (int(round(u)), int(round(v))), 15, (0, 255, 0) if req else (160, 160, 160), 1)
    cv2.putText(img, f"vtest.avi frame {frame_index}: detections (red cross: head, yellow: box), "
                     "annotated heads (green: 15 px; grey: don't-care)", (8, 566), cv2.FONT_HERSHEY_SIMPLEX, 0.42,
                (255, 255, 255), 1)
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), img)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack vtest", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--truth", choices=["gt", "hand"], default="gt",
                    help="gt: the public annotation of every frame (default); hand: 32 hand-labelled heads")
    ap.add_argument("--peers", nargs="*", choices=PEERS, metavar="PEER",
                    help=f"also run the textbook detectors ({', '.join(PEERS)}; all when none is named)")
    ap.add_argument("--gt", type=Path, default=GT_JSON, help="the annotation as head points per frame (JSON)")
    ap.add_argument("--radius", type=float, default=15.0, help="head match radius, px (default 15)")
    ap.add_argument("--plot", type=Path, help="write recall and false blobs over the sequence here (PNG)")
    ap.add_argument("--image", type=Path, help="write one frame with mvtrack-detect's blobs and the truth here")
    ap.add_argument("--frame", type=int, default=700, help="the frame for --image (default 700)")
    ap.add_argument("--json", action="store_true", help="print the result as one JSON line")
    ap.add_argument("--detect-args", default="", metavar="ARGS",
                    help="more mvtrack-detect options, e.g. \"--history-s 600\"")
    a = ap.parse_args(argv)
    if not VTEST.exists():
        print(f"mvtrack vtest: {VTEST} is missing: tools/mvtrack setup installs opencv-doc", file=sys.stderr)
        return 2
    if a.truth == "gt" and not a.gt.is_file():
        print(f"mvtrack vtest: no annotation file {a.gt} (--gt FILE, or --truth hand for the project's own labels)",
              file=sys.stderr)
        return 2
    if not (a.radius > 0):
        print("mvtrack vtest: --radius must be > 0", file=sys.stderr)
        return 2
    truth = load_truth(a.truth, a.gt)
    gt = a.truth == "gt"
    frames = sorted(f for f in truth if f >= FIRST) if gt else sorted(truth)
    parts = {"all": frames}
    if gt:
        parts = {f"{FIRST}-{frames[-1]}": frames, f"{FIRST}-{SPLIT - 1}": [f for f in frames if f < SPLIT],
                 f"{SPLIT}-{frames[-1]}": [f for f in frames if f >= SPLIT]}
    runs: dict[str, dict] = {}
    progress = not a.json
    dets, ms, masks = mvtrack_detections(shlex.split(a.detect_args))
    runs["mvtrack-detect"] = {"dets": dets, "ms": ms, "masks": masks}
    for p in (a.peers if a.peers else PEERS) if a.peers is not None else ():
        d, m = peer_detections(p, progress)
        runs[f"textbook {p}"] = {"dets": d, "ms": m}
        if p == "hog":  # the 64x128 window holds a 96 px person: its head lies h/8 below the box's top
            runs["textbook hog, h/8"] = {"ms": m, "dets": {f: [(u, v + (b[3] - b[1]) / 8.0, b) for u, v, b in x]
                                                          for f, x in d.items()}}
    result = {"truth": a.truth, "radius_px": a.radius, "detectors": {}}
    for name, r in runs.items():
        r["per_frame"] = score(r["dets"], truth, frames, a.radius, gt, r.get("masks"))
        result["detectors"][name] = {"ms_per_frame": r["ms"],
                                     **{k: summary(r["per_frame"], fs) for k, fs in parts.items()}}
    if a.plot and gt:
        plot(a.plot, runs, frames)
    if a.image:
        draw(a.image, a.frame, dets.get(a.frame, []), truth.get(a.frame, []))
    main_part = next(iter(parts))
    if a.json:
        # the project detector's whole-range figures at the top level, every detector below
        print(json.dumps({**result, **result["detectors"]["mvtrack-detect"][main_part]}))
        return 0
    print(f"vtest.avi against the {'public ground truth' if gt else 'hand labels'}: heads within {a.radius:g} px, "
          "one core, decoding excluded")
    print(f"{'detector':18s} {'frames':>9s} {'recall':>7s} {'false/frame':>11s} {'head err px':>11s} {'ms/frame':>9s}")
    for name, r in result["detectors"].items():
        for k in parts:
            s = r[k]
            print(f"{name:18s} {k:>9s} {s['recall']:7.3f} {s['false_blobs_per_frame']:11.2f} "
                  f"{s['head_error_px_median']:11.1f} {r['ms_per_frame']:9.2f}")
    ours = result["detectors"]["mvtrack-detect"]
    print("mvtrack-detect's misses: " + "; ".join(
        f"{k} " + ", ".join(f"{n} {kind.replace('_', ' ')}" for kind, n in ours[k]["misses"].items()) for k in parts))
    print("(merged: in a blob whose point is another person's head; off centre: in a blob whose point lies on the "
          f"annotated box's top edge, more than {a.radius:g} px from its centre; aside / below: in a blob whose point "
          f"lies more than {a.radius:g} px to the side or above / below; no blob: in no blob's box)")
    if "misses_by_mask" in ours[main_part]:
        print("what its mask shows at those heads: " + "; ".join(
            f"{k} " + ", ".join(f"{n} {kind.replace('_', ' ')}" for kind, n in ours[k]["misses_by_mask"].items())
            for k in parts))
        print("(outline: a top on the mask's outline; interior: foreground above it too, no edge; no head: the "
              "mask lost it)")
    if a.plot and gt:
        print(f"plot: {a.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
