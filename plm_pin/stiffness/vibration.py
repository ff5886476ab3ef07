r"""Natural frequencies at a pose: small vibrations about an elastostatic equilibrium.

Two models:

- ``"task"``: the task-space mass matrix :math:`M_x` (:func:`plm_pin.dynamics.task_space_dynamics`,
  rigid links) with :math:`K_x`: :math:`K_x \phi = \omega^2 M_x \phi`;
- ``"full"``: every motion of the compliant model (virtual joints of flexible links
  included), :math:`H \phi = \omega^2 M \phi` with the joint-space mass matrix (armature
  included) restricted to the feasible motions. Massless directions (a virtual joint
  whose tip carries no mass) have no finite frequency and are left out.

With rigid links and as many task coordinates as DOF the two coincide. The stiffness is
the symmetric part of the Hessian.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
import scipy.linalg
from numpy.typing import ArrayLike

from .._text import short
from ..core.mechanism import Mechanism
from ..dynamics.task_space import task_space_dynamics
from ..exceptions import InvalidInput, SingularConfiguration
from ..results import Result, unit
from ..tolerances import MASSLESS_RTOL
from .cartesian import StiffnessResult, stiffness

MODELS: tuple[str, ...] = ("task", "full")
"""The vibration models of :func:`natural_frequencies`."""


@dataclass(frozen=True)
class Vibration(Result):
    """Lowest natural vibrations at a pose, ascending.

    Attributes:
        model: ``"task"`` or ``"full"``.
        dofs: task coordinates.
        frequencies: natural frequencies [Hz], shape (n,).
        omega: angular frequencies [rad/s], shape (n,).
        task_shapes: task motion of each vibration [m, rad], largest entry scaled to 1, shape (n_task, n).
        joint_shapes: tree motion of each vibration (compliant model) [m, rad], same scaling, shape (nv_c, n).
    """

    model: str
    dofs: tuple[str, ...]
    frequencies: np.ndarray = field(metadata=unit("Hz"))
    omega: np.ndarray = field(metadata=unit("rad/s"))
    task_shapes: np.ndarray = field(metadata=unit("m, rad"))
    joint_shapes: np.ndarray = field(metadata=unit("m, rad"))
    _SKIPPED = ("joint_shapes",)

    @property
    def lowest(self) -> float:
        """Lowest natural frequency [Hz]."""
        return float(self.frequencies[0])


def natural_frequencies(
    mech: Mechanism,
    q: ArrayLike,
    *,
    model: str = "task",
    count: int | None = None,
    result: StiffnessResult | None = None,
    **stiffness_options: Any,
) -> Vibration:
    """Lowest natural frequencies and vibration shapes at ``q``.

    Args:
        mech: the mechanism (with a task).
        q: assembled configuration, shape (nq,).
        model: ``"task"`` (:math:`M_x`, :math:`K_x`) or ``"full"`` (compliant model).
        count: number of vibrations kept, lowest first (default all).
        result: a :func:`~plm_pin.stiffness.stiffness` result at ``q`` to reuse.
        **stiffness_options: passed to :func:`~plm_pin.stiffness.stiffness` (``wrench``,
            ``gravity``, ``internal``, ``forces``, ``compliance``).

    Raises:
        InvalidInput: an unknown model or count, and as :func:`~plm_pin.stiffness.stiffness`.
        SingularConfiguration: the equilibrium is unstable (a non-positive stiffness), and as
            :func:`~plm_pin.stiffness.stiffness`.
    """
    if not isinstance(model, str) or model not in MODELS:
        raise InvalidInput(f"model {short(model)} is not one of {list(MODELS)}")
    if count is not None and (isinstance(count, bool) or not isinstance(count, int) or count < 1):
        raise InvalidInput(f"count must be a positive integer or None, got {short(count)}")
    if result is not None and not isinstance(result, StiffnessResult):
        raise InvalidInput(
            f"result must be a StiffnessResult (plm_pin.stiffness.stiffness) or None, got {short(result)}"
        )
    res = result if result is not None else stiffness(mech, q, **stiffness_options)
    if model == "task":
        M = task_space_dynamics(mech, res.q).M_x
        K = 0.5 * (res.K_x + res.K_x.T)
        basis, T = np.eye(K.shape[0]), np.eye(K.shape[0])
    else:
        cmech = res.state.compliant.mech
        Mq = np.array(pin.crba(cmech.model, cmech.data, res.state.q))
        Mq = np.triu(Mq) + np.triu(Mq, 1).T
        basis, T = res.basis, res.T
        M = basis.T @ Mq @ basis
        K = 0.5 * (res.H + res.H.T)
    try:
        inv_w2, shapes = scipy.linalg.eigh(M, K)  # M phi = (1 / omega^2) K phi
    except np.linalg.LinAlgError:
        raise SingularConfiguration(
            f"{mech.name}: the equilibrium is unstable (stiffness not positive definite): "
            "no natural vibrations"
        ) from None
    keep = inv_w2 > MASSLESS_RTOL * max(float(inv_w2.max()), 1e-300)
    order = np.argsort(-inv_w2[keep])
    inv_w2, shapes = inv_w2[keep][order], shapes[:, keep][:, order]
    if count is not None:
        inv_w2, shapes = inv_w2[:count], shapes[:, :count]
    omega = 1.0 / np.sqrt(inv_w2)
    task_shapes = T @ shapes if model == "full" else shapes
    joint = basis @ shapes if model == "full" else np.zeros((0, shapes.shape[1]))
    big = np.max(np.abs(task_shapes), axis=0)
    big = np.where(big > 0, big, 1.0)
    signs = np.sign(task_shapes[np.argmax(np.abs(task_shapes), axis=0), np.arange(task_shapes.shape[1])])
    signs = np.where(signs == 0, 1.0, signs)
    task_shapes = task_shapes / (big * signs)
    joint = joint / (big * signs)
    for a in (omega, task_shapes, joint):
        a.setflags(write=False)
    return Vibration(model, res.dofs, omega / (2 * np.pi), omega, task_shapes, joint)
