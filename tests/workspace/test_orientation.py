"""Orientation ranges against Harada 2011 eqs. (9), (11.1) and (11.4) and Fig. 6 (l : 2 r_t = 2 : 1)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from plm_pin.exceptions import InvalidInput
from plm_pin.workspace import orientation_range
from tests.conftest import preset
from tests.workspace.conftest import FIG6_L, FIG6_RT
from tests.workspace.test_singular_loci import expected_3d3m

L, RT = 0.140, 0.05  # Harada 2011 Table 1
THETAS = np.radians(np.linspace(-80.0, 80.0, 65))  # 2.5 deg samples
XTOL = 1e-9  # tolerance asked of the ends [rad]


def _closed_form_range(y: float, l: float, rt: float) -> tuple[float, float]:
    """The 3D3M's range about theta = 0 from eq. (11) and the reach condition (9), paper's working mode."""
    ends = [theta for theta, _, _ in expected_3d3m(y, l, rt, +1)]
    below = [t for t in ends if t <= 0.0]
    above = [t for t in ends if t >= 0.0]
    return max(below, default=THETAS[0]), min(above, default=THETAS[-1])


def test_fig6_3d3m_range_ends_at_the_type4_angle_of_eq_11_4(fig6):
    """Fig. 6, y where eq. (11.4) gives 28.7 deg: the 3D3M turns down to -28.7 deg, the 3D4M all the way."""
    y = (FIG6_L + FIG6_RT) * math.sin(math.radians(28.7))
    three = orientation_range(fig6["3d3m"], "rz", THETAS, (0.0, y, 0.0), xtol=XTOL)
    assert three.lower_end == "direct" and abs(math.degrees(three.lower) + 28.7) < math.degrees(2 * XTOL)
    assert (three.upper, three.upper_end) == (THETAS[-1], "grid")
    four = orientation_range(fig6["3d4m"], "rz", THETAS, (0.0, y, 0.0), xtol=XTOL)
    assert (four.lower, four.lower_end, four.upper, four.upper_end) == (THETAS[0], "grid", THETAS[-1], "grid")
    assert four.width > three.width


@pytest.mark.parametrize("y", [0.01, 0.03, 0.06, 0.1, 0.12])
def test_3d3m_range_ends_are_the_closed_form_singular_points(y):
    """At several heights the ends are eq. (11.1) / (11.4) roots or eq. (9) / (11.2) reach limits (2 xtol)."""
    mech = preset("harada2011_3d3m")
    result = orientation_range(mech, "rz", THETAS, (0.0, y, 0.0), xtol=XTOL)
    lower, upper = _closed_form_range(y, L, RT)
    assert abs(result.lower - lower) < 2 * XTOL and abs(result.upper - upper) < 2 * XTOL
    assert {result.lower_end, result.upper_end} <= {"direct", "boundary", "grid"}


@pytest.mark.parametrize("y", [0.03, 0.1, 0.12])
def test_3d4m_range_is_the_reach_of_its_legs(y):
    """The redundant table is never singular in its mode here: its range is the reach condition (9) alone."""
    mech = preset("harada2011_3d4m")
    result = orientation_range(mech, "rz", THETAS, (0.0, y, 0.0), xtol=XTOL)
    lo, hi = paper.reachable_sin_interval(y, L, RT)
    expected = [max(math.asin(lo), THETAS[0]), min(math.asin(hi), THETAS[-1])]
    assert abs(result.lower - expected[0]) < 2 * XTOL and abs(result.upper - expected[1]) < 2 * XTOL
    assert {result.lower_end, result.upper_end} <= {"boundary", "grid"}


def test_range_about_another_reference_and_unreachable_references():
    """The range holds the reference asked for; a reference outside the samples or out of reach gives NaN."""
    mech = preset("harada2011_3d3m")
    y = 0.06
    singular = -math.acos(math.sqrt(((L + RT) ** 2 - y**2) / (L + RT) ** 2))  # eq. (11.4)
    below = orientation_range(mech, "rz", THETAS, (0.0, y, 0.0), reference=math.radians(-40.0), xtol=XTOL)
    assert abs(below.upper - singular) < 2 * XTOL and below.upper_end == "direct"
    assert below.lower < math.radians(-40.0)
    outside = orientation_range(mech, "rz", THETAS, (0.0, y, 0.0), reference=math.radians(85.0))
    assert math.isnan(outside.lower) and math.isnan(outside.width) and outside.lower_end == "unreachable"
    far = orientation_range(mech, "rz", THETAS, (0.0, 0.2, 0.0))  # the rods (0.14 m) cannot reach y = 0.2 m
    assert far.upper_end == "unreachable" and math.isnan(far.upper)
    data = json.loads(json.dumps(far.to_dict()))
    assert data["lower"] == "nan" and data["points"] == []


def test_bad_samples_and_reference_are_refused():
    """Non-increasing samples and a non-finite reference raise InvalidInput naming them."""
    mech = preset("harada2011_3d3m")
    with pytest.raises(InvalidInput, match="values must be an increasing 1-D array of at least 2 finite"):
        orientation_range(mech, "rz", [0.1, 0.0], (0.0, 0.08, 0.0))
    with pytest.raises(InvalidInput, match=r"^reference must be a finite number \[rad\], got nan$"):
        orientation_range(mech, "rz", THETAS, (0.0, 0.08, 0.0), reference=math.nan)
