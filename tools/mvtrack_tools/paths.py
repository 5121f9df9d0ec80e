"""Where the build puts things, and importing the lcm-gen Python types from it."""
from __future__ import annotations

import os
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("MVTRACK_BUILD", REPO / "build"))
DAEMON = BUILD / "bin" / "mvtrackd"


def import_types():
    """Returns the generated `mvtrack` LCM package (build/lcmtypes/python)."""
    p = str(BUILD / "lcmtypes" / "python")
    if p not in sys.path:
        sys.path.insert(0, p)
    try:
        import mvtrack  # type: ignore
    except ImportError as e:  # pragma: no cover - a clear message beats a traceback
        raise SystemExit(f"mvtrack LCM types not built ({p}): run tools/mvtrack build") from e
    return mvtrack
