"""One progress-bar policy for every long task: simulation, video, sweep, paper suite.

On a terminal a live bar (redrawn at most ten times a second); in a log or CI (stderr not a
terminal) the same line written at most every 30 s, so a log gets a few summary lines, not
hundreds of carriage returns. ``enabled=False`` (``--quiet``) shows nothing.
"""

from __future__ import annotations

import sys

__all__ = ["progress_bar"]

#: Seconds between two lines in a log (stderr not a terminal).
LOG_INTERVAL_S = 30.0


class _NoBar:
    """What a disabled bar does: nothing (tqdm itself is not imported for it: ``--help`` and
    ``--quiet`` commands do without its import)."""

    def __init__(self, initial: int = 0):
        self.n = initial

    def update(self, n: int = 1) -> None:
        self.n += n

    def set_postfix(self, *args, **kwargs) -> None:
        pass

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass


def progress_bar(total: int, desc: str, unit: str, enabled: bool = True, initial: int = 0):
    """A tqdm bar on stderr following the policy above (one that does nothing when not
    ``enabled``)."""
    if not enabled:
        return _NoBar(initial)
    from tqdm import tqdm

    terminal = sys.stderr.isatty()
    return tqdm(
        total=total,
        initial=initial,
        desc=desc,
        unit=unit,
        file=sys.stderr,
        dynamic_ncols=terminal,
        mininterval=0.1 if terminal else LOG_INTERVAL_S,
        leave=not terminal,  # in a log the last line stays as the task's summary
    )
