"""Simulate a scene seen by a camera rig: writes an LCM log (or publishes live at 25 fps) with
DETECTIONS_<camera> and GROUND_TRUTH, and the rig file.

    python -m mvtrack_tools.simulate exp1 --var 100 --occlusion --seconds 60 --seed 1 \
        --rig out/rig.yaml --log out/scene.lcm
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from .lcmio import LivePublisher, LogWriter, camera_frame, ground_truth
from .rig import Rig, smartroom
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


def write_scene(sink, rig: Rig, states: np.ndarray, dets, var_px2: float, progress: bool = True,
                frame_order_seed: int = 0) -> None:
    dt_us = int(round(1e6 / rig.frame_rate))
    rng = np.random.default_rng(frame_order_seed)
    sd = float(np.sqrt(var_px2))
    for f in tqdm(range(len(states)), desc="frames", unit="fr", disable=not progress, leave=False):
        utime = T0_UTIME + f * dt_us
        sink.write(utime, "GROUND_TRUTH", ground_truth(utime, f, [1], states[f, :3][None]))
        for k in rng.permutation(len(rig.cameras)):  # cameras arrive in any order
            cam = rig.cameras[k]
            msg = camera_frame(utime, f, cam, [(u, v) for (u, v, _) in dets[f][k]], sd)
            sink.write(utime, f"DETECTIONS_{cam.name}", msg)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack simulate", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", choices=["exp1"], help="exp1: the PKF paper's Experiment 1 (one person)")
    ap.add_argument("--var", type=float, default=100.0, help="pixel noise variance sigma^2, px^2 (default 100)")
    ap.add_argument("--occlusion", action="store_true", help="add the paper's occlusion bursts (10 frames, P=0.3)")
    ap.add_argument("--seconds", type=float, default=60.0, help="scene length (default 60)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rig", type=Path, required=True, help="rig file to write (CONTRACT section 2)")
    ap.add_argument("--log", type=Path, help="LCM log to write")
    ap.add_argument("--live", metavar="URL", help="publish live at real time on this LCM URL (ttl=0)")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    a = ap.parse_args(argv)
    if (a.log is None) == (a.live is None):
        ap.error("give exactly one of --log and --live")
    if a.var <= 0 or a.seconds <= 0:
        ap.error("--var and --seconds must be positive")
    rig = smartroom()
    a.rig.parent.mkdir(parents=True, exist_ok=True)
    rig.write(a.rig)
    _, states, dets = experiment1(rig, a.seconds, a.var, a.occlusion, a.seed)
    if a.log is not None:
        a.log.parent.mkdir(parents=True, exist_ok=True)
        sink = LogWriter(str(a.log))
    else:
        sink = LivePublisher(a.live)
    try:
        write_scene(sink, rig, states, dets, a.var, progress=not a.quiet)
    except KeyboardInterrupt:
        pass
    finally:
        sink.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
