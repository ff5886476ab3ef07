r"""Closed-chain inverse dynamics: the actuator forces that drive a trajectory, split by term and body.

At every sample :math:`(q, v, a)` of a :class:`~plm_pin.dynamics.trajectory.JointTrajectory`
(consistent with the closures), RNEA of the spanning tree gives the generalized force
:math:`\tau_{id}` (rotor armature included), and the statics balance does the rest:

.. math:: B f_c + J_\phi^T \lambda = \tau_{id} - J_w^T w,

with the same allocation rules as statics (weighted minimum norm, minimum peak, limits,
preloads, prescribed internal forces; :class:`~plm_pin.statics.AllocationRule`).

**Splits.** :math:`\tau_{id}` is a sum of terms, inertia :math:`M a`, velocity
:math:`C(q, v) v`, gravity :math:`g(q)`, and the external load; and, as RNEA is linear in
the bodies' inertias, a sum over bodies (plus the reflected rotor and screw inertias). For
the weighted minimum norm the forces are linear in :math:`\tau`, :math:`f_c = F \tau`, so
each part of :math:`\tau` maps to its own share of :math:`f_c` and the shares add up
exactly. With limits, preloads or the min-peak objective the allocation is not linear:
the shares are then those of the weighted minimum norm, and an ``"allocation"`` share holds
the difference to the forces actually chosen (``split_exact`` is False).

**Motors.** For a screw-driven slider of lead :math:`p` [m/rev], the motor torque is
:math:`\tau_m = f_c\, p / 2\pi` and its speed :math:`\dot\theta = 2\pi \dot c / p`; the power
:math:`P = f_c \dot c = \tau_m \dot\theta` does not depend on the lead (Zhao 2011, eqs. (19)-(29)).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, flag, load_arguments, mapping, repeated
from .._linalg import det_sign
from .._text import short
from ..core import closures as _closures
from ..core.checks import check_finite_model, check_samples_assembled
from ..core.mechanism import Mechanism
from ..core.task import FrameTask
from ..exceptions import (
    AllocationInfeasible,
    InvalidInput,
    InverseDynamicsFailed,
    SingularConfiguration,
)
from ..kernels import kernels_enabled
from ..results import Result, unit
from ..statics import AllocationRule, solve_balance
from ..statics.balance import (
    AnyLoad,
    Load,
    actuated_v,
    balance_factors,
    build_balance,
    compiled_factors,
    load_on_frame,
    point_closure_rows,
)
from ..statics.forces import allocation_rule
from ..tolerances import STATICS_SINGULAR_RTOL
from .trajectory import JointTrajectory, checked_trajectory

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

TERMS = ("inertia", "velocity", "gravity", "external")
"""Parts of the inverse-dynamics force by physical term."""

RESERVED_GROUPS = ("external", "other", "rotor", "screw")
"""Names of the body split's own shares, which no body group may take."""


@dataclass(frozen=True)
class InverseDynamics(Result):
    """Actuator forces along a trajectory, with their splits, motor quantities and power.

    Attributes:
        actuators: actuator (joint) names.
        t: sample times [s], shape (n,).
        f_c: actuator forces [N] or torques [N m], shape (n, n_act).
        lam: cut-joint forces [N, N m], shape (n, m).
        internal: internal-force coordinates chosen, shape (n, k).
        residual: equilibrium residual per sample [N, N m], shape (n,).
        cd: actuator velocities [m/s] or [rad/s], shape (n, n_act).
        terms: share of ``f_c`` of each term (:data:`TERMS`, and ``"allocation"`` when not
            exact), each shape (n, n_act).
        bodies: share of ``f_c`` of each body group (``"rotor"`` and ``"screw"`` for the
            reflected inertias, ``"external"`` for the load), each shape (n, n_act); computed on
            first access, from one RNEA pass per sample.
        split_exact: whether the shares add up to ``f_c`` by linearity (weighted minimum norm).
        leads: ball-screw lead of each actuator [m/rev] (NaN without one, ``'nan'`` in
            ``to_dict``), shape (n_act,).
    """

    actuators: tuple[str, ...]
    t: np.ndarray = field(metadata=unit("s"))
    f_c: np.ndarray = field(metadata=unit("N, N m"))
    lam: np.ndarray = field(metadata=unit("N, N m"))
    internal: np.ndarray = field(metadata=unit("N, N m"))
    residual: np.ndarray = field(metadata=unit("N, N m"))
    cd: np.ndarray = field(metadata=unit("m/s, rad/s"))
    terms: dict[str, np.ndarray] = field(metadata=unit("N, N m"))
    bodies: Mapping[str, np.ndarray] = field(metadata=unit("N, N m"))
    split_exact: bool
    leads: np.ndarray = field(repr=False, metadata=unit("m/rev"))
    _NONFINITE_AS_TEXT = ("leads",)

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.t.shape[0])

    @property
    def power(self) -> np.ndarray:
        r"""Mechanical power of each actuator :math:`P = f_c \dot c` [W], shape (n, n_act)."""
        return self.f_c * self.cd

    @property
    def motor_torque(self) -> np.ndarray:
        r"""Motor torque :math:`f_c p / 2\pi` of screw-driven actuators [N m] (NaN without a lead)."""
        return self.f_c * self.leads / (2.0 * np.pi)

    @property
    def motor_speed(self) -> np.ndarray:
        r"""Motor speed :math:`2\pi \dot c / p` of screw-driven actuators [rad/s] (NaN without a lead)."""
        return self.cd * 2.0 * np.pi / self.leads

    def split_power(self, split: str = "terms") -> dict[str, np.ndarray]:
        """Power of each share (``"terms"`` or ``"bodies"``) [W], each shape (n, n_act)."""
        if split not in ("terms", "bodies"):
            raise InvalidInput(f"split {split!r} is not 'terms' or 'bodies'")
        return {k: v * self.cd for k, v in getattr(self, split).items()}


