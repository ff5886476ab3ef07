r"""Legs as diagonal blocks of the inverse-kinematics Jacobian, and working-mode signatures.

With the platform (the body of the task frame) pinned, the equations
:math:`[\phi(q); x(q) - x^*; \text{the platform's other coordinates}] = 0` split into
independent sub-problems: the chain that carries the platform, then one per leg that closes
on it. Pinning the whole platform, not only the task coordinates, is what separates the
legs of a Delta whose floating platform the task places by its position alone. Their
Jacobian is block-triangular after permutation (Dulmage-Mendelsohn / block-triangular form
of its sparsity pattern), so its determinant is the product of the diagonal blocks'
determinants. The blocks that hold platform rows form the end-effector chain; the others,
grouped by connectivity, are the *legs*.

The sign of the determinant of an actuated block is its leg's *working mode* (branch), and
a zero is an actuator (type-1) singularity of that leg; blocks without an actuator (a
floating platform's, the idle gauges') carry no mode, so a platform floating or hanging on
a leg gives the same modes. A block with more rows than columns (a parallelogram: two
rods, one elbow) takes the independent rows found at the generic configuration. Passive
revolute columns are oriented by their generic axis, seen from the body the leg's passive
chain hangs from, so the two
joint-angle sets of a universal joint that point a rod the same way give the same sign.
For a PRRRP leg of Harada 2011 the block determinant is :math:`l_i z_i^T a`, so the sign is
that of :math:`z_i^T a` (the paper's square-root sign in eq. (2) is its opposite).

The pattern is read numerically at a generic assembled configuration; rows that vanish
there (the out-of-plane rows of planar closures) are dropped.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .._lazy import lazy_module
from ..tolerances import CLOSURE_TOL, LEG_SINGULAR_RTOL, PATTERN_ATOL, PATTERN_RTOL
from . import closures as _closures
from .rank import rank_of_singular_values
from .scratch import placement_views
from .task import FrameTask, Task

scipy_linalg = lazy_module("scipy.linalg")
sparse = lazy_module("scipy.sparse")
csgraph = lazy_module("scipy.sparse.csgraph")

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class Leg:
    """One diagonal block of the inverse-kinematics Jacobian.

    Attributes:
        rows: rows of the stacked ``[closure; task]`` residual in this block.
        columns: velocity indices (tree joints) in this block.
        joints: names of the joints owning ``columns``.
        actuators: actuated joints in the block.
        mode_rows: independent rows whose determinant signs the working mode (None: ``rows``).
        axes: passive revolutes' generic axes, to orient their columns (see
            :func:`working_mode_from_data`).
        followers: columns of actuator-less blocks hanging on this leg (a second rod's
            universal joint), re-solved with it when its branch changes.
    """

    rows: tuple[int, ...]
    columns: tuple[int, ...]
    joints: tuple[str, ...]
    actuators: tuple[str, ...]
    mode_rows: tuple[int, ...] | None = None
    axes: tuple[tuple[int, int, int, tuple[float, float, float]], ...] = ()
    followers: tuple[int, ...] = ()

    @property
    def square(self) -> bool:
        """Whether the block determines its joints and carries a working-mode sign.

        An actuated block with as many independent rows as columns (:attr:`mode_rows`);
        without ``mode_rows`` given, one with as many rows as columns.
        """
        if self.mode_rows is None:
            return len(self.rows) == len(self.columns)
        return bool(self.mode_rows)

    @property
    def sign_rows(self) -> tuple[int, ...]:
        """The rows whose determinant gives the sign."""
        return self.rows if self.mode_rows is None else self.mode_rows

    @property
    def label(self) -> str:
        """A readable name: its actuators, or its joints when it has none."""
        return "+".join(self.actuators or self.joints)

    @functools.cached_property
    def block(self) -> tuple[np.ndarray, ...]:
        """Index of the sign block in the stacked Jacobian: ``A[leg.block]`` is square, (columns, columns)."""
        return np.ix_(self.sign_rows, self.columns)


def ik_jacobian_from_data(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[_closures.Closure],
    task: Task,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """The stacked inverse-kinematics Jacobian ``[J_phi; J_x]``, shape (m + n_task, nv).

    From the joint Jacobians and placements already in ``data``; into ``out`` if given.
    """
    m = _closures.closure_rows(closures)
    A = np.empty((m + task.size, model.nv)) if out is None else out
    _closures.jacobian_from_data(model, data, closures, A[:m])
    task.jacobian_from_data(model, data, A[m:])
    return A


def platform_rows(task: Task) -> list[int]:
    """The task frame's twist rows (0..5 of ``v, omega``) the task leaves out (none for a joint task)."""
    if not isinstance(task, FrameTask):
        return []
    return [r for r in range(6) if r not in task.rows]


