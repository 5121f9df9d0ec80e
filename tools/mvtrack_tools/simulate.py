"""Simulate a scene seen by a camera rig: writes an LCM log (or publishes live at 25 fps) with
DETECTIONS_<camera> and GROUND_TRUTH, and the rig file.

Scenes:
  exp1         the PKF paper's Experiment 1: one person, Gaussian pixel noise, optional occlusions
  crowd        5 people entering and leaving (2 more enter late), crossing and pausing
  interaction  the paper's Experiment 2 situation: two people meet, talk close, walk around, 400 frames

crowd and interaction use a detector with misses, false alarms, merged blobs, capture jitter and
(crowd) one camera dropping out; see the options. With --render they are rendered instead: each
camera sees coloured 3D bodies (head, torso, legs), furniture, shadows and clutter; its message
carries the motion mask (1/4 resolution), hue/saturation and the blobs of the mask's connected
components (the input of mvtrackd --mode pf; misses, merges and false alarms come from the pixels).

    tools/mvtrack simulate exp1 --var 100 --occlusion --seconds 60 --rig out/rig.yaml --log out/scene.lcm
    tools/mvtrack simulate crowd --seconds 60 --seed 2 --rig out/rig.yaml --log out/crowd.lcm
    tools/mvtrack simulate interaction --render --rig out/rig.yaml --log out/interaction_pf.lcm
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from .progress import bar as progress_bar
from .lcmio import LivePublisher, LogWriter, camera_frame, ground_truth
from .rig import Rig, random_rig, smartroom
from .crowd import DetectorModel, Scene, body_box, crowd_scene, detect, interaction_scene
from .scenes import Occlusions, WalkModel, head_detections

T0_UTIME = 1_700_000_000_000_000


def experiment1(rig: Rig, seconds: float, var_px2: float, occlusion: bool, seed: int):
    """Ground-truth states (n, 6) and per-frame detections of Experiment 1."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / rig.frame_rate
    n = int(round(seconds * rig.frame_rate))
    model = WalkModel.for_room(rig.volume_min, rig.volume_max)
    states = model.sample(rng, n, dt, rig.volume_min, rig.volume_max)
    dets = head_detections(rig, states[:, :3], var_px2, rng, Occlusions() if occlusion else None)
    return model, states, dets


def with_boxes(cam, head: np.ndarray, dets, sd: float = 0.0, edge_rng: np.random.Generator | None = None) -> list[tuple]:
    """The person's blob box: the body under the head, cut by the picture. The box's edges are other
    pixels than the head point, each measured with the same pixel noise sd of its own (drawn from
    edge_rng); a burst's displaced detection (an occlusion, a bad segmentation) carries its box with
    it."""
    box = body_box(cam, head)
    if box is None:
        return [(u, v) for (u, v, _) in dets]
    true_uv = cam.project(head[None])[0]
    out = []
    for (u, v, is_true) in dets:
        du, dv = (0.0, 0.0) if is_true else (u - true_uv[0], v - true_uv[1])
        e = edge_rng.standard_normal(4) * sd if edge_rng is not None and sd > 0 else np.zeros(4)
        b = (max(0.0, box[0] + du + e[0]), max(0.0, box[1] + dv + e[1]), min(cam.width - 1.0, box[2] + du + e[2]),
             min(cam.height - 1.0, box[3] + dv + e[3]))
        out.append((u, v, b) if b[2] > b[0] and b[3] > b[1] else (u, v))
    return out


def write_scene(sink, rig: Rig, states: np.ndarray, dets, var_px2: float, progress: bool = True,
                frame_order_seed: int = 0) -> None:
    dt_us = int(round(1e6 / rig.frame_rate))
    rng = np.random.default_rng(frame_order_seed)
    # the boxes' edge noise: its own generator, seeded by the scene (the cameras' order is not)
    edge_rng = np.random.default_rng(np.frombuffer(np.ascontiguousarray(states[:2, :3], dtype=np.float64).tobytes(),
                                                   dtype=np.uint32))
    sd = float(np.sqrt(var_px2))
    for f in progress_bar(range(len(states)), desc="frames", unit="fr", enabled=progress, leave=False):
        utime = T0_UTIME + f * dt_us
        sink.write(utime, "GROUND_TRUTH", ground_truth(utime, f, [1], states[f, :3][None]))
        for k in rng.permutation(len(rig.cameras)):  # cameras arrive in any order
            cam = rig.cameras[k]
            msg = camera_frame(utime, f, cam, with_boxes(cam, states[f, :3], dets[f][k], sd, edge_rng), sd)
            sink.write(utime, f"DETECTIONS_{cam.name}", msg)


