"""A program of your own that reads mvtrackd's tracks (README, "Consuming the tracks").
Run with build/lcmtypes/python on PYTHONPATH: python3 subscribe_tracks.py [LCM_URL]"""
import sys

import lcm
from mvtrack import track_t, tracks_t


def on_tracks(channel, data):
    m = tracks_t.decode(data)
    for t in m.tracks:
        if t.status != track_t.TENTATIVE:
            print(f"{m.utime} id {t.id} at {t.position[0]:.2f} {t.position[1]:.2f} {t.position[2]:.2f} m")


lc = lcm.LCM(sys.argv[1] if len(sys.argv) > 1 else "udpm://239.255.76.67:7667?ttl=0")
lc.subscribe("TRACKS", on_tracks)
while True:
    lc.handle()