@dataclass(frozen=True)
class _BodyGroups:
    """Which bodies each group holds, for the body split of one RNEA pass."""

    names: tuple[str, ...]
    joints: tuple[tuple[int, ...], ...]  # per group, the joints whose bodies it holds
    rotor: np.ndarray  # reflected rotor inertia per velocity index
    screw: np.ndarray  # reflected screw inertia per velocity index

    def matrices(self, model: pin.Model) -> tuple[np.ndarray, np.ndarray]:
        """Membership (n_groups, njoints) and support (njoints, nv): 1 on the velocities moving a body."""
        members = np.zeros((len(self.names), model.njoints))
        for g, joints in enumerate(self.joints):
            members[g, list(joints)] = 1.0
        support = np.zeros((model.njoints, model.nv))
        for j in range(1, model.njoints):
            for k in model.supports[j][1:]:
                joint = model.joints[k]
                support[j, joint.idx_v : joint.idx_v + joint.nv] = 1.0
        return members, support


def _body_names(members: object, group: object) -> list[str]:
    """The bodies of one group: a sequence of body names (strings)."""
    if (
        isinstance(members, (str, bytes))
        or not isinstance(members, Sequence)
        or not all(isinstance(b, str) for b in members)
    ):
        raise InvalidInput(f"groups[{group!r}] must be a sequence of body names, got {short(members)}")
    return list(members)


def _body_groups(mech: Mechanism, groups: Mapping[str, Sequence[str]] | None) -> _BodyGroups:
    """The groups of bodies (bodies named by their joint's first body frame), checked.

    The default groups (one per body) are made once per model and actuator tuple, and kept
    with the mechanism.
    """
    if groups is None:
        hit = vars(mech).get(_DEFAULT_GROUPS)
        if hit is not None and hit[0] is mech.model and hit[1] is mech.actuators:
            return hit[2]
    model = mech.model
    bodies = {name: j for j, name in enumerate(mech.body_names, start=1)}
    if groups is None:
        chosen = {name: [name] for name in bodies}
        _check_group_names(list(chosen), default=True)
    else:
        what = "group names to sequences of body names"
        chosen = {str(g): _body_names(members, g) for g, members in mapping(groups, "groups", what).items()}
        _check_group_names(list(chosen), default=False)
        listed = [b for members in chosen.values() for b in members]
        unknown = sorted(set(listed) - set(bodies))
        if unknown:
            raise InvalidInput(f"bodies {unknown} are not in {mech.name}; bodies are {sorted(bodies)}")
        doubled = repeated(listed)
        if doubled:
            raise InvalidInput(f"bodies {doubled} are in more than one group")
        rest = [b for b in bodies if b not in listed]
        if rest:
            chosen["other"] = rest
    joints = tuple(tuple(bodies[b] for b in names) for names in chosen.values())
    rotor = np.zeros(model.nv)
    screw = np.zeros(model.nv)
    for act, spec in zip(mech.actuators, mech.sidecar.actuation, strict=True):
        factor = (2.0 * np.pi / spec.lead) ** 2 if spec.lead else 1.0
        rotor[act.idx_v] = spec.rotor_inertia * factor
        screw[act.idx_v] = spec.screw_inertia * factor
    rotor.setflags(write=False)
    screw.setflags(write=False)
    body = _BodyGroups(tuple(chosen), joints, rotor, screw)
    if groups is None:
        vars(mech)[_DEFAULT_GROUPS] = (model, mech.actuators, body)
    return body


