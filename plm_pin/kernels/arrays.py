"""The constant arrays of a kernel, read once from the Pinocchio model, the closures and the task."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..core.closures import Closure
from ..core.task import FrameTask, JointTask, Task

JOINT_KINDS = {
    "JointModelRX": 1,
    "JointModelRY": 1,
    "JointModelRZ": 1,
    "JointModelRevoluteUnaligned": 1,
    "JointModelPX": 2,
    "JointModelPY": 2,
    "JointModelPZ": 2,
    "JointModelPrismaticUnaligned": 2,
    "JointModelRUBX": 3,
    "JointModelRUBY": 3,
    "JointModelRUBZ": 3,
    "JointModelRevoluteUnboundedUnaligned": 3,
    "JointModelSpherical": 4,
    "JointModelFreeFlyer": 5,
    "JointModelPlanar": 6,
    "JointModelUniversal": 7,
}
"""Pinocchio joint classes the kernels handle, and their kind (the constants of :mod:`.compiled`)."""

_CLOSURE_KINDS = {"point": 0, "revolute": 1, "weld": 2, "twist": 3}


class KernelArrays(NamedTuple):
    """The constant arrays of a kernel, as the compiled functions take them.

    Attributes:
        parents: parent joint of each joint (the universe 0 first), shape (nj,).
        kinds: joint kind (:data:`JOINT_KINDS`, 0 for the universe), shape (nj,).
        place_R: joint placement rotations in the parent joint's frame, shape (nj, 3, 3).
        place_p: joint placement translations, shape (nj, 3).
        axis: axis of each one-axis joint (the first of a universal joint), shape (nj, 3).
        axis2: second axis of a universal joint, shape (nj, 3).
        idx_q: first configuration index of each joint, shape (nj,).
        idx_v: first velocity index of each joint, shape (nj,).
        f_joint: joint carrying each kernel frame (closure frames, then the task frame), shape (nf,).
        f_R: frame placement rotations in that joint's frame, shape (nf, 3, 3).
        f_p: frame placement translations, shape (nf, 3).
        support: whether velocity column c moves frame f, shape (nf, nv).
        c_kind: closure kind (0 point, 1 revolute, 2 weld, 3 twist), shape (nc,).
        c_a: kernel frame A of each closure, shape (nc,).
        c_b: kernel frame B, shape (nc,).
        c_row: first residual row of each closure, shape (nc,).
        c_axis: revolute and twist axis in B's coordinates, shape (nc, 3).
        c_E: its normal basis (e1, e2), shape (nc, 3, 2).
        t_kind: 0 no task, 1 frame task, 2 joint task.
        t_frame: kernel frame of a frame task.
        t_rows: a frame task's rows among ``x y z rx ry rz``, shape (n_task,).
        t_jq: a joint task's configuration indices, shape (n_task,).
        t_jkind: their joint kinds, shape (n_task,).
        t_jv: their velocity indices, shape (n_task,).
        m: closure rows.
        nv: velocity size.
        lower: lower position limits of the model, shape (nq,).
        upper: upper position limits, shape (nq,).
        lu_order, lu_row_ptr, lu_rows, lu_col_ptr, lu_cols: the :class:`Elimination`
            of the closure and task rows' structural pattern (which columns move their frames),
            for the square solves.
        mass: mass of the body on each joint [kg] (0 for the universe), shape (nj,).
        lever: its centre of mass in the joint frame [m], shape (nj, 3).
        rot_inertia: its rotational inertia about the centre of mass in the joint frame [kg m^2],
            shape (nj, 3, 3).
        armature: the model's armature (reflected rotor inertia) of each velocity column, shape (nv,).
        gravity: the model's gravity as a spatial motion (linear [m/s^2], then angular), shape (6,).
    """

    parents: np.ndarray
    kinds: np.ndarray
    place_R: np.ndarray
    place_p: np.ndarray
    axis: np.ndarray
    axis2: np.ndarray
    idx_q: np.ndarray
    idx_v: np.ndarray
    f_joint: np.ndarray
    f_R: np.ndarray
    f_p: np.ndarray
    support: np.ndarray
    c_kind: np.ndarray
    c_a: np.ndarray
    c_b: np.ndarray
    c_row: np.ndarray
    c_axis: np.ndarray
    c_E: np.ndarray
    t_kind: int
    t_frame: int
    t_rows: np.ndarray
    t_jq: np.ndarray
    t_jkind: np.ndarray
    t_jv: np.ndarray
    m: int
    nv: int
    lower: np.ndarray
    upper: np.ndarray
    lu_order: np.ndarray
    lu_row_ptr: np.ndarray
    lu_rows: np.ndarray
    lu_col_ptr: np.ndarray
    lu_cols: np.ndarray
    mass: np.ndarray
    lever: np.ndarray
    rot_inertia: np.ndarray
    armature: np.ndarray
    gravity: np.ndarray


class Elimination(NamedTuple):
    """The symbolic LU of a pattern (rows, n): the column order, each step's candidate rows and later columns.

    Attributes:
        order: the columns in elimination order, shape (n,).
        row_ptr: step ``j``'s candidate rows are ``rows[row_ptr[j]:row_ptr[j + 1]]``, shape (n + 1,).
        rows: the candidate rows of every step, one after the other.
        col_ptr: step ``j``'s later columns are ``cols[col_ptr[j]:col_ptr[j + 1]]``, shape (n + 1,).
        cols: the later columns the candidates may touch, of every step.
    """

    order: np.ndarray
    row_ptr: np.ndarray
    rows: np.ndarray
    col_ptr: np.ndarray
    cols: np.ndarray


def elimination(pattern: np.ndarray) -> Elimination:
    """The :class:`Elimination` of a structural pattern (rows, n) of booleans: where an entry may be nonzero.

    Columns are eliminated fewest nonzero rows first (stable: ties keep their order).
    """
    pattern = np.asarray(pattern, dtype=bool)
    n = pattern.shape[1]
    order = np.argsort(np.count_nonzero(pattern, axis=0), kind="stable")
    # each row's pattern as a bit set over the elimination steps (bit t: column order[t])
    masks = [sum(1 << t for t in np.flatnonzero(row).tolist()) for row in pattern[:, order]]
    row_ptr, rows, col_ptr, cols = [0], [], [0], []
    for j in range(n):
        candidates = [i for i, mask in enumerate(masks) if mask >> j & 1]
        later = 0
        for i in candidates:
            later |= masks[i]
        later = later >> (j + 1) << (j + 1)
        for i in candidates:  # each candidate may take the pivot row's pattern
            masks[i] |= later
        rows += candidates
        while later:
            t = (later & -later).bit_length() - 1
            cols.append(int(order[t]))
            later &= later - 1
        row_ptr.append(len(rows))
        col_ptr.append(len(cols))
    return Elimination(*(np.array(a, dtype=np.int64) for a in (order, row_ptr, rows, col_ptr, cols)))


_NO_ELIMINATION = Elimination(*[np.zeros(0, dtype=np.int64)] * len(Elimination._fields))
"""The placeholder of a kernel's elimination until its pattern is read (:func:`build_arrays`)."""


