r"""Accuracy: how errors of the description's geometry move the task pose, and the error bound they give.

The error model (:func:`error_model`) has three groups of small parameters :math:`p`, each zero
in the nominal description:

- every tree joint's placement in its parent joint's frame (``model.jointPlacements``, a URDF
  joint's ``origin``): six errors ``JOINT.x JOINT.y JOINT.z`` [m], a translation in the parent's
  frame, and ``JOINT.rx JOINT.ry JOINT.rz`` [rad], a small rotation about the joint frame's own
  axes: :math:`M \to \mathrm{Trans}(\delta p)\, M\, \mathrm{Rot}(\delta\theta)`;
- every closure frame's placement on its body (``model.frames[f].placement``, relative to the
  frame's parent joint), the same six errors, ``frame:NAME.x`` ... ``frame:NAME.rz``;
- every actuator's offset ``actuator:JOINT`` [m or rad]: the joint stands at its commanded
  value plus the offset.

With the actuators held at their commanded values, the loops closed (:math:`\phi(q, p) = 0`) and
the task pose :math:`t(q, p)`, the first-order change of the configuration :math:`\delta v`
(tangent space) and of the pose for a parameter error :math:`\delta p` solve

.. math:: \begin{bmatrix} J_\phi \\ S_a \end{bmatrix} \delta v
          = \begin{bmatrix} -\Phi_p\, \delta p \\ \delta c \end{bmatrix},
          \qquad \delta t = J_x\, \delta v + X_p\, \delta p,

where :math:`S_a` selects the actuated velocities, :math:`\delta c` are the actuator offsets,
and :math:`\Phi_p`, :math:`X_p` are the explicit derivatives of the closure residual and of the
task pose with respect to the parameters (exact, from the frames' placements: a placement error
of joint :math:`k` moves every frame it carries as a rigid displacement about the joint's frame).
Away from a direct (type 2) singularity :math:`[J_\phi; S_a]` has full column rank and the
solution is its pseudo-inverse applied to the right-hand side, so that the sensitivity is

.. math:: S = J_x \begin{bmatrix} J_\phi \\ S_a \end{bmatrix}^+
          \begin{bmatrix} -\Phi_p & 0 \\ 0 & I \end{bmatrix} + [X_p \;\; 0].

An error the rigid loops cannot absorb (an out-of-plane error of a planar mechanism, an actuator
offset of a redundantly actuated one: the real mechanism then deforms or binds) leaves the
right-hand side out of the range of :math:`[J_\phi; S_a]`; :math:`S` is then the least-squares
fit of the loops, and :attr:`Sensitivity.mismatch` says how much of the closure each unit error
leaves open.

The pose error :math:`\delta t` of a frame task is the world-aligned displacement of the
end-effector frame: its origin's displacement [m] and its small rotation vector [rad] (for a
planar task, the change of the plate angle ``rz``); of a joint task, the output joints' change.

The bound (:func:`error_bound`) takes a tolerance :math:`\tau_k` per parameter:
``worst_case`` :math:`= |S|\,\tau` is the largest first-order pose error when every error lies in
:math:`[-\tau_k, \tau_k]` (interval analysis), and ``rms`` :math:`= \sqrt{S^{\circ 2} \tau^{\circ 2}}`
is the standard deviation of the pose error when the errors are independent with standard
deviations :math:`\tau_k`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import nonnegative
from ..core import closures as _closures
from ..core.checks import check_closed
from ..core.mechanism import Mechanism, require_task
from ..core.task import FrameTask
from ..exceptions import InvalidInput, SingularConfiguration
from ..results import Result, unit
from ..tolerances import ACTUATED_SINGULAR_RTOL

PLACEMENT_ERRORS = ("x", "y", "z", "rx", "ry", "rz")
"""The six errors of a placement: translation in the parent's frame [m], rotation about its own axes [rad]."""


