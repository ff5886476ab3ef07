"""The benchmark's floors and closed form (benchmarks/harness.py) compute what the paths they time compute."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from benchmarks.harness import (
    CAPABILITY_CASES,
    GENERATED,
    Floor,
    _timing_line,
    capability_floor,
    harada_closed_form_map,
    internal_range_floor,
    machine,
    write,
)
from plm_pin.kinematics import closed_chain_jacobians, forward_kinematics, inverse_kinematics, task_pose
from plm_pin.models import PRESETS
from plm_pin.statics import force_capability, internal_force_range
from plm_pin.statics.allocation import new_highs
from plm_pin.statics.balance import load_on_frame
from plm_pin.workspace import manipulability, workspace_map
from tests.conftest import preset


def test_floor_solves_and_measures_like_plm_pin():
    """The floor's IK, FK, closure singular values and manipulability equal plm_pin's on the 3D4M."""
    mech = preset("harada2011_3d4m")
    floor = Floor(mech)
    q = mech.q_ref
    x = task_pose(mech, q) + 1e-3
    ik = inverse_kinematics(mech, x, q).q
    assert np.abs(floor.ik(q, x) - ik).max() < 1e-13
    c = mech.actuator_positions(ik)
    assert np.abs(floor.fk(q, c) - forward_kinematics(mech, c, q, all_modes=False)[0].q).max() < 1e-13
    _, s, _, _ = floor.jacobians(q)
    assert np.allclose(s, closed_chain_jacobians(mech, q).closure_singular_values, atol=1e-14)
    w, cond = floor.manipulability(q)
    ref = manipulability(mech, q)
    assert math.isclose(w, ref.w, rel_tol=1e-12) and math.isclose(cond, ref.condition_number, rel_tol=1e-12)


def test_closed_form_map_is_harada_eq_13_and_matches_the_map():
    """The vectorised closed form equals the paper module's eq. (12) J_ce, and workspace_map's w, to 1e-10."""
    mech = preset("harada2011_3d4m")
    p = PRESETS["harada2011_3d4m"].parameters
    l, rt = p["rod_lengths"][0], p["half_plate"]
    values = (np.linspace(-0.05, 0.05, 7), np.linspace(0.03, 0.11, 6))
    result = workspace_map(mech, ("x", "y"), values, (0.0, 0.08, math.radians(-20.0)))
    poses = result.poses().reshape(-1, 3)
    w = harada_closed_form_map(poses, l, rt, (-1, 1, -1, 1))
    for pose, wk in zip(poses[::5], w[::5], strict=True):
        J = paper.J_ce(pose, paper.slider_positions(pose, l, rt, (1, 2, 3, 4)), l, rt, (1, 2, 3, 4))
        assert math.isclose(wk, math.sqrt(np.linalg.det(J.T @ J)), rel_tol=1e-10)
    assert result.reachable.all()
    assert np.allclose(w, result.manipulability.reshape(-1), rtol=1e-10, atol=0.0)


def test_timing_line_prints_the_floor_and_the_ratio():
    """A row with a floor shows it and the ratio; one without shows dashes."""
    row = {"mechanism": "m", "case": "c", "seconds_per_call": 3e-4, "floor_seconds_per_call": 2e-4}
    assert _timing_line(row) == "| m | c | 300.0 us | 200.0 us | 1.50 |"
    bare = {"mechanism": "m", "case": "c", "seconds_per_call": 2.5}
    assert _timing_line(bare) == "| m | c | 2.50 s | - | - |"


def test_written_tables_state_the_date_and_machine_and_reach_the_docs(tmp_path):
    """results.md, results.json and the docs' tables carry the run's date, processor and versions."""
    import json
    import platform
    import time

    row = {"mechanism": "m", "case": "c", "seconds_per_call": 3e-4, "floor_seconds_per_call": 2e-4}
    docs = tmp_path / "docs" / "benchmarks.md"
    md = write([row], tmp_path / "bench", notes=("a note",), docs=docs)
    info = json.loads((tmp_path / "bench" / "results.json").read_text())["machine"]
    assert time.strptime(info["date"], "%Y-%m-%d")  # an ISO date (UTC)
    assert info == machine() | {"date": info["date"], "load_average": info["load_average"]}
    stated = f"Measured on {info['date']} on {info['cpu']} ({info['cores']} cores"
    for text in (md.read_text(), docs.read_text()):
        assert stated in text and f"Python {platform.python_version()}" in text
        assert "| m | c | 300.0 us | 200.0 us | 1.50 |" in text and "- a note" in text
    assert md.read_text().startswith("# plm_pin benchmarks")
    assert docs.read_text().startswith(GENERATED + "\n\n## The latest run")


@pytest.mark.parametrize("name", sorted(CAPABILITY_CASES))
def test_capability_floors_compute_force_capability_and_the_internal_range(name):
    """The floors' alpha equals force_capability's; their internal range is internal_force_range's."""
    direction, bound = CAPABILITY_CASES[name]
    mech = preset(name)
    q = mech.q_ref
    limits = np.array([[-bound, bound]] * mech.n_actuators)
    data, highs = mech.model.createData(), new_highs()
    task = load_on_frame(mech, direction)
    alpha = capability_floor(mech, data, highs, q, task.frame_id, task.wrench, limits)
    assert math.isclose(alpha, force_capability(mech, q, direction, limits=limits).alpha, rel_tol=1e-9)
    ends, G = internal_range_floor(mech, data, highs, q, limits)
    ours = internal_force_range(mech, q, limits=limits)
    R = G.T @ ours.internal_basis  # (k, k) the floor's basis in plm_pin's: a rotation (same span)
    np.testing.assert_allclose(R @ R.T, np.eye(mech.redundancy), atol=1e-12)
    if mech.redundancy == 1:  # one internal force: the extent of g^T f_c (f_p is orthogonal to g), up to sign
        lo, hi = sorted(R[0, 0] * np.array([ours.lower[0], ours.upper[0]]))
        np.testing.assert_allclose(ends[:, 0], [lo, hi], rtol=1e-9)
