"""Mode graphs: adjacency and shortest singularity-free routes, on the 2-PRRRP graph (Harada 2015, Fig. 5)."""

from __future__ import annotations

import itertools

import pytest

from plm_pin.families.prrrp import ASSEMBLY_MODES, PAPER_ASSEMBLY_ROUTE, assembly_mode_graph
from tests.conftest import preset

ASYM = "harada2015_asymmetric"


@pytest.fixture(scope="module")
def graph():
    return assembly_mode_graph(preset(ASYM))


def test_graph_edges_are_the_frontier_relation_of_fig5(graph):
    """Two modes are adjacent iff one is the other with some pair moved onto the stator (16 edges)."""

    def below(a, b):  # a lies on the boundary of b
        return a != b and all(x == y or x == 0 for x, y in zip(a, b, strict=True))

    expected = {
        frozenset((a, b)) for a, b in itertools.combinations(ASSEMBLY_MODES, 2) if below(a, b) or below(b, a)
    }
    found = {frozenset((e.a, e.b)) for e in graph.edges}
    assert found == expected and len(found) == 16
    assert set(graph.neighbours((1, 0))) == {(1, 1), (1, -1), (0, 0)}
    assert len(graph.neighbours((0, 0))) == 8


def test_shortest_singularity_free_routes_are_the_paper_route_and_its_mirror(graph):
    """Avoiding [0 0], [+ +] -> [- -] takes 4 steps, via [+ 0] [+ -] [0 -] (Fig. 6) or its mirror."""
    routes = graph.routes((1, 1), (-1, -1))
    assert routes == [PAPER_ASSEMBLY_ROUTE, ((1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1))]
    assert graph.routes((1, 1), (-1, -1), avoid_singular=False) == [((1, 1), (0, 0), (-1, -1))]
