"""Wrong answers refused (plm_pin/_arguments.py and its callers), table-driven, messages by text.

Classes: configurations off the closure manifold, NaN or negative tolerances, limits that admit
nothing, zero load directions, bodies whose inertia overflows, body groups named like the body
split's own shares.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pinocchio as pin
import pytest

from plm_pin import ClosureNotSatisfied, DescriptionError, InvalidInput
from plm_pin.core.mechanism import Mechanism
from plm_pin.dynamics import actuator_trajectory, inverse_dynamics, task_space_dynamics, task_trajectory
from plm_pin.kinematics import classify, closed_chain_jacobians
from plm_pin.kinematics.paths import redundancy_margin
from plm_pin.models import preset_names
from plm_pin.statics import force_capability, internal_force_range, static_balance, static_forces
from plm_pin.tolerances import ASSEMBLED_TOL
from plm_pin.workspace import manipulability
from tests.conftest import preset

LIMITS = [(-100.0, 100.0)] * 4  # for the 3D4M's capability and range [N]

# every public analysis that takes a configuration: (name, call(mech, q)), the preset(s) it applies to
AT_Q = [
    ("closed_chain_jacobians", lambda m, q: closed_chain_jacobians(m, q), None),
    ("classify", lambda m, q: classify(m, q), None),
    ("manipulability", lambda m, q: manipulability(m, q), None),
    ("static_forces", lambda m, q: static_forces(m, q), None),
    ("static_balance", lambda m, q: static_balance(m, q), None),
    ("task_space_dynamics", lambda m, q: task_space_dynamics(m, q), None),
    ("redundancy_margin", lambda m, q: redundancy_margin(m, q), None),
    ("force_capability", lambda m, q: force_capability(m, q, [1.0, 0, 0], limits=LIMITS), "harada2011_3d4m"),
    ("internal_force_range", lambda m, q: internal_force_range(m, q, limits=LIMITS), "harada2011_3d4m"),
]
CASES = [
    pytest.param(fname, call, name, id=f"{fname}-{name}")
    for fname, call, only in AT_Q
    for name in ([only] if only else preset_names())
]


def _open(mech: Mechanism, step: float) -> np.ndarray:
    """The reference configuration moved by ``step`` along every tree velocity (loops opened)."""
    return np.asarray(pin.integrate(mech.model, mech.q_ref, np.full(mech.nv, step)))


@pytest.mark.parametrize(("fname", "call", "name"), CASES)
@pytest.mark.parametrize("step", [0.05, 1e-5])
def test_off_manifold_configurations_are_refused(fname, call, name, step):
    """Every analysis refuses q with open loops: ClosureNotSatisfied carrying the residual and the fix."""
    mech = preset(name)
    q = _open(mech, step)
    residual = np.abs(mech.closure_residual(q))
    assert residual.max() > ASSEMBLED_TOL  # the configuration really is off the manifold
    with pytest.raises(ClosureNotSatisfied) as info:
        call(mech, q)
    exc = info.value
    assert exc.residual_norm == pytest.approx(residual.max(), rel=1e-12)
    assert exc.tolerance == ASSEMBLED_TOL
    assert re.fullmatch(
        rf"{name}: q is not assembled: closure '{exc.worst_closure}' is open by {exc.residual_norm:.3g} "
        r"\(tolerance 1e-08 m/rad\); assemble it first: mech.assemble\(q\).q",
        str(exc),
    )


@pytest.mark.parametrize(("fname", "call", "name"), [c for c in CASES if "harada2011_3d4m" in c.id])
def test_assembled_configurations_pass_and_assembling_first_is_the_fix(fname, call, name):
    """The refused configuration, assembled as the message says, is accepted (residual below 1e-8)."""
    mech = preset(name)
    q = mech.assemble(_open(mech, 0.05)).q
    call(mech, q)  # no error
    call(mech, mech.q_ref)


def test_inverse_dynamics_refuses_a_trajectory_with_one_open_sample():
    """One sample of a trajectory moved off the manifold: refused, naming the sample and its time."""
    mech = preset("harada2011_3d4m")
    x0 = np.array([0.0, 0.08, -0.3])

    def profile(t):
        return x0 + np.array([0.01 * t, 0.0, 0.0]), np.array([0.01, 0.0, 0.0]), np.zeros(3)

    traj = task_trajectory(mech, profile, np.linspace(0.0, 1.0, 5))
    inverse_dynamics(mech, traj)  # assembled: no error
    q = traj.q.copy()
    q[3, 0] += 0.002
    bad = dataclasses.replace(traj, q=q)
    with pytest.raises(
        ClosureNotSatisfied,
        match=r"^sample 3 \(t = 0\.75 s\) of the trajectory: harada2011_3d4m: q is not assembled: closure "
        r"'\w+' is open by 0\.002 \(tolerance 1e-08 m/rad\); assemble it first: mech.assemble\(q\).q$",
    ):
        inverse_dynamics(mech, bad)


# ------------------------------------------------------------------ tolerances and limits

BAD_TOLERANCES = [float("nan"), -1.0, -1e-12, float("inf"), "a", None]


@pytest.mark.parametrize("tol", BAD_TOLERANCES)
def test_classify_refuses_a_tolerance_that_is_not_a_nonnegative_number(tol):
    """classify(tol=nan) would never report a singularity; NaN, negative, inf or non-numbers are refused."""
    mech = preset("fourbar")
    shown = repr(float(tol)) if isinstance(tol, float) else repr(tol)
    with pytest.raises(InvalidInput, match=rf"^tol must be a finite number >= 0, got {re.escape(shown)}$"):
        classify(mech, mech.q_ref, tol=tol)


@pytest.mark.parametrize("rtol", [*BAD_TOLERANCES, 1.0, 2.0])
@pytest.mark.parametrize("call", [static_forces, static_balance])
def test_statics_refuses_a_singular_rtol_outside_0_1(call, rtol):
    """static_forces(singular_rtol=-1) gave a NaN residual; only [0, 1) is accepted."""
    mech = preset("harada2011_3d4m")
    shown = repr(float(rtol)) if isinstance(rtol, float | int) and not isinstance(rtol, bool) else repr(rtol)
    with pytest.raises(
        InvalidInput, match=rf"^singular_rtol must be a finite number in \[0, 1\), got {re.escape(shown)}$"
    ):
        call(mech, mech.q_ref, singular_rtol=rtol)


@pytest.mark.parametrize(
    "limits",
    [
        [(np.inf, np.inf)] * 4,
        [(-np.inf, -np.inf)] * 4,
        [(-100.0, 100.0)] * 3 + [(np.inf, np.inf)],
        [(-100.0, -np.inf)] + [(-100.0, 100.0)] * 3,
    ],
)
def test_limits_admitting_no_effort_are_refused(limits):
    """A lower bound of +inf or an upper bound of -inf is not 'no limit': refused, not ignored."""
    mech = preset("harada2011_3d4m")
    expected = r"^limits must have lower <= upper, lower < \+inf and upper > -inf for every actuator, got "
    with pytest.raises(InvalidInput, match=expected):
        static_forces(mech, mech.q_ref, limits=limits)


def test_unbounded_limits_are_still_no_limits():
    """(-inf, inf) per actuator is the same as limits=None."""
    mech = preset("harada2011_3d4m")
    free = static_forces(mech, mech.q_ref, limits=None).f_c
    np.testing.assert_array_equal(static_forces(mech, mech.q_ref, limits=[(-np.inf, np.inf)] * 4).f_c, free)


@pytest.mark.parametrize("direction", [[0.0, 0.0, 0.0], [0.0] * 6, [-0.0, 0.0, 0.0]])
def test_force_capability_refuses_a_zero_direction(direction):
    """force_capability(m, q, [0, 0, 0]) returned alpha = inf; a zero load has no capability."""
    mech = preset("harada2011_3d4m")
    expected = r"^direction must be a nonzero load \(it sets the unit of alpha\)"
    with pytest.raises(InvalidInput, match=expected):
        force_capability(mech, mech.q_ref, direction, limits=LIMITS)


# ------------------------------------------------------------------ bodies that overflow


def _crank_turning():
    """The four-bar's crank turning at 1 rad/s for 0.1 s (3 samples)."""
    fb = preset("fourbar")
    c0 = fb.actuator_positions(fb.q_ref)[0]
    return actuator_trajectory(fb, lambda t: ([c0 + t], [1.0], [0.0]), [0.0, 0.05, 0.1])


