"""Motions a study computes, to play in a report's scene or in ``plm-pin view --animate STUDY:CASE``.

A study may define ``ANIMATIONS``, a mapping from a case name to a function that computes
the motion and returns an :class:`Animation`. Functions of a study that takes a mechanism
(one with ``MECHANISM``) receive the mechanism to move (a preset name or a path); the others
take no argument. The same functions fill the study's own scenes, so the viewer plays
exactly what the report shows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput


@dataclass(frozen=True)
class Animation:
    """A motion of one mechanism.

    Attributes:
        mechanism: the mechanism that moves.
        qs: configurations, shape (n, nq) [m, rad].
        times: their times, strictly increasing, shape (n,) [s].
        caption: what the motion is.
    """

    mechanism: Mechanism
    qs: np.ndarray
    times: np.ndarray
    caption: str

    def __post_init__(self) -> None:
        qs = np.array(self.qs, dtype=float)
        times = np.array(self.times, dtype=float)
        nq = self.mechanism.nq
        if qs.ndim != 2 or qs.shape[1] != nq or qs.shape[0] < 2:
            raise InvalidInput(f"an animation needs qs of shape (n >= 2, {nq}), got {qs.shape}")
        if times.shape != (qs.shape[0],) or np.any(np.diff(times) <= 0.0):
            raise InvalidInput(f"an animation needs {qs.shape[0]} strictly increasing times [s]")
        if not (np.all(np.isfinite(qs)) and np.all(np.isfinite(times))):
            raise InvalidInput("an animation's configurations and times must be finite")
        qs.flags.writeable = False
        times.flags.writeable = False
        object.__setattr__(self, "qs", qs)
        object.__setattr__(self, "times", times)

    def thinned(self, frames: int) -> Animation:
        """The same motion with at most ``frames`` configurations (first and last kept) [-]."""
        n = self.times.size
        if n <= frames:
            return self
        keep = np.unique(np.rint(np.linspace(0, n - 1, max(frames, 2))).astype(int))
        return Animation(self.mechanism, self.qs[keep], self.times[keep], self.caption)


def parse_case(spec: str) -> tuple[str, str]:
    """``STUDY:CASE`` split in two.

    Raises:
        InvalidInput: not of the form ``STUDY:CASE``.
    """
    study, sep, case = spec.partition(":")
    if not sep or not study or not case or ":" in case:
        raise InvalidInput(f"--animate {spec!r}: give STUDY:CASE, e.g. harada2015:assembly")
    return study, case