_DEFAULT_GROUPS = "_dynamics_body_groups"
"""Attribute of a mechanism holding its model, actuator tuple and default body groups."""


def _body_forces(model: pin.Model, data: pin.Data, gravity: bool, support: np.ndarray) -> np.ndarray:
    r"""Generalized force of each body's own inertial wrench, from the RNEA pass held in ``data``.

    RNEA is linear in the bodies' inertias: :math:`\tau = \sum_b J_b^T f_b` with
    :math:`f_b = I_b a_b + v_b \times^* I_b v_b` (gravity in :math:`a_b` as RNEA puts it, or
    taken out), :math:`J_b` the body's world Jacobian (the columns of ``data.J`` of the joints
    supporting it). ``data`` must hold the joint Jacobians and the RNEA pass at one state.

    Returns:
        Shape (njoints, nv), row 0 (the universe) zero.
    """
    wrenches = np.zeros((model.njoints, 6))
    for j in range(1, model.njoints):
        inertia, oMi = model.inertias[j], data.oMi[j]
        acc = data.a_gf[j] if gravity else data.a_gf[j] + oMi.actInv(model.gravity)
        wrenches[j] = oMi.act(inertia * acc + inertia.vxiv(data.v[j])).vector
    return (wrenches @ data.J) * support


class _LazyShares(Mapping[str, np.ndarray]):
    """Shares of ``f_c`` computed on first access by ``compute`` (read-only arrays)."""

    def __init__(self, compute: Callable[[], dict[str, np.ndarray]]) -> None:
        self._compute: Callable[[], dict[str, np.ndarray]] | None = compute
        self._shares: dict[str, np.ndarray] = {}

    def _get(self) -> dict[str, np.ndarray]:
        if self._compute is not None:
            self._shares = self._compute()
            for arr in self._shares.values():
                arr.setflags(write=False)
            self._compute = None
        return self._shares

    def __getitem__(self, key: str) -> np.ndarray:
        return self._get()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._get())

    def __len__(self) -> int:
        return len(self._get())

    def __repr__(self) -> str:
        return "{...}" if self._compute is not None else repr(self._shares)

    def __reduce__(self) -> tuple[type, tuple[dict[str, np.ndarray]]]:
        """Pickled as the plain dictionary of the shares (computed first)."""
        return (dict, (dict(self._get()),))


def _check_group_names(names: Sequence[str], default: bool) -> None:
    """Refuse body groups named like a share of the split itself (:data:`RESERVED_GROUPS`)."""
    clash = sorted(set(map(str, names)) & set(RESERVED_GROUPS))
    if clash:
        whose = "bodies are" if default else "body groups are"
        raise InvalidInput(
            f"{whose} named {clash}, a name the body split keeps for its own shares "
            f"{list(RESERVED_GROUPS)}; name the groups otherwise with groups={{name: [body, ...]}}"
        )