def structure_jacobian_from_data(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[_closures.Closure],
    task: Task,
    ik_rows: np.ndarray | None = None,
) -> np.ndarray:
    """``[J_phi; J_x; J_rest]``: :func:`ik_jacobian_from_data` and the platform's other twist rows.

    Shape (m + 6, nv); ``J_rest`` holds the task frame's twist rows the task leaves out, so
    that the whole platform is pinned. A joint task has no platform: shape (m + n_task, nv).
    ``ik_rows``: ``[J_phi; J_x]`` already computed from this ``data``, copied instead of recomputed.
    """
    m = _closures.closure_rows(closures)
    rest = platform_rows(task)
    A = np.empty((m + task.size + len(rest), model.nv))
    if ik_rows is None:
        ik_jacobian_from_data(model, data, closures, task, A[: m + task.size])
    else:
        A[: m + task.size] = ik_rows
    if isinstance(task, FrameTask):
        A[m + task.size :] = pin.getFrameJacobian(model, data, task.frame_id, _LWA)[rest]
    return A


def find_legs(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[_closures.Closure],
    task: Task,
    actuated: Mapping[int, str],
    q_generic: np.ndarray,
    tol: float = CLOSURE_TOL,
) -> tuple[Leg, ...]:
    """Split the structure Jacobian at ``q_generic`` into its diagonal blocks (the legs).

    Args:
        model: the spanning tree.
        data: its scratch data (overwritten).
        closures: the compiled closures.
        task: the compiled end-effector task.
        actuated: joint name of each actuated velocity index.
        q_generic: an assembled configuration away from singularities.
        tol: the closure tolerance [m, rad], floor of the closure rank.
    """
    pin.computeJointJacobians(model, data, q_generic)
    pin.updateFramePlacements(model, data)
    A = structure_jacobian_from_data(model, data, closures, task)
    n_closure = _closures.closure_rows(closures)
    _drop_moving_platform_rows(A, n_closure, task.size, tol)
    scale = np.max(np.abs(A), axis=1, keepdims=True)
    rows_kept = np.flatnonzero(scale[:, 0] > 0.0)
    pattern = np.abs(A[rows_kept]) > PATTERN_RTOL * scale[rows_kept]
    pattern &= np.abs(A[rows_kept]) > PATTERN_ATOL
    rows_kept = rows_kept[pattern.any(axis=1)]
    pattern = pattern[pattern.any(axis=1)]
    nc = pattern.shape[1]
    col_of_row = _platform_first_matching(pattern, rows_kept >= n_closure)
    row_of_col = {c: r for r, c in col_of_row.items()}
    # directed graph on columns: c -> c' when the row matched to c also depends on c'
    src, dst = [], []
    for c, r in row_of_col.items():
        for c2 in np.flatnonzero(pattern[r]):
            src.append(c)
            dst.append(int(c2))
    graph = sparse.csr_matrix((np.ones(len(src)), (src, dst)), shape=(nc, nc))
    _, component = csgraph.connected_components(graph, directed=True, connection="strong")
    # blocks that hold task rows form the end-effector chain: merge them into one leg
    task_columns = {c for c, r in row_of_col.items() if rows_kept[r] >= n_closure}
    task_components = {component[c] for c in task_columns}
    leg_of_column = np.where(np.isin(component, list(task_components)), -1, component)
    # the other blocks group into legs by weak connectivity among themselves
    others = [c for c in range(nc) if leg_of_column[c] != -1]
    keep = [
        (a, b) for a, b in zip(src, dst, strict=True) if leg_of_column[a] != -1 and leg_of_column[b] != -1
    ]
    undirected = sparse.csr_matrix(
        (np.ones(len(keep)), ([a for a, _ in keep], [b for _, b in keep])), shape=(nc, nc)
    )
    _, weak = csgraph.connected_components(undirected, directed=False)
    for c in others:
        leg_of_column[c] = weak[c]
    joint_of_v = _joint_names_by_velocity(model)
    row_group = {int(rows_kept[r]): leg_of_column[c] for c, r in row_of_col.items()}
    for r, row in enumerate(pattern):  # unmatched rows (redundant ones) join the block they touch
        groups = {leg_of_column[c] for c in np.flatnonzero(row)}
        if int(rows_kept[r]) not in row_group and len(groups) == 1:
            row_group[int(rows_kept[r])] = groups.pop()
    legs = []
    for group in np.unique(leg_of_column):
        cols = tuple(int(c) for c in np.flatnonzero(leg_of_column == group))
        rows = tuple(sorted(int(rows_kept[row_of_col[c]]) for c in cols if c in row_of_col))
        joints = tuple(dict.fromkeys(joint_of_v[c] for c in cols))
        acts = tuple(actuated[c] for c in cols if c in actuated)
        all_rows = tuple(sorted(r for r, g in row_group.items() if g == group))
        mode_rows = _independent_rows(A, all_rows, cols) if acts else ()
        legs.append(Leg(rows, cols, joints, acts, mode_rows, _passive_axes(model, data, cols, set(actuated))))
    return tuple(sorted(_with_followers(legs, A, n_closure), key=lambda leg: leg.columns[0]))


