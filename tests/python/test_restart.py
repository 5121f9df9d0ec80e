"""mvtrackd --state: checkpoints restored across a restart, refused when unusable, identities never
reused. Offline halves of one log (deterministic) and live kill -9 / SIGTERM (tools/mvtrack restart)."""
from __future__ import annotations

import os
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

from mvtrack_tools import restart
from mvtrack_tools.lcmio import LogWriter, read_log, split_log
from mvtrack_tools.rig import smartroom
from mvtrack_tools.simulate import T0_UTIME, build_multi, write_multi

pytestmark = pytest.mark.daemon

HEADER = struct.Struct("<8s8I16sQQqqqiIII")  # mvtd_ckpt_header_t (daemon/mvtd.h), x86-64


def run(daemon: Path, rig: Path, log: Path, out: Path, *args: str) -> subprocess.CompletedProcess:
    r = subprocess.run([str(daemon), "--rig", str(rig), "--in", f"file://{log}?speed=0", "--out",
                        f"file://{out}?mode=w", *args], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return r


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    d = tmp_path_factory.mktemp("restart")
    rig = smartroom()
    rp = d / "rig.yaml"
    rig.write(rp)
    sc, frames = build_multi("interaction", rig, 3, frames=300)
    log = d / "scene.lcm"
    w = LogWriter(str(log))
    write_multi(w, sc, frames, progress=False)
    w.close()
    return d, rp, log


def ids_of(path: Path) -> dict[int, list]:
    return read_log(str(path), lambda c: c == "TRACKS").tracks


def test_state_offline_halves_continue_bit_for_bit(scene, daemon_path):
    """Cut at frame 150 with no gap: the second half restored from the first's checkpoint gives the
    whole run's tracks, bit for bit, under the same identities; a track born after the cut takes an
    identity above every one leased before it, the same one all its life."""
    d, rp, log = scene
    run(daemon_path, rp, log, d / "whole.lcm")
    a, b = d / "a.lcm", d / "b.lcm"
    split_log(log, a, b, T0_UTIME + 150 * 40000 - 20000, 0)
    state = d / "st0"
    r1 = run(daemon_path, rp, a, d / "a_out.lcm", "--state", str(state))
    assert "no checkpoint" in r1.stderr
    assert state.exists() and Path(f"{state}.ids").exists()
    r2 = run(daemon_path, rp, b, d / "b_out.lcm", "--state", str(state))
    assert "restored 2 tracks" in r2.stderr, r2.stderr
    whole, first, second = ids_of(d / "whole.lcm"), ids_of(d / "a_out.lcm"), ids_of(d / "b_out.lcm")
    assert len(second) >= 140
    before = {t.id for ts in first.values() for t in ts}
    renamed = {}
    for u, tracks in second.items():
        ref = whole[u]
        assert [(t.status, tuple(t.position), tuple(t.position_covariance)) for t in tracks] == \
               [(t.status, tuple(t.position), tuple(t.position_covariance)) for t in ref]
        for t, r in zip(tracks, ref):
            if r.id in before:
                assert t.id == r.id
            else:
                assert t.id > max(before) and renamed.setdefault(r.id, t.id) == t.id


def test_state_offline_gap_keeps_identities_stale_does_not(scene, daemon_path):
    """A 1 s outage: both people keep their identities. A 3 s outage (longer than tracks coast): the
    checkpoint is refused as stale and the people get new identities, above every earlier one."""
    d, rp, log = scene
    for gap_s, restored in ((1.0, True), (3.0, False)):
        a, b = d / f"a{gap_s}.lcm", d / f"b{gap_s}.lcm"
        split_log(log, a, b, T0_UTIME + 120 * 40000 - 20000, int(gap_s * 1e6))
        state = d / f"st{gap_s}"
        run(daemon_path, rp, a, d / f"a{gap_s}_out.lcm", "--state", str(state))
        r2 = run(daemon_path, rp, b, d / f"b{gap_s}_out.lcm", "--state", str(state))
        first, second = ids_of(d / f"a{gap_s}_out.lcm"), ids_of(d / f"b{gap_s}_out.lcm")
        before = {t.id for ts in first.values() for t in ts if t.status != 1}
        after = {t.id for ts in second.values() for t in ts if t.status != 1}
        assert len(before) == 2
        if restored:
            assert "restored 2 tracks" in r2.stderr, r2.stderr
            assert after == before
        else:
            assert "stale" in r2.stderr and r2.stderr.count("checkpoint refused") == 1, r2.stderr
            assert len(after) == 2 and min(after) > max(before)


def corrupt(data: bytes, how: str) -> bytes:
    b = bytearray(data)
    if how == "bitflip-state":
        b[HEADER.size + 100] ^= 0x10
    elif how == "bitflip-header":
        b[40] ^= 0x01
    elif how == "truncated":
        b = b[: len(b) // 2]
    elif how == "empty":
        b = bytearray()
    elif how == "garbage":
        b = bytearray(np.random.default_rng(1).integers(0, 256, len(b), dtype=np.uint8).tobytes())
    elif how == "foreign-version":
        f = list(HEADER.unpack_from(b))
        f[1] = 99
        hdr = HEADER.pack(*f)
        # a well-formed header of another format: its own CRC right, so the version is what refuses
        from zlib import crc32
        f[-2] = crc32(hdr[: HEADER.size - 8])
        b[: HEADER.size] = HEADER.pack(*f)
    return bytes(b)


@pytest.mark.parametrize("how", ["bitflip-state", "bitflip-header", "truncated", "empty", "garbage",
                                 "foreign-version", "other-rig", "other-mode"])
def test_state_unusable_checkpoint_refused_once_clean_start_ids_fresh(scene, daemon_path, how):
    d, rp, log = scene
    a, b = d / "ua.lcm", d / "ub.lcm"
    if not b.exists():
        split_log(log, a, b, T0_UTIME + 120 * 40000 - 20000, 0)
    state = d / f"st-{how}"
    run(daemon_path, rp, a, d / f"ua-{how}.lcm", "--state", str(state))
    good = state.read_bytes()
    assert len(good) > HEADER.size
    args = ["--state", str(state)]
    rig = rp
    if how == "other-rig":
        rig = d / "rig_moved.yaml"
        other = smartroom()
        other.cameras[0].tvec = other.cameras[0].tvec + np.array([0.01, 0.0, 0.0])
        other.write(rig)
    elif how == "other-mode":
        args += ["--mode", "kf"]
    else:
        state.write_bytes(corrupt(good, how))
    r = run(daemon_path, rig, b, d / f"ub-{how}.lcm", *args)
    lines = [ln for ln in r.stderr.splitlines() if str(state) in ln]
    assert len(lines) == 1 and ("refused" in lines[0] or "no checkpoint" in lines[0]), r.stderr
    first, second = ids_of(d / f"ua-{how}.lcm"), ids_of(d / f"ub-{how}.lcm")
    before = {t.id for ts in first.values() for t in ts}
    after = {t.id for ts in second.values() for t in ts}
    assert after and not (after & before), (sorted(before), sorted(after))
    assert len(second) >= 140  # tracked on from a clean start


def test_state_checkpoint_newer_than_input_refused(scene, daemon_path):
    """The same log run again on its own checkpoint: the first message is older than the saved
    state (a replay, or the cameras' clock set back), so it is refused, once, and identities are new."""
    d, rp, log = scene
    state = d / "st-future"
    run(daemon_path, rp, log, d / "f1.lcm", "--state", str(state))
    r = run(daemon_path, rp, log, d / "f2.lcm", "--state", str(state))
    lines = [ln for ln in r.stderr.splitlines() if str(state) in ln]
    assert len(lines) == 1 and "refused" in lines[0] and "after the first message" in lines[0], r.stderr
    before = {t.id for ts in ids_of(d / "f1.lcm").values() for t in ts}
    after = {t.id for ts in ids_of(d / "f2.lcm").values() for t in ts}
    assert after and min(after) > max(before)


@pytest.mark.parametrize("how", ["kill", "term", "nostate"])
def test_state_live_restart_keeps_identities_never_reuses(tmp_path, daemon_path, how):
    """Live, 5 cameras, 5 people: the daemon stopped 3.5 s in (SIGKILL, SIGTERM, or SIGKILL with
    the checkpoint deleted) and restarted 1 s later (tools/mvtrack restart)."""
    r = restart.run(how, 7.0, 3.5, 1.0, "pkf", tmp_path, 1, {"kill": 7301, "term": 7302, "nostate": 7303}[how] + os.getpid() % 100 * 3)
    assert r["present"] >= 4, r
    assert not r["reused_by_another_person"] and not r["new_ids_that_existed_before"], r
    if how == "nostate":
        assert r["kept"] == 0 and "no checkpoint" in r["restore_line"], r
    else:
        assert r["kept"] == r["present"], r
        assert "restored" in r["restore_line"], r
        # tracks again from the first frame published once it listens, or the next (a frame set
        # it caught mid-way); counted in frames, which a loaded machine does not stretch
        assert r["resume_frames_from_ready"] is not None and 0 <= r["resume_frames_from_ready"] <= 1, r


def test_state_outage_identities_over_30_scenes(tmp_path, daemon_path):
    """5 people walking a 6 x 5 m room, keeping their personal space, the log cut at 6 s and 1.5 s
    of it removed (an outage the restarted daemon did not see), 30 seeds (tools/mvtrack restart
    --offline 30 --down 1.5). Measured: 148 of 150 people keep their identity and 2 identities go
    to another person."""
    kept = present = reused = 0
    for seed in range(1, 31):
        r = restart.offline(seed, 1.5, 6.0, 14.0, tmp_path)
        kept, present, reused = kept + r["kept"], present + r["present"], reused + len(r["reused"])
    assert kept >= 0.95 * present and reused <= 4, (kept, present, reused)
