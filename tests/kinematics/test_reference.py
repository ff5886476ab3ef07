"""The reference configuration (plm_pin/kinematics/reference.py) on a planar 3-PRR written by hand.

Oracles (tests/textbook.py, from the geometry alone): the closed-form inverse kinematics
s_i = (C_i - A_i) . u_i +- sqrt(l^2 - ((C_i - A_i) . n_i)^2) and each leg's distance to its
inverse singularity, |cos| of the angle between its rod and its slider (0 when the two IK
branches of the leg merge).
"""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

import plm_pin
from plm_pin.cli import app
from plm_pin.kinematics import classify, task_pose
from plm_pin.kinematics.reference import reference_findings, reference_report
from plm_pin.tolerances import REFERENCE_MARGIN
from plm_pin.warnings import ReferenceWarning
from tests import textbook as tb


@pytest.fixture(scope="module")
def chosen(tmp_path_factory):
    """The 3-PRR without a reference in its sidecar, and the warning its loading gave."""
    folder = tmp_path_factory.mktemp("prr")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mech = tb.three_prr(folder)
    (warning,) = [w for w in caught if issubclass(w.category, ReferenceWarning)]
    return mech, str(warning.message), folder


def test_reference_without_sidecar_value_is_chosen_away_from_singularities(chosen):
    """The moved reference's legs are farther from their inverse singularities than the neutral guess's."""
    mech, _, _ = chosen
    pose = tuple(task_pose(mech, mech.q_ref))
    legs = tb.prr_inverse_margins(pose)
    assert legs.min() > 0.5  # each rod more than 30 deg from its singular direction
    neutral = mech.assemble(mech.neutral()).q  # where the loader used to close the loops
    assert legs.min() > tb.prr_inverse_margins(tuple(task_pose(mech, neutral))).min()
    report = classify(mech, mech.q_ref)
    assert min(report.constraint_margin, report.inverse_margin, report.direct_margin) > REFERENCE_MARGIN
    roots = np.array([tb.prr_ik(pose, (b, b, b)) for b in (1, -1)])  # (branch, leg)
    sliders = mech.actuator_positions(mech.q_ref)
    assert np.all(np.min(np.abs(roots - sliders), axis=0) < 1e-10)  # each slider on one of its branches


def test_the_warning_says_where_and_its_reference_entry_keeps_it(chosen, tmp_path):
    """The warning gives pose and modes; its `reference:` entry, pasted, loads the same reference silently."""
    mech, message, folder = chosen
    rep = reference_report(mech)
    assert f"working mode {rep.working_mode}" in message
    x, y, rz = task_pose(mech, mech.q_ref)
    assert f"pose x = {x:.6g}, y = {y:.6g}, rz = {rz:.6g}" in message
    entry = yaml.safe_load(re.search(r"`reference: (\{.*\})`", message).group(1))
    sidecar = yaml.safe_load((folder / "prr3.plm.yaml").read_text())
    sidecar["reference"] = entry
    for suffix in (".urdf", ".plm.yaml"):
        (tmp_path / f"prr3{suffix}").write_text((folder / f"prr3{suffix}").read_text())
    (tmp_path / "prr3.plm.yaml").write_text(yaml.safe_dump(sidecar))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ReferenceWarning)
        again = plm_pin.load(tmp_path / "prr3.urdf")
    np.testing.assert_allclose(task_pose(again, again.q_ref), task_pose(mech, mech.q_ref), atol=1e-5)


def test_info_and_check_show_the_reference_pose_and_modes(tmp_path):
    """`info` and `check` print the reference pose and working mode of a description with a reference."""
    mech = tb.three_prr(tmp_path, reference=tb.prr_reference(tb.PRR_POSE))
    np.testing.assert_allclose(task_pose(mech, mech.q_ref), tb.PRR_POSE, atol=1e-12)
    mode = reference_report(mech).working_mode
    check = CliRunner().invoke(app, ["check", str(tmp_path / "prr3.urdf")])
    assert check.exit_code == 0, check.output
    assert (
        f"note: reference: pose x = 0.01, y = -0.02, rz = 0.1; working mode {mode}; assembly mode"
        in check.stdout
    )
    info = CliRunner().invoke(app, ["info", "--json", str(tmp_path / "prr3.urdf")])
    shown = json.loads(info.stdout)["reference"]
    np.testing.assert_allclose(shown["pose"], tb.PRR_POSE, atol=1e-12)
    assert tuple(shown["working_mode"]) == mode


def test_a_mistyped_rod_moves_the_reference_and_check_fails(tmp_path):
    """Rod 2 typed 0.1 instead of 0.3: the loops close far from the sidecar's reference, `check` says so."""
    mech = tb.three_prr(tmp_path, rod=0.1, reference=tb.prr_reference(tb.PRR_POSE))
    errors = [f for f in reference_findings(mech) if f.severity == "error"]
    assert len(errors) == 1 and errors[0].message.startswith(
        "the loops closed far from the sidecar's reference"
    )
    check = CliRunner().invoke(app, ["check", str(tmp_path / "prr3.urdf")])
    assert check.exit_code == 1
    assert "error: the loops closed far from the sidecar's reference:" in check.stderr
    moved = reference_report(mech).shifts
    assert "slider2" in moved  # the slider of the mistyped rod moves to reach the platform
    pose = task_pose(mech, mech.q_ref)
    assert np.max(np.abs(pose - tb.PRR_POSE)) > 0.01


def test_a_reference_closed_at_a_dead_centre_is_moved_off_it(tmp_path):
    """A slider-crank closed at its dead centre (working mode 0) is moved by its crank.

    The neutral configuration aligns crank and rod, the slider at r + l, where the task cannot
    move; the slider lands where the closed form x = r cos(t) + sqrt(l^2 - r^2 sin(t)^2) puts it.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mech = plm_pin.load(tb.slider_crank(tmp_path))
    (warning,) = [w for w in caught if issubclass(w.category, ReferenceWarning)]
    assert "within 0 of a singularity; moved it away" in str(warning.message)
    (t,) = mech.actuator_positions(mech.q_ref)
    (x,) = task_pose(mech, mech.q_ref)
    assert x == pytest.approx(tb.slider_crank_position(t), abs=1e-10)
    assert abs(tb.slider_crank_ratio(t)) > 0.5 * tb.SLIDER_CRANK["r"]  # off the dead centres (0 at t = 0, pi)
    assert reference_report(mech).working_mode in ((1,), (-1,))
