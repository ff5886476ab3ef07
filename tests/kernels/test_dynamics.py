"""The compiled dynamics terms against Pinocchio (the oracle): mass matrix, nonlinear effects, energy, drift.

On every preset and every loadable corpus robot, and on the model holding every supported joint
type with every closure type, at random configurations and velocities.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.core import closures as C
from plm_pin.kernels import Kernel, kernel_of
from plm_pin.models import preset_names
from tests.kernels.test_parity import CORPUS, EVERY_CLOSURE, _every_joint_model, _mechanism

TOL = 1e-12


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    """Largest difference relative to the size of ``b`` (1 at least)."""
    return float(np.max(np.abs(a - b), initial=0.0)) / max(1.0, float(np.max(np.abs(b), initial=0.0)))


def _check_terms(kernel: Kernel, model: pin.Model, closures, q: np.ndarray, v: np.ndarray) -> None:
    M, h, potential, gamma = kernel.dynamics(q, v)
    data = model.createData()
    M_pin = pin.crba(model, data, q)
    M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
    assert _relative(M, M_pin) <= TOL
    assert _relative(h, pin.rnea(model, data, q, v, np.zeros(model.nv))) <= TOL
    assert _relative(h, pin.nonLinearEffects(model, data, q, v)) <= TOL
    assert abs(potential - pin.computePotentialEnergy(model, data, q)) <= TOL * max(1.0, abs(potential))
    if closures:
        assert _relative(gamma, C.drift(model, model.createData(), closures, q, v)) <= TOL


@pytest.mark.parametrize("name", [*preset_names(), *CORPUS])
def test_dynamics_terms_match_pinocchio(name, rng):
    """M (armature on its diagonal), rnea(q, v, 0), potential energy and closure drift equal Pinocchio's."""
    mech = _mechanism(name)
    kernel = kernel_of(mech)
    assert kernel is not None
    model = mech.model.copy()
    model.armature = rng.uniform(0.0, 0.1, model.nv)  # a nonzero armature on a copy
    kernel = Kernel.build(model, mech.closures, mech.task_compiled)
    for _ in range(5):
        q = pin.integrate(model, mech.q_ref, rng.normal(scale=0.3, size=mech.nv))
        _check_terms(kernel, model, mech.closures, q, rng.normal(size=mech.nv))


def test_dynamics_terms_on_every_joint_and_closure_type(rng):
    """Every supported joint type (a branch too) and every closure type, under a tilted gravity."""
    model = _every_joint_model()
    model.armature = rng.uniform(0.0, 1.0, model.nv)
    model.gravity = pin.Motion(np.array([1.0, -2.0, -9.0, 0.0, 0.0, 0.0]))
    closures = C.compile_closures(model, EVERY_CLOSURE)
    kernel = Kernel.build(model, closures, None)
    for _ in range(10):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        _check_terms(kernel, model, closures, q, rng.normal(scale=2.0, size=model.nv))
