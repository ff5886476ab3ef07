"""Harada 2011 statics, eqs. (14)-(22), reproduced from the paper's closed forms (tests/analysis/paper.py).

Conventions (paper, section 4): ``f_e = J_ce^T f_c`` is the force the actuators exert on the
end plate, so the load applied to the plate is ``wrench = -f_e``; the paper has no gravity in
its statics. ``f_l`` is the tensile force of a rod, ``f_n`` the constraint force along
``n = (0, 1)`` on a slider (eq. (16): ``f_c a + f_n n + f_l z = 0`` on the slider).

Eq. (22) as printed, ``J_ce43^T J_i^-1 f_i``, is a (3 x 4)(4,) product: a 3-vector where f_c
has 4 entries. With eqs. (18) and (21) the internal part is ``-J_c4 J_i^-1 f_i``: the rods'
axial forces ``f_l = J_i^-1 f_i`` that put the plate ends under ``f_i``, turned into actuator
forces by eq. (18). That corrected form is what is checked here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from plm_pin.statics import static_forces
from tests.analysis import paper
from tests.conftest import preset, prrrp_paper_configuration

L, RT = 0.140, 0.05
N_DIR = np.array([0.0, 1.0])
POSES = [
    (0.0, 0.08, math.radians(-20.0)),
    (0.01, 0.09, math.radians(10.0)),
    (-0.02, 0.07, 0.0),
    (0.015, 0.10, math.radians(-5.0)),
]
UNIT_LOADS = [np.array(v, dtype=float) for v in ([1, 0, 0], [0, 1, 0], [0, 0, 1])]


def _paper(pose, legs):
    """z_i (eq. (3)), J_cm = diag(z_i^T a), J_nm = diag(z_i^T n), J_ce (eq. (12)) at ``pose``."""
    c = paper.slider_positions(pose, L, RT, legs)
    z = np.array(
        [(paper.pair_position(pose, i, RT) - ci * paper.A) / L for ci, i in zip(c, legs, strict=True)]
    )
    return z, np.diag(z @ paper.A), np.diag(z @ N_DIR), paper.J_ce(pose, c, L, RT, legs)


def _ours(mech, pose):
    return prrrp_paper_configuration(mech, pose, (L,) * 4, RT, (-1, 1, -1, 1))


def _check_legs(sol, legs, f_c, J_cm, J_nm):
    """Eq. (19) per leg: f_l = -J_cm^-1 f_c, f_n = J_nm J_cm^-1 f_c, against ours."""
    f_l = -np.linalg.solve(J_cm, f_c)
    f_n = J_nm @ np.linalg.solve(J_cm, f_c)
    links = sol.link_forces()
    normals = sol.slider_normal_forces()
    for k, i in enumerate(legs):
        assert links[f"rod{i}"].axial == pytest.approx(f_l[k], abs=1e-10)
        assert links[f"rod{i}"].shear == pytest.approx(0.0, abs=1e-10)  # a two-force member without gravity
        np.testing.assert_allclose(normals[f"slider{i}"][:2] @ N_DIR, f_n[k], atol=1e-10)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("f_e", UNIT_LOADS, ids=["fx", "fy", "tau"])
def test_3d3m_eqs_15_to_19(pose, f_e):
    """3D3M: f_c = J_ce^-T f_e (15), f_l and f_n by (17)-(19), equilibrium residual <= 1e-10."""
    mech = preset("harada2011_3d3m")
    legs = (1, 2, 4)
    _, J_cm, J_nm, J_ce = _paper(pose, legs)
    sol = static_forces(mech, _ours(mech, pose), -f_e, gravity=False)
    f_c = np.linalg.solve(J_ce.T, f_e)
    np.testing.assert_allclose(sol.f_c, f_c, atol=1e-10)
    assert sol.residual <= 1e-10
    assert sol.internal.shape == (0,)
    _check_legs(sol, legs, f_c, J_cm, J_nm)


def _internal_paper(pose, z, J_cm, f_i):
    """-J_c4 J_i^-1 f_i with J_i and f_i of eq. (21)."""
    theta = pose[2]
    J_i = -np.block(
        [[z[0][:, None], z[1][:, None], np.zeros((2, 2))], [np.zeros((2, 2)), z[2][:, None], z[3][:, None]]]
    )
    f_vec = f_i * np.array([math.cos(theta), math.sin(theta), -math.cos(theta), -math.sin(theta)])
    return -J_cm @ np.linalg.solve(J_i, f_vec)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("f_e", [*UNIT_LOADS, np.zeros(3)], ids=["fx", "fy", "tau", "none"])
@pytest.mark.parametrize("f_i", [0.0, 1.0])
def test_3d4m_eqs_20_to_22(pose, f_e, f_i):
    """3D4M: f_c = (J_ce^T)^+ f_e - J_c4 J_i^-1 f_i (corrected (22)); f_l, f_n by (19); residual <= 1e-10."""
    mech = preset("harada2011_3d4m")
    legs = (1, 2, 3, 4)
    z, J_cm, J_nm, J_ce = _paper(pose, legs)
    f_c = np.linalg.pinv(J_ce.T) @ f_e + _internal_paper(pose, z, J_cm, f_i)
    q = _ours(mech, pose)
    # f_i compresses the plate: the internal part alone puts -f_i of axial force in it
    sol = static_forces(mech, q, -f_e, gravity=False, internal={"plate": -f_i})
    np.testing.assert_allclose(sol.f_c, f_c, atol=1e-10)
    assert sol.residual <= 1e-10
    _check_legs(sol, legs, f_c, J_cm, J_nm)
    if f_i == 0.0:  # minimum norm is the paper's pseudo-inverse solution
        np.testing.assert_allclose(static_forces(mech, q, -f_e, gravity=False).f_c, f_c, atol=1e-10)


@pytest.mark.parametrize("pose", POSES)
def test_3d4m_internal_force_is_one_dimensional_along_the_end_plate(pose):
    """Eq. (21) verified, not assumed: one internal mode, its forces on each plate end along the plate."""
    mech = preset("harada2011_3d4m")
    sol = static_forces(mech, _ours(mech, pose), gravity=False)
    (mode,) = sol.internal_modes()
    lam = {c.name: mode.lam[c.rows] for c in mech.closures}
    # forces on the plate (frame B of each closure): right end from rods 3 and 4
    right = lam["rod3_plate_right"] + lam["rod4_plate_right"]
    theta = pose[2]
    along = np.array([math.cos(theta), math.sin(theta), 0.0])
    assert np.linalg.norm(right) > 0.1
    np.testing.assert_allclose(np.cross(right, along), 0.0, atol=1e-12)
    # and the plate carries it as a pure axial force: zero shear at its hinge
    assert mode.link_forces["plate"].shear == pytest.approx(0.0, abs=1e-12)
    assert abs(mode.link_forces["plate"].axial) == pytest.approx(np.linalg.norm(right), rel=1e-12)