def _overflowing(joint: int, com) -> Mechanism:
    """The four-bar with the body on tree joint ``joint`` given a centre of mass at ``com`` [m]."""
    fb = preset("fourbar")
    model = pin.Model(fb.model)
    inertia = model.inertias[joint]
    model.inertias[joint] = pin.Inertia(inertia.mass, np.asarray(com, dtype=float), inertia.inertia)
    return Mechanism(model, fb.sidecar, name="fourbar")


@pytest.mark.parametrize("joint", [1, 2, 3])
@pytest.mark.parametrize("com", [(1e300, 0, 0), (0, 1e300, 0), (0, 0, -1e300), (1e200, 1e200, 0)])
@pytest.mark.parametrize(
    "call",
    [
        lambda m: static_forces(m, m.q_ref),
        lambda m: task_space_dynamics(m, m.q_ref),
        lambda m: static_balance(m, m.q_ref),
        lambda m: inverse_dynamics(m, _crank_turning()),
    ],
    ids=["static_forces", "task_space_dynamics", "static_balance", "inverse_dynamics"],
)
def test_a_centre_of_mass_that_overflows_is_refused(joint, com, call):
    """A COM at 1e300 m gave f_c = [nan] or 1e300 N; the overflowing body is named instead."""
    mech = _overflowing(joint, com)
    body = mech.body_names[joint - 1]
    with pytest.raises(
        DescriptionError,
        match=rf"^fourbar: the spatial inertia of bodies \['{body}'\] is not finite \(a mass or centre of "
        r"mass too large for floating point\); fix their <inertial> in the description$",
    ):
        call(mech)


