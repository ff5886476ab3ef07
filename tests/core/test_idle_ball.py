"""Idle spins of ball joints: a rod on a ball joint closed by a point spins about its own axis.

The RSSR spatial four-bar (a crank and a rocker on skew hinges, a coupler rod on a ball joint at
the crank, its tip closed on the rocker by a point): Grübler's spatial count is
6 (n - 1) - sum(6 - f_i) = 6 * 3 - (5 + 3 + 3 + 5) = 2, of which one is the coupler's spin about
its own axis (its centre of mass and both ends on that axis), so the mobility is 1 with 1 idle.
The oracles: that count, MuJoCo's compiled model (nv minus the rank of its equality-constraint
Jacobian counts the spin too), finite differences of the one-row ``twist`` gauge, and the
physics of the gauge (an idle spin carries no load, so its force vanishes in statics).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.core import closures as _closures
from plm_pin.statics import static_forces
from tests.conftest import fd_jacobian

mujoco = pytest.importorskip("mujoco")

COUPLER = np.array([0.2, 0.05, 0.2])  # crank tip -> rocker tip at qpos0 [m]

RSSR = f"""<mujoco model="rssr">
  <compiler angle="radian"/>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="crank">
      <joint name="crank_pivot" type="hinge" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01" mass="0.1"/>
      <body name="coupler" pos="0.1 0 0">
        <joint name="coupler_ball" type="ball"/>
        <geom type="capsule" fromto="0 0 0 {COUPLER[0]} {COUPLER[1]} {COUPLER[2]}" size="0.01" mass="0.2"/>
        <site name="coupler_tip" pos="{COUPLER[0]} {COUPLER[1]} {COUPLER[2]}"/>
      </body>
    </body>
    <body name="rocker" pos="0.3 0.05 0.05">
      <joint name="rocker_pivot" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.15" size="0.01" mass="0.1"/>
      <site name="rocker_tip" pos="0 0 0.15"/>
    </body>
  </worldbody>
  <equality><connect name="loop" site1="coupler_tip" site2="rocker_tip"/></equality>
  <actuator><motor name="drive" joint="crank_pivot"/></actuator>
</mujoco>
"""


@pytest.fixture(scope="module")
def rssr(tmp_path_factory) -> plm_pin.Mechanism:
    """The RSSR loaded from its MJCF."""
    path = tmp_path_factory.mktemp("rssr") / "rssr.xml"
    path.write_text(RSSR)
    return plm_pin.load(path)


def test_the_coupler_spin_is_idle_and_held_by_a_twist(rssr):
    """Mobility 1 with 1 idle (Grübler 2 minus the spin), held about the coupler's own axis."""
    assert (rssr.mobility, rssr.idle_mobility) == (6 * 3 - (5 + 3 + 3 + 5) - 1, 1)
    (gauge,) = rssr.idle_gauges
    assert gauge.joint == "coupler_ball" and gauge.closure.type == "twist"
    # the axis, in the ball joint's frame (the coupler's at qpos0), is the coupler's own
    axis = np.array(gauge.closure.axis)
    assert abs(abs(axis @ COUPLER / np.linalg.norm(COUPLER)) - 1.0) < 1e-6


def test_mujoco_counts_the_spin_as_a_freedom(rssr, tmp_path):
    """Nv - rank of MuJoCo's equality Jacobian is the mobility plus the idle spin."""
    m = mujoco.MjModel.from_xml_string(RSSR)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    J = np.array(d.efc_J).reshape(d.nefc, m.nv)[:3]  # the connect's three rows
    rank = np.linalg.matrix_rank(J, tol=1e-9)
    assert m.nv - rank == rssr.mobility + rssr.idle_mobility == 2


def test_the_twist_row_matches_finite_differences(rssr, rng):
    """The twist gauge's Jacobian row and drift are the first and second derivatives of its residual."""
    model = rssr.model
    q = pin.integrate(model, rssr.q_ref, rng.normal(scale=0.3, size=rssr.nv))
    np.testing.assert_allclose(
        rssr.closure_jacobian(q), fd_jacobian(rssr.closure_residual, model, q), atol=1e-7
    )
    v = rng.normal(size=rssr.nv)
    h = 1e-4

    def phi(t: float) -> np.ndarray:
        return rssr.closure_residual(pin.integrate(model, q, t * v))

    second = (phi(h) - 2.0 * phi(0.0) + phi(-h)) / h**2
    data = model.createData()
    drift = _closures.drift(model, data, rssr.closures, q, v)
    np.testing.assert_allclose(
        drift, second, atol=1e-6 * max(1.0, np.abs(drift).max())
    )  # measured 2e-8 at h = 1e-4


def test_the_gauge_carries_no_load(rssr):
    """Under gravity the twist's force vanishes: a rod spinning about its axis is not loaded by its weight."""
    forces = static_forces(rssr, rssr.q_ref)
    twist = next(c for c in rssr.closures if c.spec.type == "twist")
    assert abs(forces.lam[twist.rows][0]) < 1e-9 * max(1.0, float(np.abs(forces.lam).max()))
    assert forces.residual < 1e-9


def test_the_held_mechanism_moves_with_its_crank(rssr):
    """Assembly with the crank turned keeps every closure, the spin held at its reference."""
    q = rssr.assemble(rssr.q_ref, {"crank_pivot": 0.2}).q
    assert np.abs(rssr.closure_residual(q)).max() <= rssr.closure_tol
    J = rssr.closure_jacobian(q)
    assert rssr.nv - np.linalg.matrix_rank(J, tol=1e-9) == 1
