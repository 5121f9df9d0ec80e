"""Watch mvtrack's LCM traffic in lcm-spy, and check that every mvtrack channel decodes there.

    tools/mvtrack spy [--url URL]        lcm-spy with the mvtrack types jar on its classpath
    tools/mvtrack spy --check [--out DIR] [--seconds 10]

--check (needs no display: it starts its own Xvfb): renders a short two-person scene with masks
and colour, runs mvtrackd live in pf mode publishing particles, replays the scene live, records
everything with lcm-logger and watches it in lcm-spy; then takes a screenshot of lcm-spy
(DIR/spy.png) and decodes every recorded event the way lcm-spy does (type looked up by
fingerprint on the same classpath, tools/java/SpyCheck.java). Exit 0 when every channel
(DETECTIONS_*, GROUND_TRUTH, TRACKS, MVTRACK_STATUS, MVTRACK_PARTICLES) was seen and every event
decoded.
"""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from .paths import BUILD, DAEMON, REPO
from .replay import DEFAULT_URL, replay, safe_url, start_recorder, stop_recorder

EXPECTED = ["GROUND_TRUTH", "TRACKS", "MVTRACK_STATUS", "MVTRACK_PARTICLES"]


def classpath() -> str:
    import lcm
    lcm_jar = Path(lcm.__file__).resolve().parents[1] / "share" / "java" / "lcm.jar"
    types_jar = BUILD / "lcmtypes" / "mvtrack_lcmtypes.jar"
    for j in (lcm_jar, types_jar):
        if not j.exists():
            raise SystemExit(f"{j} missing (tools/mvtrack build makes the types jar; lcm.jar comes with lcm)")
    extra = [str(j) for j in sorted(lcm_jar.parent.glob("*.jar")) if j.name not in ("lcm.jar", "lcm-sources.jar")]
    return ":".join([str(lcm_jar), str(types_jar)] + extra)  # + jchart2d etc., which lcm.spy classes need


def spy_exe() -> str:
    exe = Path(sys.executable).parent / "lcm-spy"
    if not exe.exists():
        raise SystemExit("lcm-spy not found (it comes with the lcm Python package: tools/mvtrack setup)")
    return str(exe)


def free_display() -> int:
    for n in range(90 + os.getpid() % 50, 400):
        if not Path(f"/tmp/.X11-unix/X{n}").exists() and not Path(f"/tmp/.X{n}-lock").exists():
            return n
    raise SystemExit("no free X display number")


def make_scene(out: Path, frames: int, seed: int) -> tuple[Path, Path]:
    from .lcmio import LogWriter
    from .render import Renderer, write_rendered
    from .rig import smartroom
    from .crowd import DetectorModel, interaction_scene
    rig = smartroom()
    rig_path = out / "rig.yaml"
    rig.write(rig_path)
    scene = interaction_scene(rig, frames, seed, DetectorModel(dropout_cam=None))
    log = out / "scene.lcm"
    w = LogWriter(str(log))
    write_rendered(w, scene, Renderer(rig, seed=seed), seed, progress=False)
    w.close()
    return rig_path, log


def check(out: Path, seconds: float, port: int) -> int:
    out.mkdir(parents=True, exist_ok=True)
    cp = classpath()
    print("spy: rendering a two-person scene with masks and colour", file=sys.stderr)
    rig_path, scene = make_scene(out, int(seconds * 25) + 25, 1)
    url = safe_url(f"udpm://239.255.76.67:{port}?ttl=0")
    disp = free_display()
    env = dict(os.environ, DISPLAY=f":{disp}", CLASSPATH=cp)
    procs: list[subprocess.Popen] = []
    recorded = out / "recorded.lcm"
    try:
        procs.append(subprocess.Popen(["Xvfb", f":{disp}", "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        for _ in range(50):
            if Path(f"/tmp/.X11-unix/X{disp}").exists():
                break
            time.sleep(0.1)
        else:
            raise SystemExit("Xvfb did not start")
        spy_log = open(out / "lcm-spy.log", "w")
        procs.append(subprocess.Popen([spy_exe(), f"--lcm-url={url}"], env=env, stdout=spy_log, stderr=spy_log))
        daemon = subprocess.Popen([str(DAEMON), "--rig", str(rig_path), "--in", url, "--mode", "pf",
                                   "--publish-particles", "100"], stderr=subprocess.PIPE, text=True)
        recorder = start_recorder(recorded, url)
        time.sleep(3.0)  # lcm-spy's JVM and window come up
        print(f"spy: replaying the scene live for {seconds:g} s on {url}", file=sys.stderr)
        import threading
        player = threading.Thread(target=replay, args=(scene, url), kwargs=dict(stop_after_s=seconds, progress=False))
        player.start()
        time.sleep(max(seconds - 2.0, 1.0))  # screenshot while the traffic flows (rates shown)
        shot = out / "spy.png"
        r = subprocess.run(["java", str(REPO / "tools" / "java" / "Screenshot.java"), str(shot)], env=env,
                           capture_output=True, text=True)
        player.join()
        time.sleep(1.0)
        if r.returncode != 0:
            print(r.stderr, file=sys.stderr)
            return 1
        print(f"spy: screenshot {shot}", file=sys.stderr)
        daemon.send_signal(signal.SIGTERM)
        _, derr = daemon.communicate(timeout=10)
        stop_recorder(recorder)
        if daemon.returncode != 0:
            print(derr, file=sys.stderr)
            return 1
    finally:
        for p in reversed(procs):
            p.terminate()
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()
    r = subprocess.run(["java", "-cp", cp, str(REPO / "tools" / "java" / "SpyCheck.java"), str(recorded)],
                       capture_output=True, text=True)
    print(r.stdout.strip())
    seen = {line.split()[0] for line in r.stdout.splitlines() if line and not line.startswith("Found")}
    missing = [c for c in EXPECTED if c not in seen] + ([] if any(c.startswith("DETECTIONS_") for c in seen)
                                                        else ["DETECTIONS_*"])
    if missing:
        print(f"spy: FAIL, channels never seen: {', '.join(missing)}")
        return 1
    if r.returncode != 0:
        print("spy: FAIL, undecoded events (above)")
        return 1
    print(f"spy: PASS, every channel decoded by the classes lcm-spy uses; screenshot {out / 'spy.png'}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tools/mvtrack spy", description=__doc__.split("\n\n")[0])
    ap.add_argument("--url", default=DEFAULT_URL, help=f"LCM URL to watch (default {DEFAULT_URL})")
    ap.add_argument("--check", action="store_true", help="headless self-test under Xvfb (see above)")
    ap.add_argument("--out", type=Path, default=REPO / "out" / "spy", help="--check: output folder")
    ap.add_argument("--seconds", type=float, default=10.0, help="--check: live replay length (default 10)")
    ap.add_argument("--port", type=int, default=7300 + os.getpid() % 300, help="--check: private multicast port")
    a = ap.parse_args(argv)
    if not DAEMON.exists():
        ap.error(f"{DAEMON} not built (tools/mvtrack build)")
    if a.check:
        return check(a.out, a.seconds, a.port)
    env = dict(os.environ, CLASSPATH=classpath())
    os.execve(spy_exe(), [spy_exe(), f"--lcm-url={safe_url(a.url)}"], env)
    return 0


if __name__ == "__main__":
    sys.exit(main())