def jacobian_pattern(arrays: KernelArrays) -> np.ndarray:
    """Where the Jacobian of the closure and task rows may be nonzero, shape (m + n_task, nv).

    A closure row depends on the columns supporting either of its frames, a frame task's on
    those supporting the task frame, a joint task's on its joint's column: a structural
    pattern, true at every configuration.
    """
    m, nv = arrays.m, arrays.nv
    stops = [*arrays.c_row[1:].tolist(), m][: arrays.c_row.size]  # the closures' rows follow one another
    rows = [
        arrays.support[a] | arrays.support[b]
        for a, b, start, stop in zip(arrays.c_a, arrays.c_b, arrays.c_row, stops, strict=True)
        for _ in range(start, stop)
    ]
    if arrays.t_kind == 1:
        rows += [arrays.support[arrays.t_frame]] * arrays.t_rows.size
    rows += [np.arange(nv) == v for v in arrays.t_jv.tolist()]
    return np.array(rows, dtype=bool).reshape(-1, nv)


HEADER = 8
"""Leading entries of the packed integers: nj, nf, nc, nv, m, t_kind, t_frame, n_task."""

INT_FIELDS = (
    "parents", "kinds", "idx_q", "idx_v", "f_joint", "support", "c_kind", "c_a", "c_b", "c_row",
    "t_rows", "t_jq", "t_jkind", "t_jv",
    "lu_order", "lu_row_ptr", "lu_rows", "lu_col_ptr", "lu_cols",
)  # fmt: skip
"""The integer arrays, in their packed order (``support`` as 0 and 1)."""

