r"""Legs as diagonal blocks of the inverse-kinematics Jacobian, and working-mode signatures.

With the task frame pinned, the inverse-kinematics equations :math:`[\phi(q); x(q) - x^*] = 0`
split into independent sub-problems: the chain that carries the end effector, then one
per leg that closes on it. Their Jacobian is block-triangular after permutation
(Dulmage-Mendelsohn / block-triangular form of its sparsity pattern), so its determinant
is the product of the diagonal blocks' determinants. The blocks that hold task rows form
the end-effector chain; the others, grouped by connectivity, are the *legs*. The sign of
a leg's determinant is its *working mode* (branch), and a zero is an actuator (type-1)
singularity of that leg. For a PRRRP leg of Harada 2011 the block determinant is
:math:`l_i z_i^T a`, so the sign is that of :math:`z_i^T a` (the paper's square-root sign
in eq. (2) is its opposite).

The pattern is read numerically at a generic assembled configuration; rows that vanish
there (the out-of-plane rows of planar closures) are dropped.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, maximum_bipartite_matching

from . import closures as _closures
from .jacobians import require_task
from .task import Task

if TYPE_CHECKING:
    from ..mechanism import Mechanism

PATTERN_RTOL = 1e-9
"""Entries below ``PATTERN_RTOL`` times the largest entry of their row count as structural zeros."""

MODE_RTOL = 1e-9
"""A leg block is singular when its determinant is at most ``MODE_RTOL`` times Hadamard's bound."""


@dataclass(frozen=True)
class Leg:
    """One diagonal block of the inverse-kinematics Jacobian.

    Attributes:
        rows: rows of the stacked ``[closure; task]`` residual in this block.
        columns: velocity indices (tree joints) in this block.
        joints: names of the joints owning ``columns``.
        actuators: actuated joints in the block.
    """

    rows: tuple[int, ...]
    columns: tuple[int, ...]
    joints: tuple[str, ...]
    actuators: tuple[str, ...]

    @property
    def square(self) -> bool:
        """Whether the block determines its joints (as many rows as columns)."""
        return len(self.rows) == len(self.columns)

    @property
    def label(self) -> str:
        """A readable name: its actuators, or its joints when it has none."""
        return "+".join(self.actuators or self.joints)

    @functools.cached_property
    def block(self) -> tuple[np.ndarray, ...]:
        """Index of the block in the stacked Jacobian: ``A[leg.block]`` has shape (rows, columns)."""
        return np.ix_(self.rows, self.columns)


