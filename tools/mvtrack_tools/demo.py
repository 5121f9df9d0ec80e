"""The mvtrack demo: a 5-camera room simulated live over LCM, tracked by mvtrackd, recorded with
lcm-logger, evaluated against ground truth, plotted.

1. writes the SmartRoom rig and starts `mvtrackd --rig RIG --in URL` (live, udpm with ttl=0);
2. starts `lcm-logger` on the same URL;
3. publishes one person walking (Experiment 1, sigma^2 = 100 px^2, with occlusion bursts) at
   25 fps in real time: DETECTIONS_cam0..cam4 and GROUND_TRUTH;
4. stops the daemon (SIGTERM: it finishes the frame in hand) and the logger;
5. evaluates the live TRACKS against GROUND_TRUTH, replays the recorded detections offline
   through the other modes for comparison, and writes plots.
"""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import sysconfig
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from . import plots
from .evaluate import evaluate_single, learn_q, match_single
from .experiment1 import run_daemon
from .lcmio import LivePublisher, read_log
from .paths import DAEMON
from .rig import smartroom
from .simulate import experiment1, write_scene


def lcm_logger() -> str:
    exe = Path(sysconfig.get_paths()["purelib"]) / "bin" / "lcm-logger"
    return str(exe) if exe.exists() else "lcm-logger"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack demo", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=30.0, help="length of the live scene (default 30)")
    ap.add_argument("--var", type=float, default=100.0, help="pixel noise variance, px^2 (default 100)")
    ap.add_argument("--no-occlusion", action="store_true", help="Gaussian noise only")
    ap.add_argument("--url", default="udpm://239.255.76.67:7667?ttl=0", help="LCM URL (must carry ttl=0)")
    ap.add_argument("--out", type=Path, default=Path("out/demo"), help="output folder (default out/demo)")
    ap.add_argument("--seed", type=int, default=4)
    a = ap.parse_args(argv)
    if "ttl=0" not in a.url:
        ap.error("the LCM URL must carry ttl=0 (traffic stays on this host)")
    if not DAEMON.exists():
        ap.error(f"{DAEMON} not built: run tools/mvtrack build")
    out = a.out
    out.mkdir(parents=True, exist_ok=True)
    rig = smartroom()
    rig_path = out / "rig.yaml"
    rig.write(rig_path)
    _, train, _ = experiment1(rig, 60.0, a.var, False, seed=999)
    q = learn_q(train[:, :3], 1.0 / rig.frame_rate)
    qs = ",".join(f"{x:.6g}" for x in q)
    occ = not a.no_occlusion
    _, states, dets = experiment1(rig, a.seconds, a.var, occ, a.seed)
    log_path = out / "live.lcm"

    print(f"[demo] mvtrackd live on {a.url}, 5 cameras, {a.seconds:g} s at 25 fps, sigma^2 = {a.var:g} px^2"
          f"{', occlusion bursts' if occ else ''}")
    daemon = subprocess.Popen([str(DAEMON), "--rig", str(rig_path), "--in", a.url, "--q", qs],
                              stderr=open(out / "mvtrackd.stderr", "w"))
    logger = subprocess.Popen([lcm_logger(), "-f", "-l", a.url, str(log_path)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    try:
        time.sleep(0.7)
        if daemon.poll() is not None:
            raise SystemExit(f"[demo] mvtrackd exited early; see {out / 'mvtrackd.stderr'}")
        pub = LivePublisher(a.url)
        t0 = time.monotonic()
        write_scene(pub, rig, states, dets, a.var, progress=True)
        wall = time.monotonic() - t0
        time.sleep(0.5)
    finally:
        daemon.send_signal(signal.SIGTERM)
        rc = daemon.wait(timeout=10)
        time.sleep(0.3)
        logger.send_signal(signal.SIGINT)
        logger.wait(timeout=10)
    if rc != 0:
        raise SystemExit(f"[demo] mvtrackd exited with {rc}; see {out / 'mvtrackd.stderr'}")

    live = read_log(str(log_path))
    n_tracks = len(live.tracks)
    r = evaluate_single(str(log_path), str(log_path), rig, None)
    st = live.status[-1] if live.status else None
    print(f"[demo] published {len(states)} frames in {wall:.1f} s; mvtrackd published {n_tracks} TRACKS messages "
          f"({n_tracks / max(wall, 1e-9):.1f} Hz)")
    if st is not None:
        print(f"[demo] daemon status: {st.frames_processed} frames, {st.frame_sets_complete} complete sets, "
              f"{st.frame_sets_partial} partial, processing p50 {st.proc_ms_p50:.3f} ms / p99 {st.proc_ms_p99:.3f} ms, "
              f"latency p50 {st.latency_ms_p50:.3f} ms / p99 {st.latency_ms_p99:.3f} ms (last 512 frame sets)")
    print(f"[demo] live PKF: {r.matched}/{r.frames} frames matched within 0.5 m, 3D error mean {r.mean_mm:.1f} mm, "
          f"std {r.std_mm:.1f} mm, RMSE {r.rmse_mm:.1f} mm")

    # the same recorded detections, offline, through every mode
    sc = read_log(str(log_path), lambda c: c == "GROUND_TRUTH")
    paths = {}
    print("[demo] offline replay of the recorded detections:")
    print("        mode         mean (mm)  std (mm)  matched")
    for mode in ("pkf", "pkf-paper", "pkf-centred", "kf"):
        tr = out / f"replay_{mode}.lcm"
        run_daemon(rig_path, log_path, tr, mode, q)
        rr = evaluate_single(str(log_path), str(tr), rig, None)
        print(f"        {mode:<12} {rr.mean_mm:9.1f} {rr.std_mm:9.1f}  {rr.matched}/{rr.frames}")
        gt, est, _ = match_single(read_log(str(tr), lambda c: c == "TRACKS"), sc)
        paths[mode] = est
    gt, est_live, utimes = match_single(live, sc)
    plots.zenithal(out / "zenithal.png", rig, gt, {"pkf": est_live},
                   f"Live demo: {a.seconds:g} s, sigma^2 = {a.var:g} px^2{', occlusions' if occ else ''}")
    plots.zenithal(out / "zenithal_modes.png", rig, gt, paths, "Offline replay of the demo: all modes")
    t = (utimes - utimes[0]) * 1e-6
    plots.error_over_time(out / "error_over_time.png", t,
                          {m: np.linalg.norm(p - gt, axis=1) * 1e3 for m, p in paths.items()}, None,
                          "3D error of each mode on the demo's detections")
    for p in ("zenithal.png", "zenithal_modes.png", "error_over_time.png"):
        print(f"[demo] plot: {out / p}")
    print(f"[demo] recorded log: {log_path}; replay it offline with: build/bin/mvtrackd --rig {rig_path} "
          f"--in 'file://{log_path.resolve()}?speed=0' --out 'file:///tmp/replay.lcm?mode=w'")
    ok = r.matched >= 0.9 * r.frames
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