def write_multi(sink, scene: Scene, frames, progress: bool = True) -> None:
    """Writes a multi-person scene: GROUND_TRUTH at the nominal frame time, each camera's message
    at its own (jittered) capture time, cameras in random order, nothing from a dropped camera."""
    rig = scene.rig
    dt_us = int(round(1e6 / rig.frame_rate))
    rng = np.random.default_rng(len(frames))
    for f in progress_bar(range(scene.n_frames), desc="frames", unit="fr", enabled=progress, leave=False):
        utime = T0_UTIME + f * dt_us
        present = scene.present(f)
        pos = np.array([p.pos[f - p.f0] for p in present]).reshape(-1, 3)
        sink.write(utime, "GROUND_TRUTH", ground_truth(utime, f, [p.gid for p in present], pos))
        for k in rng.permutation(len(rig.cameras)):
            cf = frames[f][k]
            if cf is None:
                continue
            cam = rig.cameras[k]
            msg = camera_frame(utime + cf.utime_offset_us, f, cam, [(u, v, box) for (u, v, box, _) in cf.dets],
                               scene.model.sigma_px)
            sink.write(utime + cf.utime_offset_us, f"DETECTIONS_{cam.name}", msg)


def build_multi(kind: str, rig: Rig, seed: int, seconds: float | None = None, frames: int | None = None,
                model: DetectorModel | None = None):
    """A crowd or interaction scene and its per-camera detections."""
    if kind == "crowd":
        scene = crowd_scene(rig, seconds or 60.0, seed, model=model)
    else:
        scene = interaction_scene(rig, frames or 400, seed, model=model)
    return scene, detect(scene, np.random.default_rng(seed + 7919))


