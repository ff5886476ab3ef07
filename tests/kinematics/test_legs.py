"""Legs as diagonal blocks of the IK Jacobian, and working modes (plm_pin/core/legs.py).

Oracles: the mechanisms' structure (which joints form which leg, known from the papers'
figures), the product rule for determinants of block-triangular matrices, and the sign of
z_i^T a = cos(phi_i) of Harada 2011 eq. (3) for the 2-PRRRP rods.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.core.legs import (
    Leg,
    ik_jacobian_from_data,
    structure_jacobian_from_data,
    working_mode_from_data,
    working_mode_from_jacobian,
)
from plm_pin.kinematics import closed_chain_jacobians, inverse_kinematics, working_modes
from plm_pin.kinematics.jacobians import ik_jacobian
from plm_pin.kinematics.working_mode import working_mode
from plm_pin.models import preset_names
from tests import textbook as tb
from tests.conftest import preset, prrrp_paper_configuration

# name -> (joints of the end-effector chain, joints of every other leg)
STRUCTURE: dict[str, tuple[set[str], list[set[str]]]] = {
    "delta": (
        {"platform_floating"},
        [{f"crank{i}", f"u{i}aa", f"u{i}ab", f"u{i}ba", f"u{i}bb"} for i in (1, 2, 3)],
    ),
    "enferadi2017_star_triangle": ({"slider1", "pivot1", "arm1"}, [{"slider2", "arm2"}, {"slider3", "arm3"}]),
    "fivebar": ({"left_motor", "left_elbow"}, [{"right_motor", "right_elbow"}]),
    "fourbar": ({"rocker_pivot"}, [{"crank_pivot", "coupler_pivot"}]),
    "harada2011_3d3m": (
        {"slider1", "rod1_pivot", "plate_pivot"},
        [{f"slider{i}", f"rod{i}_pivot"} for i in (2, 4)],
    ),
    "harada2011_3d4m": (
        {"slider1", "rod1_pivot", "plate_pivot"},
        [{f"slider{i}", f"rod{i}_pivot"} for i in (2, 3, 4)],
    ),
    "harada2015_asymmetric": (
        {"slider1", "rod1_pivot", "plate_pivot"},
        [{f"slider{i}", f"rod{i}_pivot"} for i in (2, 3, 4)],
    ),
    "planar_3rpr": ({"pivot1", "extend1", "wrist1"}, [{f"pivot{i}", f"extend{i}"} for i in (2, 3)]),
    "stewart_6ups": ({"platform_floating"}, [{f"u{i}a", f"u{i}b", f"extend{i}"} for i in range(1, 7)]),
    "zhao2011_6pss": (
        {"platform_floating"},
        [{f"slider{i}", f"u{i}a", f"u{i}b"} for i in (2, 3, 4, 5, 6, 7)],
    ),
    "zhao2011_8pss": ({"platform_floating"}, [{f"slider{i}", f"u{i}a", f"u{i}b"} for i in range(1, 9)]),
}


def test_every_preset_has_a_structure():
    """The leg structure below covers every preset."""
    assert set(STRUCTURE) == set(preset_names())


@pytest.mark.parametrize("name", preset_names())
def test_legs_are_the_expected_square_blocks(name):
    """Legs: the end-effector chain (task rows) and one leg per loop, all square, partitioning joints.

    Only the actuated ones carry a working-mode sign (the fourbar's rocker and the 8-PSS's
    floating platform do not).
    """
    mech = preset(name)
    chain_joints, other_joints = STRUCTURE[name]
    legs = mech.legs
    assert len(legs) == 1 + len(other_joints)
    assert all(len(leg.rows) == len(leg.columns) for leg in legs)
    assert [leg.square for leg in legs] == [bool(leg.actuators) for leg in legs]  # actuated legs are signed
    n_closure = mech.n_closure_rows
    chains = [leg for leg in legs if any(r >= n_closure for r in leg.rows)]
    assert len(chains) == 1
    assert set(chains[0].joints) == chain_joints
    assert set(range(n_closure, n_closure + mech.task_compiled.size)) <= set(chains[0].rows)
    others = sorted((set(leg.joints) for leg in legs if leg is not chains[0]), key=sorted)
    assert others == sorted(other_joints, key=sorted)
    columns = sorted(c for leg in legs for c in leg.columns)
    assert columns == list(range(mech.nv))
    rows = [r for leg in legs for r in leg.rows]
    assert len(rows) == len(set(rows)) == mech.nv


@pytest.mark.parametrize("name", preset_names())
def test_each_cut_leg_carries_one_actuator(name):
    """Every leg closing on the end effector holds one actuator; the actuators are all accounted for."""
    mech = preset(name)
    n_closure = mech.n_closure_rows
    actuated = []
    for leg in mech.legs:
        if not any(r >= n_closure for r in leg.rows):
            assert len(leg.actuators) == 1
            assert leg.label == leg.actuators[0]
        actuated.extend(leg.actuators)
    assert sorted(actuated) == sorted(a.joint for a in mech.actuators)


@pytest.mark.parametrize("name", preset_names())
def test_ik_jacobian_determinant_is_the_product_of_the_leg_blocks(name):
    """Block-triangular: |det| of the IK Jacobian on the legs' rows is the product of the blocks' |det|.

    The IK Jacobian with the platform's twist rows the task leaves out (a Delta's rotations),
    as the legs are found: the structure Jacobian, the IK Jacobian itself for a 6-D or joint task.
    """
    mech = preset(name)
    q = mech.q_ref
    ik_jacobian(mech, q)  # fills the joint Jacobians and placements of mech.data
    A = structure_jacobian_from_data(mech.model, mech.data, mech.closures, mech.task_compiled)
    rows = sorted(r for leg in mech.legs for r in leg.rows)
    full = abs(np.linalg.det(A[rows]))
    blocks = math.prod(abs(np.linalg.det(A[np.ix_(leg.rows, leg.columns)])) for leg in mech.legs)
    assert full == pytest.approx(blocks, rel=1e-9)
    assert full > 0.0


def _rod_signs(mech, q) -> tuple[int, ...]:
    """sign(z_i^T a) = sign(cos phi_i) per leg, phi_i the rod angle (eq. (3)), in the legs' order."""
    out = []
    for leg in mech.legs:
        i = leg.actuators[0].removeprefix("slider")
        phi = q[mech.model.joints[mech.model.getJointId(f"rod{i}_pivot")].idx_q]
        out.append(int(np.sign(math.cos(phi))))
    return tuple(out)


