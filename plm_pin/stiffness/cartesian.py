r"""Cartesian stiffness of a closed chain: the Hessian of the potential condensed on the task.

The feasible motions of the compliant model, :math:`v = N s` with :math:`N` an orthonormal
basis of the null space of the closure rows and of the rigid drives' locks, carry the
Hessian :math:`H_N = N^T H N` (:mod:`~plm_pin.stiffness.equilibrium`). A small extra load
:math:`\delta w` on the task frame moves the equilibrium by :math:`H_N \delta s = T^T \delta w`
with :math:`T = J_x N`, so that the task compliance and stiffness are

.. math:: C_x = T H_N^{-1} T^T, \qquad K_x = C_x^{-1}.

The idle mobilities of the mechanism (the spin of an S-S strut about its axis) are held by
its gauge closures (:mod:`plm_pin.core.idle`), so :math:`N` does not contain them.
Other motions no spring resists and the task does not see (an unsprung passive mobility
away from the task, without gravity) are left out; a task motion no spring resists is
refused. With rigid links and
as many task coordinates as DOF, :math:`K_x = T^{-T} H_N T^{-1} = J_{ce}^T K_a J_{ce}` plus
the geometric terms (Griffis and Duffy). The share of each source,
:math:`K_x^{(s)} = \Sigma^T H_N^{(s)} \Sigma` with :math:`\Sigma = H_N^{-1} T^T K_x` (the
motion per task displacement), adds up to :math:`K_x`.

Eigen-stiffnesses are read on the compliance, translational and rotational blocks apart so
that units do not mix: :math:`1/\mathrm{eig}(C_{tt})` [N/m] under pure forces, and
:math:`1/\mathrm{eig}(C_{rr})` [N m/rad] under pure moments.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import as_vector
from .._linalg import lu_solve
from ..core.closures import jacobian_from_data
from ..core.mechanism import Mechanism, require_task
from ..description.compliance import ComplianceSpec
from ..exceptions import InvalidInput, SingularConfiguration
from ..results import Result, unit
from ..statics import StaticForces
from ..tolerances import CONSTRAINT_NULL_RTOL, TASK_COMPLIANCE_RTOL, TASK_UNRESISTED_RTOL, UNRESISTED_RTOL
from .equilibrium import GEOMETRIC, ElasticState, elastic_state, hessian, with_locks
from .model import SOURCES


@dataclass(frozen=True)
class EigenStiffness(Result):
    """Principal stiffnesses of one block of the compliance.

    Attributes:
        values: eigen-stiffnesses, ascending [N/m] or [N m/rad] (``unit``), shape (k,).
        directions: unit directions in the block's task coordinates, one per column, shape (k, k).
        dofs: the task coordinates of the block.
        unit: unit of ``values``.
    """

    values: np.ndarray = field(metadata=unit("N/m, N m/rad"))
    directions: np.ndarray = field(metadata=unit("-"))
    dofs: tuple[str, ...]
    unit: str


def _entry_units(dofs: tuple[str, ...], kind: str) -> list[str]:
    rot = [d.startswith("r") for d in dofs]
    if kind == "K":
        table = {(False, False): "N/m", (False, True): "N/rad", (True, False): "N", (True, True): "N m/rad"}
    else:
        table = {
            (False, False): "m/N",
            (False, True): "m/(N m)",
            (True, False): "rad/N",
            (True, True): "rad/(N m)",
        }
    return [table[(a, b)] for a in rot for b in rot]


@dataclass(frozen=True)
class StiffnessResult(Result):
    r"""Cartesian stiffness at an equilibrium.

    Attributes:
        dofs: task coordinates, e.g. ``("x", "y", "rz")``.
        q: rigid configuration, shape (nq,).
        K_x: task stiffness [N/m, N/rad, N, N m/rad] (see ``to_dict`` for each entry's unit),
            shape (n_task, n_task).
        C_x: task compliance :math:`K_x^{-1}`, shape (n_task, n_task).
        translational: eigen-stiffness under pure forces [N/m].
        rotational: eigen-stiffness under pure moments [N m/rad].
        contributions: :math:`K_x^{(s)}` of each source (``actuators``, ``joints``, ``links``,
            ``gravity``, ``load``, ``closures``), summing to ``K_x``, each (n_task, n_task).
        f_c: actuator forces at the equilibrium [N, N m], shape (n_act,).
        lam: cut-joint forces at the equilibrium [N, N m], shape (m,).
        basis: compliant-model motions kept, :math:`v = B s`, shape (nv_c, r).
        H: Hessian of the potential on them, shape (r, r).
        T: task rates per motion, shape (n_task, r).
        idle: idle mobilities of the mechanism, held by its gauges (left out; see
            :attr:`plm_pin.core.mechanism.Mechanism.idle_mobility`).
        unresisted: other motions no spring resists and the task does not see (left out).
        state: the equilibrium.
    """

    dofs: tuple[str, ...]
    q: np.ndarray = field(metadata=unit("m, rad"))
    K_x: np.ndarray = field(metadata=unit("N/m, N/rad, N, N m/rad"))
    C_x: np.ndarray = field(metadata=unit("m/N, m/(N m), rad/N, rad/(N m)"))
    translational: EigenStiffness = field(metadata=unit("N/m"))
    rotational: EigenStiffness = field(metadata=unit("N m/rad"))
    contributions: dict[str, np.ndarray] = field(metadata=unit("N/m, N/rad, N, N m/rad"))
    f_c: np.ndarray = field(metadata=unit("N, N m"))
    lam: np.ndarray = field(metadata=unit("N, N m"))
    basis: np.ndarray
    H: np.ndarray
    T: np.ndarray
    idle: int
    unresisted: int
    state: ElasticState
    _SKIPPED = ("basis", "H", "T", "state")

    @property
    def min_translational(self) -> float:
        """Smallest translational eigen-stiffness [N/m] (NaN when the task has no translation)."""
        v = self.translational.values
        return float(v[0]) if v.size else float("nan")

    def compliance_along(self, direction: ArrayLike) -> float:
        """Displacement per unit force along a unit task-translation direction [m/N].

        Args:
            direction: direction in the task's translation coordinates (normalised here),
                shape (n_translations,).

        Raises:
            InvalidInput: wrong size or a zero vector.
        """
        lin = [i for i, d in enumerate(self.dofs) if not d.startswith("r")]
        u = as_vector(direction, len(lin), "direction")
        norm = float(np.linalg.norm(u))
        if norm == 0.0:
            raise InvalidInput("direction must be a non-zero vector")
        u = u / norm
        return float(u @ self.C_x[np.ix_(lin, lin)] @ u)

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON, with the unit of every entry of ``K_x`` and ``C_x`` (row-major)."""
        units = {"K_x": _entry_units(self.dofs, "K"), "C_x": _entry_units(self.dofs, "C")}
        return {**super().to_dict(), "units": units}


def null_basis(
    A: np.ndarray, nv: int, rtol: float = CONSTRAINT_NULL_RTOL, closure_tol: float = 0.0
) -> np.ndarray:
    """Orthonormal basis of the null space of ``A``, shape (nv, nullity).

    Rank by SVD: singular values above ``rtol`` times the largest and above ``closure_tol``
    times ``max(s_max, 1)`` (the dependent rows of a description that closes only to its
    closure tolerance [m, rad] sit below it; see :mod:`plm_pin.core.rank`).
    """
    if A.shape[0] == 0:
        return np.eye(nv)
    _, s, Vt = np.linalg.svd(A)
    rank = int(np.count_nonzero(s > max(rtol * max(s[0], 1e-300), closure_tol * max(s[0], 1.0))))
    return Vt[rank:].T.copy()


def condense(state: ElasticState) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray], int]:
    r"""Motions kept, task rates, Hessian and its terms on them, and the number of unresisted motions.

    Returns:
        ``B`` (nv_c, r), ``T`` (n_task, r), ``H`` (r, r), the terms of ``H`` (each (r, r)) and
        the number of motions left out (no spring resists them, the task does not see them).

    Raises:
        SingularConfiguration: a task motion that no spring resists.
    """
    cm = state.compliant
    mech = cm.mech
    task = require_task(mech)
    full = hessian(state)  # leaves the kinematics of state.q in mech.data
    A = with_locks(cm, jacobian_from_data(mech.model, mech.data, mech.closures))
    N = null_basis(A, mech.nv, closure_tol=mech.closure_tol)
    T = task.jacobian_from_data(mech.model, mech.data).reshape(task.size, -1) @ N
    stack = np.array(list(full.values()))  # (n_terms, nv_c, nv_c)
    H = N.T @ stack.sum(axis=0) @ N
    mu, Z = np.linalg.eigh(0.5 * (H + H.T))
    scale = max(float(np.max(np.abs(mu), initial=0.0)), 1e-300)
    free = np.abs(mu) <= UNRESISTED_RTOL * scale
    if free.any():
        seen = np.linalg.norm(T @ Z[:, free], axis=0)
        if np.max(seen) > TASK_UNRESISTED_RTOL * max(float(np.linalg.norm(T)), 1e-300):
            raise SingularConfiguration(
                f"{cm.rigid.name}: {int(np.count_nonzero(seen > TASK_UNRESISTED_RTOL * np.linalg.norm(T)))} "
                "task motion(s) "
                "resisted by no spring (zero stiffness): every drive that holds the task needs a stiffness "
                "under compliance.actuators, or the pose is singular"
            )
    Y = Z[:, ~free]
    B = N @ Y
    terms = dict(zip(full, B.T @ stack @ B, strict=True))
    return B, T @ Y, Y.T @ H @ Y, terms, int(np.count_nonzero(free))