class _Buffer:
    """Holds rendered messages so that a live run publishes them at the scene's pace (rendering is
    slower than real time)."""

    def __init__(self):
        self.events = []

    def write(self, utime, channel, msg):
        self.events.append((utime, channel, msg))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack simulate", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", choices=["exp1", "crowd", "interaction"])
    ap.add_argument("--var", type=float, default=100.0, help="exp1: pixel noise variance sigma^2, px^2 (default 100)")
    ap.add_argument("--occlusion", action="store_true", help="exp1: add the paper's occlusion bursts (10 frames, P=0.3)")
    ap.add_argument("--seconds", type=float, default=60.0, help="exp1, crowd: scene length (default 60)")
    ap.add_argument("--frames", type=int, default=400, help="interaction: frames (default 400)")
    ap.add_argument("--sigma", type=float, default=4.0, help="crowd, interaction: pixel noise sigma (default 4)")
    ap.add_argument("--miss", type=float, default=0.10, help="crowd, interaction: miss probability (default 0.1)")
    ap.add_argument("--fa", type=float, default=0.3, help="crowd, interaction: false alarms per camera per frame (0.3)")
    ap.add_argument("--no-merge", action="store_true", help="crowd, interaction: never merge touching blobs")
    ap.add_argument("--jitter-ms", type=float, default=3.0, help="crowd, interaction: capture jitter, +-ms (default 3)")
    ap.add_argument("--dropout-cam", type=int, default=1, help="crowd: camera that drops out (-1: none; default 1)")
    ap.add_argument("--dropout-s", type=float, default=20.0, help="crowd: dropout start (default 20 s), lasting 4 s")
    ap.add_argument("--render", action="store_true",
                    help="crowd, interaction: render masks, hue/saturation and blobs from them (for --mode pf); "
                         "--sigma, --miss, --fa and --no-merge do not apply (the pixels decide)")
    ap.add_argument("--no-colour", action="store_true", help="with --render: masks without hue/saturation (MS)")
    ap.add_argument("--mask-scale", type=int, default=4, help="with --render: image pixels per mask pixel (default 4)")
    ap.add_argument("--fragments", choices=["holes", "rows", "camouflage"], default="holes",
                    help="with --render: how bodies break into pieces: holes (default), rows (every body also cut "
                         "on a few fixed bands of image rows per camera), camouflage (a person's trousers or "
                         "shirt match the background)")
    ap.add_argument("--video", type=Path, metavar="DIR",
                    help="crowd, interaction: render RGB video per camera (DIR/<camera>.avi, MJPEG) through the "
                         "rig's lens model, with GROUND_TRUTH in --log; run tools/mvtrack detect on it")
    ap.add_argument("--rig-seed", type=int, default=0, metavar="N",
                    help="0 (default): the smart room; N: a random room and rig from seed N (--cameras)")
    ap.add_argument("--cameras", type=int, default=5, help="cameras of a --rig-seed rig (default 5)")
    ap.add_argument("--jobs", type=int, default=2, help="--video: cameras rendered in parallel (default 2)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rig", type=Path, required=True, help="rig file to write (docs/interfaces.md section 2)")
    ap.add_argument("--log", type=Path, help="LCM log to write")
    ap.add_argument("--live", metavar="URL", help="publish live at real time on this LCM URL (ttl=0)")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    a = ap.parse_args(argv)
    if (a.log is None) == (a.live is None):
        ap.error("give exactly one of --log and --live")
    if a.var <= 0 or a.seconds <= 0 or a.frames <= 0 or a.sigma <= 0 or not 0 <= a.miss < 1 or a.fa < 0 \
            or a.jitter_ms < 0:
        ap.error("--var, --seconds, --frames, --sigma must be positive; --miss in [0, 1); --fa, --jitter-ms >= 0")
    if a.render and a.scene == "exp1":
        ap.error("--render applies to crowd and interaction")
    if not 1 <= a.mask_scale <= 16:
        ap.error("--mask-scale must be in 1..16")
    if a.video is not None and (a.scene == "exp1" or a.render or a.live is not None):
        ap.error("--video applies to crowd and interaction, with --log (ground truth), without --render")
    if not 2 <= a.cameras <= 16:
        ap.error("--cameras must be 2..16")
    rig = smartroom() if not a.rig_seed else random_rig(np.random.default_rng(a.rig_seed), a.cameras)
    a.rig.parent.mkdir(parents=True, exist_ok=True)
    rig.write(a.rig)
    if a.log is not None:
        a.log.parent.mkdir(parents=True, exist_ok=True)
        sink = LogWriter(str(a.log))
    else:
        sink = LivePublisher(a.live)
    try:
        if a.scene == "exp1":
            _, states, dets = experiment1(rig, a.seconds, a.var, a.occlusion, a.seed)
            write_scene(sink, rig, states, dets, a.var, progress=not a.quiet)
        else:
            model = DetectorModel(a.sigma, a.miss, a.fa, not a.no_merge, a.jitter_ms,
                                  None if a.dropout_cam < 0 or a.scene == "interaction" else a.dropout_cam,
                                  a.dropout_s, 4.0)
            if a.video is not None:
                from .video import write_truth, write_video

                if a.scene == "crowd":
                    scene = crowd_scene(rig, a.seconds, a.seed, model=model)
                else:
                    scene = interaction_scene(rig, a.frames, a.seed, model=model)
                write_truth(sink, scene)
                res = write_video(a.video, scene, a.seed, jobs=a.jobs, progress=not a.quiet)
                scene.info.update(videos=len(res), render_ms_per_frame=round(float(np.mean(
                    [r["render_ms_per_frame"] for r in res])), 1))
            elif a.render:
                from .render import MaskModel, Renderer, write_rendered

                scene = crowd_scene(rig, a.seconds, a.seed, model=model) if a.scene == "crowd" else \
                    interaction_scene(rig, a.frames, a.seed, model=model)
                buf = _Buffer() if a.live is not None else sink
                stats = write_rendered(buf, scene, Renderer(rig, MaskModel(scale=a.mask_scale, fragments=a.fragments), seed=a.seed), a.seed,
                                       colour=not a.no_colour, progress=not a.quiet)
                if a.live is not None:
                    for ev in progress_bar(buf.events, desc="publish", unit="msg", enabled=not a.quiet):
                        sink.write(*ev)
                scene.info.update(stats)
            else:
                scene, frames = build_multi(a.scene, rig, a.seed, a.seconds, a.frames, model)
                write_multi(sink, scene, frames, progress=not a.quiet)
            if not a.quiet:
                print(f"{a.scene}: {len(scene.people)} people, {scene.n_frames} frames; detector: "
                      + ", ".join(f"{k} {v}" for k, v in scene.info.items()), file=sys.stderr)
    except KeyboardInterrupt:
        pass
    finally:
        sink.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