@pytest.mark.parametrize("name", ["harada2011_3d4m", "harada2011_3d3m", "harada2015_asymmetric"])
def test_prrrp_working_mode_is_the_sign_of_z_dot_a(name):
    """A 2-PRRRP leg's working mode is sign(z_i^T a): minus the (M.5) signs (- + - +) at the reference."""
    mech = preset(name)
    expected = {"harada2011_3d3m": (1, -1, -1)}.get(name, (1, -1, 1, -1))
    assert working_mode(mech, mech.q_ref) == expected
    assert _rod_signs(mech, mech.q_ref) == expected
    for sol in working_modes(mech, (0.01, 0.09, 0.2)):
        assert working_mode(mech, sol.q) == _rod_signs(mech, sol.q) == sol.mode


def test_vertical_rod_gives_a_zero_mode():
    """A rod normal to the stator (condition (9)) zeroes its leg's block determinant: mode 0 for that leg."""
    mech = preset("harada2015_asymmetric")
    theta = -0.3
    x, y = 0.0, 0.17 + 0.05 * math.sin(theta)  # left pair at l2 = 0.17 m: rod 2 vertical
    q = prrrp_paper_configuration(mech, (x, y, theta), (0.24, 0.17, 0.17, 0.24), 0.05, (-1, 1, -1, 1))
    assert np.max(np.abs(mech.closure_residual(q))) < 1e-15
    assert working_mode(mech, q) == (1, 0, 1, -1)


@pytest.mark.parametrize("pose", [(0.25, 0.35, math.pi / 2), (0.2, 0.2, 0.6), (0.3, 0.25, 2.5)])
def test_star_triangle_keeps_one_working_mode(pose):
    """The star-triangle's legs have J_ii = sin(phi) > 0 for phi in (0, pi): one working mode everywhere."""
    mech = preset("enferadi2017_star_triangle")
    assert working_mode(mech, inverse_kinematics(mech, pose).q) == working_mode(mech, mech.q_ref)


def test_fivebar_has_four_working_modes_with_every_sign():
    """Each RR leg of the five-bar reaches the tip elbow-up or elbow-down: 4 working modes, all sign pairs."""
    mech = preset("fivebar")
    solutions = working_modes(mech, [0.02, 0.25])
    assert sorted(s.mode for s in solutions) == sorted(itertools.product((-1, 1), repeat=2))
    for s in solutions:
        assert s.residual_norm <= 1e-12


def test_working_mode_from_jacobian_signs_are_lapack_determinant_signs(rng):
    """Block signs (1 x 1 to 4 x 4) are numpy's determinant signs; a rank-deficient block gives 0."""
    A = rng.normal(size=(11, 11))
    sizes = (1, 2, 3, 4)
    starts = np.cumsum((0, *sizes))
    legs = [Leg(tuple(range(a, b)), tuple(range(a, b))[::-1], (), ()) for a, b in itertools.pairwise(starts)]
    legs.append(Leg((10,), (9, 10), (), ()))  # not square: no sign
    expected = tuple(int(np.sign(np.linalg.det(A[np.ix_(leg.rows, leg.columns)]))) for leg in legs[:-1])
    assert working_mode_from_jacobian(A, legs) == expected
    for leg in legs[1:4]:  # repeat a column of each block of size 2 to 4: singular
        B = A.copy()
        B[list(leg.rows), leg.columns[0]] = B[list(leg.rows), leg.columns[1]]
        signs = working_mode_from_jacobian(B, legs)
        assert signs[legs.index(leg)] == 0


