"""Shortest forward paths of bounded curvature between two poses (Dubins' six words).

A word is three segments, each a left arc (``L``), a right arc (``R``) or a straight (``S``), of
radius ``radius``: LSL, RSR, LSR, RSL, RLR, LRL. Dubins (1957) showed the shortest path of
bounded curvature between two poses is one of them. :func:`dubins_words` gives every word that
exists for two poses, shortest first; each is checked by integrating its segments
(:func:`sample_word`) to the goal pose, so a formula's slip shows as a missing word, never as a
wrong path.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from tt_mujoco.reference.paths import ArcsPath

__all__ = ["Word", "ahead", "arcs_path", "dubins_words", "sample_word", "word_pieces"]

_TAU = 2.0 * math.pi


class Word(NamedTuple):
    """A Dubins path: its segments' kinds (``"LSL"``, ...), their lengths (m) and radius."""

    kinds: str
    lengths: tuple[float, float, float]
    radius: float

    @property
    def length(self) -> float:
        return sum(self.lengths)


def _mod(angle: float) -> float:
    return angle % _TAU


def _words(a: float, b: float, d: float) -> dict[str, tuple[float, float, float] | None]:
    """Each word's normalised segment lengths (radius 1) from heading ``a`` to ``b`` (measured
    from the line joining the poses) over normalised distance ``d``, or None."""
    sa, sb, ca, cb, cab = math.sin(a), math.sin(b), math.cos(a), math.cos(b), math.cos(a - b)
    out: dict[str, tuple[float, float, float] | None] = {}
    p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)
    if p2 >= 0:
        th = math.atan2(cb - ca, d + sa - sb)
        out["LSL"] = (_mod(-a + th), math.sqrt(p2), _mod(b - th))
    p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)
    if p2 >= 0:
        th = math.atan2(ca - cb, d - sa + sb)
        out["RSR"] = (_mod(a - th), math.sqrt(p2), _mod(-b + th))
    p2 = -2 + d * d + 2 * cab + 2 * d * (sa + sb)
    if p2 >= 0:
        p = math.sqrt(p2)
        th = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out["LSR"] = (_mod(-a + th), p, _mod(-b + th))
    p2 = -2 + d * d + 2 * cab - 2 * d * (sa + sb)
    if p2 >= 0:
        p = math.sqrt(p2)
        th = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out["RSL"] = (_mod(a - th), p, _mod(b - th))
    c = (6 - d * d + 2 * cab + 2 * d * (sa - sb)) / 8
    if abs(c) <= 1:
        p = _mod(_TAU - math.acos(c))
        t = _mod(a - math.atan2(ca - cb, d - sa + sb) + p / 2)
        out["RLR"] = (t, p, _mod(a - b - t + p))
    c = (6 - d * d + 2 * cab + 2 * d * (sb - sa)) / 8
    if abs(c) <= 1:
        p = _mod(_TAU - math.acos(c))
        t = _mod(-a - math.atan2(ca - cb, d + sa - sb) + p / 2)
        out["LRL"] = (t, p, _mod(b - a - t + p))
    return out


def sample_word(start, word: Word, step: float) -> np.ndarray:
    """Poses ``(x, y, heading)`` along ``word`` from pose ``start``, about ``step`` apart
    (m), both ends included; arcs are followed exactly."""
    x, y, heading = start
    out = [(x, y, heading)]
    for kind, length in zip(word.kinds, word.lengths, strict=True):
        n = max(1, math.ceil(length / step))
        turn = {"L": 1.0, "R": -1.0, "S": 0.0}[kind] / word.radius
        x0, y0, h0 = x, y, heading
        for i in range(1, n + 1):
            s = length * i / n
            if turn == 0.0:
                x, y, heading = x0 + s * math.cos(h0), y0 + s * math.sin(h0), h0
            else:
                heading = h0 + turn * s
                x = x0 + (math.sin(heading) - math.sin(h0)) / turn
                y = y0 - (math.cos(heading) - math.cos(h0)) / turn
            out.append((x, y, heading))
    return np.array(out)


def dubins_words(start, goal, radius: float, tolerance: float = 1e-6) -> list[Word]:
    """Every Dubins word from pose ``start`` to pose ``goal`` (``(x, y, heading)``, m and rad)
    with arcs of ``radius``, shortest first; only words whose integrated end is within
    ``tolerance`` of ``goal``."""
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    d = math.hypot(dx, dy) / radius
    phi = math.atan2(dy, dx)
    a, b = _mod(start[2] - phi), _mod(goal[2] - phi)
    words = []
    for kinds, lengths in _words(a, b, d).items():
        if lengths is None:
            continue
        word = Word(kinds, tuple(radius * v for v in lengths), radius)
        end = sample_word(start, word, max(word.length, 1e-9))[-1]
        turned = math.remainder(end[2] - goal[2], _TAU)
        if math.hypot(end[0] - goal[0], end[1] - goal[1]) <= tolerance and abs(turned) <= 1e-6:
            words.append(word)
    return sorted(words, key=lambda w: w.length)


def ahead(pose, distance: float) -> tuple[float, float, float]:
    """The pose ``distance`` (m) ahead of ``pose`` ``(x, y, heading)`` along its heading."""
    x, y, heading = pose
    return x + distance * math.cos(heading), y + distance * math.sin(heading), heading


def word_pieces(word: Word) -> list[tuple[float, float]]:
    """A word's segments as ``(length, kappa)`` pieces (left arcs positive)."""
    turn = {"L": 1.0 / word.radius, "R": -1.0 / word.radius, "S": 0.0}
    return [(length, turn[kind]) for kind, length in zip(word.kinds, word.lengths, strict=True)]


def arcs_path(start, pieces) -> ArcsPath:
    """The planned path from pose ``start`` through ``(length, kappa)`` ``pieces`` (zero
    lengths left out: where two pieces of a plan meet, one may be empty)."""
    return ArcsPath("plan", start, [(length, kappa) for length, kappa in pieces if length > 1e-9])
