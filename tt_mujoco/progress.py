"""One progress-bar policy for every long task: simulation, video, sweep, paper suite.

On a terminal a live bar (redrawn at most ten times a second); in a log or CI (stderr not a
terminal) the same line written at most every 30 s, so a log gets a few summary lines, not
hundreds of carriage returns. ``enabled=False`` (``--quiet``) shows nothing.
"""

from __future__ import annotations

import sys

from tqdm import tqdm

__all__ = ["progress_bar"]

#: Seconds between two lines in a log (stderr not a terminal).
LOG_INTERVAL_S = 30.0


def progress_bar(total: int, desc: str, unit: str, enabled: bool = True, initial: int = 0):
    """A tqdm bar on stderr following the policy above (a disabled one when not ``enabled``)."""
    terminal = sys.stderr.isatty()
    return tqdm(
        total=total,
        initial=initial,
        desc=desc,
        unit=unit,
        file=sys.stderr,
        disable=not enabled,
        dynamic_ncols=terminal,
        mininterval=0.1 if terminal else LOG_INTERVAL_S,
        leave=not terminal,  # in a log the last line stays as the task's summary
    )
