r"""Static balance of a closed chain: the one equation behind every static force.

At rest the tree's generalized forces balance:

.. math:: B f_c + J_\phi^T \lambda = \tau, \qquad \tau = g(q) - J_w^T w

with :math:`f_c` the actuator forces [N] or torques [N m], :math:`B` the selection of the
actuated velocities, :math:`\lambda` the forces of the cut joints (closure rows, in the
convention of :mod:`plm_pin.core.closures`: force on frame B, its opposite on frame A),
:math:`g` the generalized gravity and :math:`w` an external wrench applied to a frame.

Projecting on the feasible motions :math:`N` (:math:`J_\phi N = 0`) removes :math:`\lambda`:

.. math:: C^T f_c = N^T \tau, \qquad C = B^T N,

``mobility`` equations in ``n_act`` unknowns (virtual work: what the actuators do on every
feasible motion balances the load). With redundancy the solutions form an affine set
:math:`f_c = f_p + G y`: :math:`f_p` the minimum-norm solution and :math:`G` an orthonormal
basis of the **internal forces** (the null space of :math:`C^T`): forces the actuators
exert against each other without moving anything. :math:`\lambda` then follows from
:math:`J_\phi^T \lambda = \tau - B f_c`, unique when the closure rows are independent.
With a task, :math:`C^T = T^T J_{ce}^T`, so this is Harada 2011's
:math:`J_{ce}^T f_c = f_e` (eqs. (15), (20)) with :math:`f_e = -w` at zero gravity.

**Bases.** :math:`N` is an orthonormal basis of the feasible motions turned along the right
singular vectors of :math:`C`, so that :math:`C` has orthogonal columns of decreasing norm
(their signs are the factorisation's: only products such as :math:`C^T f = N^T \tau` are
meaningful). The internal basis :math:`G`, in which the internal coordinates are read and
prescribed, does not depend on the factorisation: it is the pivoted Gram-Schmidt basis of
the internal-force space (see :func:`oriented_internal_basis`); with one internal force
(the 3D4M), the unit internal force whose largest entry is positive.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, field
from types import ModuleType
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike
from scipy.linalg import blas as _blas
from scipy.linalg import lapack as _lapack

from .._arguments import as_vector, check_tolerance, flag
from ..core import closures as _closures
from ..core.checks import check_assembled, check_finite_model, check_finite_result
from ..core.mechanism import Mechanism
from ..core.scratch import placement_views
from ..core.task import FrameTask, JointTask
from ..exceptions import FrameNotFound, InvalidInput, SingularConfiguration
from ..kernels import kernels_enabled
from ..results import Result, unit
from ..tolerances import EQUILIBRIUM_RTOL, INTERNAL_TIE_RTOL, STATICS_SINGULAR_RTOL

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class Load(Result):
    """An external wrench applied to one frame of the mechanism.

    Attributes:
        frame: frame name.
        frame_id: Pinocchio frame index.
        wrench: ``(force [N], moment [N m])`` about the frame origin, world-aligned, shape (6,).
    """

    frame: str
    frame_id: int
    wrench: np.ndarray = field(metadata=unit("N, N m"))

    def generalized_force(self, model: pin.Model, data: pin.Data) -> np.ndarray:
        r""":math:`J_w^T w` with the frame Jacobian already in ``data``, shape (nv,) [N, N m]."""
        return np.asarray(pin.getFrameJacobian(model, data, self.frame_id, _LWA).T @ self.wrench)


@dataclass(frozen=True)
class JointLoad(Result):
    r"""Forces applied by the outside along output joints: the load of a joint task.

    A torque on a revolute joint is a pair of opposite moments about its axis on the two
    bodies it joins (a force on a prismatic joint, a pair of opposite forces along it): it
    enters the balance on that joint's coordinate alone, :math:`\tau = g - S_o^T f_o`.

    Attributes:
        joints: the output joints.
        v_indices: their velocity indices.
        forces: the load along each [N m] (revolute) or [N] (prismatic), shape (n,).
    """

    joints: tuple[str, ...]
    v_indices: tuple[int, ...]
    forces: np.ndarray = field(metadata=unit("N, N m"))

    def generalized_force(self, model: pin.Model, data: pin.Data | None = None) -> np.ndarray:
        r""":math:`S_o^T f_o`: the forces on their joints' coordinates, shape (nv,) [N, N m]."""
        out = np.zeros(model.nv)
        out[list(self.v_indices)] = self.forces
        return out


