"""A flood of false alarms: does mvtrackd confirm a ghost?

The scene (the daemon test's, tests/python/test_multi.py): the SmartRoom, two people standing at
(1.5, 1.5) and (4.0, 3.5) with heads at 1.7 and 1.8 m, 2 px detection noise, 6 s at 25 fps; from
frame 50 every camera also reports --false-alarms uniform random points per frame, shuffled among
the true detections (no box beyond the head-topped one every simulated detection has, no colour).
Over MVT_MAX_DETECTIONS (64) the daemon keeps each track's nearest detection first.

For every seed: the confirmed tracks that are not the two people (ghosts), the frames with a false
positive, identity switches and misses (CLEAR MOT at 0.5 m). Writes OUT/flood.md and summary.json.

    tools/mvtrack flood [--seeds 4-19] [--false-alarms 300] [--daemon-args "--motion cv"] [--out out/flood]
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

from .lcmio import LogWriter, camera_frame, ground_truth, read_log
from .mot import clear_mot, pair_frames
from .paths import DAEMON, REPO
from .progress import bar
from .rig import smartroom
from .simulate import T0_UTIME

PEOPLE = np.array([[1.5, 1.5, 1.7], [4.0, 3.5, 1.8]])
FRAMES, FLOOD_FROM = 150, 50


def write_flood_log(path: Path, rig, seed: int, n_false: int) -> None:
    """The flood scene's log (GROUND_TRUTH and DETECTIONS_<camera>) for one seed."""
    rng = np.random.default_rng(seed)
    w = LogWriter(str(path))
    for f in range(FRAMES):
        u = T0_UTIME + f * 40000
        w.write(u, "GROUND_TRUTH", ground_truth(u, f, [1, 2], PEOPLE))
        for cam in rig.cameras:
            dets = [tuple(p) for p in cam.project(PEOPLE) + rng.normal(0, 2, (2, 2))]
            if f >= FLOOD_FROM:
                dets += [(rng.uniform(0, cam.width - 1), rng.uniform(0, cam.height - 1)) for _ in range(n_false)]
                rng.shuffle(dets)
            w.write(u, f"DETECTIONS_{cam.name}", camera_frame(u, f, cam, dets, 2.0))
    w.close()


def score(log: Path, tracks: Path, frame_rate: float) -> dict:
    """Ghosts (confirmed or coasting identities other than the people's 1 and 2) and CLEAR MOT."""
    tr = read_log(str(tracks), lambda c: c in ("TRACKS", "MVTRACK_STATUS"))
    gt = read_log(str(log), lambda c: c == "GROUND_TRUTH")
    res = clear_mot(pair_frames(gt, tr, frame_rate))
    ghosts = {t.id for v in tr.tracks.values() for t in v if t.status in (2, 3)} - {1, 2}
    return {"ghosts": len(ghosts), "false_positive_frames": int(res.false_positives),
            "id_switches": int(res.id_switches), "misses": int(res.misses),
            "max_tracks": max((len(v) for v in tr.tracks.values()), default=0),
            "rejected_over_capacity": int(tr.status[-1].rejected_over_capacity) if tr.status else 0}


def seeds_of(text: str) -> list[int]:
    """'4-19' or '3,6,8' or '5'."""
    out: list[int] = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b) + 1)) if b else [int(a)]
    return out


def main(argv: list[str] | None = None) -> int:
    head, _, rest = __doc__.partition("\n\n")
    ap = argparse.ArgumentParser(prog="mvtrack flood", description=head,
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=rest)
    ap.add_argument("--seeds", default="4-19", help="seeds: 4-19, 3,6,8 or 5 (default 4-19)")
    ap.add_argument("--false-alarms", type=int, default=300, help="per camera and frame (default 300)")
    ap.add_argument("--daemon-args", default="", help="more mvtrackd options, e.g. '--motion cv'")
    ap.add_argument("--out", type=Path, default=REPO / "out/flood", help="output folder (default out/flood)")
    a = ap.parse_args(argv)
    try:
        seeds = seeds_of(a.seeds)
    except ValueError:
        ap.error(f"--seeds: cannot read '{a.seeds}' (e.g. 4-19 or 3,6,8)")
    if a.false_alarms < 0:
        ap.error("--false-alarms must be >= 0")
    if not DAEMON.exists():
        print(f"mvtrack flood: {DAEMON} is not built (tools/mvtrack build)", file=sys.stderr)
        return 2
    a.out.mkdir(parents=True, exist_ok=True)
    rig = smartroom()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        rp = Path(tmp) / "rig.yaml"
        rig.write(rp)
        for seed in bar(seeds, desc="floods", unit="seed"):
            log, trk = Path(tmp) / f"flood_{seed}.lcm", Path(tmp) / f"tracks_{seed}.lcm"
            write_flood_log(log, rig, seed, a.false_alarms)
            r = subprocess.run([str(DAEMON), "--rig", str(rp), "--in", f"file://{log}?speed=0", "--out",
                                f"file://{trk}?mode=w"] + shlex.split(a.daemon_args), capture_output=True, text=True)
            if r.returncode != 0:
                print(f"mvtrack flood: mvtrackd failed on seed {seed}: {r.stderr.strip()}", file=sys.stderr)
                return 2
            rows.append({"seed": seed, "false_alarms": a.false_alarms, **score(log, trk, rig.frame_rate)})
    lines = [f"Flood of {a.false_alarms} false alarms per camera and frame for {(FRAMES - FLOOD_FROM) / 25:.0f} s, "
             f"daemon args '{a.daemon_args}'", "",
             "| seed | ghosts | false-positive frames | ID switches | misses |", "| --- | --- | --- | --- | --- |"]
    lines += [f"| {r['seed']} | {r['ghosts']} | {r['false_positive_frames']} | {r['id_switches']} | {r['misses']} |"
              for r in rows]
    lines += ["", f"ghosts in all: {sum(r['ghosts'] for r in rows)} over {len(rows)} floods"]
    (a.out / "flood.md").write_text("\n".join(lines) + "\n")
    (a.out / "summary.json").write_text(json.dumps(rows, indent=1))
    print("\n".join(lines))
    print(f"wrote {a.out / 'flood.md'} and summary.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
