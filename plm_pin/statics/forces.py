r"""Static forces of a closed chain in one call: balance, allocation, and every force it implies.

:func:`static_forces` sets up the balance (:mod:`~plm_pin.statics.balance`), allocates the
actuator forces (:mod:`~plm_pin.statics.allocation`) and returns a :class:`StaticForces`
from which cut-joint forces, joint reactions, slider normal forces, link axial forces
(:mod:`~plm_pin.statics.reactions`) and the internal-force directions are read.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import effort_limits, finite_number, load_arguments, mapping, optional_name, real_numbers
from .._linalg import lu_solve
from .._text import short
from ..core.checks import check_finite_result
from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput
from ..results import Result, unit
from ..tolerances import LINK_FORCE_RTOL, STATICS_SINGULAR_RTOL
from . import reactions as _reactions
from .allocation import OBJECTIVES, Allocation, Inequalities, allocate, check_weights, min_norm
from .balance import StaticBalance, finite, static_balance


@dataclass(frozen=True)
class InternalDirection(Result):
    """One internal-force direction: actuator forces that balance nothing but each other, and what they load.

    Attributes:
        f_c: actuator forces of the direction (a unit vector of the internal basis) [N, N m], shape (n_act,).
        lam: cut-joint forces it causes [N, N m], shape (m,).
        link_forces: axial forces it causes in the hinged links (tension positive) [N].
        slider_normal_forces: normal forces it causes on the prismatic guides [N].
    """

    f_c: np.ndarray = field(metadata=unit("N, N m"))
    lam: np.ndarray = field(metadata=unit("N, N m"))
    link_forces: dict[str, _reactions.LinkForce] = field(metadata=unit("N"))
    slider_normal_forces: dict[str, np.ndarray] = field(metadata=unit("N"))


@dataclass(frozen=True)
class StaticForces(Result):
    r"""A static equilibrium: actuator forces, cut-joint forces and the balance they satisfy.

    Attributes:
        mechanism: the mechanism.
        balance: the balance that was solved (load, feasible motions, internal basis).
        f_c: actuator forces [N] or torques [N m], in actuator order, shape (n_act,).
        lam: cut-joint forces :math:`\lambda` [N, N m], in closure-row order, shape (m,).
        internal: internal-force coordinates in ``balance.internal_basis``, shape (k,).
        residual: equilibrium residual :math:`\|B f_c + J_\phi^T \lambda - \tau\|_\infty` [N, N m].
        active: names of the limits and conditions at their bounds.
        objective: the allocation objective used.
    """

    mechanism: Mechanism
    balance: StaticBalance
    f_c: np.ndarray = field(metadata=unit("N, N m"))
    lam: np.ndarray = field(metadata=unit("N, N m"))
    internal: np.ndarray = field(metadata=unit("N, N m"))
    residual: float = field(metadata=unit("N, N m"))
    active: tuple[str, ...]
    objective: str

    @property
    def saturated(self) -> tuple[str, ...]:
        """Actuators at one of their limits."""
        names = {a.joint for a in self.mechanism.actuators}
        return tuple(n for n in self.active if n in names)

    @functools.cached_property
    def _transmitted(self) -> tuple[np.ndarray, np.ndarray]:
        b = self.balance
        return _reactions.transmitted_forces(self.mechanism, b.q, self.lam, b.load, b.gravity, b.v, b.a)

    def joint_reactions(self) -> dict[str, _reactions.JointReaction]:
        """Force and moment every joint passes from parent to child, keyed by joint name."""
        return _reactions.joint_reactions(self.mechanism, *self._transmitted)

    def link_forces(self) -> dict[str, _reactions.LinkForce]:
        """Axial force (tension positive) and shear of every hinged link, keyed by link name."""
        return _reactions.link_forces(self.mechanism, self._transmitted[0], self.lam)

    def slider_normal_forces(self) -> dict[str, np.ndarray]:
        """Force each prismatic guide exerts normal to its axis [N], world, keyed by joint name."""
        return _reactions.slider_normal_forces(self.mechanism, self._transmitted[0])

    def internal_directions(self) -> tuple[InternalDirection, ...]:
        """The internal-force basis with its physical reading (loads in the links and guides)."""
        return internal_directions(self.mechanism, self.balance)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary of the forces (reactions included)."""
        acts = [a.joint for a in self.mechanism.actuators]
        return {
            "f_c": dict(zip(acts, self.f_c.tolist(), strict=True)),
            "lam": {c.name: self.lam[c.rows].tolist() for c in self.mechanism.closures},
            "internal": self.internal.tolist(),
            "residual": self.residual,
            "active": list(self.active),
            "objective": self.objective,
            "link_forces": {k: v.to_dict() for k, v in self.link_forces().items()},
            "slider_normal_forces": {k: v.tolist() for k, v in self.slider_normal_forces().items()},
        }