FLOAT_FIELDS = (
    "place_R", "place_p", "axis", "axis2", "f_R", "f_p", "c_axis", "c_E", "lower", "upper",
    "mass", "lever", "rot_inertia", "armature", "gravity",
)  # fmt: skip
"""The float arrays, in their packed order."""


def pack(arrays: KernelArrays) -> tuple[np.ndarray, np.ndarray]:
    """``arrays`` as one integer and one float array (what :func:`.compiled.unpack` reads back as views).

    The integers start with :data:`HEADER` sizes, then the start offsets of the
    :data:`INT_FIELDS` in the integers and of the :data:`FLOAT_FIELDS` in the floats (each
    list closed by its end), then the integer arrays; a compiled call then unboxes two arrays.
    """
    ints = [np.asarray(getattr(arrays, f), dtype=np.int64).reshape(-1) for f in INT_FIELDS]
    floats = [np.asarray(getattr(arrays, f), dtype=float).reshape(-1) for f in FLOAT_FIELDS]
    start = HEADER + len(INT_FIELDS) + len(FLOAT_FIELDS) + 2
    int_ends = start + np.cumsum([0] + [a.size for a in ints])
    float_ends = np.cumsum([0] + [a.size for a in floats])
    header = [
        arrays.parents.size,
        arrays.f_joint.size,
        arrays.c_kind.size,
        arrays.nv,
        arrays.m,
        arrays.t_kind,
        arrays.t_frame,
        arrays.t_rows.size + arrays.t_jq.size,
    ]
    packed = np.concatenate([np.array(header, dtype=np.int64), int_ends, float_ends, *ints]).astype(np.int64)
    return packed, np.concatenate(floats)


def _ints(values: list[int]) -> np.ndarray:
    return np.array(values, dtype=np.int64).reshape(-1)


def unsupported_joints(model: pin.Model) -> list[str]:
    """Names and classes of the joints of ``model`` the kernels do not handle."""
    return [
        f"{model.names[j]} ({model.joints[j].shortname()})"
        for j in range(1, model.njoints)
        if model.joints[j].shortname() not in JOINT_KINDS
    ]


def kernel_frames(closures: tuple[Closure, ...], task: Task | None) -> list[int]:
    """Pinocchio indices of the kernel frames: the closure frames in first-use order, then a frame task's."""
    frame_ids = list(dict.fromkeys([f for c in closures for f in c.frame_ids]))
    if isinstance(task, FrameTask) and task.frame_id not in frame_ids:
        frame_ids.append(task.frame_id)
    return frame_ids


