"""tools/mvtrack view in a real browser: Debian's Chromium (headless, through chromedriver) loads the
page on a replayed scene and the daemon's tracks of it; what a person would see is checked against
/state.json and the TRACKS messages."""
from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from mvtrack_tools.crowd import DetectorModel
from mvtrack_tools.lcmio import LogWriter, read_log
from mvtrack_tools.rig import smartroom
from mvtrack_tools.simulate import build_multi, write_multi

REPO = Path(__file__).resolve().parents[2]
OUT = REPO / "out" / "view-test"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _get(url: str):
    with urllib.request.urlopen(url, timeout=5) as r:
        return json.loads(r.read())


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    from mvtrack_tools.paths import DAEMON

    d = tmp_path_factory.mktemp("view")
    rig = smartroom()
    rig.write(d / "rig.yaml")
    # camera 1 (cam1) sends nothing during [6, 10) s
    sc, frames = build_multi("crowd", rig, 2, seconds=16.0, model=DetectorModel(dropout_s=6.0, dropout_len_s=4.0))
    w = LogWriter(str(d / "scene.lcm"))
    write_multi(w, sc, frames, progress=False)
    w.close()
    r = subprocess.run([str(DAEMON), "--rig", str(d / "rig.yaml"), "--in", f"file://{d / 'scene.lcm'}?speed=0",
                        "--out", f"file://{d / 'tracks.lcm'}?mode=w"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return d


@pytest.fixture(scope="module")
def view(scene):
    port = _free_port()
    env = dict(os.environ, PYTHONPATH=str(REPO / "tools"))
    p = subprocess.Popen([sys.executable, "-m", "mvtrack_tools.view", "--in", f"file://{scene / 'scene.lcm'}",
                          "--in", f"file://{scene / 'tracks.lcm'}", "--rig", str(scene / "rig.yaml"),
                          "--port", str(port)], env=env, stderr=subprocess.PIPE, text=True)
    url = f"http://127.0.0.1:{port}"
    for _ in range(100):
        try:
            _get(url + "/state.json")
            break
        except OSError:
            if p.poll() is not None:
                pytest.fail(f"view exited: {p.stderr.read()}")
            time.sleep(0.1)
    yield url
    p.terminate()
    p.wait(timeout=10)


def _seek(driver, t_s: float, page_state_js: str):
    """Pauses the replay at t_s seconds from the log's start, through the page's own socket, and
    waits until the page shows that moment."""
    driver.execute_script("""
        const r = last.replay;
        ws.send(JSON.stringify({cmd: 'pause'}));
        ws.send(JSON.stringify({cmd: 'seek', t: r.t0 + arguments[0] * 1e6}));""", t_s)
    for _ in range(100):
        st = driver.execute_script(page_state_js)
        if st["replayPaused"] and st["clock"].startswith(f"{t_s:.1f} /"):
            time.sleep(0.5)  # one more push after the seek has settled
            return driver.execute_script(page_state_js)
        time.sleep(0.1)
    pytest.fail(f"the page never showed {t_s} s: {st}")


@pytest.mark.browser
def test_view_in_chromium_shows_the_tracks_and_a_stopped_camera(scene, view):
    from mvtrack_tools.view import PAGE_STATE_JS, headless_chromium

    tracks = read_log(str(scene / "tracks.lcm"), lambda c: c == "TRACKS").tracks
    driver = headless_chromium()
    try:
        driver.get(view + "/")
        for _ in range(100):
            if driver.execute_script("return typeof last !== 'undefined' && last !== null && last.replay !== null"):
                break
            time.sleep(0.1)
        else:
            pytest.fail("the page never drew a state")
        OUT.mkdir(parents=True, exist_ok=True)
        for t_s, stopped in ((8.0, ["cam1"]), (13.0, [])):
            st = _seek(driver, t_s, PAGE_STATE_JS)
            state = _get(view + "/state.json")
            ids = sorted(t["id"] for t in state["tracks"])
            # what is drawn on the floor plan is the state the server holds ...
            assert sorted(st["labels"]) == ids, (st, ids)
            # ... which is the daemon's TRACKS message of that moment
            assert sorted(t.id for t in tracks[state["utime"]]) == ids
            assert len(ids) >= 3, ids
            assert st["tiles"] == ["cam0", "cam1", "cam2", "cam3", "cam4"], st
            # a camera that stopped sending is shown stopped, in its tile and in the health table
            assert st["stoppedTiles"] == stopped and st["stoppedRows"] == stopped, (t_s, st)
            driver.save_screenshot(str(OUT / f"view_{t_s:.0f}s.png"))
    finally:
        driver.quit()


def test_view_refuses_bad_input(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(REPO / "tools"))
    for args, why in ((["--in", f"file://{tmp_path / 'none.lcm'}"], "no such log"),
                      (["--rig", str(tmp_path / "none.yaml")], "no such rig file"),
                      (["--in", "udpm://239.255.76.67:7667"], "ttl=0"),
                      (["--rate", "100"], "--rate")):
        r = subprocess.run([sys.executable, "-m", "mvtrack_tools.view", *args], env=env, capture_output=True,
                           text=True, timeout=60)
        assert r.returncode == 2, (args, r.stderr)
        assert why in r.stderr and len(r.stderr.strip().splitlines()) == 1, (args, r.stderr)