AnyLoad = Load | JointLoad
"""An external load: a wrench on a frame, or forces along a joint task's output joints."""


def load_on_frame(mech: Mechanism, wrench: ArrayLike, frame: str | None = None) -> AnyLoad:
    """Check an external wrench and the frame it acts on.

    Args:
        mech: the mechanism.
        wrench: ``(fx, fy, fz, mx, my, mz)`` [N, N m] about the frame origin, world-aligned;
            or, on the task frame, one value per task coordinate (``x y rz`` of a planar
            task: ``fx fy mz``); for a joint task with no ``frame``, one force [N] or torque
            [N m] per output joint (a :class:`JointLoad`).
        frame: frame the wrench acts on; default the end-effector (task) frame.

    Raises:
        InvalidInput: wrong size, non-finite values, or no frame given and no task.
        FrameNotFound: unknown frame (the message lists the frames).
    """
    task = mech.task_compiled
    if frame is None and isinstance(task, JointTask):
        forces = as_vector(wrench, task.size, "wrench")
        forces.setflags(write=False)
        return JointLoad(task.dofs, task.v_indices, forces)
    return wrench_on_frame(mech, wrench, frame)


def wrench_on_frame(mech: Mechanism, wrench: ArrayLike, frame: str | None = None) -> Load:
    """:func:`load_on_frame` for a wrench on a frame (default: the task frame of a frame task).

    Raises:
        InvalidInput: wrong size, non-finite values, or no frame given and no frame task.
        FrameNotFound: unknown frame (the message lists the frames).
    """
    task = mech.task_compiled
    if frame is None:
        if not isinstance(task, FrameTask):
            raise InvalidInput(f"{mech.name} has no end-effector frame; name the frame the wrench acts on")
        frame_id = task.frame_id
        frame = mech.model.frames[frame_id].name
    else:
        if not mech.model.existFrame(frame):
            raise FrameNotFound(frame, mech.frame_names)
        frame_id = mech.model.getFrameId(frame)
    arr = np.asarray(wrench, dtype=float) if np.ndim(wrench) == 1 else np.asarray(wrench)
    on_task = isinstance(task, FrameTask) and frame_id == task.frame_id and arr.shape == (task.size,)
    if on_task and isinstance(task, FrameTask):
        w = np.zeros(6)
        w[list(task.rows)] = as_vector(arr, task.size, "wrench")
    else:
        sizes = f"6 or {task.size} (one per task coordinate {' '.join(task.dofs)})" if task else "6"
        if arr.shape != (6,):
            raise InvalidInput(f"wrench on frame {frame!r} must have {sizes} entries, got shape {arr.shape}")
        w = as_vector(arr, 6, "wrench")
    w.setflags(write=False)
    return Load(frame, frame_id, w)