def build_arrays(model: pin.Model, closures: tuple[Closure, ...], task: Task | None) -> KernelArrays:
    """The kernel arrays of ``model`` with ``closures`` and ``task`` (every joint must be supported)."""
    nj, nv = model.njoints, model.nv
    data = model.createData()
    pin.computeJointJacobians(model, data, pin.neutral(model))
    kinds, axis, axis2 = np.zeros(nj, np.int64), np.zeros((nj, 3)), np.zeros((nj, 3))
    place_R, place_p = np.zeros((nj, 3, 3)), np.zeros((nj, 3))
    place_R[0] = np.eye(3)
    for j in range(1, nj):
        joint = model.joints[j]
        kinds[j] = kind = JOINT_KINDS[joint.shortname()]
        place_R[j] = model.jointPlacements[j].rotation
        place_p[j] = model.jointPlacements[j].translation
        S = pin.getJointJacobian(model, data, j, pin.ReferenceFrame.LOCAL)  # the motion subspace at q = 0
        if kind in (1, 3, 7):
            axis[j] = S[3:, joint.idx_v]
        elif kind == 2:
            axis[j] = S[:3, joint.idx_v]
        if kind == 7:
            axis2[j] = S[3:, joint.idx_v + 1]
    frame_ids = kernel_frames(closures, task)
    nf = len(frame_ids)
    f_joint = _ints([model.frames[f].parentJoint for f in frame_ids])
    f_R = np.array([model.frames[f].placement.rotation for f in frame_ids]).reshape(nf, 3, 3)
    f_p = np.array([model.frames[f].placement.translation for f in frame_ids]).reshape(nf, 3)
    support = np.zeros((nf, nv), dtype=np.bool_)
    for i, j in enumerate(f_joint.tolist()):
        while j > 0:
            support[i, model.idx_vs[j] : model.idx_vs[j] + model.nvs[j]] = True
            j = model.parents[j]
    nc = len(closures)
    c_axis, c_E = np.zeros((nc, 3)), np.zeros((nc, 3, 2))
    for i, c in enumerate(closures):
        if c.axis is not None and c.normal_basis is not None:
            c_axis[i], c_E[i] = c.axis, c.normal_basis
    t_rows = t_jq = t_jkind = t_jv = _ints([])
    t_kind = t_frame = 0
    if isinstance(task, FrameTask):
        t_kind, t_frame, t_rows = 1, frame_ids.index(task.frame_id), _ints(list(task.rows))
    elif isinstance(task, JointTask):
        t_kind = 2
        t_jq = _ints([model.idx_qs[j] for j in task.joint_ids])
        t_jkind = _ints([int(kinds[j]) for j in task.joint_ids])
        t_jv = _ints(list(task.v_indices))
    arrays = KernelArrays(
        _ints(list(model.parents)),
        kinds,
        place_R,
        place_p,
        axis,
        axis2,
        _ints(list(model.idx_qs)),
        _ints(list(model.idx_vs)),
        f_joint,
        f_R,
        f_p,
        support,
        _ints([_CLOSURE_KINDS[c.spec.type] for c in closures]),
        _ints([frame_ids.index(c.frame_ids[0]) for c in closures]),
        _ints([frame_ids.index(c.frame_ids[1]) for c in closures]),
        _ints([c.rows.start for c in closures]),
        c_axis,
        c_E,
        t_kind,
        t_frame,
        t_rows,
        t_jq,
        t_jkind,
        t_jv,
        closures[-1].rows.stop if closures else 0,
        nv,
        np.array(model.lowerPositionLimit, dtype=float),
        np.array(model.upperPositionLimit, dtype=float),
        *_NO_ELIMINATION,
        np.array([model.inertias[j].mass for j in range(nj)], dtype=float),
        np.array([model.inertias[j].lever for j in range(nj)], dtype=float).reshape(nj, 3),
        np.array([model.inertias[j].inertia for j in range(nj)], dtype=float).reshape(nj, 3, 3),
        np.array(model.armature, dtype=float).reshape(nv),
        np.array(model.gravity.vector, dtype=float),
    )
    e = elimination(jacobian_pattern(arrays))
    return arrays._replace(
        lu_order=e.order, lu_row_ptr=e.row_ptr, lu_rows=e.rows, lu_col_ptr=e.col_ptr, lu_cols=e.cols
    )
