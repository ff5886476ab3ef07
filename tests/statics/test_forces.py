"""Static forces against independent paths: virtual work by finite differences of the IK, RNEA drives."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.exceptions import FrameNotFound, InvalidInput, SingularConfiguration
from plm_pin.kinematics import inverse_kinematics, task_pose
from plm_pin.statics import static_forces
from plm_pin.statics.allocation import min_norm
from plm_pin.statics.balance import load_on_frame
from tests.conftest import preset, prrrp_paper_configuration


def _virtual_work_defect(mech, q, f_c, force, h=1e-5):
    """max_k |f_c . dc_k + force . dp_k - dU_k| over task directions k (central differences of the IK).

    Quasi-static virtual work: what the actuators and the external force do on a feasible
    displacement equals the rise of potential energy. Computed with the inverse kinematics and
    pin.computePotentialEnergy only: no statics code involved.
    """
    x0 = task_pose(mech, q)
    worst = 0.0
    for k in range(x0.size):
        ends = []
        for sign in (1.0, -1.0):
            x = x0.copy()
            x[k] += sign * h
            sol = inverse_kinematics(mech, x, q)
            pin.framesForwardKinematics(mech.model, mech.data, sol.q)
            p = mech.data.oMf[mech.task_compiled.frame_id].translation.copy()
            ends.append((sol.actuators, p, pin.computePotentialEnergy(mech.model, mech.data, sol.q)))
        (c1, p1, u1), (c2, p2, u2) = ends
        worst = max(worst, abs(f_c @ (c1 - c2) + force @ (p1 - p2) - (u1 - u2)) / (2 * h))
    return worst


@pytest.mark.parametrize(
    "name",
    ["harada2011_3d4m", "harada2011_3d3m", "zhao2011_8pss", "zhao2011_6pss", "enferadi2017_star_triangle"],
)
def test_gravity_and_a_force_satisfy_virtual_work(name, rng):
    """f_c . dc + F . dp = dU along every task direction (IK finite differences), for min-norm forces."""
    mech = preset(name)
    q = mech.q_ref
    force = rng.normal(size=3) * 10.0
    sol = static_forces(mech, q, np.concatenate([force, np.zeros(3)]))
    scale = max(np.max(np.abs(sol.f_c)), 1.0)
    assert _virtual_work_defect(mech, q, sol.f_c, force) <= 1e-6 * scale
    assert sol.residual <= 1e-10 * scale


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss", "fivebar", "fourbar"])
def test_rnea_reactions_drive_exactly_the_actuators(name, rng):
    """The joint forces RNEA transmits have S^T f = f_c on actuated joints and 0 on passive ones."""
    mech = preset(name)
    sol = static_forces(mech, mech.q_ref)
    reactions = sol.joint_reactions()
    actuated = {a.joint: f for a, f in zip(mech.actuators, sol.f_c, strict=True)}
    scale = max(np.max(np.abs(sol.f_c)), 1.0)
    for joint, r in reactions.items():
        expected = actuated.get(joint, 0.0)
        np.testing.assert_allclose(r.drive, expected, atol=1e-10 * scale)


def test_8pss_holds_its_platform_with_min_norm_and_bounded_allocation():
    """The 8-PSS holds its platform against gravity; with limits below the min-norm peak it redistributes."""
    mech = preset("zhao2011_8pss")
    q = mech.q_ref
    free = static_forces(mech, q)
    assert free.internal.shape == (2,)
    peak = np.max(np.abs(free.f_c))
    least = np.max(np.abs(static_forces(mech, q, objective="max").f_c))
    assert least < peak
    bound = 0.5 * (least + peak)
    held = static_forces(mech, q, limits=[[-bound, bound]] * mech.n_actuators)
    assert np.max(np.abs(held.f_c)) <= bound * (1 + 1e-9)
    assert held.saturated  # the limit is active
    assert held.residual <= 1e-9
    six = static_forces(preset("zhao2011_6pss"), preset("zhao2011_6pss").q_ref)
    assert six.internal.shape == (0,)  # non-redundant: one answer, nothing to choose


def test_3d3m_refuses_a_load_at_a_direct_singularity():
    """At the type-4 singularity (11.4) the 3D3M cannot resist a force: a clear error, not huge numbers."""
    mech = preset("harada2011_3d3m")
    theta = math.radians(-20.0)  # sign for y > 0, as found for Fig. 6 (tests/analysis)
    y = (0.14 + 0.05) * math.sin(-theta)  # eq. (11.4): cos(theta)^2 = ((l + rt)^2 - y^2) / (l + rt)^2
    q = prrrp_paper_configuration(mech, (0.0, y, theta), (0.14,) * 4, 0.05, (-1, 1, -1, 1))
    for load in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]):
        try:
            sol = static_forces(mech, q, load, gravity=False)
        except SingularConfiguration as exc:
            assert "direct singularity" in str(exc)
        else:  # a load orthogonal to the unheld motion is still held, with bounded forces
            assert np.max(np.abs(sol.f_c)) < 1e3
    with pytest.raises(SingularConfiguration, match="cannot resist the load"):
        static_forces(mech, q, [1.0, 1.0, 1.0], gravity=False)
    assert static_forces(mech, q, gravity=False).f_c == pytest.approx(np.zeros(3))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"wrench": [1.0, 2.0]}, r"wrench on frame 'plate_center' must have 6 or 3"),
        ({"wrench": [1.0, np.nan, 0.0]}, "non-finite"),
        ({"wrench": [0.0] * 6, "frame": "nope"}, "frame 'nope' not found"),
        ({"objective": "min"}, r"objective 'min' is not one of \['norm', 'max'\]"),
        ({"weights": [1.0, -1.0, 1.0, 1.0]}, "symmetric positive definite"),
        ({"weights": [1.0, 1.0]}, r"weights must be 4 positive numbers"),
        ({"limits": [[1.0, 0.0]] * 4}, "lower <= upper"),
        ({"limits": "paper"}, "is not 'description', None"),
        ({"internal": [1.0, 2.0]}, r"internal must be 1 finite numbers"),
        ({"internal": {"rod9": 1.0}}, r"links \['rod9'\] are not hinged links"),
        ({"internal": {"rod1": 1.0, "rod2": 1.0}}, "has 1 internal force"),
        ({"link_limits": {"rod1": (1.0, 0.0)}}, "lower <= upper"),
        ({"min_compression": np.inf}, r"min_compression must be a finite number \[N\], got inf"),
        ({"min_compression": "10"}, r"min_compression must be a finite number \[N\], got '10'"),
        (
            {"link_limits": [("rod1", (0.0, 1.0))]},
            r"link_limits must be a mapping of link names to \(lower, upper\)",
        ),
        (
            {"link_limits": {"rod1": 5.0}},
            r"link_limits\['rod1'\] must be \(lower, upper\) axial forces \[N\]",
        ),
        ({"internal": [np.nan]}, r"^internal has non-finite entries at indices \[0\]$"),
        ({"internal": {"rod1": "a"}}, r"^internal\['rod1'\] must be a finite number \[N\], got 'a'$"),
        ({"weights": [1.0, np.nan, 1.0, np.inf]}, r"^weights has non-finite entries at indices \[1, 3\]$"),
        ({"objective": ["norm"]}, r"^objective \['norm'\] is not one of"),
    ],
)
def test_bad_input_is_refused_with_a_clear_message(kwargs, message):
    """Malformed wrenches, objectives, weights, limits and preloads raise InvalidInput naming the problem."""
    mech = preset("harada2011_3d4m")
    with pytest.raises((InvalidInput, FrameNotFound), match=message):
        static_forces(mech, mech.q_ref, **kwargs)


def test_to_dict_is_json_ready():
    """The solution serialises to JSON with the actuator and closure names."""
    import json

    mech = preset("harada2011_3d4m")
    d = json.loads(json.dumps(static_forces(mech, mech.q_ref).to_dict()))
    assert set(d["f_c"]) == {"slider1", "slider2", "slider3", "slider4"}
    assert set(d["lam"]) == {c.name for c in mech.closures}


def test_load_balance_and_allocation_write_their_fields():
    """A load, a balance and an allocation are results: to_dict writes their fields as plain JSON."""
    import json

    mech = preset("harada2011_3d4m")
    load = load_on_frame(mech, [1.0, 2.0, 0.1])
    assert json.loads(json.dumps(load.to_dict(), allow_nan=False)) == {
        "frame": load.frame,
        "frame_id": load.frame_id,
        "wrench": [1.0, 2.0, 0.0, 0.0, 0.0, 0.1],
    }
    balance = static_forces(mech, mech.q_ref, [1.0, 2.0, 0.1]).balance
    data = json.loads(json.dumps(balance.to_dict(), allow_nan=False))
    assert data["load"] == balance.load.to_dict() and data["tau"] == balance.tau.tolist()
    assert data["v"] is None and data["internal_basis"] == balance.internal_basis.tolist()
    alloc = min_norm(np.array([1.0, -1.0]), np.array([[1.0], [1.0]]), np.eye(2))
    assert json.loads(json.dumps(alloc.to_dict(), allow_nan=False)) == {
        "f_c": [1.0, -1.0],
        "y": [0.0],
        "active": [],
    }
