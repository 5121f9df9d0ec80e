"""From camera pixels to 3D tracks, end to end: rendered video -> mvtrack-detect -> mvtrackd -> scores.

For every rig, scene and seed:
  1. render the scene as one MJPEG video per camera (tools/mvtrack simulate --video: textured room,
     articulated people, shadows, illumination drift, noise, compression) with the ground truth;
  2. run build/bin/mvtrack-detect on all cameras in lockstep (masks and hue/saturation included);
  3. run build/bin/mvtrackd on the detections in each --modes (pkf: the blobs, pf: the masks);
  4. score CLEAR MOT (0.5 m, motmetrics) and the 3D error against the head tops.
Writes out/pixels/pixels.md (the table), summary.json, per run a zenithal plot (tracks over the
truth) and per rig one camera view with the detections and the tracks reprojected.

Rigs: `--rigs 0 11` means the smart room (0) and the random room and rig of seed 11 (5 cameras,
other room size, placements, lenses and image sizes). Videos are kept under out/pixels/video/ and
reused when present; so are the detections, while the detector binary and its arguments are the same
(--fresh renders and detects again).

    tools/mvtrack pixels [--scenes crowd interaction] [--seeds 3] [--rigs 0 11] [--modes pkf pf]
                         [--seconds 60] [--jobs 2] [--out out/pixels]
"""
from __future__ import annotations

import argparse
import hashlib
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np

from . import plots
from .crowd import DetectorModel, crowd_scene, interaction_scene
from .detect import run as run_detect
from .experiment1 import run_daemon
from .lcmio import LogWriter, read_log
from .mot import as_dict, clear_mot, pair_frames
from .detect import DETECT
from .paths import DAEMON
from .pf_run import head_stats
from .rig import Rig, random_rig, smartroom
from .simulate import T0_UTIME
from .video import write_truth, write_video

Q = np.array([0.5, 0.5, 0.05])


def rig_for(seed: int, cameras: int) -> Rig:
    return smartroom() if seed == 0 else random_rig(np.random.default_rng(seed), cameras)


def scene_for(kind: str, rig: Rig, seed: int, seconds: float):
    model = DetectorModel(dropout_cam=None)
    if kind == "crowd":
        return crowd_scene(rig, seconds, seed, model=model)
    return interaction_scene(rig, 400, seed, model=model)


def prepare(out: Path, rig_seed: int, cameras: int, kind: str, seed: int, seconds: float, jobs: int, fresh: bool,
            progress: bool) -> tuple[Rig, Path, Path, dict]:
    """Renders (or reuses) the videos and the truth log of one run."""
    rig = rig_for(rig_seed, cameras)
    d = out / "video" / f"rig{rig_seed}_{kind}_{seed}"
    stamp = d / "done.json"
    rig_path, truth = d / "rig.yaml", d / "truth.lcm"
    d.mkdir(parents=True, exist_ok=True)
    probe = d / "rig.new.yaml"
    rig.write(probe)
    rig_sha = hashlib.sha1(probe.read_bytes()).hexdigest()
    if stamp.exists() and not fresh:
        info = json.loads(stamp.read_text())
        old = info.get("rig_sha") or (rig_path.exists() and hashlib.sha1(rig_path.read_bytes()).hexdigest())
        if old == rig_sha:  # videos of another rig (the generator changed) are not reused
            probe.unlink()
            return rig, rig_path, truth, info
    probe.replace(rig_path)
    scene = scene_for(kind, rig, seed, seconds)
    w = LogWriter(str(truth))
    write_truth(w, scene)
    w.close()
    t0 = time.perf_counter()
    res = write_video(d, scene, seed, jobs=jobs, progress=progress)
    info = {"people": len(scene.people), "frames": scene.n_frames, "lead_in_frames": res[0]["lead_in_frames"],
            "render_s": round(time.perf_counter() - t0, 1),
            "render_ms_per_frame": round(float(np.mean([r["render_ms_per_frame"] for r in res])), 1),
            "rig_sha": rig_sha}
    stamp.write_text(json.dumps(info))
    return rig, rig_path, truth, info