def inverse_dynamics(
    mech: Mechanism,
    trajectory: JointTrajectory,
    *,
    wrench: ArrayLike | Callable[[float], ArrayLike] | None = None,
    frame: str | None = None,
    gravity: bool = True,
    groups: Mapping[str, Sequence[str]] | None = None,
    objective: str = "norm",
    weights: ArrayLike | None = None,
    limits: str | ArrayLike | None = "description",
    internal: ArrayLike | Mapping[str, float] | None = None,
    min_compression: float | None = None,
    link_limits: Mapping[str, tuple[float, float]] | None = None,
    singular_rtol: float = STATICS_SINGULAR_RTOL,
) -> InverseDynamics:
    """Actuator forces driving ``trajectory``, split by term and by body.

    By default (minimum norm, no load) it computes per sample the forces, the cut-joint forces,
    the internal coordinates, the residual and the split by term; the split by body is
    computed when :attr:`InverseDynamics.bodies` is first read.

    Args:
        mech: the mechanism.
        trajectory: consistent samples (``task_trajectory`` or ``actuator_trajectory``).
        wrench: external wrench applied to ``frame`` [N, N m], constant or ``t -> wrench``
            (see :func:`~plm_pin.statics.load_on_frame`).
        frame: frame the wrench acts on; default the task frame.
        gravity: include the bodies' weight (the model's gravity).
        groups: body groups for the body split, ``{group: [body, ...]}`` with bodies among
            :attr:`Mechanism.body_names`; bodies not listed form ``"other"``; default one
            group per body. No group may be named as one of :data:`RESERVED_GROUPS`.
        objective: allocation objective, as in :func:`~plm_pin.statics.static_forces`.
        weights: actuator weights.
        limits: actuator effort limits.
        internal: prescribed internal forces.
        min_compression: preload: every hinged link in compression by this much [N].
        link_limits: bounds on named links' axial forces [N].
        singular_rtol: see :data:`~plm_pin.tolerances.STATICS_SINGULAR_RTOL`.

    Raises:
        InvalidInput: malformed options, a trajectory of another mechanism, or a body group
            named as one of :data:`RESERVED_GROUPS`.
        DescriptionError: a body's inertia is not finite (see :func:`plm_pin.core.checks.check_finite_model`).
        ClosureNotSatisfied: a sample of ``trajectory`` is off the closure manifold (see
            :func:`plm_pin.core.checks.check_assembled`).
        InverseDynamicsFailed: at the first sample whose allocation is infeasible, whose load
            cannot be resisted, or (non-redundant mechanisms with a square task) past a direct
            singularity (a sign change of det J_ce), with the samples before it.
    """
    trajectory = checked_trajectory(trajectory, "trajectory")
    load_arguments(None if callable(wrench) else wrench, frame, limits, mech.n_actuators)
    check_tolerance(singular_rtol, "singular_rtol", relative=True)
    flag(gravity, "gravity")
    rule = allocation_rule(
        mech,
        objective=objective,
        weights=weights,
        limits=limits,
        internal=internal,
        min_compression=min_compression,
        link_limits=link_limits,
    )
    if trajectory.q.shape[1:] != (mech.nq,) or trajectory.v.shape[1:] != (mech.nv,):
        raise InvalidInput(
            f"the trajectory has q of width {trajectory.q.shape[1]} and v of width {trajectory.v.shape[1]}; "
            f"{mech.name} has nq = {mech.nq}, nv = {mech.nv}"
        )
    kinematics = _Kinematics.of(mech, trajectory, wrench is not None, frame)
    check_finite_model(mech)
    load_at = _load_function(mech, wrench, frame)
    body = _body_groups(mech, groups)
    return _run(mech, trajectory, kinematics, rule, load_at, body, gravity, singular_rtol, wrench is None)


@dataclass(frozen=True)
class _Kinematics:
    """The Jacobians of every sample, from one Pinocchio pass each (the closure check's pass)."""

    J_phi: np.ndarray  # (n, m, nv)
    J_load: np.ndarray | None  # (n, 6, nv): the load frame's, world-aligned
    J_task: np.ndarray | None  # (n, n_task, nv): for the direct-singularity watch of a square task

    @classmethod
    def of(cls, mech: Mechanism, trajectory: JointTrajectory, loaded: bool, frame: str | None) -> _Kinematics:
        """Run the pass over the trajectory and refuse it if a sample is off the closure manifold.

        Raises:
            ClosureNotSatisfied: as :func:`plm_pin.core.checks.check_samples_assembled` (its message).
        """
        model, closures = mech.model, mech.closures
        data = mech.data  # this pass calls no user code: the calling thread's scratch data
        task = mech.task_compiled
        n, m = trajectory.t.shape[0], mech.n_closure_rows
        frame_id = None
        if loaded and frame is None:
            frame_id = task.frame_id if isinstance(task, FrameTask) else None
        elif loaded and model.existFrame(frame):
            frame_id = model.getFrameId(frame)
        square = task is not None and task.size == mech.mobility == mech.n_actuators
        J_phi = np.empty((n, m, model.nv))
        J_load = np.empty((n, 6, model.nv)) if frame_id is not None else None
        J_task = np.empty((n, task.size, model.nv)) if square and task is not None else None
        worst = np.zeros(n)  # largest closure residual of each sample
        rows = point_closure_rows(mech, data)  # compiled, the same numbers and decision; None: Pinocchio's
        bound = _closures.BoundClosures(data, closures) if closures and rows is None else None  # live views
        closed, tol = True, mech.assembled_tol
        phi = np.empty(m)
        for i, q in enumerate(trajectory.q):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            if rows is not None:
                closed = rows(J_phi[i], tol) and closed
            elif bound is not None:
                worst[i] = abs(bound.residual(phi)).max()
                bound.jacobian(model, J_phi[i])
            if J_load is not None:
                J_load[i] = pin.getFrameJacobian(model, data, frame_id, _LWA)
            if J_task is not None and task is not None:
                task.jacobian_from_data(model, data, J_task[i])
        if not closed or not np.all(worst <= tol):  # NaN refused too
            check_samples_assembled(mech, trajectory.q, trajectory.t)  # raises, naming the first open sample
        return cls(J_phi, J_load, J_task)


