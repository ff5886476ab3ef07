r"""Task-space dynamics of a closed chain: :math:`M_x \ddot x + h_x + g_x = f_x`.

The tree's equations of motion with the closure forces :math:`\lambda`,

.. math:: M(q)\, a + C(q, v)\, v + g(q) = \tau + J_\phi^T \lambda,

are projected on the feasible motions :math:`v = S \dot x`
(:attr:`plm_pin.kinematics.ClosedChainJacobians.S`, :math:`J_\phi S = 0`, :math:`J_x S = I`),
which removes the closure forces. Every feasible acceleration is
:math:`a = S \ddot x + a_0` with :math:`a_0` the tree acceleration at zero task
acceleration,

.. math::
    J_\phi a_0 + \dot J_\phi v = 0, \qquad J_x a_0 + \dot J_x v = 0, \qquad
    a_0 = a_p - S (\dot J_x v + J_x a_p),

:math:`a_p` the minimum-norm solution of the closure rows. Hence

.. math::
    M_x = S^T M S, \qquad h_x = S^T (C(q, v)\, v + M a_0), \qquad g_x = S^T g(q),
    \qquad f_x = S^T \tau,

:math:`f_x` being the generalized task force of the applied joint forces; with actuator
forces :math:`f_c` alone, :math:`f_x = J_{ce}^T f_c` (:math:`S_a S = J_{ce}`), Harada 2011
eq. (23) with :math:`\mathbf f_e = f_x`. :math:`M` holds the armature (reflected rotor
inertia) on its diagonal (``pin.crba``) and :math:`g` uses the model's gravity:
:math:`g_x` is the task force that *holds* the mechanism against gravity (for Harada's
tables, gravity along -y, :math:`g_y = (2 m_l + m_t) g > 0`).

Meaning of the rows. Task velocities are the world-aligned twist rows of the end-effector
frame (:mod:`plm_pin.core.task`): the velocity of the frame origin and the angular
velocity :math:`\omega`, both in world axes. So :math:`\ddot x` is the classical
acceleration of the origin and the angular acceleration :math:`\dot\omega`, and the rows of
:math:`f_x` are the force on the origin and the moment about it (world axes) whose power
is :math:`f_x^T \dot x`. For a planar task ``x y rz`` these are the Lagrangian coordinates
:math:`(x, y, \theta)` of the papers (:math:`\omega_z = \dot\theta`); for spatial rotations
:math:`\ddot x` is :math:`\dot\omega`, *not* the second derivative of the roll-pitch-yaw
angles :math:`r`: the kinetic energy is :math:`\tfrac12 \dot x^T M_x \dot x`, which in rpy
rates (:math:`\omega = E(r) \dot r`) reads :math:`\tfrac12 \dot r^T E^T M_x E \dot r`.

At a constraint singularity (the closure Jacobian loses rank, see
:func:`plm_pin.kinematics.classify`) the terms are those of the generic mobility and lose
their meaning; :func:`plm_pin.dynamics.decoupling.decoupling_check` skips such poses.

Units (SI): for rows :math:`i, j` linear (l) or angular (a), :math:`M_{x,ij}` is [kg]
(l-l), [kg m] (l-a) or [kg m^2] (a-a); :math:`h_x, g_x, f_x` are [N] (l) or [N m] (a).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import as_vector, check_tolerance
from .._linalg import lu_solve
from ..core.checks import check_assembled, check_finite_model, check_finite_result
from ..core.mechanism import Mechanism, require_task
from ..core.task import check_task_vector
from ..exceptions import InvalidInput, SingularConfiguration
from ..kinematics.jacobians import check_square_task, closed_chain_jacobians
from ..kinematics.singularity import SINGULARITY_TOL, inverse_margins
from ..results import Result, unit
from ..tolerances import FEASIBLE_VELOCITY_RTOL, ILL_CONDITIONED_MARGIN
from ..warnings import IllConditionedWarning
from .trajectory import particular_acceleration


def task_units(dofs: tuple[str, ...]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """SI units of the task-space terms: of each entry of ``M_x`` (row-major) and of each row of ``f_x``.

    Args:
        dofs: task coordinates, among ``x y z rx ry rz``.

    Returns:
        The units of ``M_x`` flattened row by row (``kg``, ``kg m``, ``kg m^2``) and of the
        force rows (``N``, ``N m``).
    """
    angular = [d.startswith("r") for d in dofs]
    mass = tuple(("kg", "kg m", "kg m", "kg m^2")[2 * ai + aj] for ai in angular for aj in angular)
    return mass, tuple("N m" if a else "N" for a in angular)


@dataclass(frozen=True)
class TaskSpaceDynamics(Result):
    r"""Task-space terms of a closed chain at one state :math:`(q, v)`: :math:`M_x \ddot x + h_x + g_x = f_x`.

    Rows follow ``dofs`` (the task's coordinates); see the module docstring for their
    meaning and units. Arrays are read-only.

    Attributes:
        dofs: task coordinates, e.g. ``("x", "y", "rz")``.
        q: configuration, shape (nq,).
        v: tree velocity :math:`S \dot x` [m/s, rad/s], shape (nv,).
        xdot: task velocity :math:`J_x v` (twist rows) [m/s, rad/s], shape (n_task,).
        M_x: task inertia :math:`S^T M S` [kg, kg m, kg m^2], shape (n_task, n_task), symmetric.
        h_x: velocity terms :math:`S^T (C v + M a_0)` [N, N m], shape (n_task,).
        g_x: gravity terms :math:`S^T g` [N, N m], shape (n_task,).
        S: velocity map :math:`v = S \dot x`, shape (nv, n_task).
        M: joint-space inertia with armature [kg, kg m, kg m^2], shape (nv, nv).
        h: joint-space velocity terms :math:`C v + M a_0` [N, N m], shape (nv,).
        g: joint-space gravity terms [N, N m], shape (nv,).
    """

    dofs: tuple[str, ...]
    q: np.ndarray = field(metadata=unit("m, rad"))
    v: np.ndarray = field(metadata=unit("m/s, rad/s"))
    xdot: np.ndarray = field(metadata=unit("m/s, rad/s"))
    M_x: np.ndarray = field(metadata=unit("kg, kg m, kg m^2"))
    h_x: np.ndarray = field(metadata=unit("N, N m"))
    g_x: np.ndarray = field(metadata=unit("N, N m"))
    S: np.ndarray
    M: np.ndarray = field(metadata=unit("kg, kg m, kg m^2"))
    h: np.ndarray = field(metadata=unit("N, N m"))
    g: np.ndarray = field(metadata=unit("N, N m"))
    _SKIPPED = ("S", "M", "h", "g")

    def __post_init__(self) -> None:
        n, nv = len(self.dofs), self.v.shape[0]
        shapes = {
            "xdot": (n,),
            "M_x": (n, n),
            "h_x": (n,),
            "g_x": (n,),
            "S": (nv, n),
            "M": (nv, nv),
            "h": (nv,),
            "g": (nv,),
        }
        for name, shape in shapes.items():
            arr = getattr(self, name)
            if arr.shape != shape:
                raise InvalidInput(f"{name} has shape {arr.shape}, expected {shape}")
        for name in ("q", "v", *shapes):
            getattr(self, name).setflags(write=False)

    def force(self, xddot: ArrayLike) -> np.ndarray:
        r"""Task force :math:`f_x = M_x \ddot x + h_x + g_x` [N, N m] at a task acceleration, shape (n_task,).

        Args:
            xddot: task acceleration (twist-row derivatives) [m/s^2, rad/s^2], shape (n_task,).
        """
        return self.M_x @ check_task_vector(xddot, len(self.dofs), "xddot") + self.h_x + self.g_x

    def acceleration(self, f_x: ArrayLike) -> np.ndarray:
        r"""Task acceleration :math:`M_x^{-1} (f_x - h_x - g_x)` [m/s^2, rad/s^2], shape (n_task,).

        Args:
            f_x: generalized task force, e.g. :math:`J_{ce}^T f_c` [N, N m], shape (n_task,).
        """
        return lu_solve(self.M_x, check_task_vector(f_x, len(self.dofs), "f_x") - self.h_x - self.g_x)

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON, with the units of ``M_x`` (row-major) and of the force rows."""
        mass_units, force_units = task_units(self.dofs)
        units = {"M_x": list(mass_units), "h_x": list(force_units), "g_x": list(force_units)}
        return {**super().to_dict(), "units": units}


def task_space_dynamics(
    mech: Mechanism,
    q: ArrayLike,
    v: ArrayLike | None = None,
    *,
    xdot: ArrayLike | None = None,
    singularity_tol: float = SINGULARITY_TOL,
) -> TaskSpaceDynamics:
    r"""Task inertia, velocity and gravity terms at an assembled state.

    Args:
        mech: the mechanism (its task must have as many coordinates as it has DOF).
        q: assembled configuration, shape (nq,).
        v: feasible tree velocity (:math:`J_\phi v = 0`) [m/s, rad/s], shape (nv,).
        xdot: task velocity (twist rows) [m/s, rad/s], shape (n_task,), instead of ``v``
            (then :math:`v = S \dot x`). Neither: at rest (:math:`h_x = 0`).
        singularity_tol: inverse margin at or below which ``q`` counts as inverse-singular [-]
            (the tolerance of :func:`plm_pin.kinematics.classify`; a finite number >= 0).

    Returns:
        :math:`M_x, h_x, g_x` with the joint-space terms they come from.

    Raises:
        InvalidInput: no task, a task size different from the DOF, malformed ``q``, ``v`` or
            ``xdot``, both ``v`` and ``xdot``, or ``v`` opening the loops.
        DescriptionError: a body's inertia is not finite (see :func:`plm_pin.core.checks.check_finite_model`).
        ClosureNotSatisfied: ``q`` is not assembled to :attr:`Mechanism.assembled_tol`.
        SingularConfiguration: at an inverse-kinematics (type 1) singularity, where :math:`S`
            is undefined: an inverse margin at or below ``singularity_tol``, as
            :func:`plm_pin.kinematics.classify` decides.

    Warns:
        IllConditionedWarning: when the inverse margin is below :data:`ILL_CONDITIONED_MARGIN`
            (near a type 1 singularity, e.g. a four-bar's rocker at its extreme): the terms
            are large and inaccurate.
    """
    task = require_task(mech)
    check_square_task(task.size, mech.mobility, "task-space dynamics needs", mech.name)
    tol = check_tolerance(singularity_tol, "singularity_tol")
    qa = check_assembled(mech, q)
    check_finite_model(mech)
    jac = closed_chain_jacobians(mech, qa)
    margin = float(inverse_margins(jac.T, jac.J_x))
    if margin <= tol:
        raise SingularConfiguration(
            f"{mech.name}: inverse-kinematics (type 1) singular configuration: inverse margin {margin:.3g} "
            f"at or below the tolerance {tol:.3g} (as plm_pin.kinematics.classify decides); S and M_x are "
            "undefined there"
        )
    S = jac.S  # (nv, n_task)
    if margin < ILL_CONDITIONED_MARGIN:
        warnings.warn(
            f"{mech.name}: near an inverse (type 1) singularity: inverse margin {margin:.3g} below "
            f"{ILL_CONDITIONED_MARGIN:.0e}; M_x grows as 1/margin^2 and is inaccurate",
            IllConditionedWarning,
            stacklevel=2,
        )
    if xdot is not None:
        if v is not None:
            raise InvalidInput("give the tree velocity v or the task velocity xdot, not both")
        va = S @ check_task_vector(xdot, task.size, "xdot")
    elif v is None:
        va = np.zeros(mech.nv)
    else:
        va = as_vector(v, mech.nv, "v")
        opening = float(np.max(np.abs(jac.J_phi @ va), initial=0.0))
        if opening > FEASIBLE_VELOCITY_RTOL * max(1.0, float(np.max(np.abs(va)))):
            raise InvalidInput(
                f"{mech.name}: v is not a feasible velocity: |J_phi v| = {opening:.3g} opens the loops "
                f"(tolerance {FEASIBLE_VELOCITY_RTOL:.0e} x max(1, |v|)); pass xdot, or v = S @ xdot"
            )
    model, data = mech.model, mech.data
    a_p = particular_acceleration(mech, qa, va, jac)  # leaves the kinematics of (q, v, 0) in data
    a0 = a_p - S @ (task.drift_from_data(model, data) + jac.J_x @ a_p)
    M = np.array(pin.crba(model, data, qa))  # whole symmetric matrix, armature included (Pinocchio 4.1)
    g = np.array(pin.computeGeneralizedGravity(model, data, qa))
    h = np.array(pin.rnea(model, data, qa, va, a0)) - g
    M_x = S.T @ M @ S
    check_finite_result(mech, "the task-space terms", M_x=M_x, h=h, g=g)
    return TaskSpaceDynamics(
        dofs=tuple(task.dofs),
        q=qa.copy(),
        v=va,
        xdot=jac.J_x @ va,
        M_x=0.5 * (M_x + M_x.T),
        h_x=S.T @ h,
        g_x=S.T @ g,
        S=S,
        M=M,
        h=h,
        g=g,
    )
