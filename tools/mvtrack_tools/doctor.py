"""What the cameras of a room send, against its rig: listens to the detections for a few seconds and
names each fault with what to fix.

For every DETECTIONS_<camera> channel heard: the camera's name against the rig's, its rate against
the rig's frame_rate (off by more than 10 %: a fault), its image size against the rig's, its clock
against this host's and against the other cameras' (the daemon assembles frames by capture time
within half a frame period: a camera more than CLOCK_MS off the others' median lands in the wrong
frame set), and its messages' size against one UDP datagram (an LCM message over 65,499 bytes goes
out in several datagrams, each in IP fragments, and is lost whole when any of them is: a mask at
--mask-scale 4 of a busy room may need that). A rig camera that sends nothing is a fault too.

The clock offset is the median of (message utime - arrival time on this host): transport delay
included, so it is compared between cameras, not with zero.

    tools/mvtrack doctor --rig RIG.yaml [--in URL] [--seconds 5] [--json]

Exit 0 when nothing is wrong, 1 when something is (each fault one line, with what to fix), 2 on
bad input.
"""
from __future__ import annotations

import argparse
import json
import select
import sys
import time
from pathlib import Path

import numpy as np

from .paths import import_types

DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"
CLOCK_MS = 10.0          # a quarter of a 25 fps frame: half a period is where frame sets split
RATE_TOLERANCE = 0.10
LCM_DATAGRAM = 65499     # LCM's udpm sends larger messages in fragments
IP_PAYLOAD = 1472        # one Ethernet frame's UDP payload


def listen(url: str, seconds: float) -> dict[str, dict]:
    import lcm

    mt = import_types()
    lc = lcm.LCM(url)
    seen: dict[str, dict] = {}

    def on(channel, data):
        now_us = time.time() * 1e6
        s = seen.setdefault(channel[len("DETECTIONS_"):], {"arrive": [], "utime": [], "sizes": [], "bad": 0,
                                                            "width": None, "height": None, "names": set()})
        s["sizes"].append(len(data))
        try:
            m = mt.camera_frame_t.decode(data)
        except Exception:  # noqa: BLE001 - an undecodable message is counted, not fatal
            s["bad"] += 1
            return
        s["arrive"].append(now_us)
        s["utime"].append(float(m.utime))
        s["width"], s["height"] = int(m.width), int(m.height)
        s["names"].add(m.camera)

    lc.subscribe("DETECTIONS_.*", on)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        r, _, _ = select.select([lc.fileno()], [], [], max(0.0, min(0.1, end - time.monotonic())))
        if r:
            lc.handle()
    return seen


def diagnose(rig, seen: dict[str, dict]) -> tuple[list[dict], list[str]]:
    cams = {c.name: c for c in rig.cameras}
    rows, faults = [], []
    offsets = {}
    for name, s in sorted(seen.items()):
        n = len(s["arrive"])
        row = {"camera": name, "messages": n, "undecodable": s["bad"], "in_rig": name in cams,
               "max_bytes": max(s["sizes"]) if s["sizes"] else 0}
        if n >= 2:
            span = (s["utime"][-1] - s["utime"][0]) * 1e-6
            row["rate_hz"] = (n - 1) / span if span > 0 else float("nan")
            off = (np.array(s["utime"]) - np.array(s["arrive"])) * 1e-3
            row["clock_offset_ms"] = float(np.median(off))
            offsets[name] = row["clock_offset_ms"]
        row["image"] = [s["width"], s["height"]]
        rows.append(row)
        if name not in cams:
            faults.append(f"{name}: sends on DETECTIONS_{name} but the rig has no camera of that name "
                          f"(it has {', '.join(sorted(cams))}): rename the detector's --video NAME= or the rig's camera")
            continue
        c = cams[name]
        if s["bad"]:
            faults.append(f"{name}: {s['bad']} undecodable messages: a sender of another message type on this channel")
        if "rate_hz" in row and abs(row["rate_hz"] / rig.frame_rate - 1.0) > RATE_TOLERANCE:
            faults.append(f"{name}: {row['rate_hz']:.1f} frames a second, the rig says {rig.frame_rate:g}: set the "
                          f"camera to {rig.frame_rate:g} fps or the rig's frame_rate to what the cameras deliver")
        if s["width"] is not None and (s["width"], s["height"]) != (c.width, c.height):
            faults.append(f"{name}: images {s['width']}x{s['height']}, the rig says {c.width}x{c.height}: the "
                          f"calibration is for another resolution; calibrate at this one or set the camera to it")
        if row["max_bytes"] > LCM_DATAGRAM:
            frags = -(-row["max_bytes"] // IP_PAYLOAD)
            faults.append(f"{name}: messages up to {row['max_bytes']:,} bytes ({frags} IP fragments; one lost loses "
                          f"the message): a larger --mask-scale, or no --masks on a lossy network")
    for name in sorted(set(cams) - set(seen)):
        faults.append(f"{name}: the rig's camera sends nothing: is its mvtrack-detect running, with --video {name}=..., "
                      f"on this LCM URL?")
    if len(offsets) >= 2:
        for name, off in offsets.items():
            others = np.median([o for k, o in offsets.items() if k != name])
            rel = off - others
            for r in rows:
                if r["camera"] == name:
                    r["clock_vs_others_ms"] = float(rel)
            if abs(rel) > CLOCK_MS and name in cams:
                faults.append(f"{name}: clock {rel:+.0f} ms against the other cameras' (more than {CLOCK_MS:g} ms): "
                              f"synchronise its host's clock (NTP or PTP)")
    return rows, faults


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack doctor", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rig", type=Path, required=True, help="the room's rig file")
    ap.add_argument("--in", dest="url", default=DEFAULT_URL, help=f"LCM URL to listen on (default {DEFAULT_URL})")
    ap.add_argument("--seconds", type=float, default=5.0, help="how long to listen (default 5)")
    ap.add_argument("--json", action="store_true", help="print the result as one JSON line")
    a = ap.parse_args(argv)
    from .rig import Rig

    if not (0.5 <= a.seconds <= 600):
        print("mvtrack doctor: --seconds must be in 0.5..600", file=sys.stderr)
        return 2
    if a.url.startswith("udpm://") and "ttl=0" not in a.url:
        print("mvtrack doctor: LCM multicast URLs must carry ttl=0", file=sys.stderr)
        return 2
    if not a.rig.is_file():
        print(f"mvtrack doctor: no rig file {a.rig}", file=sys.stderr)
        return 2
    try:
        rig = Rig.read(a.rig)
    except Exception as e:  # noqa: BLE001 - any unreadable rig is the user's input
        print(f"mvtrack doctor: cannot read the rig {a.rig}: {e}".splitlines()[0], file=sys.stderr)
        return 2
    seen = listen(a.url, a.seconds)
    rows, faults = diagnose(rig, seen)
    if a.json:
        print(json.dumps({"cameras": rows, "faults": faults}))
    else:
        print(f"listened {a.seconds:g} s on {a.url}: {len(seen)} cameras heard, the rig has {len(rig.cameras)}")
        for r in rows:
            print(f"  {r['camera']:12s} {r['messages']:5d} messages  {r.get('rate_hz', float('nan')):6.1f} Hz  "
                  f"{r['image'][0]}x{r['image'][1]}  clock vs others {r.get('clock_vs_others_ms', float('nan')):+7.1f} ms  "
                  f"largest message {r['max_bytes']:,} bytes")
        print("no fault found" if not faults else f"{len(faults)} faults:")
        for f in faults:
            print(f"  {f}")
    return 1 if faults else 0


if __name__ == "__main__":
    sys.exit(main())
