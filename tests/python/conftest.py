from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tools"))
os.environ.setdefault("MVTRACK_BUILD", str(REPO / "build"))


def pytest_configure(config):
    config.addinivalue_line("markers", "daemon: runs build/bin/mvtrackd on logs or live LCM")
    config.addinivalue_line("markers", "detect: runs build/bin/mvtrack-detect on video")
    config.addinivalue_line("markers", "accuracy: detect tests that measure accuracy (not run under ASan)")
    config.addinivalue_line("markers", "browser: tools/mvtrack view in headless Chromium")
    config.addinivalue_line("markers", "tools: the tools alone, without a daemon or a detector")


@pytest.fixture
def daemon_path() -> Path:
    from mvtrack_tools.paths import DAEMON
    if not DAEMON.exists():
        pytest.fail(f"{DAEMON} is not built")
    return DAEMON
