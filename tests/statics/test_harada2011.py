"""Harada 2011 statics, eqs. (14)-(22), against the paper's closed forms (analyses/_harada2011_paper.py).

Conventions and the correction of eq. (22) are in that module's docstring: the load applied
to the plate is ``wrench = -f_e``, and the paper has no gravity in its statics.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from plm_pin.statics import static_forces
from tests.conftest import preset, prrrp_paper_configuration

L, RT = 0.140, 0.05
POSES = [
    (0.0, 0.08, math.radians(-20.0)),
    (0.01, 0.09, math.radians(10.0)),
    (-0.02, 0.07, 0.0),
    (0.015, 0.10, math.radians(-5.0)),
]
UNIT_LOADS = [np.array(v, dtype=float) for v in ([1, 0, 0], [0, 1, 0], [0, 0, 1])]


def _ours(mech, pose):
    return prrrp_paper_configuration(mech, pose, (L,) * 4, RT, (-1, 1, -1, 1))


def _check_legs(sol, legs, f_l, f_n):
    """Eq. (19) per leg against ours: rod axial forces (no shear) and guide normal forces."""
    links = sol.link_forces()
    normals = sol.slider_normal_forces()
    for k, i in enumerate(legs):
        assert links[f"rod{i}"].axial == pytest.approx(f_l[k], abs=1e-10)
        assert links[f"rod{i}"].shear == pytest.approx(0.0, abs=1e-10)  # a two-force member without gravity
        np.testing.assert_allclose(normals[f"slider{i}"][:2] @ paper.N_DIR, f_n[k], atol=1e-10)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("f_e", UNIT_LOADS, ids=["fx", "fy", "tau"])
def test_3d3m_eqs_15_to_19(pose, f_e):
    """3D3M: f_c = J_ce^-T f_e (15), f_l and f_n by (17)-(19), equilibrium residual <= 1e-10."""
    mech = preset("harada2011_3d3m")
    legs = (1, 2, 4)
    f_c, f_l, f_n = paper.statics(pose, f_e, L, RT, legs)
    sol = static_forces(mech, _ours(mech, pose), -f_e, gravity=False)
    np.testing.assert_allclose(sol.f_c, f_c, atol=1e-10)
    assert sol.residual <= 1e-10
    assert sol.internal.shape == (0,)
    _check_legs(sol, legs, f_l, f_n)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("f_e", [*UNIT_LOADS, np.zeros(3)], ids=["fx", "fy", "tau", "none"])
@pytest.mark.parametrize("f_i", [0.0, 1.0])
def test_3d4m_eqs_20_to_22(pose, f_e, f_i):
    """3D4M: f_c = (J_ce^T)^+ f_e - J_c4 J_i^-1 f_i (corrected (22)); f_l, f_n by (19); residual <= 1e-10."""
    mech = preset("harada2011_3d4m")
    legs = (1, 2, 3, 4)
    f_c, f_l, f_n = paper.statics(pose, f_e, L, RT, legs, f_i)
    q = _ours(mech, pose)
    # f_i compresses the plate: the internal part alone puts -f_i of axial force in it
    sol = static_forces(mech, q, -f_e, gravity=False, internal={"plate": -f_i})
    np.testing.assert_allclose(sol.f_c, f_c, atol=1e-10)
    assert sol.residual <= 1e-10
    _check_legs(sol, legs, f_l, f_n)
    if f_i == 0.0:  # minimum norm is the paper's pseudo-inverse solution
        np.testing.assert_allclose(static_forces(mech, q, -f_e, gravity=False).f_c, f_c, atol=1e-10)


@pytest.mark.parametrize("pose", POSES)
def test_3d4m_internal_force_is_one_dimensional_along_the_end_plate(pose):
    """Eq. (21) verified, not assumed: one internal-force direction, its forces on each plate end along it."""
    mech = preset("harada2011_3d4m")
    sol = static_forces(mech, _ours(mech, pose), gravity=False)
    (direction,) = sol.internal_directions()
    lam = {c.name: direction.lam[c.rows] for c in mech.closures}
    # forces on the plate (frame B of each closure): right end from rods 3 and 4
    right = lam["rod3_plate_right"] + lam["rod4_plate_right"]
    theta = pose[2]
    along = np.array([math.cos(theta), math.sin(theta), 0.0])
    assert np.linalg.norm(right) > 0.1
    np.testing.assert_allclose(np.cross(right, along), 0.0, atol=1e-12)
    # and the plate carries it as a pure axial force: zero shear at its hinge
    assert direction.link_forces["plate"].shear == pytest.approx(0.0, abs=1e-12)
    assert abs(direction.link_forces["plate"].axial) == pytest.approx(np.linalg.norm(right), rel=1e-12)
