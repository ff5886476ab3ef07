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

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from .._checks import check_finite_model, check_samples_assembled, checked_trajectory, load_arguments
from ..exceptions import AllocationInfeasible, InvalidInput, PlmError, SingularConfiguration
from ..statics import AllocationRule, generalized_balance, load_on_frame, solve_balance
from ..statics.balance import SINGULAR_RTOL, Load
from .trajectory import JointTrajectory

if TYPE_CHECKING:
    from ..mechanism import Mechanism

TERMS = ("inertia", "velocity", "gravity", "external")
"""Parts of the inverse-dynamics force by physical term."""

RESERVED_GROUPS = ("external", "other", "rotor", "screw")
"""Names of the body split's own shares, which no body group may take."""


@dataclass(frozen=True)
class InverseDynamics:
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
            reflected inertias, ``"external"`` for the load), each shape (n, n_act).
        split_exact: whether the shares add up to ``f_c`` by linearity (weighted minimum norm).
        leads: ball-screw lead of each actuator [m/rev] (NaN without one), shape (n_act,).
    """

    actuators: tuple[str, ...]
    t: np.ndarray
    f_c: np.ndarray
    lam: np.ndarray
    internal: np.ndarray
    residual: np.ndarray
    cd: np.ndarray
    terms: dict[str, np.ndarray]
    bodies: dict[str, np.ndarray]
    split_exact: bool
    leads: np.ndarray = field(repr=False)

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

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary."""
        return {
            "actuators": list(self.actuators),
            "t": self.t.tolist(),
            "f_c": self.f_c.tolist(),
            "lambda": self.lam.tolist(),
            "internal": self.internal.tolist(),
            "residual": self.residual.tolist(),
            "cd": self.cd.tolist(),
            "terms": {k: v.tolist() for k, v in self.terms.items()},
            "bodies": {k: v.tolist() for k, v in self.bodies.items()},
            "split_exact": self.split_exact,
            "leads": [None if np.isnan(p) else float(p) for p in self.leads],
        }


class InverseDynamicsFailed(PlmError):
    """Inverse dynamics stopped at a sample: infeasible allocation or an unresisted load.

    Attributes:
        partial: the samples computed before it.
        index: the sample that failed.
        time: its time [s].
        cause: the error met there (:class:`AllocationInfeasible` with the saturated actuators,
            or :class:`SingularConfiguration`).
    """

    def __init__(
        self, message: str, partial: InverseDynamics, index: int, time: float, cause: PlmError
    ) -> None:
        self.partial = partial
        self.index = index
        self.time = time
        self.cause = cause
        super().__init__(message)


@dataclass(frozen=True)
class _BodyGroups:
    """Models whose only inertias are one group's bodies, for RNEA per group."""

    names: tuple[str, ...]
    models: tuple[pin.Model, ...]
    datas: tuple[pin.Data, ...]
    rotor: np.ndarray  # reflected rotor inertia per velocity index
    screw: np.ndarray  # reflected screw inertia per velocity index


