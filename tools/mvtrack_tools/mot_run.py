"""Many people: run the issue's acceptance scenes through mvtrackd and score them.

  crowd        60 s, 5 people entering and leaving (2 more enter late), 10 % misses, 0.3 false
               alarms per camera per frame, merged blobs, camera 1 absent for 4 s, +-3 ms jitter
  interaction  400 frames, two people meeting and talking close (the PKF paper's Experiment 2)

For each scene and seed: simulate (tools/mvtrack simulate), run mvtrackd offline on the log, score
CLEAR MOT and OSPA (mvtrack_tools.mot), write a zenithal plot and a timeline per run. Prints a
table and writes summary.json.

    tools/mvtrack mot [--seeds 3] [--daemon-args ARGS] [--out out/mot]
"""
from __future__ import annotations

import argparse
import json
import shlex
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .progress import bar as progress_bar
from . import plots
from .experiment1 import run_daemon
from .lcmio import LogWriter, read_log
from .mot import as_dict, clear_mot, covered_only, pair_frames, views_per_person
from .paths import DAEMON
from .rig import random_rig, smartroom
from .simulate import build_multi, write_multi

Q = np.array([0.5, 0.5, 0.05])  # the daemon's default white-acceleration density


def rig_of(a: argparse.Namespace):
    """The run's rig: the smart room, or with --rig-seed N a random room and rig (random_rig:
    room size, camera placement, intrinsics, distortion, image sizes) with --cameras cameras."""
    seed = getattr(a, "rig_seed", 0)
    if not seed:
        return smartroom()
    return random_rig(np.random.default_rng(seed), getattr(a, "cameras", 5))


def run_scenes(ap: argparse.ArgumentParser, a: argparse.Namespace, run_one, *args) -> list[dict]:
    """Checks the common options (--out, --seeds, --scenes, --jobs), writes the rig, then runs
    run_one(out, scene, seed, *args) for every scene and seed in parallel with a progress bar."""
    if not DAEMON.exists():
        ap.error(f"{DAEMON} not built: run tools/mvtrack build")
    if a.seeds < 1:
        ap.error("--seeds must be >= 1")
    (a.out / "logs").mkdir(parents=True, exist_ok=True)
    rig_of(a).write(a.out / "rig.yaml")
    jobs = [(k, s) for k in a.scenes for s in range(1, a.seeds + 1)]
    rows: list[dict] = []
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        futs = [ex.submit(run_one, a.out, k, s, *args) for k, s in jobs]
        for f in progress_bar(futs, desc="scenes", unit="scene"):
            rows.extend(f.result())
    return rows


def run_one(out: Path, kind: str, seed: int, plot: bool, extra: list[str] | None = None,
            rig=None) -> list[dict]:
    rig = rig or smartroom()
    rig_path = out / "rig.yaml"
    scene, frames = build_multi(kind, rig, seed)
    log = out / "logs" / f"{kind}_{seed}.lcm"
    w = LogWriter(str(log))
    write_multi(w, scene, frames, progress=False)
    w.close()
    sc = read_log(str(log), lambda c: c == "GROUND_TRUTH")
    trk_path = out / "logs" / f"{kind}_{seed}_tracks.lcm"
    run_daemon(rig_path, log, trk_path, "pkf", Q, extra or [])
    tr = read_log(str(trk_path), lambda c: c in ("TRACKS", "MVTRACK_STATUS"))
    fr = pair_frames(sc, tr, rig.frame_rate)
    r = as_dict(clear_mot(fr))
    views = views_per_person(rig, fr)
    n_gt = sum(len(v) for v in views)
    cov = clear_mot(covered_only(fr, views))
    r.update(gt_under_2_views_pct=100.0 * sum(int((v < 2).sum()) for v in views) / max(1, n_gt),
             mota_covered=cov.mota, id_switches_covered=cov.id_switches, idf1_covered=cov.idf1)
    st = tr.status[-1] if tr.status else None
    if st is not None:
        r.update(births=st.births, fragments=st.fragments)
    r.update(scene=kind, seed=seed, **{f"sim_{k}": v for k, v in scene.info.items()})
    if plot:
        name = f"{kind}_{seed}"
        ttl = (f"{kind} seed {seed}: MOTA {r['mota']:.3f}, MOTP {r['motp_mm']:.0f} mm, "
               f"{r['id_switches']} ID switches")
        plots.zenithal_multi(out / f"{name}_zenithal.png", rig, sc, tr, ttl)
        plots.timeline(out / f"{name}_timeline.png", sc, tr, rig.frame_rate, ttl)
    return [r]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack mot", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("out/mot"), help="output folder (default out/mot)")
    ap.add_argument("--seeds", type=int, default=3, help="seeds per scene (default 3)")
    ap.add_argument("--scenes", nargs="+", default=["crowd", "interaction"], choices=["crowd", "interaction"])
    ap.add_argument("--daemon-args", default="", metavar="ARGS",
                    help="more mvtrackd options for every run, e.g. \"--mode kf\"")
    ap.add_argument("--rig-seed", type=int, default=0, metavar="N",
                    help="0 (default): the smart room; N: a random room and rig from seed N")
    ap.add_argument("--cameras", type=int, default=5, help="cameras of a --rig-seed rig (default 5)")
    ap.add_argument("--jobs", type=int, default=2, help="runs in parallel (default 2)")
    ap.add_argument("--no-plots", action="store_true")
    a = ap.parse_args(argv)
    out = a.out
    if a.cameras < 2 or a.cameras > 8:
        ap.error("--cameras must be 2..8")
    rows = run_scenes(ap, a, run_one, not a.no_plots, shlex.split(a.daemon_args), rig_of(a))
    rows.sort(key=lambda r: (r["scene"], r["seed"]))
    (out / "summary.json").write_text(json.dumps(rows, indent=1, default=float))
    print(f"{'scene':12s} {'seed':>4s} {'MOTA':>6s} {'MOTP mm':>8s} {'IDsw':>5s} {'IDF1':>6s} "
          f"{'FP':>5s} {'miss':>5s} {'OSPA m':>7s} {'ids':>4s} {'<2cam%':>6s} {'MOTA2':>6s}")
    for r in rows:
        print(f"{r['scene']:12s} {r['seed']:4d} {r['mota']:6.3f} {r['motp_mm']:8.1f} "
              f"{r['id_switches']:5d} {r['idf1']:6.3f} {r['false_positives']:5d} {r['misses']:5d} "
              f"{r['ospa_m']:7.3f} {r['track_ids']:4d} {r['gt_under_2_views_pct']:6.1f} {r['mota_covered']:6.3f}")
    print("<2cam%: ground-truth person-frames in fewer than 2 cameras' pictures; MOTA2: MOTA with those as "
          "don't-care (no 3D position without two views)")
    print(f"wrote {out / 'summary.json'} and plots in {out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