def internal_directions(mech: Mechanism, balance: StaticBalance) -> tuple[InternalDirection, ...]:
    """Read each internal-force basis vector as the forces it causes (no load, no gravity)."""
    out = []
    for k in range(balance.n_internal):
        g = balance.internal_basis[:, k].copy()
        lam = -balance.lambda_map @ balance.generalized(g)
        forces, _ = _reactions.transmitted_forces(mech, balance.q, lam, None, False)
        out.append(
            InternalDirection(
                g,
                lam,
                _reactions.link_forces(mech, forces, lam),
                _reactions.slider_normal_forces(mech, forces),
            )
        )
    return tuple(out)


def actuator_limits(mech: Mechanism, limits: ArrayLike | None) -> np.ndarray:
    """Actuator effort limits as an (n_act, 2) array with infinities where unbounded.

    Args:
        mech: the mechanism.
        limits: ``"description"`` (the sidecar's ``limits``), None (unbounded), or an
            array-like (n_act, 2) of lower and upper efforts [N, N m].

    Raises:
        InvalidInput: wrong shape, NaN, a lower bound above its upper bound, a lower bound of
            +inf or an upper bound of -inf (no effort would be admissible).
    """
    n = mech.n_actuators
    effort_limits(limits, "limits", n)
    if isinstance(limits, str):
        if limits != "description":
            raise InvalidInput(f"limits {limits!r} is not 'description', None or an ({n}, 2) array")
        return np.array(
            [a.limits if a.limits is not None else (-np.inf, np.inf) for a in mech.actuators]
        ).reshape(n, 2)
    if limits is None:
        return np.tile([-np.inf, np.inf], (n, 1))
    arr = np.asarray(limits, dtype=float)
    if arr.shape != (n, 2) or np.isnan(arr).any() or (arr[:, 0] > arr[:, 1]).any():
        raise InvalidInput(f"limits must be an ({n}, 2) array of lower <= upper efforts, got {arr.tolist()}")
    if (arr[:, 0] == np.inf).any() or (arr[:, 1] == -np.inf).any():
        raise InvalidInput(
            f"limits must have lower bounds below +inf and upper bounds above -inf (-inf, inf: no "
            f"limit), got {arr.tolist()}"
        )
    return arr


@dataclass(frozen=True)
class AllocationRule:
    """How to choose the actuator forces among those that balance a load (checked once, reused per sample).

    Attributes:
        objective: ``"norm"`` or ``"max"``.
        weights: SPD weight matrix (n_act, n_act).
        limits: effort limits (n_act, 2), infinite where none [N, N m].
        internal: prescribed internal forces (coordinates or ``{link: axial force}``), or None.
        min_compression: compression required in every hinged link [N], or None.
        link_limits: bounds on named links' axial forces [N], or None.
    """

    objective: str
    weights: np.ndarray
    limits: np.ndarray
    internal: np.ndarray | Mapping[str, float] | None = None
    min_compression: float | None = None
    link_limits: Mapping[str, tuple[float, float]] | None = None

    @classmethod
    def checked(
        cls,
        mech: Mechanism,
        *,
        objective: str = "norm",
        weights: ArrayLike | None = None,
        limits: str | ArrayLike | None = "description",
        internal: ArrayLike | Mapping[str, float] | None = None,
        min_compression: float | None = None,
        link_limits: Mapping[str, tuple[float, float]] | None = None,
    ) -> AllocationRule:
        """Check the options against ``mech`` (see :func:`static_forces` for their meaning).

        Raises:
            InvalidInput: an unknown objective, bad weights or limits, internal forces, a
                minimum compression or link limits of the wrong type.
        """
        if not isinstance(objective, str) or objective not in OBJECTIVES:
            raise InvalidInput(f"objective {short(objective)} is not one of {list(OBJECTIVES)}")
        W = check_weights(weights, mech.n_actuators)
        bounds = actuator_limits(mech, limits)
        if isinstance(internal, Mapping):
            internal = {
                _link_name(name, "internal"): finite_number(value, f"internal[{name!r}]", "N")
                for name, value in internal.items()
            }
        elif internal is not None:
            internal = np.asarray(real_numbers(internal, "internal"), dtype=float)
        if min_compression is not None:
            min_compression = finite_number(min_compression, "min_compression", "N")
        if link_limits is not None:
            link_limits = {
                _link_name(name, "link_limits"): _force_bounds(pair, f"link_limits[{name!r}]")
                for name, pair in mapping(
                    link_limits, "link_limits", "link names to (lower, upper) axial forces [N]"
                ).items()
            }
        return cls(objective, W, bounds, internal, min_compression, link_limits)

    @functools.cached_property
    def unweighted(self) -> bool:
        """Whether the weights are the identity (the plain minimum norm)."""
        return bool(np.array_equal(self.weights, np.eye(self.weights.shape[0])))

    @functools.cached_property
    def is_linear(self) -> bool:
        """Whether the chosen forces are linear in the load: weighted minimum norm, nothing else."""
        return (
            self.objective == "norm"
            and self.internal is None
            and self.min_compression is None
            and not self.link_limits
            and not np.isfinite(self.limits).any()
        )

    def linear_map(self, balance: StaticBalance) -> np.ndarray:
        r"""The forces per generalized force for a linear rule, shape (n_act, nv).

        :math:`F = (I - G (G^T W G)^{-1} G^T W) P`: the weighted minimum norm of the balance.
        """
        return self.weighted_map(balance.force_map, balance.internal_basis)

    def weighted_map(self, P: np.ndarray, G: np.ndarray) -> np.ndarray:
        """:meth:`linear_map` from the minimum-norm map ``P`` (n_act, nv) and the internal basis ``G``."""
        if G.shape[1] == 0 or self.unweighted:
            return P  # W = I: P is that minimum norm (G^T P = 0)
        WG = self.weights @ G
        if G.shape[1] == 1:  # one internal force (3D4M): a scalar
            return P - G @ ((WG.T @ P) / float(G[:, 0] @ WG[:, 0]))
        return P - G @ lu_solve(G.T @ WG, WG.T @ P)


