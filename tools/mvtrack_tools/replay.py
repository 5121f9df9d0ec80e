"""Record live LCM traffic to a log, and replay a log live.

    tools/mvtrack record OUT.lcm [--url URL] [--channels REGEX] [--seconds S]
    tools/mvtrack replay LOG.lcm [--url URL] [--speed X] [--channels REGEX] [--loop]

record runs LCM's own lcm-logger (from the lcm package) on the URL until Ctrl-C or --seconds.
replay publishes every event of a log at its recorded pace (scaled by --speed; 0 = as fast as
possible) on the URL, with LCM's Python API; a progress bar shows how far it is. Multicast URLs
must carry ttl=0 (nothing leaves this machine); a URL without recv_buf_size gets 4 MB so that
foreground masks (tens of kB a message, many UDP fragments) are not dropped on receipt.
"""
from __future__ import annotations

from .progress import bar as progress_bar

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import lcm

DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"


def safe_url(url: str) -> str:
    """Refuses multicast without ttl=0; adds a receive buffer large enough for mask messages."""
    if url.startswith("udpm://"):
        if not re.search(r"[?&]ttl=0(&|$)", url):
            raise SystemExit(f"refusing {url}: multicast URLs must carry ttl=0 (nothing leaves this machine)")
        if "recv_buf_size=" not in url:
            url += "&recv_buf_size=4194304"
    return url


def logger_exe() -> str:
    exe = shutil.which("lcm-logger") or str(Path(sys.executable).parent / "lcm-logger")
    if not os.path.exists(exe):
        raise SystemExit("lcm-logger not found (it comes with the lcm Python package: tools/mvtrack setup)")
    return exe


def start_recorder(out: Path, url: str, channels: str = ".*") -> subprocess.Popen:
    return subprocess.Popen([logger_exe(), "--force", f"--lcm-url={safe_url(url)}", f"--channel={channels}",
                             "--quiet", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def stop_recorder(p: subprocess.Popen) -> None:
    p.send_signal(signal.SIGINT)
    try:
        p.wait(timeout=5)
    except subprocess.TimeoutExpired:
        p.kill()


def replay(log: Path, url: str, speed: float = 1.0, channels: str = ".*", loop: bool = False,
           stop_after_s: float | None = None, progress: bool = True) -> int:
    """Publishes log's events on url at speed x their recorded pace. Returns events published."""
    lc = lcm.LCM(safe_url(url))
    want = re.compile(channels)
    total = sum(1 for _ in lcm.EventLog(str(log), "r"))
    if total == 0:
        raise SystemExit(f"{log}: no events")
    sent = 0
    t_start = time.monotonic()
    bar = None
    if progress:
                bar = progress_bar(total=total, unit="ev", desc=f"replay {log.name}", leave=False)
    while True:
        t0_wall, t0_log = None, None
        for ev in lcm.EventLog(str(log), "r"):
            if stop_after_s is not None and time.monotonic() - t_start >= stop_after_s:
                loop = False
                break
            if bar is not None:
                bar.update(1)
            if not want.fullmatch(ev.channel):
                continue
            if speed > 0:
                if t0_wall is None:
                    t0_wall, t0_log = time.monotonic(), ev.timestamp
                delay = t0_wall + (ev.timestamp - t0_log) * 1e-6 / speed - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            lc.publish(ev.channel, ev.data)
            sent += 1
        if not loop:
            break
        if bar is not None:
            bar.reset()
    if bar is not None:
        bar.close()
    return sent


def main_record(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tools/mvtrack record", description="Record live LCM traffic (lcm-logger).")
    ap.add_argument("out", type=Path, help="log file to write (overwritten)")
    ap.add_argument("--url", default=DEFAULT_URL, help=f"LCM URL (default {DEFAULT_URL})")
    ap.add_argument("--channels", default=".*", help="channel regex (default: all)")
    ap.add_argument("--seconds", type=float, help="stop after this long (default: until Ctrl-C)")
    a = ap.parse_args(argv)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    p = start_recorder(a.out, a.url, a.channels)
    print(f"record: {a.channels} on {safe_url(a.url)} -> {a.out}" + (f" for {a.seconds:g} s" if a.seconds else
                                                                       " (Ctrl-C stops)"), file=sys.stderr)
    try:
        if a.seconds:
            time.sleep(a.seconds)
        else:
            p.wait()
    except KeyboardInterrupt:
        pass
    stop_recorder(p)
    n = sum(1 for _ in lcm.EventLog(str(a.out), "r")) if a.out.exists() else 0
    print(f"record: {n} events in {a.out}")
    return 0 if p.returncode in (0, -signal.SIGINT) else 1


def main_replay(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tools/mvtrack replay", description="Publish a log live at its recorded pace.")
    ap.add_argument("log", type=Path)
    ap.add_argument("--url", default=DEFAULT_URL, help=f"LCM URL (default {DEFAULT_URL})")
    ap.add_argument("--speed", type=float, default=1.0, help="pace factor: 2 = twice as fast, 0 = no waiting")
    ap.add_argument("--channels", default=".*", help="channel regex (default: all)")
    ap.add_argument("--loop", action="store_true", help="start again at the end (Ctrl-C stops)")
    a = ap.parse_args(argv)
    if not a.log.exists():
        ap.error(f"{a.log}: no such file")
    if a.speed < 0:
        ap.error("--speed must be >= 0")
    try:
        n = replay(a.log, a.url, a.speed, a.channels, a.loop)
    except KeyboardInterrupt:
        return 0
    print(f"replay: {n} events published on {safe_url(a.url)}")
    return 0


if __name__ == "__main__":  # python -m mvtrack_tools.replay record|replay ARGS
    if len(sys.argv) < 2 or sys.argv[1] not in ("record", "replay"):
        raise SystemExit("usage: python -m mvtrack_tools.replay record|replay ...")
    sys.exit((main_record if sys.argv[1] == "record" else main_replay)(sys.argv[2:]))