def _run(
    mech: Mechanism,
    trajectory: JointTrajectory,
    kinematics: _Kinematics,
    rule: AllocationRule,
    load_at: Callable[[float], AnyLoad | None],
    body: _BodyGroups,
    gravity: bool,
    singular_rtol: float,
    unloaded: bool,
) -> InverseDynamics:
    """The trajectory loop: RNEA and one factorisation of the balance per sample, on a data of its own."""
    model, act_v = mech.model, actuated_v(mech)
    data = model.createData()
    n, n_act, nv = trajectory.t.shape[0], mech.n_actuators, mech.nv
    compiled = kernels_enabled()  # the factorisation in one compiled call (balance_factors when it declines)
    missing = {"rotor": not body.rotor.any(), "screw": not body.screw.any(), "external": unloaded}
    absent = tuple(name for name, gone in missing.items() if gone)
    out = _Buffers(n, n_act, nv, mech.n_closure_rows, absent)
    linear = rule.is_linear
    previous_sign = 0.0
    parts = np.zeros((nv, len(TERMS)))  # the terms of tau, columns in the order of TERMS
    for i in range(n):
        q, v, a = trajectory.q[i], trajectory.v[i], trajectory.a[i]
        load = load_at(float(trajectory.t[i]))
        J_phi = kinematics.J_phi[i]
        tau_full = pin.rnea(model, data, q, v, a).copy()
        nle = pin.nonLinearEffects(model, data, q, v).copy()
        g_full = pin.computeGeneralizedGravity(model, data, q)
        parts[:, 0] = tau_full - nle
        parts[:, 1] = nle - g_full
        parts[:, 2] = g_full if gravity else 0.0
        if isinstance(load, Load) and kinematics.J_load is not None:
            parts[:, 3] = -(kinematics.J_load[i].T @ load.wrench)
        elif load is not None:
            parts[:, 3] = -load.generalized_force(model, data)
        tau = parts.sum(axis=1)
        try:
            if linear:  # weighted minimum norm: the forces are F tau, one factorisation
                factors = compiled_factors(mech, J_phi, act_v, tau, singular_rtol) if compiled else None
                if factors is None:  # kernels off, or the compiled call declined: the LAPACK path decides
                    factors = balance_factors(mech, J_phi, act_v, tau, singular_rtol)
                F = rule.weighted_map(factors.P, factors.G)
                f_c = F @ tau
                applied = tau.copy()
                applied[act_v] -= f_c
                lam = factors.lambda_map @ applied
                out.residual[i] = float(abs(J_phi.T @ lam - applied).max(initial=0.0))
                out.internal.append(factors.G.T @ f_c)
                N, C = factors.N, factors.C
            else:
                balance = build_balance(mech, q, tau, load, gravity, J_phi, act_v, singular_rtol, v, a)
                sol = solve_balance(mech, balance, rule)
                F = rule.linear_map(balance)
                f_c, lam = sol.f_c, sol.lam
                out.residual[i] = sol.residual
                out.internal.append(sol.internal)
                N, C = balance.N, balance.C
            if (
                kinematics.J_task is not None
            ):  # a sign change of det J_ce between samples: a direct singularity
                sign = det_sign(C) * det_sign(kinematics.J_task[i] @ N)
                if sign * previous_sign < 0:
                    raise SingularConfiguration(
                        f"det J_ce changed sign after t = {trajectory.t[i - 1]:.9g} s: the trajectory "
                        "crossed a direct (type 2) singularity, where the actuators cannot hold the mechanism"
                    )
                previous_sign = sign
        except (AllocationInfeasible, SingularConfiguration) as exc:
            if len(out.internal) > i:
                out.internal.pop()
            partial = out.result(mech, trajectory, body, gravity, i, linear)
            raise InverseDynamicsFailed(
                f"inverse dynamics stopped at sample {i} (t = {trajectory.t[i]:.6g} s): {exc}",
                partial,
                i,
                float(trajectory.t[i]),
                exc,
            ) from exc
        out.shares[i] = F @ parts  # (n_act, 4), in the order of TERMS
        if "rotor" not in absent:
            out.fixed["rotor"][i] = F @ (body.rotor * a)
        if "screw" not in absent:
            out.fixed["screw"][i] = F @ (body.screw * a)
        out.F[i] = F
        out.f_c[i], out.lam[i] = f_c, lam
    return out.result(mech, trajectory, body, gravity, n, linear)