@pytest.mark.parametrize("edit", ["replaced", "in place"])
def test_a_body_that_overflows_after_a_passing_check_is_refused(edit):
    """The finiteness verdict is kept per mechanism, yet an inertia edited after a passing call is refused."""
    mech = preset("fourbar")
    mech = Mechanism(pin.Model(mech.model), mech.sidecar, name="fourbar")  # not the shared preset
    static_forces(mech, mech.q_ref)  # passes: the verdict is kept
    static_forces(mech, mech.q_ref)
    if edit == "replaced":
        inertia = mech.model.inertias[2]
        mech.model.inertias[2] = pin.Inertia(inertia.mass, np.array([0.0, 1e300, 0.0]), inertia.inertia)
    else:
        mech.model.inertias[2].lever[1] = 1e300
    with pytest.raises(
        DescriptionError, match=rf"^fourbar: the spatial inertia of bodies \['{mech.body_names[1]}'\]"
    ):
        static_forces(mech, mech.q_ref)
    with pytest.raises(DescriptionError, match=r"is not finite"):  # refused again: no verdict kept for it
        static_forces(mech, mech.q_ref)


# ------------------------------------------------------------------ body groups


@pytest.mark.parametrize("group", ["rotor", "screw", "external", "other"])
def test_body_groups_named_like_the_split_shares_are_refused(group):
    """A group named 'rotor' or 'external' was swallowed by the split's own share; refused with the names."""
    mech = preset("harada2011_3d4m")
    traj = task_trajectory(
        mech, lambda t: (np.array([0.0, 0.08, -0.3]), np.zeros(3), np.zeros(3)), np.linspace(0.0, 1.0, 2)
    )
    with pytest.raises(
        InvalidInput,
        match=rf"^body groups are named \['{group}'\], a name the body split keeps for its own shares "
        r"\['external', 'other', 'rotor', 'screw'\]; name the groups otherwise with "
        r"groups=\{name: \[body, \.\.\.\]\}$",
    ):
        inverse_dynamics(mech, traj, groups={group: ["plate"], "sliders": ["slider1", "slider2"]})
    ok = inverse_dynamics(mech, traj, groups={"plate": ["plate"]})
    assert set(ok.bodies) == {"plate", "other"}  # no rotor, screw or load on this table: no such share
    np.testing.assert_allclose(sum(ok.bodies.values()), ok.f_c, atol=1e-10 * np.max(np.abs(ok.f_c)))


@pytest.mark.parametrize("speed", [1e160, -1e200, 1e250])
def test_task_space_terms_that_overflow_are_refused(speed):
    """A velocity whose squares overflow gives h = inf or NaN: refused by the final guard, not returned."""
    mech = preset("fourbar")
    S = closed_chain_jacobians(mech, mech.q_ref).S
    with (
        np.errstate(over="ignore", invalid="ignore"),
        pytest.raises(
            InvalidInput,
            match=r"^fourbar: the task-space terms are not finite \(h\); an input is too large for "
            r"floating point$",
        ),
    ):
        task_space_dynamics(mech, mech.q_ref, xdot=[speed])
    assert np.all(np.isfinite(S * speed))  # the velocity itself is finite


@pytest.mark.parametrize("size", [1, 3, 64, 65, 500])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_vectors_with_a_non_finite_entry_are_refused_at_any_length(size, bad):
    from plm_pin._arguments import as_vector

    x = np.ones(size)
    x[size // 2] = bad
    with pytest.raises(InvalidInput, match=rf"x has non-finite entries at indices \[{size // 2}\]"):
        as_vector(x, size, "x")


@pytest.mark.parametrize("size", [2, 64, 65])
def test_vectors_of_huge_finite_entries_pass_though_their_sum_overflows(size):
    from plm_pin._arguments import as_vector

    x = np.full(size, np.finfo(float).max)
    assert sum(x.tolist()) == np.inf  # the quick check's sum overflows: the full check must decide
    np.testing.assert_array_equal(as_vector(x, size, "x"), x)
