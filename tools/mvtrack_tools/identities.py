"""Who had which identity, and how each identity switch came about.

Matches TRACKS to GROUND_TRUTH as tools/mvtrack mot does (CLEAR MOT, 0.5 m, motmetrics) and prints
every identity switch with its kind, then per person the runs of identities that covered them:

  born      the new track was under 1 s old: the person's track was lost (deleted, or it drifted
            off) and a birth, an identity recovery or a re-acquisition picked them up
  took      the new track was following another person less than 1 s before: a swap or a
            takeover in a knot of people (the other person's run shows the same track)
  passed    the new track followed another person longer ago: that person's identity, kept
            for recovery or re-acquisition after their track was lost, went to this person
  returned  the new track was this person's before (they lost it for a while and got it back)
  ghost     the new track was older but had followed nobody (a ghost that drifted onto them)

    tools/mvtrack identities --scene SCENE.lcm --tracks TRACKS.lcm [--json]

SCENE.lcm holds GROUND_TRUTH (a simulated or rendered scene, or tools/mvtrack pixels' truth.lcm);
TRACKS.lcm holds mvtrackd's TRACKS (both may be the same log).
"""
from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from dataclasses import asdict

from .lcmio import read_log
from .mot import SWITCH_KINDS, clear_mot, identity_switches, pair_frames


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack identities", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True, help="log with GROUND_TRUTH")
    ap.add_argument("--tracks", required=True, help="log with TRACKS")
    ap.add_argument("--frame-rate", type=float, default=25.0, help="ground truth's frame rate (default 25)")
    ap.add_argument("--json", action="store_true", help="print JSON instead of text")
    a = ap.parse_args(argv)
    try:
        scene = read_log(a.scene, lambda c: c == "GROUND_TRUTH")
        tracks = read_log(a.tracks, lambda c: c == "TRACKS")
    except (OSError, ValueError) as e:
        ap.error(f"cannot read the logs: {e}")
    if not scene.gt:
        ap.error(f"{a.scene} holds no GROUND_TRUTH")
    if not tracks.tracks:
        ap.error(f"{a.tracks} holds no TRACKS")
    frames = pair_frames(scene, tracks, a.frame_rate)
    switches, runs = identity_switches(frames)
    m = clear_mot(frames)
    if a.json:
        json.dump({"switches": [asdict(s) for s in switches], "runs": {str(k): v for k, v in runs.items()},
                   "mota": m.mota, "idf1": m.idf1, "id_switches": m.id_switches, "false_positives": m.false_positives,
                   "misses": m.misses}, sys.stdout, indent=1)
        print()
        return 0
    t0 = frames[0].utime
    for s in switches:
        was = f" (it was following person {s.was_following})" if s.was_following is not None else ""
        print(f"{(s.utime - t0) * 1e-6:7.2f} s  person {s.person}: track {s.old_track} -> {s.new_track}  {s.kind}{was}")
    kinds = Counter(s.kind for s in switches)
    print(f"{len(switches)} switches: " + ", ".join(f"{kinds[k]} {k}" for k in SWITCH_KINDS))
    for o, r in sorted(runs.items()):
        print(f"person {o}: " + " ".join(f"{'missed' if h is None else h}[{a_}-{b}]" for h, a_, b in r))
    print(f"MOTA {m.mota:.3f}, IDF1 {m.idf1:.3f}, {m.id_switches} switches")
    return 0


if __name__ == "__main__":
    sys.exit(main())
