"""Progress bars that show on a terminal and stay out of logs.

tqdm redraws its bar with carriage returns; written to a file or a pipe (CI, systemd, `| tee`)
that becomes one long line of bars mixed with the output. Every bar of the tools goes through
bar(): shown when asked for and stderr is a terminal (tqdm's disable=None), never otherwise.
"""
from __future__ import annotations

from typing import Any

from tqdm import tqdm


def bar(iterable: Any = None, *, enabled: bool = True, **kwargs: Any) -> tqdm:
    """tqdm(iterable, **kwargs), disabled when not `enabled` or when stderr is not a terminal."""
    return tqdm(iterable, disable=None if enabled else True, **kwargs)