@dataclass(frozen=True)
class ErrorModel(Result):
    """The geometric parameters whose errors :func:`sensitivity` considers, in column order.

    Attributes:
        names: parameter names: ``JOINT.x`` ... ``JOINT.rz`` per tree joint (model order), then
            ``frame:NAME.x`` ... per closure frame (sidecar order), then ``actuator:JOINT``.
        units: the unit of each, ``"m"`` or ``"rad"``.
        joints: the tree joints whose placements are parameters, in model order.
        frames: the closure frames whose placements are parameters.
        actuators: the actuated joints whose offsets are parameters.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    joints: tuple[str, ...]
    frames: tuple[str, ...]
    actuators: tuple[str, ...]

    @property
    def size(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def tolerances(self, length: float, angle: float) -> np.ndarray:
        """One tolerance per parameter: ``length`` [m] for those in m, ``angle`` [rad] for those in rad.

        Raises:
            InvalidInput: a tolerance that is negative or not finite.
        """
        t_len = nonnegative(length, "length", "m")
        t_ang = nonnegative(angle, "angle", "rad")
        return np.array([t_len if u == "m" else t_ang for u in self.units])

    def check(self, tolerances: ArrayLike) -> np.ndarray:
        """``tolerances`` as an array of one finite number >= 0 per parameter [m, rad].

        Raises:
            InvalidInput: a wrong size, a negative or non-finite entry.
        """
        try:
            arr = np.asarray(tolerances, dtype=float)
        except (TypeError, ValueError):
            arr = np.full(0, np.nan)
        if arr.shape != (self.size,) or not np.all(np.isfinite(arr)) or np.any(arr < 0):
            raise InvalidInput(
                f"tolerances must be {self.size} finite numbers >= 0 [m, rad], one per parameter of "
                f"error_model (ErrorModel.tolerances(length, angle) makes them), got shape {arr.shape}"
            )
        return arr


def error_model(mech: Mechanism) -> ErrorModel:
    """The parameters of the accuracy analysis of ``mech`` (see the module docstring).

    Args:
        mech: the mechanism.

    Returns:
        Their names and units, 6 per tree joint, 6 per closure frame and 1 per actuator.
    """
    model = mech.model
    joints = tuple(str(n) for n in model.names[1:])
    frames = tuple(dict.fromkeys(f for spec in mech.sidecar.closures for f in spec.frames))
    actuators = tuple(a.joint for a in mech.actuators)
    names: list[str] = []
    units: list[str] = []
    for prefix in (*joints, *(f"frame:{f}" for f in frames)):
        names += [f"{prefix}.{e}" for e in PLACEMENT_ERRORS]
        units += ["m"] * 3 + ["rad"] * 3
    names += [f"actuator:{a}" for a in actuators]
    units += ["m" if a.kind == "prismatic" else "rad" for a in mech.actuators]
    return ErrorModel(tuple(names), tuple(units), joints, frames, actuators)


@dataclass(frozen=True)
class Sensitivity(Result):
    """First-order sensitivity of the task pose to the parameters of :func:`error_model`.

    Attributes:
        S: d(task pose)/d(parameters), shape (n_task, n_params) [task unit per parameter unit].
        dofs: the task coordinates (rows).
        names: the parameters (columns).
        units: each parameter's unit.
        mismatch: norm of the linearised closure residual a unit error of each parameter leaves
            open, shape (n_params,) [m, rad per parameter unit]; 0 for an error the rigid loops absorb.
    """

    S: np.ndarray = field(metadata=unit("task unit per parameter unit"))
    dofs: tuple[str, ...]
    names: tuple[str, ...]
    units: tuple[str, ...]
    mismatch: np.ndarray = field(metadata=unit("m, rad per parameter unit"))

    def largest(self, row: int, count: int) -> list[tuple[str, float]]:
        """The ``count`` parameters moving task coordinate ``row`` most, with ``|S|``, largest first."""
        return _ranked(np.abs(self.S[row]), self.names, count)


def _ranked(values: np.ndarray, names: tuple[str, ...], count: int) -> list[tuple[str, float]]:
    order = np.argsort(-values, kind="stable")[:count]
    return [(names[k], float(values[k])) for k in order]


@dataclass(frozen=True)
class ErrorBound(Result):
    """Pose error bound for given tolerances of the parameters.

    Attributes:
        dofs: the task coordinates.
        worst_case: largest first-order error of each coordinate, ``|S| tol`` [m, rad].
        rms: its standard deviation for independent errors of standard deviation ``tol`` [m, rad].
        sensitivity: the sensitivity the bound comes from.
        tolerances: the tolerance of each parameter [m, rad].
    """

    dofs: tuple[str, ...]
    worst_case: np.ndarray = field(metadata=unit("m, rad"))
    rms: np.ndarray = field(metadata=unit("m, rad"))
    sensitivity: Sensitivity
    tolerances: np.ndarray = field(metadata=unit("m, rad"))

    def contributions(self, row: int, count: int) -> list[tuple[str, float]]:
        """The ``count`` largest terms ``|S| tol`` of coordinate ``row``'s worst case [m, rad], descending."""
        return _ranked(np.abs(self.sensitivity.S[row]) * self.tolerances, self.sensitivity.names, count)