def solve_balance(mech: Mechanism, balance: StaticBalance, rule: AllocationRule) -> StaticForces:
    """Allocate the actuator forces of a balance by ``rule`` and complete the solution.

    Raises:
        AllocationInfeasible: the limits and conditions cannot all be met.
        InvalidInput: malformed preload names or values.
    """
    f_p, G = balance.f_particular, balance.internal_basis
    if not rule.is_linear:
        result = _allocated(mech, balance, rule)
        f_c, y, active = result.f_c, result.y, result.active
    elif rule.unweighted:  # the minimum norm (min_norm with W = I)
        f_c, y, active = _plain_min_norm(f_p, G)
    else:
        result = min_norm(f_p, G, rule.weights)
        f_c, y, active = result.f_c, result.y, result.active
    tau = balance.tau
    Bf = np.zeros(tau.shape[0])  # balance.generalized(f_c)
    Bf[balance.actuated_v] = f_c
    lam = balance.lambda_map @ (tau - Bf)  # balance.closure_forces(f_c)
    if not (finite(f_c) and finite(lam)):
        check_finite_result(mech, "static forces", f_c=f_c, lam=lam)
    for a in (f_c, lam, y):
        a.setflags(write=False)
    residual = float(abs(Bf + balance.J_phi.T @ lam - tau).max(initial=0.0))  # balance.residual(f_c, lam)
    return StaticForces(mech, balance, f_c, lam, y, residual, active, rule.objective)