def _body_shares(
    mech: Mechanism, traj: JointTrajectory, body: _BodyGroups, gravity: bool, F: np.ndarray
) -> dict[str, np.ndarray]:
    """Share of ``f_c`` of each body group at the first ``len(F)`` samples, one RNEA pass each."""
    model = mech.model
    data = model.createData()
    out = np.zeros((len(body.names), F.shape[0], F.shape[1]))
    members, support = body.matrices(model)
    for i in range(F.shape[0]):
        pin.computeJointJacobians(model, data, traj.q[i])
        pin.rnea(model, data, traj.q[i], traj.v[i], traj.a[i])
        per_group = members @ _body_forces(model, data, gravity, support)  # (n_groups, nv)
        out[:, i] = per_group @ F[i].T
    return dict(zip(body.names, out, strict=True))


def _load_function(
    mech: Mechanism, wrench: ArrayLike | Callable[[float], ArrayLike] | None, frame: str | None
) -> Callable[[float], AnyLoad | None]:
    """``t -> Load`` for a constant or time-varying wrench, checked on first use."""
    if wrench is None:
        return lambda t: None
    if callable(wrench):
        return lambda t: load_on_frame(mech, wrench(t), frame)
    constant = load_on_frame(mech, wrench, frame)
    return lambda t: constant


class _Buffers:
    """Per-sample outputs, filled in place."""

    def __init__(self, n: int, n_act: int, nv: int, m: int, absent: tuple[str, ...]) -> None:
        self.absent = absent  # shares the mechanism does not have (no rotor, no screw, no load)
        self.f_c = np.zeros((n, n_act))
        self.lam = np.zeros((n, m))
        self.residual = np.zeros(n)
        self.internal: list[np.ndarray] = []
        self.shares = np.zeros((n, n_act, len(TERMS)))  # the share of each term, in the order of TERMS
        self.fixed = {name: np.zeros((n, n_act)) for name in ("rotor", "screw")}
        self.F = np.zeros((n, n_act, nv))  # weighted minimum-norm map of each sample

    def result(
        self,
        mech: Mechanism,
        traj: JointTrajectory,
        body: _BodyGroups,
        gravity: bool,
        count: int,
        linear: bool,
    ) -> InverseDynamics:
        """The first ``count`` samples as an :class:`InverseDynamics` (body split on first access)."""
        f_c = self.f_c[:count]
        terms = {name: np.ascontiguousarray(self.shares[:count, :, k]) for k, name in enumerate(TERMS)}
        if not linear:
            terms["allocation"] = f_c - sum(terms.values(), np.zeros_like(f_c))
        fixed = {k: v[:count] for k, v in self.fixed.items() if k not in self.absent}
        if "external" not in self.absent:  # the load's share: that of its term (an array of its own)
            fixed["external"] = np.ascontiguousarray(self.shares[:count, :, TERMS.index("external")])
        F = self.F[:count]

        def bodies() -> dict[str, np.ndarray]:
            return {**_body_shares(mech, traj, body, gravity, F), **fixed}

        k = self.internal[0].shape[0] if self.internal else 0
        internal = np.array(self.internal).reshape(count, k)
        leads = np.array([a.lead if a.lead else np.nan for a in mech.actuators], dtype=float)
        arrays = [
            traj.t[:count].copy(),
            f_c,
            self.lam[:count],
            internal,
            self.residual[:count],
            traj.cd[:count].copy(),
        ]
        for arr in [*arrays, *terms.values(), leads]:
            arr.setflags(write=False)
        return InverseDynamics(
            tuple(a.joint for a in mech.actuators),
            arrays[0],
            arrays[1],
            arrays[2],
            arrays[3],
            arrays[4],
            arrays[5],
            terms,
            _LazyShares(bodies),
            linear,
            leads,
        )
