"""The mvtrack demo: a 5-camera room simulated live over LCM, tracked by mvtrackd, recorded with
lcm-logger, evaluated against ground truth, plotted.

1. writes the SmartRoom rig and starts `mvtrackd --rig RIG --in URL` (live, udpm with ttl=0);
2. starts `lcm-logger` on the same URL;
3. publishes one person walking (Experiment 1, sigma^2 = 100 px^2, with occlusion bursts) at
   25 fps in real time: DETECTIONS_cam0..cam4 and GROUND_TRUTH;
4. stops the daemon (SIGTERM: it finishes the frame in hand) and the logger;
5. evaluates the live TRACKS against GROUND_TRUTH, replays the recorded detections offline
   through the other modes for comparison, and writes plots.

With --pixels, the same from camera pixels: renders the crowd scene (people entering, walking,
leaving) as one MJPEG video per camera (reused when present), replays the five videos through
`mvtrack-detect --realtime` live over LCM into `mvtrackd`, records with lcm-logger, scores CLEAR
MOT against the ground truth and draws the tracks from above and one camera's view.
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


class LiveDaemon:
    """mvtrackd live on url and lcm-logger recording it to log_path, for the length of a with block;
    then SIGTERM to the daemon (it finishes the frame in hand) and SIGINT to the logger. Raises
    SystemExit when the daemon does not start or does not exit with 0."""

    def __init__(self, rig_path: Path, url: str, out: Path, log_path: Path, extra: list[str] | None = None):
        self.cmd = [str(DAEMON), "--rig", str(rig_path), "--in", url] + (extra or [])
        self.url, self.log_path, self.stderr = url, log_path, out / "mvtrackd.stderr"

    def __enter__(self) -> "LiveDaemon":
        self.daemon = subprocess.Popen(self.cmd, stderr=open(self.stderr, "w"))
        self.logger = subprocess.Popen([lcm_logger(), "-f", "-l", self.url, str(self.log_path)],
                                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(0.7)
        if self.daemon.poll() is not None:
            self.logger.send_signal(signal.SIGINT)
            raise SystemExit(f"[demo] mvtrackd exited early; see {self.stderr}")
        return self

    def __exit__(self, *exc) -> None:
        self.daemon.send_signal(signal.SIGTERM)
        rc = self.daemon.wait(timeout=10)
        time.sleep(0.3)
        self.logger.send_signal(signal.SIGINT)
        self.logger.wait(timeout=10)
        if rc != 0 and exc[0] is None:
            raise SystemExit(f"[demo] mvtrackd exited with {rc}; see {self.stderr}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack demo", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=30.0, help="length of the live scene (default 30)")
    ap.add_argument("--var", type=float, default=100.0, help="pixel noise variance, px^2 (default 100)")
    ap.add_argument("--no-occlusion", action="store_true", help="Gaussian noise only")
    ap.add_argument("--url", default="udpm://239.255.76.67:7667?ttl=0", help="LCM URL (must carry ttl=0)")
    ap.add_argument("--out", type=Path, default=Path("out/demo"), help="output folder (default out/demo)")
    ap.add_argument("--seed", type=int, default=4)
    ap.add_argument("--pixels", action="store_true",
                    help="from camera pixels: rendered video -> mvtrack-detect live -> mvtrackd (crowd scene)")
    a = ap.parse_args(argv)
    if "ttl=0" not in a.url:
        ap.error("the LCM URL must carry ttl=0 (traffic stays on this host)")
    if not DAEMON.exists():
        ap.error(f"{DAEMON} not built: run tools/mvtrack build")
    out = a.out
    out.mkdir(parents=True, exist_ok=True)
    if a.pixels:
        return pixels_demo(a, out)
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
    with LiveDaemon(rig_path, a.url, out, log_path, []):  # the defaults: the IMM, nothing learnt
        pub = LivePublisher(a.url)
        t0 = time.monotonic()
        write_scene(pub, rig, states, dets, a.var, progress=True)
        wall = time.monotonic() - t0
        time.sleep(0.5)

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
    print(f"        (pkf: the defaults; the others with q learnt from ground truth: {qs})")
    print("        mode           mean (mm)  std (mm)  matched")
    for mode in ("pkf", "pkf-learnt-q", "pkf-paper", "pkf-centred", "kf"):
        tr = out / f"replay_{mode}.lcm"
        run_daemon(rig_path, log_path, tr, mode, q)
        rr = evaluate_single(str(log_path), str(tr), rig, None)
        print(f"        {mode:<14} {rr.mean_mm:7.1f} {rr.std_mm:9.1f}  {rr.matched}/{rr.frames}")
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


def pixels_demo(a: argparse.Namespace, out: Path) -> int:
    """Rendered crowd video -> mvtrack-detect --realtime (live, LCM) -> mvtrackd -> CLEAR MOT."""
    from .detect import DETECT
    from .mot import as_dict, clear_mot, pair_frames
    from .pixels import camera_view, prepare
    from .simulate import T0_UTIME

    if not DETECT.exists():
        raise SystemExit(f"[demo] {DETECT} not built: run tools/mvtrack build")
    print(f"[demo] rendering the crowd scene, {a.seconds:g} s, as video from 5 cameras (reused when present)")
    rig, rig_path, truth, info = prepare(out, 0, 5, "crowd", a.seed, a.seconds, 2, False, sys.stderr.isatty())
    d = rig_path.parent
    lead = info["lead_in_frames"]
    start = T0_UTIME - int(round(lead * 1e6 / rig.frame_rate))
    log_path = out / "live_pixels.lcm"
    print(f"[demo] mvtrackd live on {a.url}; mvtrack-detect replays the 5 videos at 25 fps "
          f"({info['people']} people, {(info['frames'] + lead) / rig.frame_rate:.0f} s with the empty-room start)")
    with LiveDaemon(rig_path, a.url, out, log_path):
        cmd = [str(DETECT), "--rig", str(rig_path), "--out", a.url, "--start-utime", str(start), "--realtime",
               "--status-s", "10"]
        for c in rig.cameras:
            cmd += ["--video", f"{c.name}={d / (c.name + '.avi')}"]
        t0 = time.monotonic()
        det = subprocess.run(cmd)
        wall = time.monotonic() - t0
        time.sleep(0.5)
    if det.returncode != 0:
        raise SystemExit(f"[demo] mvtrack-detect exited with {det.returncode}")
    live = read_log(str(log_path), lambda c: c in ("TRACKS", "MVTRACK_STATUS"))
    gt = read_log(str(truth), lambda c: c == "GROUND_TRUTH")
    r = as_dict(clear_mot(pair_frames(gt, live, rig.frame_rate)))
    n = len(live.tracks)
    print(f"[demo] {wall:.1f} s live; mvtrackd published {n} TRACKS messages ({n / max(wall, 1e-9):.1f} Hz)")
    st = live.status[-1] if live.status else None
    if st is not None:
        print(f"[demo] daemon status: {st.frames_processed} frames, latency p50 {st.latency_ms_p50:.3f} ms / "
              f"p99 {st.latency_ms_p99:.3f} ms")
    print(f"[demo] from pixels, live PKF: MOTA {r['mota']:.3f}, MOTP {r['motp_mm']:.0f} mm, {r['id_switches']} "
          f"identity switches, IDF1 {r['idf1']:.3f}, {r['false_positives']} false positives, {r['misses']} misses")
    ttl = f"Live demo from pixels: MOTA {r['mota']:.3f}, MOTP {r['motp_mm']:.0f} mm, {r['id_switches']} switches"
    plots.zenithal_multi(out / "pixels_zenithal.png", rig, gt, live, ttl)
    camera_view(out / "pixels_view.png", rig, d, log_path, log_path, 0, min(info["frames"] - 1, 300), lead, ttl)
    for p in ("pixels_zenithal.png", "pixels_view.png"):
        print(f"[demo] plot: {out / p}")
    print(f"[demo] recorded log (detections and tracks): {log_path}; videos in {d}")
    return 0 if r["mota"] >= 0.8 else 1


if __name__ == "__main__":
    sys.exit(main())
