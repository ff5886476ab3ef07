r"""Mode-transition graphs: modes, their singularity, adjacency and singularity-free routes.

Generic: the modes are sign tuples (one sign per sub-mechanism or per leg) of any
mechanism, and the graph is built by the caller from representatives and walks between
them (for the 2-PRRRP: :func:`plm_pin.families.prrrp.assembly_mode_graph`).

- :class:`ModeGraph`: modes, the rank of the closed-chain direct Jacobian :math:`C` at a
  representative of each, adjacency, and the shortest routes that avoid the singular modes.
- :func:`compress_modes`: the sequence of distinct modes a sampled path visits.

Units: margins are normalised singular-value ratios [-].
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..exceptions import InvalidInput
from ..results import Result, unit

Mode = tuple[int, ...]
"""A mode: one sign (+1, -1, or 0 at the boundary) per sub-mechanism or per leg."""


def compress_modes(modes: Sequence[Mode]) -> tuple[Mode, ...]:
    """The sequence of distinct modes visited (consecutive repeats dropped)."""
    out: list[Mode] = []
    for m in modes:
        if not out or out[-1] != tuple(m):
            out.append(tuple(m))
    return tuple(out)


@dataclass(frozen=True)
class ModeNode(Result):
    """One mode of a :class:`ModeGraph`, evaluated at a representative configuration.

    Attributes:
        mode: the mode signs.
        label: the mode written as in the paper, e.g. ``[+ 0]``.
        q: representative configuration (read-only), shape (nq,).
        rank: rank of the closed-chain direct Jacobian :math:`C` there (relative tolerance
            :data:`plm_pin.tolerances.RANK_RTOL`).
        full_rank: the mechanism's mobility (rank of a non-singular :math:`C`).
        direct_margin: direct margin there [-].
        redundancy_margin: :func:`plm_pin.kinematics.paths.redundancy_margin` there [-].
    """

    mode: Mode
    label: str
    q: np.ndarray = field(metadata=unit("m, rad"))
    rank: int = field(metadata=unit("-"))
    full_rank: int = field(metadata=unit("-"))
    direct_margin: float = field(metadata=unit("-"))
    redundancy_margin: float = field(metadata=unit("-"))
    _DERIVED = ("singular",)

    def __post_init__(self) -> None:
        self.q.setflags(write=False)

    @property
    def singular(self) -> bool:
        """Whether :math:`C` loses rank in this mode (direct singularity)."""
        return self.rank < self.full_rank


@dataclass(frozen=True)
class ModeEdge(Result):
    """A direct transition between two modes, found by a walk between their representatives.

    Attributes:
        a: first mode.
        b: second mode.
        min_direct_margin: smallest direct margin along the walk, ends included [-].
        samples: number of assembled samples of the walk.
    """

    a: Mode
    b: Mode
    min_direct_margin: float = field(metadata=unit("-"))
    samples: int = field(metadata=unit("-"))


@dataclass(frozen=True)
class ModeGraph(Result):
    """State-transition graph of modes (Harada 2015, Fig. 5, for the 2-PRRRP).

    Attributes:
        nodes: the modes with their representatives and ranks.
        edges: the direct transitions (undirected).
        label_of: writes a mode as text.
    """

    nodes: tuple[ModeNode, ...]
    edges: tuple[ModeEdge, ...]
    label_of: Callable[[Mode], str] = field(default=lambda m: str(m), repr=False, compare=False)
    _SKIPPED = ("label_of",)
    _DERIVED = ("singular_modes",)

    def node(self, mode: Sequence[int]) -> ModeNode:
        """The node of ``mode``.

        Raises:
            InvalidInput: when the graph has no such mode.
        """
        for n in self.nodes:
            if n.mode == tuple(mode):
                return n
        raise InvalidInput(f"no mode {tuple(mode)}; modes are {[n.label for n in self.nodes]}")

    def adjacent(self, a: Sequence[int], b: Sequence[int]) -> bool:
        """Whether the two modes are joined by an edge."""
        pair = {tuple(a), tuple(b)}
        return any({e.a, e.b} == pair for e in self.edges)

    def neighbours(self, mode: Sequence[int]) -> tuple[Mode, ...]:
        """Modes joined to ``mode`` by an edge, in node order."""
        return tuple(n.mode for n in self.nodes if self.adjacent(mode, n.mode))

    @property
    def singular_modes(self) -> tuple[Mode, ...]:
        """Modes where :math:`C` loses rank."""
        return tuple(n.mode for n in self.nodes if n.singular)

    def routes(
        self, start: Sequence[int], goal: Sequence[int], *, avoid_singular: bool = True
    ) -> list[tuple[Mode, ...]]:
        """Every shortest route from ``start`` to ``goal`` (breadth-first), in node order.

        Args:
            start: first mode.
            goal: last mode.
            avoid_singular: never pass through a singular mode.

        Returns:
            The routes, each a tuple of modes from ``start`` to ``goal``; empty when none
            exists.

        Raises:
            InvalidInput: unknown modes, or a singular start or goal with ``avoid_singular``.
        """
        s, g = self.node(start).mode, self.node(goal).mode
        banned = set(self.singular_modes) if avoid_singular else set()
        if s in banned or g in banned:
            raise InvalidInput(f"start {self.label_of(s)} or goal {self.label_of(g)} is a singular mode")
        order = [n.mode for n in self.nodes if n.mode not in banned]
        dist = {s: 0}
        frontier = [s]
        while frontier and g not in dist:
            nxt = []
            for m in frontier:
                for nb in self.neighbours(m):
                    if nb in dist or nb in banned:
                        continue
                    dist[nb] = dist[m] + 1
                    nxt.append(nb)
            frontier = sorted(nxt, key=order.index)
        if g not in dist:
            return []

        def back(m: Mode) -> list[tuple[Mode, ...]]:
            if m == s:
                return [(s,)]
            out: list[tuple[Mode, ...]] = []
            for nb in self.neighbours(m):
                if dist.get(nb) == dist[m] - 1:
                    out.extend((*r, m) for r in back(nb))
            return out

        return sorted(back(g), key=lambda r: [order.index(m) for m in r])