def _eigen(C: np.ndarray, idx: list[int], dofs: tuple[str, ...], unit: str) -> EigenStiffness:
    if not idx:
        return EigenStiffness(np.zeros(0), np.zeros((0, 0)), (), unit)
    block = C[np.ix_(idx, idx)]
    c, vec = np.linalg.eigh(0.5 * (block + block.T))
    order = np.argsort(-c)  # largest compliance = smallest stiffness first
    values, directions = 1.0 / c[order], vec[:, order]
    values.setflags(write=False)
    directions.setflags(write=False)
    return EigenStiffness(values, directions, tuple(dofs[i] for i in idx), unit)


def stiffness(
    mech: Mechanism,
    q: ArrayLike,
    wrench: ArrayLike | None = None,
    frame: str | None = None,
    *,
    gravity: bool = True,
    internal: ArrayLike | Mapping[str, float] | None = None,
    forces: StaticForces | None = None,
    compliance: ComplianceSpec | None = None,
) -> StiffnessResult:
    r"""Task stiffness :math:`K_x` at the equilibrium at ``q`` (springs plus geometric stiffness).

    Args:
        mech: the mechanism (with a task).
        q: assembled configuration, shape (nq,).
        wrench: external wrench held at ``q`` on ``frame`` [N, N m] (its geometric stiffness
            is included); see :func:`plm_pin.statics.static_forces`.
        frame: frame the wrench acts on; default the task frame.
        gravity: include the bodies' weight (and its geometric stiffness).
        internal: internal preload, as in :func:`~plm_pin.statics.static_forces`; on the
            3D4M, Harada 2011's :math:`f_i` is ``{"plate": -f_i}``.
        forces: a static solution at ``q`` instead of the four arguments above.
        compliance: the springs; default the sidecar's ``compliance``.

    Returns:
        The stiffness, compliance, eigen-stiffnesses and the share of each source.

    Raises:
        InvalidInput: malformed arguments, ``q`` not the configuration of ``forces``, no task or
            no compliance.
        SingularConfiguration: the load cannot be held, a task motion is resisted by no spring,
            or the springs leave a task direction rigid (infinite stiffness).
    """
    require_task(mech)
    state = elastic_state(
        mech, q, wrench, frame, gravity=gravity, internal=internal, forces=forces, compliance=compliance
    )
    B, T, H, terms, unresisted = condense(state)
    HiT = lu_solve(H, T.T)
    C = T @ HiT
    s = np.linalg.svd(C, compute_uv=False)
    if s.size == 0 or s[-1] <= TASK_COMPLIANCE_RTOL * s[0]:
        moving = int(np.count_nonzero(s > TASK_COMPLIANCE_RTOL * (s[0] if s.size else 1.0)))
        raise SingularConfiguration(
            f"{mech.name}: the springs let the task move in {moving}"
            f" of {T.shape[0]} directions; the others are rigid (give the drives or links a compliance)"
        )
    K = np.linalg.inv(C)
    Sigma = HiT @ K  # (r, n_task): motion per task displacement
    contributions = {k: Sigma.T @ terms[k] @ Sigma for k in (*SOURCES, *GEOMETRIC)}
    dofs = tuple(require_task(mech).dofs)
    lin = [i for i, d in enumerate(dofs) if not d.startswith("r")]
    rot = [i for i, d in enumerate(dofs) if d.startswith("r")]
    for a in (K, C, B, H, T, *contributions.values()):
        a.setflags(write=False)
    return StiffnessResult(
        dofs=dofs,
        q=state.forces.balance.q,
        K_x=K,
        C_x=C,
        translational=_eigen(C, lin, dofs, "N/m"),
        rotational=_eigen(C, rot, dofs, "N m/rad"),
        contributions=contributions,
        f_c=state.forces.f_c,
        lam=state.lam,
        basis=B,
        H=H,
        T=T,
        idle=mech.idle_mobility,
        unresisted=unresisted,
        state=state,
    )
