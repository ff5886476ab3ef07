"""Every preset builder refuses non-physical parameters with one InvalidInput naming the parameter and range.

Classes: lengths not > 0 (negative, zero, NaN, inf, text, booleans), masses and inertias below 0, vectors of
the wrong size or with a bad entry, and geometrically impossible combinations (bars that cannot meet, poses
out of reach).
"""

from __future__ import annotations

import math
import re
from typing import Any

import pytest

from plm_pin import InvalidInput, build_mechanism
from plm_pin.models import PRESETS

BAD_LENGTHS = [-0.05, 0.0, math.nan, math.inf, -math.inf, "0.1", None, True]
"""Values that are not a length > 0 [m]."""

BAD_MASSES = [-1e-3, math.nan, math.inf, "1", None, False]
"""Values that are not a mass or inertia >= 0."""

# (preset, scalar length parameters)
LENGTHS = [
    ("fourbar", ["crank", "coupler", "rocker", "ground"]),
    ("fivebar", ["base", "proximal", "distal"]),
    ("harada2011_3d4m", ["half_plate"]),
    ("harada2015_asymmetric", ["half_plate"]),
    ("enferadi2017_star_triangle", ["side"]),
]
# (preset, scalar parameters that must be >= 0, their unit)
MASSES = [
    ("fourbar", [("density", "kg/m"), ("gravity", "m/s^2")]),
    ("fivebar", [("density", "kg/m")]),
    ("harada2011_3d4m", [("slider_mass", "kg"), ("plate_mass", "kg"), ("plate_inertia", "kg m^2")]),
    (
        "enferadi2017_star_triangle",
        [("slider_mass", "kg"), ("link_mass", "kg"), ("link_inertia", "kg m^2"), ("star_mass", "kg")],
    ),
    (
        "zhao2011_8pss",
        [("strut_mass", "kg"), ("platform_mass", "kg"), ("slider_mass", "kg"), ("rotor_inertia", "kg m^2")],
    ),
]


def build(preset: str, **changes: Any) -> Any:
    """Call the preset's builder with its parameters and ``changes`` (no Mechanism is made)."""
    p = PRESETS[preset]
    return p.builder(name=preset, source="", **{**p.parameters, **changes})


def shown(value: Any) -> str:
    """The value as the message quotes it (its repr), escaped for a regular expression."""
    return re.escape(repr(value))


@pytest.mark.parametrize(
    ("preset", "parameter"), [(p, name) for p, names in LENGTHS for name in names], ids=str
)
@pytest.mark.parametrize("value", BAD_LENGTHS, ids=repr)
def test_a_length_that_is_not_positive_and_finite_is_refused(preset, parameter, value):
    """A negative half plate, a zero rod, NaN, inf, text or a boolean: refused, naming the parameter."""
    with pytest.raises(
        InvalidInput,
        match=rf"^{parameter} must be a length > 0 \[m\] \(a finite number\), got {shown(value)}$",
    ):
        build(preset, **{parameter: value})


@pytest.mark.parametrize(
    ("preset", "parameter", "unit"), [(p, n, u) for p, pairs in MASSES for n, u in pairs], ids=str
)
@pytest.mark.parametrize("value", BAD_MASSES, ids=repr)
def test_a_mass_or_inertia_below_zero_is_refused(preset, parameter, unit, value):
    """Masses, inertias, densities and gravity magnitudes must be finite and >= 0, in their unit."""
    with pytest.raises(
        InvalidInput,
        match=rf"^{parameter} must be a finite number >= 0 \[{re.escape(unit)}\], got {shown(value)}$",
    ):
        build(preset, **{parameter: value})