@dataclass(frozen=True)
class StaticBalance(Result):
    r"""The balance :math:`B f_c + J_\phi^T \lambda = \tau` at one configuration, ready to solve.

    Attributes:
        q: configuration, shape (nq,).
        tau: generalized force the actuators and closures must supply, :math:`g(q) - J_w^T w`,
            shape (nv,) [N, N m].
        load: the external wrench, or None.
        gravity: whether gravity is included in ``tau``.
        J_phi: closure Jacobian, shape (m, nv).
        N: orthonormal basis of the feasible motions, shape (nv, mobility), along the right
            singular vectors of ``C`` (see the module docstring).
        C: actuator rates per feasible motion :math:`B^T N`, shape (n_act, mobility),
            orthogonal columns of decreasing norm.
        f_particular: minimum-norm actuator forces, shape (n_act,) [N, N m].
        internal_basis: orthonormal basis :math:`G` of the internal forces, shape (n_act, k),
            oriented by :func:`oriented_internal_basis` (the same at a configuration whatever
            the factorisation).
        actuated_v: velocity index of each actuator, shape (n_act,).
        lambda_map: truncated pseudo-inverse of :math:`J_\phi^T`, shape (m, nv): the cut-joint
            forces that balance a generalized force (least squares where the closure rows are
            dependent).
        force_map: :math:`P`, shape (n_act, nv): the minimum-norm actuator forces balancing a
            generalized force, ``f_particular = P @ tau`` (the balance is linear in the load).
        v: joint velocities when ``tau`` comes from inverse dynamics (None: at rest).
        a: joint accelerations when ``tau`` comes from inverse dynamics (None: at rest).
    """

    q: np.ndarray = field(metadata=unit("m, rad"))
    tau: np.ndarray = field(metadata=unit("N, N m"))
    load: AnyLoad | None
    gravity: bool
    J_phi: np.ndarray
    N: np.ndarray
    C: np.ndarray
    f_particular: np.ndarray = field(metadata=unit("N, N m"))
    internal_basis: np.ndarray = field(metadata=unit("-"))
    actuated_v: np.ndarray
    lambda_map: np.ndarray
    force_map: np.ndarray
    v: np.ndarray | None = field(default=None, metadata=unit("m/s, rad/s"))
    a: np.ndarray | None = field(default=None, metadata=unit("m/s^2, rad/s^2"))

    @property
    def n_internal(self) -> int:
        """Number of independent internal forces (the degree of redundancy here)."""
        return int(self.internal_basis.shape[1])

    def generalized(self, f_c: np.ndarray) -> np.ndarray:
        r""":math:`B f_c`, shape (nv,)."""
        out = np.zeros(self.tau.shape[0])
        out[self.actuated_v] = f_c
        return out

    def closure_forces(self, f_c: np.ndarray) -> np.ndarray:
        r"""Cut-joint forces :math:`\lambda` balancing ``f_c``, shape (m,) [N, N m].

        The least-squares (minimum-norm) solution of :math:`J_\phi^T \lambda = \tau - B f_c`.
        """
        return self.lambda_map @ (self.tau - self.generalized(f_c))

    def residual(self, f_c: np.ndarray, lam: np.ndarray) -> float:
        r"""Equilibrium residual :math:`\|B f_c + J_\phi^T \lambda - \tau\|_\infty` [N, N m]."""
        return float(abs(self.generalized(f_c) + self.J_phi.T @ lam - self.tau).max(initial=0.0))

    def scale(self, f_c: np.ndarray) -> float:
        """Largest generalized force in the balance, for relative tolerances [N, N m]."""
        return float(max(np.max(np.abs(self.tau), initial=0.0), np.max(np.abs(f_c), initial=0.0), 1e-300))


def static_balance(
    mech: Mechanism,
    q: ArrayLike,
    wrench: ArrayLike | None = None,
    frame: str | None = None,
    *,
    gravity: bool = True,
    singular_rtol: float = STATICS_SINGULAR_RTOL,
) -> StaticBalance:
    r"""Set up the static balance at ``q``: load, feasible motions, minimum-norm forces, internal basis.

    Args:
        mech: the mechanism.
        q: an assembled configuration, shape (nq,).
        wrench: external wrench applied to ``frame`` (see :func:`load_on_frame`), or None.
        frame: frame the wrench acts on; default the task frame.
        gravity: include the weight of the bodies (the model's gravity).
        singular_rtol: relative singular-value threshold, see :data:`STATICS_SINGULAR_RTOL`.

    Raises:
        InvalidInput: malformed ``q`` or wrench, or ``singular_rtol`` not in [0, 1).
        DescriptionError: the weight of a body is not finite (its inertia overflows).
        ClosureNotSatisfied: ``q`` is off the closure manifold (residual above
            ``mech.assembled_tol``); assemble it first, ``mech.assemble(q).q``.
        SingularConfiguration: the actuators (direct singularity) or the closures
            (constraint singularity) cannot resist the load at ``q``; the message names
            the unresisted generalized-force component.
    """
    qa = mech.check_q(q)
    model, data = mech.model, mech.data
    J_phi = assembled_closure_jacobian(mech, data, qa)
    check_finite_model(mech)
    load = None if wrench is None else load_on_frame(mech, wrench, frame)
    # the default tolerance is a valid float: its check costs more than the rest of this setup
    rtol = (
        singular_rtol
        if singular_rtol is STATICS_SINGULAR_RTOL
        else check_tolerance(singular_rtol, "singular_rtol", relative=True)
    )
    flag(gravity, "gravity")
    if load is None:  # 0 + g, as the loaded sum below, without the zeros
        tau = pin.computeGeneralizedGravity(model, data, qa) + 0.0 if gravity else np.zeros(model.nv)
    else:
        tau = _loaded(model, data, load, None)
        if gravity:
            tau += pin.computeGeneralizedGravity(model, data, qa)
    return build_balance(mech, qa, tau, load, gravity, J_phi, actuated_v(mech), rtol)