def ik_jacobian(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """Stacked Jacobian ``[J_phi; J_x]`` of the inverse-kinematics equations, shape (m + n_task, nv)."""
    task = require_task(mech)
    pin.computeJointJacobians(mech.model, mech.data, q)
    pin.updateFramePlacements(mech.model, mech.data)
    return ik_jacobian_from_data(mech.model, mech.data, mech.closures, task)


def ik_jacobian_from_data(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[_closures.Closure],
    task: Task,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """:func:`ik_jacobian` from joint Jacobians and placements already in ``data`` (into ``out`` if given)."""
    m = _closures.closure_rows(closures)
    A = np.empty((m + task.size, model.nv)) if out is None else out
    _closures.jacobian_from_data(model, data, closures, A[:m])
    task.jacobian_from_data(model, data, A[m:])
    return A


def find_legs(mech: Mechanism, q_generic: np.ndarray) -> tuple[Leg, ...]:
    """Split the inverse-kinematics Jacobian at ``q_generic`` into its diagonal blocks."""
    A = ik_jacobian(mech, q_generic)
    scale = np.max(np.abs(A), axis=1, keepdims=True)
    rows_kept = np.flatnonzero(scale[:, 0] > 0.0)
    pattern = np.abs(A[rows_kept]) > PATTERN_RTOL * scale[rows_kept]
    pattern &= np.abs(A[rows_kept]) > 1e-12
    rows_kept = rows_kept[pattern.any(axis=1)]
    pattern = pattern[pattern.any(axis=1)]
    nc = pattern.shape[1]
    match = maximum_bipartite_matching(csr_matrix(pattern.astype(np.int8)), perm_type="column")
    # match[r] = column matched to row r (or -1)
    col_of_row = {r: int(c) for r, c in enumerate(match) if c >= 0}
    row_of_col = {c: r for r, c in col_of_row.items()}
    # directed graph on columns: c -> c' when the row matched to c also depends on c'
    src, dst = [], []
    for c, r in row_of_col.items():
        for c2 in np.flatnonzero(pattern[r]):
            src.append(c)
            dst.append(int(c2))
    graph = csr_matrix((np.ones(len(src)), (src, dst)), shape=(nc, nc))
    _, component = connected_components(graph, directed=True, connection="strong")
    # blocks that hold task rows form the end-effector chain: merge them into one leg
    n_closure = mech.n_closure_rows
    task_columns = {c for c, r in row_of_col.items() if rows_kept[r] >= n_closure}
    task_components = {component[c] for c in task_columns}
    leg_of_column = np.where(np.isin(component, list(task_components)), -1, component)
    # the other blocks group into legs by weak connectivity among themselves
    others = [c for c in range(nc) if leg_of_column[c] != -1]
    keep = [
        (a, b) for a, b in zip(src, dst, strict=True) if leg_of_column[a] != -1 and leg_of_column[b] != -1
    ]
    undirected = csr_matrix(
        (np.ones(len(keep)), ([a for a, _ in keep], [b for _, b in keep])), shape=(nc, nc)
    )
    _, weak = connected_components(undirected, directed=False)
    for c in others:
        leg_of_column[c] = weak[c]
    joint_of_v = _joint_names_by_velocity(mech)
    actuated = {a.idx_v: a.joint for a in mech.actuators}
    legs = []
    for group in np.unique(leg_of_column):
        cols = tuple(int(c) for c in np.flatnonzero(leg_of_column == group))
        rows = tuple(sorted(int(rows_kept[row_of_col[c]]) for c in cols if c in row_of_col))
        joints = tuple(dict.fromkeys(joint_of_v[c] for c in cols))
        legs.append(Leg(rows, cols, joints, tuple(actuated[c] for c in cols if c in actuated)))
    return tuple(sorted(legs, key=lambda leg: leg.columns[0]))


def _joint_names_by_velocity(mech: Mechanism) -> list[str]:
    names = [""] * mech.nv
    for jid in range(1, mech.model.njoints):
        j = mech.model.joints[jid]
        for k in range(j.idx_v, j.idx_v + j.nv):
            names[k] = mech.model.names[jid]
    return names


def working_mode(mech: Mechanism, q: Any, rtol: float = MODE_RTOL) -> tuple[int, ...]:
    """Sign (+1, -1, or 0 when singular) of each square leg block's determinant at ``q``.

    See :func:`working_mode_from_jacobian`.
    """
    return working_mode_from_jacobian(ik_jacobian(mech, mech.check_q(q)), mech.legs, rtol)


def working_mode_from_jacobian(
    A: np.ndarray, legs: Sequence[Leg], rtol: float = MODE_RTOL
) -> tuple[int, ...]:
    """Working mode from the stacked Jacobian ``A`` of :func:`ik_jacobian`: one sign per square leg.

    The sign of each square leg block's determinant, 0 when it is at most ``rtol`` times the
    product of the block's column norms (Hadamard's bound), so the test is scale-free.
    """
    return tuple(_determinant_sign(A[leg.block], rtol) for leg in legs if leg.square)


def _determinant_sign(M: np.ndarray, rtol: float) -> int:
    """Sign of ``det(M)`` for a square ``M``: +1, -1, or 0 at or below ``rtol`` times Hadamard's bound.

    Blocks up to 3 x 3 (every leg of the presets but the 6-DOF end-effector chains) are
    expanded in Python floats, cheaper than LAPACK at this size.
    """
    n = M.shape[0]
    if n == 1:
        det = float(M[0, 0])
        bound = abs(det)
    elif n == 2:
        (a, b), (c, d) = M.tolist()
        det = a * d - b * c
        bound = math.sqrt((a * a + c * c) * (b * b + d * d))
    elif n == 3:
        (a, b, c), (d, e, f), (g, h, i) = M.tolist()
        det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
        bound = math.sqrt((a * a + d * d + g * g) * (b * b + e * e + h * h) * (c * c + f * f + i * i))
    else:
        det = float(np.linalg.det(M))
        bound = float(np.prod(np.linalg.norm(M, axis=0)))
    if abs(det) <= rtol * bound:
        return 0
    return 1 if det > 0 else -1