VECTORS = [
    # (preset, parameter, bad value, message)
    (
        "harada2011_3d4m",
        "rod_lengths",
        (-0.14, 0.14, 0.14, 0.14),
        r"4 lengths > 0 \[m\], .* at indices \[0\]",
    ),
    (
        "harada2011_3d4m",
        "rod_lengths",
        (0.14, 0.0, 0.14, math.nan),
        r"4 lengths > 0 \[m\], .* at indices \[1, 3\]",
    ),
    ("harada2011_3d4m", "rod_lengths", (0.14, 0.14, 0.14), r"4 lengths > 0 \[m\], got \(0.14, 0.14, 0.14\)$"),
    ("harada2011_3d4m", "rod_lengths", "0.14", r"real numbers \(array-like\), got '0.14'"),
    ("harada2011_3d4m", "rod_lengths", {"l1": 0.14}, r"real numbers \(array-like\)"),
    (
        "harada2011_3d4m",
        "rod_masses",
        (0.026, -0.026, 0.026, 0.026),
        r"4 masses >= 0 \[kg\], .* at indices \[1\]",
    ),
    ("harada2011_3d4m", "rod_inertias", (1e-4,) * 3 + (math.inf,), r"4 inertias >= 0 \[kg m\^2\].* \[3\]"),
    ("harada2011_3d4m", "reference_pose", (0.0, math.nan, 0.0), r"non-finite entries at indices \[1\]"),
    ("harada2011_3d4m", "reference_pose", (0.0, 0.08), r"an array of shape \(3,\) of x \[m\], y \[m\]"),
    (
        "harada2011_3d4m",
        "working_modes",
        (1, 1, 1),
        r"four signs \(\+1 or -1\), one per leg, got \(1, 1, 1\)",
    ),
    ("harada2011_3d4m", "working_modes", (1, 2, 1, 1), r"four signs \(\+1 or -1\)"),
    ("harada2011_3d4m", "working_modes", "+-+-", r"None or a sequence of signs"),
    ("harada2011_3d4m", "legs", "1234", r"distinct leg numbers among 1..4, got '1234'"),
    ("harada2011_3d4m", "legs", (1, 2, 5), r"distinct leg numbers among 1..4"),
    ("harada2011_3d4m", "legs", (1, 1, 2, 3), r"distinct leg numbers among 1..4"),
    ("harada2011_3d4m", "actuator_stiffness", -1e6, r"None or a finite number > 0 \[N/m\], got -1000000.0"),
    ("harada2011_3d4m", "gravity", -9.8, r"a finite number >= 0 \[m/s\^2\], got -9.8"),
    ("zhao2011_8pss", "strut_lengths", [1.0] * 7 + [-1.0], r"8 lengths > 0 \[m\], .* at indices \[7\]"),
    ("zhao2011_8pss", "strut_inertia", (1.0, 1.0, -1.0), r"3 inertias >= 0 \[kg m\^2\], .* at indices \[2\]"),
    ("zhao2011_8pss", "platform_inertia", (1.0, math.nan, 1.0), r"3 inertias >= 0 \[kg m\^2\]"),
    ("zhao2011_8pss", "lead", 0.0, r"a positive finite number \[m/rev\], got 0.0"),
    ("zhao2011_8pss", "lead", "0.01", r"a positive finite number \[m/rev\], got '0.01'"),
    ("zhao2011_8pss", "stroke", (1.5, 0.0), r"\(lower, upper\) slider limits \[m\] with lower < upper"),
    ("zhao2011_8pss", "stroke", (0.0, math.inf), r"non-finite entries at indices \[1\]"),
    (
        "zhao2011_8pss",
        "guide_points",
        [[0.0, 0.0]] * 8,
        r"shape \(8, 3\) of points \[m\], got shape \(8, 2\)",
    ),
    ("zhao2011_8pss", "home_pose", (0.0,) * 5, r"shape \(6,\) of x, y, z \[m\]"),
    ("zhao2011_8pss", "gravity", (0.0, 0.0, math.nan), r"non-finite entries at indices \[2\]"),
    ("zhao2011_8pss", "legs", [], r"distinct leg numbers among 1..8, got \[\]"),
    ("fivebar", "tip", (0.0, math.nan), r"non-finite entries at indices \[1\]"),
    ("fivebar", "tip", 0.25, r"an array of shape \(2,\) of coordinates \[m\]"),
    ("fourbar", "crank_angle", math.nan, r"a finite number \[rad\], got nan"),
    ("fourbar", "crank_angle", "60", r"a finite number \[rad\], got '60'"),
    (
        "enferadi2017_star_triangle",
        "reference_pose",
        (1.0, 1.0),
        r"shape \(3,\) of x \[m\], y \[m\], phi \[rad\]",
    ),
]


