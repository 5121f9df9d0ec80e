"""Bodies in pieces: the PKF on the connected components of rendered masks, per fragmentation model.

For every fragmentation model, scene and seed: render the scene (tools/mvtrack simulate --render
--fragments MODEL: the masks' connected components are the blobs, a body in several pieces, the
masks and hue/saturation sent), run mvtrackd on the log, and score CLEAR MOT (0.5 m) with the
identity switches per minute, and the column ghosts: confirmed tracks standing in a person's
column (within 0.3 m horizontally) at least 0.3 m below that person's head, counted per frame.

Models (tools/mvtrack_tools/render.py): holes (low-frequency holes, the renderer's default),
rows (also, every body cut on a few fixed bands of image rows per camera), camouflage (also, a
person's trousers or shirt match the background).

    tools/mvtrack fragments [--models holes rows camouflage] [--scenes interaction crowd] [--seeds 3]
                            [--daemon-args "--mode kf"] [--out out/fragments] [--json]
"""
from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np

from .lcmio import read_log
from .mot import as_dict, clear_mot, pair_frames
from .paths import BUILD, REPO

COLUMN_M = 0.3
BELOW_M = 0.3


def column_ghosts(frames) -> int:
    """Confirmed tracks in a person's column, BELOW_M or more under their head (track-frames)."""
    n = 0
    for fs in frames:
        if not len(fs.gt_pos) or not len(fs.hyp_pos):
            continue
        d = np.linalg.norm(fs.gt_pos[:, None, :2] - fs.hyp_pos[None, :, :2], axis=2)
        below = fs.hyp_pos[None, :, 2] < fs.gt_pos[:, None, 2] - BELOW_M
        n += int(((d < COLUMN_M) & below).any(axis=0).sum())
    return n


def run(out: Path, model: str, scene: str, seed: int, daemon_args: list[str]) -> dict:
    rig = out / "rig.yaml"
    log = out / "logs" / f"{scene}_{model}_{seed}.lcm"
    log.parent.mkdir(parents=True, exist_ok=True)
    if not log.exists():
        subprocess.run([sys.executable, "-m", "mvtrack_tools.simulate", scene, "--render", "--fragments", model,
                        "--seed", str(seed), "--rig", str(rig), "--log", str(log), "--quiet"], check=True,
                       cwd=REPO / "tools")
    trk = out / "tracks" / f"{scene}_{model}_{seed}.lcm"
    trk.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run([str(BUILD / "bin" / "mvtrackd"), "--rig", str(rig), "--in", f"file://{log}?speed=0",
                    "--out", f"file://{trk}?mode=w"] + daemon_args, check=True, stderr=subprocess.DEVNULL)
    frames = pair_frames(read_log(str(log)), read_log(str(trk)))
    r = as_dict(clear_mot(frames))
    minutes = len(frames) / 25.0 / 60.0
    r.update(model=model, scene=scene, seed=seed, column_ghosts=column_ghosts(frames),
             switches_per_min=r["id_switches"] / minutes if minutes > 0 else float("nan"))
    return r


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack fragments", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", nargs="+", default=["holes", "rows", "camouflage"],
                    choices=["holes", "rows", "camouflage"])
    ap.add_argument("--scenes", nargs="+", default=["interaction", "crowd"], choices=["interaction", "crowd"])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--daemon-args", default="", metavar="ARGS", help="more mvtrackd options")
    ap.add_argument("--out", type=Path, default=Path("out/fragments"))
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    a.out = a.out.resolve()
    rows = []
    for model in a.models:
        for scene in a.scenes:
            for seed in range(1, a.seeds + 1):
                r = run(a.out, model, scene, seed, shlex.split(a.daemon_args))
                rows.append(r)
                if not a.json:
                    print(f"{model:10s} {scene:11s} {seed}  MOTA {r['mota']:.3f}  switches {r['id_switches']} "
                          f"({r['switches_per_min']:.2f}/min)  IDF1 {r['idf1']:.3f}  FP {r['false_positives']}  "
                          f"misses {r['misses']}  column ghosts {r['column_ghosts']}", flush=True)
    (a.out / "summary.json").write_text(json.dumps(rows, indent=1))
    if a.json:
        print(json.dumps(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
