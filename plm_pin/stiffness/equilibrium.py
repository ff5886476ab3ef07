r"""An elastostatic equilibrium of the compliant model and the Hessian of its potential.

At a configuration :math:`q` held by actuator forces :math:`f_c` and cut-joint forces
:math:`\lambda` (:func:`plm_pin.statics.static_forces`: gravity, an external wrench, internal
preload), the springs' rest positions are taken such that :math:`q` is the equilibrium:
each drive spring carries its :math:`f_c`, each virtual joint the wrench its link passes to
its tip, passive joint springs none. The generalized force residual

.. math:: r(q) = g(q) - J_w^T w - J_\phi^T \lambda - F_s(q)

(:math:`F_s` the springs' generalized forces) then vanishes, and its derivative on the
tangent space at fixed loads and multipliers is the Hessian of the Lagrangian of the total
potential,

.. math:: H = K_s + \frac{\partial g}{\partial q} - \frac{\partial (J_w^T w)}{\partial q}
          - \frac{\partial (J_\phi^T \lambda)}{\partial q},

springs plus the geometric stiffness of gravity, of the load and of the constraint forces
(:mod:`~plm_pin.stiffness.geometric`): this is where internal preload changes the stiffness.
Every term is exact (Pinocchio's gravity derivatives and closed forms); :math:`H` is
symmetric for conservative loads (no external moment in 3-D).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._text import short
from ..core import closures as _closures
from ..core.mechanism import Mechanism
from ..description.compliance import ComplianceSpec
from ..exceptions import InvalidInput
from ..results import Result, unit
from ..statics import Load, StaticForces, static_forces
from ..statics.balance import AnyLoad, JointLoad, wrench_on_frame
from ..tolerances import ASSEMBLED_TOL
from .geometric import TreeDerivatives, closure_derivative
from .model import SOURCES, CompliantModel, compliant_model

GEOMETRIC: tuple[str, ...] = ("gravity", "load", "closures")
"""The geometric-stiffness terms, in the order results list them."""

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class ElasticState(Result):
    """A loaded equilibrium of the compliant model.

    Attributes:
        compliant: the compliant model.
        q: compliant configuration, shape (nq_c,).
        forces: the rigid static solution holding it (actuator and cut-joint forces).
        load: the external wrench on the compliant model, or None.
        gravity: whether the bodies' weight is included.
        spring_forces: generalized force each spring (and each rigid drive) exerts, shape (nv_c,) [N, N m].
    """

    compliant: CompliantModel
    q: np.ndarray = field(metadata=unit("m, rad"))
    forces: StaticForces
    load: Load | None
    gravity: bool
    spring_forces: np.ndarray = field(metadata=unit("N, N m"))
    _SKIPPED = ("compliant",)

    @property
    def lam(self) -> np.ndarray:
        """Cut-joint forces [N, N m], shape (m,)."""
        return self.forces.lam


def elastic_state(
    mech: Mechanism,
    q: ArrayLike,
    wrench: ArrayLike | None = None,
    frame: str | None = None,
    *,
    gravity: bool = True,
    internal: ArrayLike | Mapping[str, float] | None = None,
    forces: StaticForces | None = None,
    compliance: ComplianceSpec | None = None,
) -> ElasticState:
    """The equilibrium at ``q`` under gravity, ``wrench`` and internal preload.

    Args:
        mech: the mechanism.
        q: assembled configuration, shape (nq,).
        wrench: external wrench on ``frame`` (see :func:`plm_pin.statics.static_forces`).
        frame: frame the wrench acts on; default the task frame.
        gravity: include the bodies' weight.
        internal: internal preload, as ``internal`` of :func:`~plm_pin.statics.static_forces`
            (Harada 2011's :math:`f_i` on the 3D4M: ``{"plate": -f_i}``); default the
            minimum-norm forces.
        forces: a static solution at ``q`` to use instead (then ``wrench``, ``frame``,
            ``gravity`` and ``internal`` are taken from it and must not be given; ``q`` must
            be the configuration it was solved at).
        compliance: the springs; default the sidecar's.

    Raises:
        InvalidInput: malformed arguments, ``q`` not the configuration of ``forces``, no compliance.
        SingularConfiguration: the load cannot be held at ``q``.
    """
    cm = compliant_model(mech, compliance)
    if forces is not None and not isinstance(forces, StaticForces):
        raise InvalidInput(
            "forces must be a StaticForces result (plm_pin.statics.static_forces) or None, got "
            f"{short(forces)}"
        )
    if forces is None:
        forces = static_forces(mech, q, wrench, frame, gravity=gravity, internal=internal, limits=None)
    elif wrench is not None or frame is not None or internal is not None:
        raise InvalidInput("give either forces= or the wrench, frame and internal preload, not both")
    else:
        _check_forces_at(mech, q, forces)
    balance = forces.balance
    qc = cm.lift(balance.q)
    load = None
    if isinstance(balance.load, JointLoad):
        raise InvalidInput(
            f"{mech.name}: the elastostatics take a wrench on a frame, not forces along a joint task's joints"
        )
    if balance.load is not None:
        load = wrench_on_frame(cm.mech, balance.load.wrench, balance.load.frame)
    if cm.mech is mech and forces.mechanism is mech and balance.v is None and balance.a is None:
        tau, J_phi = balance.tau, balance.J_phi  # rigid links: the static balance is the compliant model's
    else:
        tau = generalized_load(cm.mech, qc, load, balance.gravity)
        J_phi = cm.mech.closure_jacobian(qc)
    spring = tau - J_phi.T @ forces.lam
    spring.setflags(write=False)
    qc.setflags(write=False)
    return ElasticState(cm, qc, forces, load, balance.gravity, spring)


def _check_forces_at(mech: Mechanism, q: ArrayLike, forces: StaticForces) -> None:
    """Refuse a static solution ``forces`` solved at another configuration than ``q``.

    The two agree when they differ by at most :data:`~plm_pin.tolerances.ASSEMBLED_TOL` [m, rad]
    on the tangent space (room for a ``q`` read back from a file).

    Raises:
        InvalidInput: a malformed ``q``, or ``forces`` solved at another configuration (the
            message gives the largest difference).
    """
    qa = mech.check_q(q)
    q_forces = forces.balance.q
    if q_forces.shape != qa.shape:
        raise InvalidInput(
            f"{mech.name}: forces= were solved on {forces.mechanism.name} (nq = {q_forces.size}), "
            f"not on this mechanism (nq = {qa.size})"
        )
    gap = float(np.max(np.abs(pin.difference(mech.model, q_forces, qa)), initial=0.0))
    if gap > ASSEMBLED_TOL:
        raise InvalidInput(
            f"{mech.name}: q is not the configuration forces= were solved at: they differ by up to "
            f"{gap:.3g} m/rad (tolerance {ASSEMBLED_TOL:.0e}); pass q=forces.balance.q or solve the "
            "forces at q"
        )


def generalized_load(mech: Mechanism, q: np.ndarray, load: AnyLoad | None, gravity: bool) -> np.ndarray:
    r""":math:`g(q) - J_w^T w`, shape (nv,) [N, N m]."""
    model, data = mech.model, mech.data
    tau = np.array(pin.computeGeneralizedGravity(model, data, q)) if gravity else np.zeros(model.nv)
    if load is not None:
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        tau -= load.generalized_force(model, data)
    return tau


def hessian_terms(
    mech: Mechanism, q: np.ndarray, load: AnyLoad | None, gravity: bool, lam: np.ndarray
) -> dict[str, np.ndarray]:
    r"""The geometric-stiffness terms of :math:`H` at ``q``, by :data:`GEOMETRIC` name, each (nv, nv).

    ``gravity``: :math:`\partial g / \partial q`; ``load``: :math:`-\partial (J_w^T w)/\partial q`;
    ``closures``: :math:`-\partial (J_\phi^T \lambda) / \partial q`. Leaves the joint Jacobians
    and frame placements at ``q`` in ``mech.data``.
    """
    model, data = mech.model, mech.data
    nv = model.nv
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    tree = TreeDerivatives(model, data)
    out = {"gravity": np.zeros((nv, nv)), "load": np.zeros((nv, nv))}
    if isinstance(load, Load):  # a joint load's generalized force does not change with q
        M = data.oMf[load.frame_id]
        joint = model.frames[load.frame_id].parentJoint
        w = load.wrench
        out["load"] = -tree.dead_wrenches([joint], w[None, :3], w[None, 3:], M.translation[None])
    out["closures"] = -closure_derivative(tree, data, mech.closures, lam)
    if gravity:
        out["gravity"] = np.array(pin.computeGeneralizedGravityDerivatives(model, data, q))
    return out


def hessian(state: ElasticState) -> dict[str, np.ndarray]:
    """Every term of the Hessian :math:`H` of the compliant model at ``state``, each (nv_c, nv_c).

    Keys: the spring sources (:data:`~plm_pin.stiffness.model.SOURCES`) then :data:`GEOMETRIC`.
    Leaves the joint Jacobians and frame placements at ``state.q`` in the compliant model's data.
    """
    cm = state.compliant
    terms = dict(cm.springs)
    terms.update(hessian_terms(cm.mech, state.q, state.load, state.gravity, state.lam))
    return {k: terms[k] for k in (*SOURCES, *GEOMETRIC)}


def closure_and_locks(cm: CompliantModel, q: np.ndarray) -> np.ndarray:
    """Constraint rows of the compliant model: closures then locked drives, shape (m + n_locked, nv_c)."""
    return with_locks(cm, _closures.jacobian(cm.mech.model, cm.mech.data, cm.mech.closures, q))


def with_locks(cm: CompliantModel, J_phi: np.ndarray) -> np.ndarray:
    """Closure rows ``J_phi`` (m, nv_c) then the rows locking the rigid drives, shape (m + n_locked, nv_c)."""
    E = np.zeros((cm.locked.size, cm.mech.nv))
    E[np.arange(cm.locked.size), cm.locked] = 1.0
    return np.vstack([J_phi, E])