def actuated_v(mech: Mechanism) -> np.ndarray:
    """:attr:`Mechanism.actuated_v_indices`, once per actuator tuple, read-only, kept with the mechanism."""
    hit = vars(mech).get(_ACTUATED)
    if hit is not None and hit[0] is mech.actuators:
        return hit[1]
    act_v = mech.actuated_v_indices
    act_v.setflags(write=False)
    vars(mech)[_ACTUATED] = (mech.actuators, act_v)
    return act_v


_ACTUATED = "_statics_actuated_v"
"""Attribute of a mechanism holding its actuator tuple and their velocity indices."""


def assembled_closure_jacobian(mech: Mechanism, data: pin.Data, q: np.ndarray) -> np.ndarray:
    r"""Closure Jacobian at ``q`` from one kinematics pass, which also checks that ``q`` is assembled.

    ``pin.computeJointJacobians`` and ``pin.updateFramePlacements`` fill ``data`` (the frame
    Jacobians and placements of ``q`` stay there for the caller); the closure residual read
    from the same placements is the one :func:`~plm_pin.core.checks.check_assembled` takes.

    Raises:
        ClosureNotSatisfied: as :func:`~plm_pin.core.checks.check_assembled` (its message).
    """
    model, closures = mech.model, mech.closures
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    if not closures:
        return np.empty((0, model.nv))
    rows = point_closure_rows(mech, data)
    if rows is not None:  # one compiled call, the same numbers
        J_phi = np.empty((rows.m, model.nv))
        closed = rows(J_phi, mech.assembled_tol)
    else:
        bound = _closures.BoundClosures(data, closures)
        J_phi = bound.jacobian(model, np.empty((bound.rows, model.nv)))
        closed = np.max(np.abs(bound.residual(np.empty(bound.rows)))) <= mech.assembled_tol
    if not closed:
        check_assembled(mech, q)  # raises, with the residual and the worst closure
    return J_phi


class _PointRows:
    """What :func:`point_closure_rows` returns: the compiled point-closure rows on one Pinocchio data."""

    __slots__ = ("_args", "_kernel", "_t", "closures", "data", "m")

    def __init__(self, mech: Mechanism, data: pin.Data, points: PointClosures) -> None:
        self._kernel = _compiled().point_closure_rows
        self.closures, self.data = mech.closures, data
        self._t = placement_views(data, points.frames)[0]  # live views of the frame positions
        self._args = (data.J, points.support, points.plus, points.minus, points.axis)
        self.m = int(points.plus.shape[0])

    def __call__(self, out: np.ndarray, tol: float) -> bool:
        r"""Write :math:`J_\phi` into ``out`` (m, nv); whether the configuration closes to ``tol`` [m]."""
        Jw, support, plus, minus, axis = self._args
        t = np.concatenate(self._t).reshape(-1, 3)  # (n_frames, 3)
        return bool(self._kernel(Jw, t, support, plus, minus, axis, tol, out))


def point_closure_rows(mech: Mechanism, data: pin.Data) -> _PointRows | None:
    r"""The compiled closure rows of ``mech`` on ``data``, or None where the Pinocchio path runs.

    ``rows(out, tol)`` writes :math:`J_\phi` (m, nv) from the joint Jacobians and frame
    placements in ``data`` (``pin.computeJointJacobians`` and ``pin.updateFramePlacements`` of
    the configuration) and returns whether the closure residual is within ``tol``:
    the numbers and the decision of :class:`~plm_pin.core.closures.BoundClosures`, bit for
    bit (:func:`~plm_pin.statics._compiled.point_closure_rows`). None when the kernels are off
    or a closure has rotation rows (or there is none). The last one made in the calling
    thread is kept with the mechanism, for its data.
    """
    closures = mech.closures
    if not closures or not kernels_enabled():
        return None
    rows = getattr(mech._local, "statics_rows", None)
    if rows is not None and rows.data is data and rows.closures is closures:
        return rows
    points = point_closures(mech)
    if points is None:
        return None
    rows = mech._local.statics_rows = _PointRows(mech, data, points)
    return rows


