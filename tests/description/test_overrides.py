"""Sweeps and variants of a user's description (plm_pin/description/overrides.py).

The 6-UPS Stewart platform of tests/textbook.py is written to disk and varied by name: a
base joint moved, the platform's mass changed; manipulability and statics are compared with
the closed forms |det J| and J^T f = -m (g, 0) of the textbook.
"""

from __future__ import annotations

import numpy as np
import pytest

import plm_pin
from plm_pin import InvalidInput
from plm_pin.statics import static_forces
from plm_pin.sweep import sweep
from tests import textbook as tb


@pytest.fixture(scope="module")
def stewart_path(tmp_path_factory):
    """The 6-UPS written to a folder; its URDF path."""
    folder = tmp_path_factory.mktemp("stewart")
    tb.stewart(folder)
    return folder / "stewart.urdf"


def test_sweep_of_a_description_moves_a_base_joint(stewart_path):
    """Sweeping u0a.x (base joint B_0's x) gives w = |det J| of the closed form with B_0 moved."""
    xs = [0.44, 0.5]
    result = sweep(
        str(stewart_path), parameters={"u0a.x": xs}, poses={"x": [0.01]}, pose=list(tb.STEWART_POSE)
    )
    B, _ = tb.stewart_points()
    for k, x in enumerate(xs):
        moved = B.copy()
        moved[0, 0] = x
        _, J = tb.stewart_legs(tb.STEWART_POSE, moved)
        w = float(result.dataset["manipulability"].values[k, 0])
        assert w == pytest.approx(abs(np.linalg.det(J)), rel=1e-9)


def test_mass_override_changes_statics_by_the_closed_form(stewart_path):
    """Platform mass 2 -> 3 kg: the leg forces change by -dm J^-T (g, 0), the struts' share cancelling."""
    light = plm_pin.build_mechanism(str(stewart_path), {"platform.mass": 2.0})
    heavy = plm_pin.build_mechanism(str(stewart_path), {"platform.mass": 3.0})
    jid = heavy.model.getJointId("platform_free")
    assert heavy.model.inertias[jid].mass == pytest.approx(3.0)
    np.testing.assert_allclose(heavy.model.inertias[jid].inertia, 1.5 * light.model.inertias[jid].inertia)
    x = tb.STEWART_POSE
    f = [static_forces(m, plm_pin.kinematics.inverse_kinematics(m, x).q).f_c for m in (light, heavy)]
    _, J = tb.stewart_legs(x)
    g = np.array([*heavy.sidecar.gravity, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(f[1] - f[0], -1.0 * np.linalg.solve(J.T, g), atol=1e-9)


def test_description_parameters_are_checked_before_any_work(stewart_path):
    """An unknown name lists the valid ones; a length on a joint at its parent's origin is refused."""
    with pytest.raises(InvalidInput, match=r"^unknown parameter 'leg0\.stroke' of .*stewart\.urdf; its "):
        sweep(str(stewart_path), parameters={"leg0.stroke": [0.1]}, poses={"x": [0.01]})
    with pytest.raises(
        InvalidInput,
        match=r"^parameter 'leg0\.length': joint 'leg0' sits at its parent's origin, so there is no",
    ):
        plm_pin.build_mechanism(str(stewart_path), {"leg0.length": 0.4})
    with pytest.raises(InvalidInput, match=r"^parameter 'platform\.mass' must be a finite positive number"):
        plm_pin.build_mechanism(str(stewart_path), {"platform.mass": -1.0})
    with pytest.raises(InvalidInput, match=r"or give the path of a description$"):
        sweep("no/such/robot.urdf", parameters={"a.mass": [1.0]}, poses={"x": [0.0]})