def _body_groups(mech: Mechanism, groups: Mapping[str, Sequence[str]] | None) -> _BodyGroups:
    """One zero-armature model per group of bodies (bodies named by their joint's first body frame)."""
    model = mech.model
    bodies = {name: j for j, name in enumerate(mech.body_names, start=1)}
    if groups is None:
        chosen = {name: [name] for name in bodies}
        _check_group_names(list(chosen), default=True)
    else:
        chosen = {str(g): list(members) for g, members in groups.items()}
        _check_group_names(list(chosen), default=False)
        listed = [b for members in chosen.values() for b in members]
        unknown = sorted(set(listed) - set(bodies))
        if unknown:
            raise InvalidInput(f"bodies {unknown} are not in {mech.name}; bodies are {sorted(bodies)}")
        doubled = sorted({b for b in listed if listed.count(b) > 1})
        if doubled:
            raise InvalidInput(f"bodies {doubled} are in more than one group")
        rest = [b for b in bodies if b not in listed]
        if rest:
            chosen["other"] = rest
    models, datas = [], []
    for members in chosen.values():
        m = pin.Model(model)
        keep = {bodies[b] for b in members}
        for j in range(1, m.njoints):
            if j not in keep:
                m.inertias[j] = pin.Inertia.Zero()
        m.armature = np.zeros(m.nv)
        models.append(m)
        datas.append(m.createData())
    rotor = np.zeros(model.nv)
    screw = np.zeros(model.nv)
    for act, spec in zip(mech.actuators, mech.sidecar.actuation, strict=True):
        factor = (2.0 * np.pi / spec.lead) ** 2 if spec.lead else 1.0
        rotor[act.idx_v] = spec.rotor_inertia * factor
        screw[act.idx_v] = spec.screw_inertia * factor
    return _BodyGroups(tuple(chosen), tuple(models), tuple(datas), rotor, screw)


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
    wrench: Any = None,
    frame: str | None = None,
    gravity: bool = True,
    groups: Mapping[str, Sequence[str]] | None = None,
    objective: str = "norm",
    weights: Any = None,
    limits: Any = "description",
    internal: Any = None,
    min_compression: float | None = None,
    link_limits: Mapping[str, tuple[float, float]] | None = None,
    singular_rtol: float = SINGULAR_RTOL,
) -> InverseDynamics:
    """Actuator forces driving ``trajectory``, split by term and by body.

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
        singular_rtol: see :data:`~plm_pin.statics.balance.SINGULAR_RTOL`.

    Raises:
        InvalidInput: malformed options, a trajectory of another mechanism, or a body group
            named as one of :data:`RESERVED_GROUPS`.
        DescriptionError: a body's inertia is not finite (see :func:`plm_pin._checks.check_finite_model`).
        ClosureNotSatisfied: a sample of ``trajectory`` is off the closure manifold (see
            :func:`plm_pin._checks.check_assembled`).
        InverseDynamicsFailed: at the first sample whose allocation is infeasible, whose load
            cannot be resisted, or (non-redundant mechanisms with a square task) past a direct
            singularity (a sign change of det J_ce), with the samples before it.
    """
    trajectory = checked_trajectory(trajectory, "trajectory")
    load_arguments(wrench, frame, limits, mech.n_actuators)
    rule = AllocationRule.checked(
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
    check_samples_assembled(mech, trajectory.q, trajectory.t)
    check_finite_model(mech)
    load_at = _load_function(mech, wrench, frame)
    body = _body_groups(mech, groups)
    model, data = mech.model, mech.data
    n, n_act = trajectory.t.shape[0], mech.n_actuators
    absent = tuple(
        name
        for name, missing in (
            ("rotor", not body.rotor.any()),
            ("screw", not body.screw.any()),
            ("external", wrench is None),
        )
        if missing
    )
    out = _Buffers(n, n_act, mech.n_closure_rows, body.names, absent)
    square = mech.task_compiled is not None and mech.task_compiled.size == mech.mobility == n_act
    previous_sign = 0.0
    for i in range(n):
        q, v, a = trajectory.q[i], trajectory.v[i], trajectory.a[i]
        load = load_at(float(trajectory.t[i]))
        tau_full = pin.rnea(model, data, q, v, a).copy()
        tau = tau_full if gravity else tau_full - pin.computeGeneralizedGravity(model, data, q)
        try:
            balance = generalized_balance(
                mech, q, tau, load=load, gravity=gravity, v=v, a=a, singular_rtol=singular_rtol
            )
            sol = solve_balance(mech, balance, rule)
            if square:  # a sign change of det J_ce between samples: a direct singularity was crossed
                sign = _direct_sign(mech, balance.N, balance.C)
                if sign * previous_sign < 0:
                    raise SingularConfiguration(
                        f"det J_ce changed sign after t = {trajectory.t[i - 1]:.9g} s: the trajectory "
                        "crossed a direct (type 2) singularity, where the actuators cannot hold the mechanism"
                    )
                previous_sign = sign
        except (AllocationInfeasible, SingularConfiguration) as exc:
            partial = out.result(mech, trajectory, i, rule.is_linear)
            raise InverseDynamicsFailed(
                f"inverse dynamics stopped at sample {i} (t = {trajectory.t[i]:.6g} s): {exc}",
                partial,
                i,
                float(trajectory.t[i]),
                exc,
            ) from exc
        F = rule.linear_map(balance)  # (n_act, nv) weighted minimum norm
        nle = pin.nonLinearEffects(model, data, q, v)
        g_full = pin.computeGeneralizedGravity(model, data, q)
        parts = {
            "inertia": tau_full - nle,
            "velocity": nle - g_full,
            "gravity": g_full if gravity else np.zeros(mech.nv),
            "external": balance.tau - tau,
        }
        for name, part in parts.items():
            out.terms[name][i] = F @ part
        for name, m, d in zip(body.names, body.models, body.datas, strict=True):
            tau_b = pin.rnea(m, d, q, v, a)
            if not gravity:
                tau_b = tau_b - pin.computeGeneralizedGravity(m, d, q)
            out.bodies[name][i] = F @ tau_b
        out.bodies["rotor"][i] = F @ (body.rotor * a)
        out.bodies["screw"][i] = F @ (body.screw * a)
        out.bodies["external"][i] = out.terms["external"][i]
        out.f_c[i], out.lam[i], out.residual[i] = sol.f_c, sol.lam, sol.residual
        out.internal.append(sol.internal)
    return out.result(mech, trajectory, n, rule.is_linear)


def _direct_sign(mech: Mechanism, N: np.ndarray, C: np.ndarray) -> float:
    r"""Sign of :math:`\det J_{ce} = \det C / \det T`, independent of the basis :math:`N`.

    ``mech.data`` must hold the joint Jacobians of the configuration.
    """
    task = mech.task_compiled
    assert task is not None
    T = task.jacobian_from_data(mech.model, mech.data) @ N
    return float(np.sign(np.linalg.det(C)) * np.sign(np.linalg.det(T)))


def _load_function(mech: Mechanism, wrench: Any, frame: str | None) -> Callable[[float], Load | None]:
    """``t -> Load`` for a constant or time-varying wrench, checked on first use."""
    if wrench is None:
        return lambda t: None
    if callable(wrench):
        return lambda t: load_on_frame(mech, wrench(t), frame)
    constant = load_on_frame(mech, wrench, frame)
    return lambda t: constant


class _Buffers:
    """Per-sample outputs, filled in place."""

    def __init__(self, n: int, n_act: int, m: int, groups: tuple[str, ...], absent: tuple[str, ...]) -> None:
        self.absent = absent  # shares the mechanism does not have (no rotor, no screw, no load)
        self.f_c = np.zeros((n, n_act))
        self.lam = np.zeros((n, m))
        self.residual = np.zeros(n)
        self.internal: list[np.ndarray] = []
        self.terms = {name: np.zeros((n, n_act)) for name in TERMS}
        self.bodies = {name: np.zeros((n, n_act)) for name in (*groups, "rotor", "screw", "external")}

    def result(self, mech: Mechanism, traj: JointTrajectory, count: int, linear: bool) -> InverseDynamics:
        """The first ``count`` samples as an :class:`InverseDynamics`."""
        f_c = self.f_c[:count]
        terms = {k: v[:count] for k, v in self.terms.items()}
        if not linear:
            terms["allocation"] = f_c - sum(terms.values(), np.zeros_like(f_c))
        bodies = {k: v[:count] for k, v in self.bodies.items() if k not in self.absent}
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
        for arr in [*arrays, *terms.values(), *bodies.values(), leads]:
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
            bodies,
            linear,
            leads,
        )