def detect(rig: Rig, d: Path, det: Path, lead: int, extra: list[str], progress: bool, fresh: bool = False) -> float:
    """mvtrack-detect over every camera's video; video frame i is stamped as scene frame i - lead.

    The detections are reused when the same detector binary already ran with the same arguments on
    the same videos (a stamp beside them records the binary's hash, the arguments and the videos'
    stamp); --fresh runs it again. Returns the detection time (of the run that made them)."""
    start = T0_UTIME - int(round(lead * 1e6 / rig.frame_rate))
    args = ["--rig", str(d / "rig.yaml"), "--out", f"file://{det}?mode=w", "--start-utime", str(start), "--masks",
            "--status-s", "0", "--quiet"]
    for c in rig.cameras:
        args += ["--video", f"{c.name}={d / (c.name + '.avi')}"]
    stamp = d / "detections.json"
    videos = d / "done.json"  # the videos' stamp (prepare); without it, never reuse
    key = {"detector_sha": hashlib.sha1(DETECT.read_bytes()).hexdigest(), "args": args + extra,
           "videos": videos.read_text() if videos.exists() else None}
    if not fresh and key["videos"] is not None and det.exists() and stamp.exists():
        old = json.loads(stamp.read_text())
        if old.get("key") == key:
            return float(old["detect_s"])
    stamp.unlink(missing_ok=True)
    t0 = time.perf_counter()
    rc = run_detect(args + extra, progress=progress, desc=f"detect {d.name}")
    if rc != 0:
        raise RuntimeError(f"mvtrack-detect failed ({rc}) on {d}")
    dt = time.perf_counter() - t0
    stamp.write_text(json.dumps({"key": key, "detect_s": round(dt, 1)}))
    return dt


