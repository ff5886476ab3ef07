"""Study animations (plm_pin/report/animation.py): checked motions, thinning, and the lookup by case."""

from __future__ import annotations

import re

import numpy as np
import pytest

from plm_pin.exceptions import InvalidInput
from plm_pin.report import Animation, find_study
from plm_pin.report.animation import parse_case
from plm_pin.report.study import compute_animation
from tests.conftest import preset
from tests.report.conftest import make_study


def _motion(n: int) -> Animation:
    mech = preset("fourbar")
    return Animation(mech, np.tile(mech.q_ref, (n, 1)), np.linspace(0.0, 1.0, n), "still")


def test_thinned_keeps_the_ends_and_spreads_the_rest():
    """At most `frames` samples, the first and last among them, evenly spread; short motions untouched."""
    motion = _motion(1001)
    thin = motion.thinned(11)
    np.testing.assert_allclose(thin.times, np.linspace(0.0, 1.0, 11))
    assert thin.qs.shape == (11, motion.mechanism.nq)
    assert _motion(5).thinned(11).times.size == 5
    assert not thin.qs.flags.writeable and not thin.times.flags.writeable


@pytest.mark.parametrize(
    ("qs", "times", "message"),
    [
        (np.zeros((1, 3)), [0.0], "an animation needs qs of shape (n >= 2, 3), got (1, 3)"),
        (np.zeros((2, 4)), [0.0, 1.0], "an animation needs qs of shape (n >= 2, 3), got (2, 4)"),
        (np.zeros((2, 3)), [1.0, 1.0], "an animation needs 2 strictly increasing times [s]"),
        (np.full((2, 3), np.nan), [0.0, 1.0], "an animation's configurations and times must be finite"),
    ],
)
def test_bad_motions_are_refused(qs, times, message):
    """Too few or wrong-sized configurations, times not increasing, non-finite values: InvalidInput."""
    with pytest.raises(InvalidInput, match=re.escape(message)):
        Animation(preset("fourbar"), qs, times, "bad")


def test_cases_are_looked_up_with_the_choices_in_the_message():
    """STUDY:CASE parses; an unknown case, or a mechanism for a fixed-mechanism study, is refused by name."""
    assert parse_case("harada2015:assembly") == ("harada2015", "assembly")
    for bad in ("harada2015", ":x", "a:", "a:b:c"):
        with pytest.raises(InvalidInput, match="give STUDY:CASE"):
            parse_case(bad)
    study = find_study("harada2015")
    with pytest.raises(InvalidInput, match=re.escape("its animations are ['assembly', 'working']")):
        compute_animation(study, "flip")
    with pytest.raises(InvalidInput, match="animates its own mechanisms: give no mechanism"):
        compute_animation(study, "working", "fourbar")
    with pytest.raises(InvalidInput, match="it defines no animations"):
        compute_animation(make_study(), "any")


def test_every_study_animation_runs():
    """Each case of every study's ANIMATIONS gives a motion of at least 50 frames of a known mechanism."""
    from plm_pin.report import study_names

    cases = [(name, case) for name in study_names() for case in find_study(name).animations]
    assert len(cases) >= 9
    for name, case in cases:
        if name == "overview":
            motion = compute_animation(find_study(name), case, "fourbar")
        else:
            motion = compute_animation(find_study(name), case)
        assert motion.times.size >= 50 and motion.qs.shape[1] == motion.mechanism.nq, (name, case)