def compiled_factors(
    mech: Mechanism, J_phi: np.ndarray, act_v: np.ndarray, tau: np.ndarray, singular_rtol: float
) -> BalanceFactors | None:
    """:func:`balance_factors` in one compiled call, for loops whose configuration changes at each call.

    Nothing is kept or reused, and the arrays stay writable. Call it when
    :func:`~plm_pin.kernels.kernels_enabled`; None when the compiled call declines (then
    :func:`balance_factors` decides, and words the error).
    """
    status, *arrays = _compiled().factor(
        J_phi, act_v, tau, singular_rtol, mech.closure_tol, EQUILIBRIUM_RTOL, INTERNAL_TIE_RTOL
    )
    return BalanceFactors(*arrays) if status == 0 else None  # 0: _compiled.OK


class PointClosures(NamedTuple):
    """The closures of a mechanism whose closures are all point closures, as index arrays.

    Attributes:
        frames: the closure frames, in first-use order (as :class:`~plm_pin.core.closures.BoundClosures`).
        support: whether each velocity moves each frame (its joint's support), shape (n_frames, nv).
        plus: frame B of each closure row (index in ``frames``), shape (m,).
        minus: frame A of each closure row, shape (m,).
        axis: the coordinate (0, 1, 2) of each closure row, shape (m,).
    """

    frames: tuple[int, ...]
    support: np.ndarray
    plus: np.ndarray
    minus: np.ndarray
    axis: np.ndarray


def point_closures(mech: Mechanism) -> PointClosures | None:
    """The :class:`PointClosures` of ``mech``, once per closure tuple; None if a closure has rotations."""
    closures = mech.closures
    hit = vars(mech).get(_POINTS)
    if hit is not None and hit[0] is closures:
        return hit[1]
    points = None
    if all(c.spec.type == "point" for c in closures):
        model = mech.model
        frames = tuple(dict.fromkeys(f for c in closures for f in c.frame_ids))
        support = np.zeros((len(frames), model.nv), dtype=bool)
        for k, f in enumerate(frames):
            for j in model.supports[model.frames[f].parentJoint][1:]:  # the universe moves nothing
                support[k, model.idx_vs[j] : model.idx_vs[j] + model.nvs[j]] = True
        m = _closures.closure_rows(closures)
        plus, minus, axis = (np.zeros(m, dtype=np.int64) for _ in range(3))
        for c in closures:
            rows = slice(c.rows.start, c.rows.start + 3)
            plus[rows], minus[rows] = frames.index(c.frame_ids[1]), frames.index(c.frame_ids[0])
            axis[rows] = (0, 1, 2)
        points = PointClosures(frames, support, plus, minus, axis)
    vars(mech)[_POINTS] = (closures, points)
    return points


_POINTS = "_statics_point_closures"
"""Attribute of a mechanism holding its closure tuple and their :class:`PointClosures` (or None)."""


def generalized_balance(
    mech: Mechanism,
    q: np.ndarray,
    tau: np.ndarray,
    *,
    load: AnyLoad | None = None,
    gravity: bool = True,
    v: np.ndarray | None = None,
    a: np.ndarray | None = None,
    singular_rtol: float = STATICS_SINGULAR_RTOL,
) -> StaticBalance:
    r"""The balance :math:`B f_c + J_\phi^T \lambda = \tau - J_w^T w` for a given generalized force.

    Inverse dynamics uses it with :math:`\tau` from RNEA at :math:`(q, v, a)`.

    Args:
        mech: the mechanism.
        q: a checked configuration, shape (nq,).
        tau: generalized force to balance, without the load [N, N m], shape (nv,).
        load: external wrench, or None; its generalized force is subtracted from ``tau``.
        gravity: whether ``tau`` includes the bodies' weight (recorded for the reactions).
        v: joint velocities, when ``tau`` is an inverse-dynamics force (recorded for the reactions).
        a: joint accelerations, likewise.
        singular_rtol: see :data:`STATICS_SINGULAR_RTOL`.

    Raises:
        InvalidInput: ``singular_rtol`` not in [0, 1), or ``tau`` (load included) not finite.
        DescriptionError: ``tau`` is not finite because a body's inertia overflows.
        SingularConfiguration: as :func:`static_balance`.
    """
    rtol = check_tolerance(singular_rtol, "singular_rtol", relative=True)
    model, data = mech.model, mech.data
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J_phi = _closures.jacobian_from_data(model, data, mech.closures)
    applied = _loaded(model, data, load, tau)
    return build_balance(mech, q, applied, load, gravity, J_phi, mech.actuated_v_indices, rtol, v, a)