def _plain_min_norm(f_p: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """:func:`~plm_pin.statics.allocation.min_norm` with unit weights: ``(f_c, y, active)``.

    ``W G`` is ``G`` itself, so the products are those of ``min_norm`` without the product by ``I``.
    """
    k = G.shape[1]
    if k == 0:
        y = np.zeros(0)
    elif k == 1:  # one internal force (3D4M): a scalar
        g = G[:, 0]
        y = np.array([-(g @ f_p) / (g @ g)])
    else:
        y = lu_solve(G.T @ G, -(G.T @ f_p))
    return f_p + G @ y, y, ()


def _allocated(mech: Mechanism, balance: StaticBalance, rule: AllocationRule) -> Allocation:
    """The allocation of a rule with inequalities, a prescribed internal force or the min-peak objective."""
    f_p, G = balance.f_particular, balance.internal_basis
    bounds = rule.limits
    names = tuple(a.joint for a in mech.actuators)
    finite = np.flatnonzero(np.isfinite(bounds).any(axis=1))
    ineq = Inequalities(
        tuple(names[i] for i in finite), f_p[finite], G[finite], bounds[finite, 0], bounds[finite, 1]
    )
    conditions = _link_conditions(mech, balance, rule.min_compression, rule.link_limits)
    if conditions is not None:
        ineq = Inequalities(
            ineq.names + conditions.names,
            np.concatenate([ineq.offset, conditions.offset]),
            np.vstack([ineq.D, conditions.D]),
            np.concatenate([ineq.lower, conditions.lower]),
            np.concatenate([ineq.upper, conditions.upper]),
        )
    internal = rule.internal
    if isinstance(internal, Mapping):
        internal = _internal_from_links(mech, balance, internal)
    return allocate(
        f_p, G, ineq, weights=rule.weights, objective=rule.objective, internal=internal, actuator_names=names
    )


def static_forces(
    mech: Mechanism,
    q: ArrayLike,
    wrench: ArrayLike | None = None,
    frame: str | None = None,
    *,
    gravity: bool = True,
    objective: str = "norm",
    weights: ArrayLike | None = None,
    limits: str | ArrayLike | None = "description",
    internal: ArrayLike | Mapping[str, float] | None = None,
    min_compression: float | None = None,
    link_limits: Mapping[str, tuple[float, float]] | None = None,
    singular_rtol: float = STATICS_SINGULAR_RTOL,
) -> StaticForces:
    r"""Actuator and cut-joint forces holding the mechanism at ``q`` under gravity and a wrench.

    By default (gravity, minimum norm, the description's limits) it computes the actuator
    forces, the cut-joint forces, the internal coordinates and the residual; reactions, link
    forces and internal-force directions are computed when asked for.

    Args:
        mech: the mechanism.
        q: an assembled configuration, shape (nq,).
        wrench: external wrench **applied to** ``frame`` [N, N m]: 6 values ``(force, moment)``
            about the frame origin, world-aligned, or one per task coordinate on the task
            frame. Harada 2011's :math:`f_e = J_{ce}^T f_c` is the force the actuators exert
            on the end effector, so it corresponds to ``wrench = -f_e`` with ``gravity=False``.
        frame: frame the wrench acts on; default the task frame.
        gravity: include the weight of the bodies.
        objective: ``"norm"`` (weighted minimum norm) or ``"max"`` (minimum largest force).
        weights: actuator weights: None (all 1), a vector or an SPD matrix.
        limits: actuator effort limits: ``"description"``, None or an (n_act, 2) array.
        internal: prescribe the internal forces instead of optimising them: coordinates in
            the internal basis (shape (k,)), or the axial force [N] (tension positive) that the
            internal part alone puts in ``k`` named hinged links, ``{link: force}``. Harada
            2011's :math:`f_i` (eqs. (20)-(22)), a compression of the end plate, is
            ``internal={"plate": -f_i}`` on the 3D4M preset.
        min_compression: every hinged link (see :mod:`~plm_pin.statics.reactions`) in
            compression by at least this much [N] (a preload condition).
        link_limits: bounds on the axial force (tension positive) [N] of named links.
        singular_rtol: see :data:`~plm_pin.tolerances.STATICS_SINGULAR_RTOL`.

    Raises:
        InvalidInput: malformed arguments (the message names the valid choices).
        SingularConfiguration: the load cannot be resisted at ``q``.
        AllocationInfeasible: the limits and conditions cannot all be met; the error carries
            the least-violating allocation and the saturated actuators.
    """
    options = dict(
        objective=objective,
        weights=weights,
        limits=limits,
        internal=internal,
        min_compression=min_compression,
        link_limits=link_limits,
    )
    if default_options(**options):
        real_numbers(wrench, "wrench")  # load_arguments with the default limits
        optional_name(frame, "frame")
    else:
        load_arguments(wrench, frame, limits, mech.n_actuators)
    rule = allocation_rule(mech, **options)
    balance = static_balance(mech, q, wrench, frame, gravity=gravity, singular_rtol=singular_rtol)
    return solve_balance(mech, balance, rule)


def default_options(
    objective: object,
    weights: object,
    limits: object,
    internal: object,
    min_compression: object,
    link_limits: object,
) -> bool:
    """Whether the allocation options are the defaults (minimum norm, the description's limits)."""
    return (
        isinstance(objective, str)
        and objective == "norm"
        and weights is None
        and isinstance(limits, str)
        and limits == "description"
        and internal is None
        and min_compression is None
        and link_limits is None
    )


def allocation_rule(mech: Mechanism, **options: Any) -> AllocationRule:
    """The checked rule of ``options`` (:meth:`AllocationRule.checked`); :func:`default_rule` for defaults."""
    return default_rule(mech) if default_options(**options) else AllocationRule.checked(mech, **options)


def default_rule(mech: Mechanism) -> AllocationRule:
    """``AllocationRule.checked(mech)`` (minimum norm, the description's limits), once per actuator tuple.

    Kept with the mechanism, its arrays read-only: the rule of every call with the default options.
    """
    hit = vars(mech).get(_DEFAULT_RULE)
    if hit is not None and hit[0] is mech.actuators:
        return hit[1]
    rule = AllocationRule.checked(mech)
    for arr in (rule.weights, rule.limits):
        arr.setflags(write=False)
    vars(mech)[_DEFAULT_RULE] = (mech.actuators, rule)
    return rule


_DEFAULT_RULE = "_statics_default_rule"
"""Attribute of a mechanism holding its actuator tuple and the default allocation rule."""


def _link_name(name: object, argument: str) -> str:
    """``name`` if it is a link name (a string); ``argument`` is named in the message otherwise."""
    if not isinstance(name, str):
        raise InvalidInput(f"{argument} must be keyed by link names (strings), got the key {short(name)}")
    return name


def _force_bounds(pair: object, name: str) -> tuple[float, float]:
    """``pair`` as ``(lower, upper)`` [N]: two real numbers, not NaN, lower <= upper (infinities allowed)."""
    arr = np.asarray(real_numbers(pair, name), dtype=float)  # None: NaN, refused below
    if arr.shape != (2,) or np.isnan(arr).any() or arr[0] > arr[1]:
        raise InvalidInput(
            f"{name} must be (lower, upper) axial forces [N] with lower <= upper, got {short(pair)}"
        )
    return float(arr[0]), float(arr[1])


def _link_conditions(
    mech: Mechanism,
    balance: StaticBalance,
    min_compression: float | None,
    link_limits: Mapping[str, tuple[float, float]] | None,
) -> Inequalities | None:
    """Axial-force conditions as rows on the internal coordinates (axial forces are affine in them)."""
    if min_compression is None and not link_limits:
        return None
    links = [h.link for h in _reactions.hinged_links(mech)]
    bounds: dict[str, tuple[float, float]] = {}
    if min_compression is not None:
        if not np.isfinite(min_compression):
            raise InvalidInput(f"min_compression must be a finite force [N], got {min_compression}")
        if not links:
            raise InvalidInput(f"{mech.name} has no hinged links to hold in compression")
        bounds = {name: (-np.inf, -float(min_compression)) for name in links}
    for name, (lo, hi) in (link_limits or {}).items():
        if name not in links:
            raise InvalidInput(f"link {name!r} is not a hinged link; hinged links are {links}")
        if np.isnan(lo) or np.isnan(hi) or lo > hi:
            raise InvalidInput(f"link_limits[{name!r}] must be (lower <= upper) [N], got {(lo, hi)}")
        old = bounds.get(name, (-np.inf, np.inf))
        bounds[name] = (max(old[0], lo), min(old[1], hi))
    lam_p = balance.closure_forces(balance.f_particular)
    forces_p, _ = _reactions.transmitted_forces(
        mech, balance.q, lam_p, balance.load, balance.gravity, balance.v, balance.a
    )
    axial_p = _reactions.link_forces(mech, forces_p, lam_p)
    directions = internal_directions(mech, balance)
    chosen = list(bounds)
    D = np.array([[d.link_forces[name].axial for d in directions] for name in chosen]).reshape(
        len(chosen), len(directions)
    )
    return Inequalities(
        tuple(f"{name} axial" for name in chosen),
        np.array([axial_p[name].axial for name in chosen]),
        D,
        np.array([bounds[name][0] for name in chosen]),
        np.array([bounds[name][1] for name in chosen]),
    )


def _internal_from_links(mech: Mechanism, balance: StaticBalance, targets: Mapping[str, float]) -> np.ndarray:
    """Internal coordinates giving the internal part the named link axial forces."""
    k = balance.n_internal
    directions = internal_directions(mech, balance)
    links = [h.link for h in _reactions.hinged_links(mech)]
    unknown = [name for name in targets if name not in links]
    if unknown:
        raise InvalidInput(f"links {unknown} are not hinged links; hinged links are {links}")
    if len(targets) != k:
        raise InvalidInput(
            f"{mech.name} has {k} internal force(s) at this configuration; "
            f"name {k} link(s), got {list(targets)}"
        )
    R = np.array([[d.link_forces[name].axial for d in directions] for name in targets]).reshape(k, k)
    s = np.linalg.svd(R, compute_uv=False) if k else np.zeros(0)
    if k and s[-1] <= LINK_FORCE_RTOL * max(s[0], 1e-300):
        raise InvalidInput(
            f"the internal forces do not load the links {list(targets)} independently; choose others"
        )
    return lu_solve(R, np.array([float(v) for v in targets.values()])) if k else np.zeros(0)