@pytest.mark.parametrize(("preset", "parameter", "value", "message"), VECTORS, ids=lambda v: str(v)[:30])
def test_vectors_of_the_wrong_size_or_with_a_bad_entry_are_refused(preset, parameter, value, message):
    """Sequences and poses: the parameter named, the size and unit stated, the bad indices listed."""
    with pytest.raises(InvalidInput, match=rf"^{parameter} (must be|has) (.* )?{message}"):
        build(preset, **{parameter: value})


IMPOSSIBLE = [
    # (preset, changes, message): each checked by hand against the geometry
    # |A D| = |(0.25, 0.433) - (0.3, 0)| = 0.4359 m > coupler + rocker = 0.3 m
    (
        "fourbar",
        {"crank": 0.5, "coupler": 0.1},
        r"^crank_angle = 1.0472 rad: the coupler and rocker \(0.1 m, 0.2 m\) cannot meet: their pivots are "
        r"0.43589 m apart, outside \[0.1, 0.3\] m$",
    ),
    # a long rocker: |A D| = 0.2646 m < rocker - coupler = 0.75 m
    ("fourbar", {"rocker": 1.0}, r"^crank_angle = .* cannot meet: .* outside \[0.75, 1.25\] m$"),
    # tip (0, 1): |tip - (-0.1, 0)| = 1.005 m > proximal + distal = 0.35 m
    (
        "fivebar",
        {"tip": (0.0, 1.0)},
        r"^tip \(0.0, 1.0\) m, left side: the proximal and distal links \(0.15 m, 0.2 m\) cannot meet: "
        r"their pivots are 1.00499 m apart",
    ),
    # rods of 1 cm cannot reach a plate 8 cm above the stator
    (
        "harada2011_3d4m",
        {"rod_lengths": (0.01, 0.14, 0.14, 0.14)},
        r"^reference_pose \(0.0, 0.08, -0.349\d+\) is out of reach: leg 1 cannot reach its pair",
    ),
    # a plate wider than the rods can span at theta = -20 deg: L_y = 0.08 + 0.3 sin(20 deg) = 0.183 m > 0.14 m
    ("harada2011_3d4m", {"half_plate": 0.3}, r"^reference_pose .* is out of reach: leg \d cannot reach"),
    # star at a corner beyond the base: a slider off its rail
    ("enferadi2017_star_triangle", {"reference_pose": (5.0, 5.0, 1.0)}, r"^reference pose .*: leg \d has q"),
    # struts of 1 cm cannot reach the platform
    ("zhao2011_8pss", {"strut_lengths": [0.01] * 8}, r"^leg \d: the strut \(l = 0.01 m\) cannot reach"),
]


@pytest.mark.parametrize(("preset", "changes", "message"), IMPOSSIBLE, ids=lambda v: str(v)[:30])
def test_geometrically_impossible_combinations_are_refused(preset, changes, message):
    """Bars that cannot meet and poses out of reach: refused before any URDF is built, saying why."""
    with pytest.raises(InvalidInput, match=message):
        build(preset, **changes)


def test_build_mechanism_passes_the_refusal_through_and_the_presets_still_build():
    """build_mechanism reports the builder's refusal unchanged; the presets' own parameters pass."""
    with pytest.raises(
        InvalidInput, match=r"^half_plate must be a length > 0 \[m\] \(a finite number\), got -0.05$"
    ):
        build_mechanism("harada2011_3d4m", {"half_plate": -0.05})
    for name in PRESETS:
        build(name)