def _placement_columns(
    mech: Mechanism, data: pin.Data, frame_id: int, frame_column: dict[int, int], n_params: int
) -> np.ndarray:
    """World-aligned displacement of frame ``frame_id`` per unit parameter, shape (6, n_params).

    Rows: the frame origin's displacement (3) and its world rotation vector (3).
    """
    model = mech.model
    frame = model.frames[frame_id]
    out = np.zeros((6, n_params))
    p_f = data.oMf[frame_id].translation
    for k in list(model.supports[frame.parentJoint])[1:]:  # the universe carries no placement
        col = 6 * (k - 1)
        parent = data.oMi[model.parents[k]]
        K0 = parent * model.jointPlacements[k]
        out[:3, col : col + 3] = parent.rotation
        out[:3, col + 3 : col + 6] = -pin.skew(p_f - K0.translation) @ K0.rotation
        out[3:, col + 3 : col + 6] = K0.rotation
    col = frame_column.get(frame_id)
    if col is not None:
        out[:3, col : col + 3] = data.oMi[frame.parentJoint].rotation
        out[3:, col + 3 : col + 6] = data.oMf[frame_id].rotation
    return out


def sensitivity(mech: Mechanism, q: ArrayLike) -> Sensitivity:
    """Sensitivity of the task pose to the description's geometric errors at an assembled ``q``.

    See the module docstring for the model and the formula.

    Args:
        mech: the mechanism (it needs a task).
        q: an assembled configuration, shape (nq,).

    Returns:
        The sensitivity matrix with its row and column names.

    Raises:
        InvalidInput: a malformed ``q`` or a mechanism without a task.
        ClosureNotSatisfied: ``q`` is off the closure manifold.
        SingularConfiguration: the actuators do not fix the configuration (a direct, type 2,
            singularity, or fewer actuators than DOF).
    """
    task = require_task(mech)
    qa = mech.check_q(q)
    model, data = mech.model, mech.data
    pin.computeJointJacobians(model, data, qa)
    pin.updateFramePlacements(model, data)
    check_closed(mech, qa, _closures.residual_from_placements(data, mech.closures))
    errors = error_model(mech)
    n_p, n_act = errors.size, mech.n_actuators
    frame_column = {model.getFrameId(f): 6 * (len(errors.joints) + i) for i, f in enumerate(errors.frames)}
    J_phi = _closures.jacobian_from_data(model, data, mech.closures)
    m = J_phi.shape[0]
    moved = {}
    for c in mech.closures:
        for f in c.frame_ids:
            if f not in moved:
                moved[f] = _placement_columns(mech, data, f, frame_column, n_p)
    rhs = np.zeros((m + n_act, n_p))
    for c in mech.closures:
        fa, fb = c.frame_ids
        d = moved[fb] - moved[fa]
        rows = c.rows
        rhs[rows.start : rows.start + c.point_rows] = -d[: c.point_rows]
        if c.spec.type != "point":
            rhs[c.rotation_rows] = -_closures.angular_rows(c, data) @ d[3:]
    rhs[m + np.arange(n_act), n_p - n_act + np.arange(n_act)] = 1.0
    A = np.zeros((m + n_act, mech.nv))
    A[:m] = J_phi
    A[m + np.arange(n_act), mech.actuated_v_indices] = 1.0
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    if s.size < mech.nv or s[-1] <= ACTUATED_SINGULAR_RTOL * s[0]:
        raise SingularConfiguration(
            f"{mech.name}: the actuators do not fix the configuration (smallest singular value of "
            f"[J_phi; S_a] {s[-1] if s.size else 0.0:.3g}, largest {s[0] if s.size else 0.0:.3g}): a direct "
            "(type 2) singularity, where the pose error is unbounded"
        )
    dv = Vt.T @ ((U.T @ rhs) / s[:, None])
    mismatch = np.linalg.norm(rhs - A @ dv, axis=0)
    S = task.jacobian_from_data(model, data) @ dv
    if isinstance(task, FrameTask):
        S += _placement_columns(mech, data, task.frame_id, frame_column, n_p)[task.selectors[0]]
    return Sensitivity(S, tuple(task.dofs), errors.names, errors.units, mismatch)


def error_bound(mech: Mechanism, q: ArrayLike, tolerances: ArrayLike) -> ErrorBound:
    r"""Worst-case and RMS task-pose error at ``q`` for tolerances of the geometric parameters.

    Args:
        mech: the mechanism (it needs a task).
        q: an assembled configuration, shape (nq,).
        tolerances: one per parameter of :func:`error_model` [m or rad], >= 0; build them with
            :meth:`ErrorModel.tolerances` (one length and one angle for all).

    Returns:
        ``worst_case`` :math:`= |S| \tau` and ``rms`` :math:`= \sqrt{S^2 \tau^2}` per task coordinate.

    Raises:
        InvalidInput: malformed tolerances (see also :func:`sensitivity`).
        SingularConfiguration: see :func:`sensitivity`.
    """
    tol = error_model(mech).check(tolerances)
    sens = sensitivity(mech, q)
    worst = np.abs(sens.S) @ tol
    rms = np.sqrt((sens.S**2) @ (tol**2))
    return ErrorBound(sens.dofs, worst, rms, sens, tol)