def camera_view(path: Path, rig: Rig, d: Path, det: Path, trk: Path, k: int, frame: int, lead: int, title: str) -> None:
    """One camera's frame with its detections (boxes, head points) and the tracks reprojected."""
    import cv2
    import lcm

    from .lcmio import mt

    cam = rig.cameras[k]
    cap = cv2.VideoCapture(str(d / f"{cam.name}.avi"))
    cap.set(cv2.CAP_PROP_POS_FRAMES, frame + lead)
    ok, img = cap.read()
    if not ok:
        return
    dets, tracks = [], []
    for ev in lcm.EventLog(str(det), "r"):
        if ev.channel == f"DETECTIONS_{cam.name}":
            m = mt.camera_frame_t.decode(ev.data)
            if m.frame == frame + lead:
                dets = list(m.detections)
                break
    utime = T0_UTIME + int(round(frame * 1e6 / rig.frame_rate))
    for ev in lcm.EventLog(str(trk), "r"):
        if ev.channel == "TRACKS":
            m = mt.tracks_t.decode(ev.data)
            if abs(m.utime - utime) < 20000:
                tracks = [t for t in m.tracks if t.status in (2, 3)]
                break
    for x in dets:
        x0, y0, x1, y1 = (int(round(v)) for v in x.bbox)
        cv2.rectangle(img, (x0, y0), (x1, y1), (0, 255, 255), 1)
        cv2.drawMarker(img, (int(round(x.u)), int(round(x.v))), (0, 0, 255), cv2.MARKER_CROSS, 12, 2)
    for t in tracks:
        p = np.array(t.position, float)
        if cam.depth(p)[0] <= 0.1:
            continue
        uv = cam.project(p)[0]
        foot = cam.project(np.array([p[0], p[1], 0.0]))[0]
        col = tuple(int(255 * c) for c in plots._id_colour(t.id)[:3][::-1])
        cv2.line(img, (int(uv[0]), int(uv[1])), (int(foot[0]), int(foot[1])), col, 2)
        cv2.circle(img, (int(uv[0]), int(uv[1])), 6, col, 2)
        cv2.putText(img, str(t.id), (int(uv[0]) + 8, int(uv[1]) - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.6, col, 2)
    cv2.putText(img, title, (8, cam.height - 10), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
    cv2.imwrite(str(path), img)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack pixels", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("out/pixels"), help="output folder (default out/pixels)")
    ap.add_argument("--scenes", nargs="+", default=["crowd", "interaction"], choices=["crowd", "interaction"])
    ap.add_argument("--seeds", type=int, default=3, help="seeds per scene and rig (default 3)")
    ap.add_argument("--rigs", type=int, nargs="+", default=[0, 11],
                    help="rig seeds: 0 the smart room, N a random room and rig (default 0 11)")
    ap.add_argument("--cameras", type=int, default=5, help="cameras of a random rig (default 5)")
    ap.add_argument("--modes", nargs="+", default=["pkf", "pf"], help="mvtrackd modes (default pkf pf)")
    ap.add_argument("--seconds", type=float, default=60.0, help="crowd length (default 60)")
    ap.add_argument("--detect-args", default="", metavar="ARGS", help="more mvtrack-detect options")
    ap.add_argument("--daemon-args", default="", metavar="ARGS", help="more mvtrackd options for every run")
    ap.add_argument("--jobs", type=int, default=2, help="processes rendering cameras (default 2)")
    ap.add_argument("--fresh", action="store_true",
                    help="render the videos and run the detector again even when their outputs are current")
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    a = ap.parse_args(argv)
    if not DAEMON.exists():
        ap.error(f"{DAEMON} not built: run tools/mvtrack build")
    if a.seeds < 1 or a.seconds <= 0 or not 2 <= a.cameras <= 16:
        ap.error("--seeds >= 1, --seconds > 0, --cameras 2..16")
    a.out.mkdir(parents=True, exist_ok=True)
    progress = not a.quiet and sys.stderr.isatty()
    rows = []
    for rig_seed in a.rigs:
        for kind in a.scenes:
            for seed in range(1, a.seeds + 1):
                rig, rig_path, truth, info = prepare(a.out, rig_seed, a.cameras, kind, seed, a.seconds, a.jobs, a.fresh,
                                                     progress)
                d = rig_path.parent
                det = d / "detections.lcm"
                det_s = detect(rig, d, det, info["lead_in_frames"], shlex.split(a.detect_args), progress, a.fresh)
                gt = read_log(str(truth), lambda c: c == "GROUND_TRUTH")
                for mode in a.modes:
                    trk = d / f"tracks_{mode}.lcm"
                    run_daemon(rig_path, det, trk, mode, Q, shlex.split(a.daemon_args))
                    tr = read_log(str(trk), lambda c: c in ("TRACKS", "MVTRACK_STATUS"))
                    r = as_dict(clear_mot(pair_frames(gt, tr, rig.frame_rate)))
                    r.update(head_stats(gt, tr))
                    r.update(rig=rig_seed, scene=kind, seed=seed, mode=mode, detect_s=round(det_s, 1), **info)
                    rows.append(r)
                    name = f"rig{rig_seed}_{kind}_{seed}_{mode}"
                    ttl = (f"rig {rig_seed} {kind} seed {seed}, {mode} from pixels: MOTA {r['mota']:.3f}, "
                           f"MOTP {r['motp_mm']:.0f} mm, {r['id_switches']} switches")
                    if not a.no_plots:
                        plots.zenithal_multi(a.out / f"{name}_zenithal.png", rig, gt, tr, ttl)
                        if seed == 1:
                            camera_view(a.out / f"{name}_view.png", rig, d, det, trk, 0, min(info["frames"] - 1, 200),
                                        info["lead_in_frames"], ttl)
                    print(f"{name}: MOTA {r['mota']:.3f} MOTP {r['motp_mm']:.1f} mm switches {r['id_switches']} "
                          f"IDF1 {r['idf1']:.3f} FP {r['false_positives']} miss {r['misses']}", flush=True)
    (a.out / "summary.json").write_text(json.dumps(rows, indent=1, default=float))
    lines = ["| rig | scene | mode | MOTA | MOTP (mm) | ID switches | IDF1 | FP | misses |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for rig_seed in a.rigs:
        for kind in a.scenes:
            for mode in a.modes:
                rs = sorted((r for r in rows if r["rig"] == rig_seed and r["scene"] == kind and r["mode"] == mode),
                            key=lambda r: r["seed"])
                if not rs:
                    continue
                j = lambda key, fmt: " / ".join(fmt.format(r[key]) for r in rs)  # noqa: E731
                lines.append(f"| {'smart room' if rig_seed == 0 else f'random {rig_seed}'} | {kind} | {mode} | "
                             f"{j('mota', '{:.3f}')} | {j('motp_mm', '{:.0f}')} | {j('id_switches', '{}')} | "
                             f"{j('idf1', '{:.2f}')} | {j('false_positives', '{}')} | {j('misses', '{}')} |")
    (a.out / "pixels.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"wrote {a.out / 'pixels.md'}, summary.json and plots in {a.out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