def _with_followers(legs: list[Leg], A: np.ndarray, m: int) -> list[Leg]:
    """Attach each actuator-less block off the platform to the first signed leg its rows touch."""
    out = list(legs)
    for block in legs:
        if block.square or any(r >= m for r in block.rows):
            continue
        touched = {int(c) for r in block.rows for c in np.flatnonzero(A[r])}
        for k, leg in enumerate(out):
            if leg.square and touched & set(leg.columns):
                out[k] = dataclasses.replace(leg, followers=leg.followers + block.columns)
                break
    return out


def _drop_moving_platform_rows(A: np.ndarray, m: int, n_task: int, tol: float) -> None:
    """Zero the platform rows outside the task that some feasible motion moves (in place).

    The platform is pinned along the directions no motion moves (a translational Delta's
    rotations); along the others the task frame's body differs between branches (the rod
    carrying a single-rod Delta's tip), which pinning it would hide.
    """
    J_phi = A[:m]
    if m:
        _, s, Vt = np.linalg.svd(J_phi)
        N = Vt[rank_of_singular_values(s, tol).rank :].T  # (nv, raw mobility)
    else:
        N = np.eye(A.shape[1])
    extra = A[m + n_task :]
    moved = np.abs(extra @ N).max(axis=1, initial=0.0) > PATTERN_RTOL * max(float(np.abs(A).max()), 1.0)
    extra[moved] = 0.0


def _platform_first_matching(pattern: np.ndarray, platform: np.ndarray) -> dict[int, int]:
    """Row -> column matching that pins the platform first: its rows, then the closures' on the rest.

    A maximum matching of the whole pattern may give a platform column to a redundant closure
    row and tie the legs together through it.
    """
    out: dict[int, int] = {}
    taken = np.zeros(pattern.shape[1], dtype=bool)
    for stage in (platform, ~platform):
        rows = np.flatnonzero(stage)
        sub = pattern[rows] & ~taken
        match = csgraph.maximum_bipartite_matching(sparse.csr_matrix(sub.astype(np.int8)), perm_type="column")
        for r, c in zip(rows, match, strict=True):
            if c >= 0:
                out[int(r)] = int(c)
                taken[c] = True
    return out


