"""tools/mvtrack doctor: a test set-up with one fault per camera, live over LCM (ttl=0), each named."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from mvtrack_tools.lcmio import camera_frame
from mvtrack_tools.rig import smartroom

REPO = Path(__file__).resolve().parents[2]
URL = "udpm://239.255.76.67:7691?ttl=0"


def publish(rig, seconds: float) -> None:
    """cam0 and cam3 sound; 'door' not in the rig; cam1 at 12 fps; cam2 at 640x480; cam3's clock
    60 ms ahead... of cam0's and cam4's, which are exact; so cam3 is the clock fault."""
    import lcm

    lc = lcm.LCM(URL)
    cams = {c.name: c for c in rig.cameras}
    door = type("C", (), {"name": "door", "width": 768, "height": 576})()
    small = type("C", (), {"name": "cam2", "width": 640, "height": 480})()
    plan = [(cams["cam0"], 25.0, 0.0), (door, 25.0, 0.0), (cams["cam1"], 12.0, 0.0), (small, 25.0, 0.0),
            (cams["cam3"], 25.0, 60.0), (cams["cam4"], 25.0, 0.0)]
    t0 = time.time()
    nxt = [t0] * len(plan)
    frame = [0] * len(plan)
    while time.time() - t0 < seconds:
        now = time.time()
        for i, (cam, fps, ahead_ms) in enumerate(plan):
            if now >= nxt[i]:
                m = camera_frame(int(now * 1e6 + ahead_ms * 1e3), frame[i], cam, [(300.0, 200.0)], 2.0)
                lc.publish(f"DETECTIONS_{cam.name}", m.encode())
                frame[i] += 1
                nxt[i] += 1.0 / fps
        time.sleep(0.002)


def test_doctor_names_each_fault(tmp_path):
    rig = smartroom()
    rig.write(tmp_path / "rig.yaml")
    env = dict(os.environ, PYTHONPATH=str(REPO / "tools"))
    p = subprocess.Popen([sys.executable, "-m", "mvtrack_tools.doctor", "--rig", str(tmp_path / "rig.yaml"),
                          "--in", URL, "--seconds", "4", "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=env)
    time.sleep(0.5)
    t = threading.Thread(target=publish, args=(rig, 3.8))
    t.start()
    out, err = p.communicate(timeout=30)
    t.join()
    assert p.returncode == 1, err
    r = json.loads(out.strip().splitlines()[-1])
    faults = r["faults"]
    by_cam = {f.split(":")[0]: f for f in faults}
    assert "door" in by_cam and "no camera of that name" in by_cam["door"], faults
    assert "cam1" in by_cam and "frames a second" in by_cam["cam1"], faults
    assert "cam2" in by_cam and "640x480" in by_cam["cam2"], faults
    assert "cam3" in by_cam and "clock +6" in by_cam["cam3"], faults
    assert "cam0" not in by_cam and "cam4" not in by_cam, faults
    assert len(faults) == 4, faults
    rows = {x["camera"]: x for x in r["cameras"]}
    assert abs(rows["cam3"]["clock_vs_others_ms"] - 60.0) < 5.0, rows["cam3"]
    assert abs(rows["cam1"]["rate_hz"] - 12.0) < 1.0, rows["cam1"]


def test_doctor_refuses_bad_input(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(REPO / "tools"))
    for args in (["--rig", str(tmp_path / "missing.yaml")],
                 ["--rig", str(tmp_path / "missing.yaml"), "--in", "udpm://239.255.76.67:7691"],
                 ["--rig", str(tmp_path / "x.yaml"), "--seconds", "0"]):
        r = subprocess.run([sys.executable, "-m", "mvtrack_tools.doctor", *args], capture_output=True, text=True,
                           env=env, timeout=30)
        assert r.returncode == 2, (args, r.stderr)
        assert len(r.stderr.strip().splitlines()) == 1, r.stderr