def _loaded(model: pin.Model, data: pin.Data, load: AnyLoad | None, tau: np.ndarray | None) -> np.ndarray:
    r"""A new array :math:`\tau - J_w^T w` (``tau`` None: zero), the frame Jacobian taken from ``data``."""
    out = np.zeros(model.nv) if tau is None else np.array(tau, dtype=float)
    if load is not None:
        out -= load.generalized_force(model, data)
    return out


def closure_factors(
    J_phi: np.ndarray, singular_rtol: float = STATICS_SINGULAR_RTOL, closure_tol: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    r"""Orthonormal feasible motions :math:`N` (:math:`J_\phi N = 0`) and the minimum-norm closure-force map.

    Feasible motions come from the local rank of :math:`J_\phi`: at a constraint singularity the
    motion the closures no longer forbid joins :math:`N`, so the actuators must hold it too (or
    the load is refused). Rows that are exactly zero (the out-of-plane rows of planar point
    closures) are dropped; when the rest is clearly of full rank (a triangular condition
    estimate above ``1e3 * singular_rtol``, far above any ratio the SVD would call singular)
    one Householder QR of :math:`J_\phi^T` gives both maps, else the SVD decides the rank with
    ``singular_rtol``, or at ``closure_tol * max(s_max, 1)`` when that is larger (the dependent
    rows of a description whose loops close to ``closure_tol`` [m, rad], a rounded CAD export, sit
    below it; see :mod:`plm_pin.core.rank`). LAPACK is called directly: on the 3D4M's 6 x 9 rows
    the QR costs 3 us
    against 9 us for the SVD (11 against 60 us on the 8-PSS's 24 x 30).

    Returns:
        ``N``, shape (nv, nullity), in no particular orientation; ``lambda_map``, shape (m, nv):
        the minimum-norm :math:`\lambda` with :math:`J_\phi^T \lambda = y` for :math:`y` in
        the range of :math:`J_\phi^T`.
    """
    m, nv = J_phi.shape
    lambda_map = np.zeros((m, nv))
    rows = np.flatnonzero(J_phi.any(axis=1))  # ndarray methods: numpy's function wrappers cost more
    r = rows.size
    if r == 0:
        return np.eye(nv), lambda_map
    if r <= nv:
        qr, tau, _, info = _lapack.dgeqrf(J_phi[rows].T, overwrite_a=1)  # J_phi^T = Q R, (nv, r)
        R = qr[:r]
        if (
            info == 0
            and R.diagonal().all()
            and _lapack.dtrcon(R, norm="1")[0] > 1e3 * max(singular_rtol, closure_tol)
        ):
            full = np.zeros((nv, nv), order="F")
            full[:, :r] = qr
            Q = _lapack.dorgqr(full, tau, overwrite_a=1)[0]  # (nv, nv)
            # lambda_map = R^-1 Q1^T, as (Q1 R^-T)^T
            lambda_map[rows] = _blas.dtrsm(1.0, R, Q[:, :r], side=1, trans_a=1).T
            return Q[:, r:], lambda_map
    U, s, Vt = np.linalg.svd(J_phi)
    rank = int(np.count_nonzero(s > max(singular_rtol * s[0], closure_tol * max(s[0], 1.0))))
    return Vt[rank:].T, (U[:, :rank] / s[:rank]) @ Vt[:rank]


def oriented_internal_basis(G: np.ndarray) -> np.ndarray:
    r"""The internal basis of the space spanned by the orthonormal ``G``, whatever the orientation of ``G``.

    Pivoted Gram-Schmidt on the actuators: the first column is the unit internal force with
    the largest share on a single actuator (the projection of that actuator's unit vector on
    the internal space, normalised), that share positive; each next column likewise in the
    part of the internal space orthogonal to the columns before. Shares equal to
    :data:`INTERNAL_TIE_RTOL` are taken in actuator order. The pivot actuators :math:`p_j` give
    :math:`G_{p_j j} > 0` and :math:`G_{p_i j} = 0` for :math:`i < j`; with one internal force,
    :math:`G` is the unit internal force whose largest entry is positive.

    Args:
        G: orthonormal basis of the internal forces, shape (n_act, k).

    Returns:
        The oriented basis, shape (n_act, k), spanning the same space.
    """
    k = G.shape[1]
    if k == 1:  # one internal force (3D4M): its sign only
        g = abs(G[:, 0])
        pivot = int((g >= (1.0 - INTERNAL_TIE_RTOL) * g.max()).argmax())
        return G if G[pivot, 0] > 0.0 else -G
    A = G.T  # (k, n_act): column i holds the projection of actuator i's unit vector, in G
    shares = np.einsum("ij,ij->j", A, A)  # squared norms of what remains of each projection
    Q = np.zeros((k, k))
    for j in range(k):
        pivot = int((shares >= (1.0 - INTERNAL_TIE_RTOL) ** 2 * shares.max()).argmax())
        w = A[:, pivot] - Q @ (Q.T @ A[:, pivot])  # Q's columns past j are still zero
        Q[:, j] = w / np.sqrt(w @ w)
        shares = shares - (Q[:, j] @ A) ** 2
    return G @ Q


class BalanceFactors(NamedTuple):
    r"""The factorisation of one balance, reused for every generalized force at that configuration.

    Attributes:
        N: orthonormal feasible motions, shape (nv, nullity).
        lambda_map: minimum-norm cut-joint forces per generalized force, shape (m, nv).
        C: :math:`B^T N`, shape (n_act, nullity).
        P: minimum-norm actuator forces per generalized force, shape (n_act, nv).
        G: internal-force basis (:func:`oriented_internal_basis`), shape (n_act, k).
    """

    N: np.ndarray
    lambda_map: np.ndarray
    C: np.ndarray
    P: np.ndarray
    G: np.ndarray


_COMPILED: list[ModuleType] = []
"""Holds :mod:`plm_pin.statics._compiled` once imported (it imports numba)."""


def _compiled() -> ModuleType:
    """:mod:`plm_pin.statics._compiled`, imported on first use (it imports numba)."""
    if not _COMPILED:
        from . import _compiled as compiled

        _COMPILED.append(compiled)
    return _COMPILED[0]


_LAST: weakref.WeakKeyDictionary[Mechanism, tuple[tuple[bytes, bytes, float, float], BalanceFactors]] = (
    weakref.WeakKeyDictionary()
)
"""Each mechanism's last compiled factorisation, keyed by J_phi, the actuated velocities, the tolerances."""


def balance_factors(
    mech: Mechanism, J_phi: np.ndarray, act_v: np.ndarray, tau: np.ndarray, singular_rtol: float
) -> BalanceFactors:
    r"""Factor the balance at a configuration and check that ``tau`` can be resisted there.

    The QR (or SVD) of :math:`J_\phi` (:func:`closure_factors`), then the small SVD of
    :math:`C = B^T N`, which decides direct singularities with ``singular_rtol``.

    The common case (closure rows clearly of full rank, a load the actuators hold) runs as one
    compiled call when the kernels are enabled (:func:`~plm_pin.kernels.kernels_enabled`);
    the same factorisation, to round-off. Its last result is kept with the mechanism and
    reused for the next load at the same :math:`J_\phi` (the load cases of one
    configuration), after checking that the actuators hold that load too.

    Raises:
        SingularConfiguration: as :func:`static_balance`.
    """
    if kernels_enabled():
        key = (J_phi.tobytes(), act_v.tobytes(), singular_rtol, mech.closure_tol)
        last = _LAST.get(mech)
        if last is not None and last[0] == key:
            factors = last[1]
            unheld = factors.N[:, factors.C.shape[0] - factors.G.shape[1] :]  # motions C does not hold
            if not unheld.size or abs(unheld.T @ tau).max() <= EQUILIBRIUM_RTOL * max(
                abs(tau).max(initial=0.0), 1e-300
            ):
                return factors
        status, *arrays = _compiled().factor(
            J_phi, act_v, tau, singular_rtol, mech.closure_tol, EQUILIBRIUM_RTOL, INTERNAL_TIE_RTOL
        )
        if status == 0:  # _compiled.OK
            for arr in arrays:
                arr.setflags(write=False)  # shared by the load cases of this configuration
            _LAST[mech] = (key, BalanceFactors(*arrays))
            return _LAST[mech][1]
    N, lambda_map = closure_factors(J_phi, singular_rtol, mech.closure_tol)
    C = N[act_v]  # (n_act, nullity)
    b = N.T @ tau  # (nullity,)
    if C.size:
        U, s, Vt, info = _lapack.dgesdd(C, full_matrices=1)  # C = U[:, :k] diag(s) Vt
    if not C.size or info != 0:
        U, s, Vt = np.linalg.svd(C)
    r = int(np.count_nonzero(s > singular_rtol * (s[0] if s.size else 1.0)))
    unresisted = Vt[r:] @ b  # load on feasible motions the actuators do not hold
    if unresisted.size and abs(unresisted).max() > EQUILIBRIUM_RTOL * max(abs(tau).max(initial=0.0), 1e-300):
        kind = "constraint" if N.shape[1] > mech.mobility else "direct"
        s_phi = np.linalg.svd(J_phi, compute_uv=False)
        raise SingularConfiguration(
            f"{mech.name}: {kind} singularity, the actuators cannot resist the load: "
            f"{N.shape[1] - r} feasible motion(s) not held (actuator singular values {s.tolist()}, "
            f"closure singular values {s_phi.tolist()}); the load's component along them is "
            f"{unresisted.tolist()} [N, N m]"
        )
    N = N @ Vt.T  # along C's right singular vectors: C = B^T N has orthogonal columns, largest first
    P = (U[:, :r] / s[:r]) @ N[:, :r].T  # (n_act, nv)
    G = oriented_internal_basis(U[:, r:]) if r < U.shape[1] else U[:, r:]
    factors = BalanceFactors(N, lambda_map, N[act_v], P, G)
    for arr in factors:
        arr.setflags(write=False)  # as the compiled factors: they go into the balance as they are
    return factors


def build_balance(
    mech: Mechanism,
    q: np.ndarray,
    tau: np.ndarray,
    load: AnyLoad | None,
    gravity: bool,
    J_phi: np.ndarray,
    act_v: np.ndarray,
    singular_rtol: float,
    v: np.ndarray | None = None,
    a: np.ndarray | None = None,
) -> StaticBalance:
    r"""The :class:`StaticBalance` of ``tau`` at ``q``: ``tau`` checked finite, then :func:`balance_factors`.

    The common step of :func:`static_balance`, :func:`generalized_balance` and the inverse
    dynamics, which compute ``tau`` and :math:`J_\phi` their own ways.

    Args:
        mech: the mechanism.
        q: configuration, shape (nq,).
        tau: generalized forces to balance [N, N m], shape (nv,).
        load: the external load in ``tau`` (recorded), or None.
        gravity: whether ``tau`` holds gravity (recorded).
        J_phi: closure Jacobian at ``q``, shape (m, nv).
        act_v: velocity indices of the actuated joints, shape (n_act,).
        singular_rtol: relative tolerance of the direct-singularity decision (:data:`SINGULAR_RTOL`).
        v: joint velocities in ``tau`` [m/s, rad/s] (recorded), or None.
        a: joint accelerations in ``tau`` [m/s^2, rad/s^2] (recorded), or None.

    Raises:
        InvalidInput: ``tau`` is not finite (DescriptionError when a body's inertia overflows).
        SingularConfiguration: as :func:`static_balance`.
    """
    if not finite(tau):
        check_finite_result(mech, "the generalized forces to balance", tau=tau)
    N, lambda_map, C, P, G = balance_factors(mech, J_phi, act_v, tau, singular_rtol)
    f_p = P @ tau
    for arr in (f_p, q, tau, J_phi):  # the factors are read-only already
        arr.setflags(write=False)
    return StaticBalance(q, tau, load, gravity, J_phi, N, C, f_p, G, act_v, lambda_map, P, v, a)


def finite(x: np.ndarray) -> bool:
    """Whether every entry of the vector ``x`` is finite (a sum of a few Python floats, else numpy).

    A finite sum means no NaN nor infinity; a sum that overflows on finite entries is decided
    by ``isfinite``.
    """
    return math.isfinite(sum(x.tolist())) or bool(np.isfinite(x).all())