def _independent_rows(A: np.ndarray, rows: tuple[int, ...], cols: tuple[int, ...]) -> tuple[int, ...]:
    """As many independent rows of ``A[rows, cols]`` as columns (pivoted QR), or () if it lacks rank."""
    if len(rows) < len(cols):
        return ()
    block = A[np.ix_(rows, cols)]
    _, R, piv = scipy_linalg.qr(block.T, pivoting=True)
    scale = max(float(np.abs(R[0, 0])), 1e-300)
    if abs(R[len(cols) - 1, len(cols) - 1]) <= PATTERN_RTOL * scale:
        return ()
    return tuple(sorted(rows[int(k)] for k in piv[: len(cols)]))


def _passive_axes(
    model: pin.Model, data: pin.Data, cols: tuple[int, ...], actuated: set[int]
) -> tuple[tuple[int, int, int, tuple[float, float, float]], ...]:
    """(column in the block, joint id, root joint id, axis in the root's frame) of passive revolutes.

    The root is the nearest ancestor that is not a passive joint of this block (the body the
    passive chain hangs from). Read from the placements and joint Jacobians left in
    ``data`` by :func:`structure_jacobian_from_data`.
    """
    passive = {c for c in cols if c not in actuated}
    out = []
    for k, c in enumerate(cols):
        if c not in passive:
            continue
        jid = _joint_of_column(model, c)
        joint = model.joints[jid]
        if joint.nv == 1 and not joint.shortname().startswith("JointModelP"):
            root = int(model.parents[jid])
            while root > 0 and model.joints[root].idx_v in passive:
                root = int(model.parents[root])
            axis = _axis_in(model, data, jid, root)
            out.append((k, jid, root, (float(axis[0]), float(axis[1]), float(axis[2]))))
    return tuple(out)


def _axis_in(model: pin.Model, data: pin.Data, jid: int, root: int) -> np.ndarray:
    """World axis of revolute ``jid`` expressed in the frame of joint ``root``, shape (3,)."""
    world = pin.getJointJacobian(model, data, jid, _LWA)[3:, model.joints[jid].idx_v]
    return np.asarray(data.oMi[root].rotation.T @ world)


def _joint_of_column(model: pin.Model, c: int) -> int:
    for jid in range(1, model.njoints):
        j = model.joints[jid]
        if j.idx_v <= c < j.idx_v + j.nv:
            return jid
    raise IndexError(c)  # pragma: no cover - every column belongs to a joint


def _joint_names_by_velocity(model: pin.Model) -> list[str]:
    names = [""] * model.nv
    for jid in range(1, model.njoints):
        j = model.joints[jid]
        for k in range(j.idx_v, j.idx_v + j.nv):
            names[k] = model.names[jid]
    return names


def working_mode_from_data(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[_closures.Closure],
    task: Task,
    legs: Sequence[Leg],
    rtol: float = LEG_SINGULAR_RTOL,
    ik_rows: np.ndarray | None = None,
) -> tuple[int, ...]:
    """Working mode from joint Jacobians and placements already in ``data``.

    The structure Jacobian, with each passive revolute column turned to keep its axis on
    the side of its generic axis (seen from the body its chain hangs from), then the signs
    of :func:`working_mode_from_jacobian`. ``ik_rows``: ``[J_phi; J_x]`` already computed
    from this ``data`` (see :func:`structure_jacobian_from_data`); when every sign row is among
    them, the structure Jacobian is not built.
    """
    layout = sign_layout(legs)
    if ik_rows is not None and layout.n_rows <= ik_rows.shape[0]:  # no sign row among the platform's others
        A = ik_rows
    else:
        A = structure_jacobian_from_data(model, data, closures, task, ik_rows)
    signs = _block_signs(A, layout, rtol)
    if layout.roots:
        # negating a column negates the determinant exactly: count the turned columns of each leg
        R = np.array(placement_views(data, layout.roots, joints=True)[1])  # (n_roots, 3, 3)
        world = data.J[3:, layout.axis_columns]  # (3, n_axes): the revolutes' world axes (_axis_in's)
        # (R_root^T world) . generic = world . (R_root generic)
        away = np.einsum("aji,ja,ai->a", R[layout.axis_roots], world, layout.axis_generic) < 0.0
        turned = np.bincount(layout.axis_legs[away], minlength=layout.n_square).tolist()
        signs = [-s if t % 2 else s for s, t in zip(signs, turned, strict=True)]
    return tuple(signs)