def _turned_block_signs(mech, A) -> tuple[int, ...]:
    """One leg at a time: LAPACK's determinant sign of each square block, its passive columns turned."""
    out = []
    for leg in mech.legs:
        if not leg.square:
            continue
        M = A[np.ix_(leg.sign_rows, leg.columns)]
        for k, jid, root, generic in leg.axes:
            world = pin.getJointJacobian(mech.model, mech.data, jid, pin.LOCAL_WORLD_ALIGNED)[
                3:, leg.columns[k]
            ]
            if mech.data.oMi[root].rotation.T @ world @ np.array(generic) < 0.0:
                M[:, k] *= -1.0
        out.append(int(np.sign(np.linalg.det(M))))
    return tuple(out)


@pytest.mark.parametrize("name", ["zhao2011_8pss", "delta", "harada2011_3d4m"])
def test_working_mode_from_data_is_the_sign_of_each_turned_block(name, rng):
    """Working modes, from the structure Jacobian or the IK rows, are per-leg LAPACK determinant signs."""
    mech = preset(name)
    task = mech.task_compiled
    for _ in range(10):
        q = pin.integrate(mech.model, mech.q_ref, 0.3 * rng.normal(size=mech.nv))
        pin.computeJointJacobians(mech.model, mech.data, q)
        pin.updateFramePlacements(mech.model, mech.data)
        A = structure_jacobian_from_data(mech.model, mech.data, mech.closures, task)
        expected = _turned_block_signs(mech, A)
        assert working_mode_from_data(mech.model, mech.data, mech.closures, task, mech.legs) == expected
        ik_rows = ik_jacobian_from_data(mech.model, mech.data, mech.closures, task)
        got = working_mode_from_data(mech.model, mech.data, mech.closures, task, mech.legs, ik_rows=ik_rows)
        assert got == expected


DELTA_SIGNS = list(itertools.product((1, -1), repeat=3))


@pytest.fixture(scope="module")
def deltas(tmp_path_factory):
    """Single-rod Delta, parallelogram Delta on a floating platform, and hanging on leg 0's rod."""
    folder = tmp_path_factory.mktemp("delta")
    return {
        "single": (tb.delta(folder, False, name="single"), 0.0),
        "floating": (tb.delta(folder, True, name="floating"), tb.DELTA["r"]),
        "hanging": (tb.delta(folder, True, False, name="hanging"), tb.DELTA["r"]),
    }


def _same_angles(a, b) -> bool:
    return bool(np.allclose(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))), 0.0, atol=1e-9))


@pytest.mark.parametrize("kind", ["single", "floating", "hanging"])
def test_delta_has_eight_working_modes_one_sign_per_leg(deltas, kind):
    """Every Delta lists the 8 closed-form elbow branches, mode = minus Clavel's sign, whatever its tree.

    The closed form (tests/textbook.py) gives each motor angle t_i = atan2(b, a) + s_i acos(c / |(a, b)|);
    the parallelogram's platform floating or hanging on leg 0 gives the same legs and signs.
    """
    mech, r = deltas[kind]
    assert [leg.label for leg in mech.legs if leg.square] == ["m0", "m1", "m2"]
    solutions = working_modes(mech, tb.DELTA_POINT)
    assert sorted(s.mode for s in solutions) == sorted(DELTA_SIGNS)
    for sol in solutions:
        assert sol.residual_norm <= 1e-11
        signs = tuple(-m for m in sol.mode)
        assert _same_angles(sol.actuators, tb.delta_ik(tb.DELTA_POINT, signs, r))
    chosen = inverse_kinematics(mech, tb.DELTA_POINT, mode=(1, -1, 1))
    assert _same_angles(chosen.actuators, tb.delta_ik(tb.DELTA_POINT, (-1, 1, -1), r))


def test_three_rrr_working_modes_are_the_elbow_branches(tmp_path):
    """3-RRR: 8 working modes whose motor angles are Gosselin's closed-form elbow branches."""
    mech = tb.three_rrr(tmp_path)
    solutions = working_modes(mech, tb.RRR_POSE)
    assert len({s.mode for s in solutions}) == 8
    closed = [tb.rrr_ik(tb.RRR_POSE, s) for s in DELTA_SIGNS]
    for sol in solutions:
        assert sum(_same_angles(sol.actuators, c) for c in closed) == 1
    at_ref = working_mode(mech, mech.q_ref)  # the reference is in branch (+1, +1, +1)
    flipped = next(s for s in solutions if s.mode == tuple(-m for m in at_ref))
    assert _same_angles(flipped.actuators, tb.rrr_ik(tb.RRR_POSE, (-1, -1, -1)))


def test_three_rrr_actuator_jacobian_is_the_closed_form(tmp_path):
    """3-RRR J_ce at two poses equals Gosselin's rows [e_i, R c_i x e_i] / (l1 a_i x e_i)."""
    mech = tb.three_rrr(tmp_path)
    for pose in (tb.RRR_POSE, (0.05, 0.03, -0.1)):
        sol = inverse_kinematics(mech, pose)
        J = closed_chain_jacobians(mech, sol.q).J_ce
        np.testing.assert_allclose(J, tb.rrr_jce(pose, sol.actuators), atol=1e-10)