def working_mode_from_jacobian(
    A: np.ndarray, legs: Sequence[Leg], rtol: float = LEG_SINGULAR_RTOL
) -> tuple[int, ...]:
    """Working mode from a stacked Jacobian ``A`` (:func:`structure_jacobian_from_data`), one sign per leg.

    The sign of each square leg block's determinant, 0 when it is at most ``rtol`` times the
    product of the block's column norms (Hadamard's bound), so the test is scale-free. The
    passive axes are not turned here (see :func:`working_mode_from_data`).
    """
    return tuple(_block_signs(A, sign_layout(legs), rtol))


@dataclass(frozen=True)
class SignLayout:
    """Where the square legs' sign blocks and passive revolutes sit, to read them in a few array operations.

    Attributes:
        blocks: per block size, the legs' positions among the square legs and their sign
            rows and columns (W, n).
        n_square: number of square legs.
        n_rows: rows of the stacked Jacobian the sign blocks reach (their largest row + 1).
        roots: the distinct root joints of the passive revolutes.
        axis_roots: per passive revolute, the position of its root in ``roots`` (n_axes,).
        axis_columns: its velocity column (n_axes,).
        axis_legs: the position of its leg among the square legs (n_axes,).
        axis_generic: its generic axis in the root's frame (n_axes, 3).
    """

    blocks: tuple[tuple[tuple[int, ...], np.ndarray, np.ndarray], ...]
    n_square: int
    n_rows: int
    roots: tuple[int, ...]
    axis_roots: np.ndarray
    axis_columns: np.ndarray
    axis_legs: np.ndarray
    axis_generic: np.ndarray


_LAYOUTS: dict[int, tuple[tuple[Leg, ...], SignLayout]] = {}


def sign_layout(legs: Sequence[Leg]) -> SignLayout:
    """The layout of ``legs``, built once per tuple object (a mechanism's ``legs``), kept alive with it."""
    hit = _LAYOUTS.get(id(legs))
    if hit is not None and hit[0] is legs:
        return hit[1]
    layout = _build_sign_layout(legs)
    if isinstance(legs, tuple):  # immutable: safe to keep by identity
        if len(_LAYOUTS) >= 256:
            _LAYOUTS.clear()
        _LAYOUTS[id(legs)] = (legs, layout)
    return layout


def _build_sign_layout(legs: Sequence[Leg]) -> SignLayout:
    """The :class:`SignLayout` of ``legs``."""
    square = [leg for leg in legs if leg.square]
    blocks = []
    for n in sorted({len(leg.columns) for leg in square}):  # the blocks of one size in one gather
        which = [i for i, leg in enumerate(square) if len(leg.columns) == n]
        rows = np.array([square[i].sign_rows for i in which], dtype=np.intp).reshape(-1, n)
        cols = np.array([square[i].columns for i in which], dtype=np.intp).reshape(-1, n)
        blocks.append((tuple(which), rows, cols))
    axes = [
        (i, leg.columns[k], root, generic) for i, leg in enumerate(square) for k, _, root, generic in leg.axes
    ]
    roots = tuple(sorted({root for _, _, root, _ in axes}))
    return SignLayout(
        tuple(blocks),
        len(square),
        max((max(leg.sign_rows) + 1 for leg in square), default=0),
        roots,
        np.array([roots.index(root) for _, _, root, _ in axes], dtype=np.intp),
        np.array([c for _, c, _, _ in axes], dtype=np.intp),
        np.array([i for i, _, _, _ in axes], dtype=np.intp),
        np.array([generic for _, _, _, generic in axes], dtype=float).reshape(-1, 3),
    )


def _block_signs(A: np.ndarray, layout: SignLayout, rtol: float) -> list[int]:
    """Determinant signs of the square legs' blocks of ``A``, unturned: one gather per block size."""
    out = [0] * layout.n_square
    for which, rows, cols in layout.blocks:
        for i, M in zip(which, A[rows[:, :, None], cols[:, None, :]], strict=True):
            out[i] = _determinant_sign(M, rtol)
    return out


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
