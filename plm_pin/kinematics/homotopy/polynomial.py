r"""The closure equations of a mechanism as a square polynomial system.

Generated from the description (the Pinocchio tree, its closures, its actuation), for any
mechanism whose loop joints are revolute, prismatic, spherical or free-flyer joints.

Unknowns :math:`x` (one block per passive joint on a loop, in joint order):

- revolute: :math:`(c, s)`, the cosine and sine of the angle, with
  :math:`c^2 + s^2 - 1 = 0` (degree 2);
- prismatic: the displacement :math:`d` (enters linearly);
- spherical: a quaternion :math:`(w, x, y, z)` with :math:`w^2 + x^2 + y^2 + z^2 - 1 = 0`
  (degree 2; the rotation matrix is quadratic in it, and :math:`\pm` the quaternion give
  the same rotation, so every assembly appears twice among the solutions);
- free flyer: a translation (linear) and a quaternion as above.

Parameters :math:`p`: the actuated joint positions (an angle [rad] enters through its
cosine and sine, a displacement [m] linearly).

Joints held by the gauge of an idle mobility (:mod:`plm_pin.core.idle`) are fixed at their
gauge value; joints that carry no closure frame are left out (they do not enter the
closures). Each joint's local transform :math:`X_j` is polynomial in its block (degree 1 in
:math:`(c, s)` or :math:`d`, 2 in a quaternion), and a frame's world placement is the
product :math:`\prod_j M_j X_j` along its path, so its entries have degree at most the sum
of these block degrees along the path (:attr:`PolynomialForm.degrees`).

Closure entries (the residuals of :mod:`plm_pin.core.closures` written polynomially):

- point: :math:`p_B - p_A` (3 entries);
- weld: the point entries and the 9 entries of :math:`R_A^T R_B - I`;
- revolute: the point entries and :math:`R_A^T R_B u - u` (3 entries);
- distance (a leg that ends in revolutes meeting at one point O, then a rigid strut to the
  closure point B at distance L from O: a universal or spherical joint then a strut, as in
  Stewart-Gough legs): :math:`|p_B - O|^2 - L^2` (1 entry, twice the degree of B's path);
  the leg's revolutes leave the system, which removes the two mirror angle sets of each
  universal joint from the count. With an actuated prismatic strut (U-P-S, S-P-S legs),
  :math:`L^2 = |c + q e|^2` is given by the actuator :math:`q` (:func:`_distance_legs`).

Entries that vanish identically (the out-of-plane rows of a planar chain) are dropped.
When as many remain as unknowns after the unit equations, they are the equations
(:math:`C` selects them); otherwise a fixed random matrix :math:`C` (seeded) combines them
into that many, so the system is square. A solution of the
square system is kept only when the full set of entries vanishes too (redundant actuation,
and the random combination, add spurious solutions that this filter removes).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...core.idle import GAUGE_PREFIX
from ...core.mechanism import Mechanism
from ...tolerances import CONCURRENT_AXES_TOL, HOMOTOPY_ZERO_ENTRY_RTOL
from .form import (
    FIXED,
    FREE_FLYER,
    PRISMATIC,
    PRISMATIC_PARAM,
    REVOLUTE,
    REVOLUTE_PARAM,
    SPHERICAL,
    LegAim,
    PolynomialForm,
)

_SIZES = {FIXED: 0, REVOLUTE: 2, PRISMATIC: 1, SPHERICAL: 4, FREE_FLYER: 7}  # unknowns per joint
_ENTRIES = {0: 3, 1: 12, 2: 6, 3: 1}  # point, weld, revolute, distance
SEED = 20261204
"""Seed of the random combination and of the generic parameters (fixed: results are reproducible)."""


class NotPolynomial(Exception):
    """The mechanism has no polynomial form here (a joint kind or a count it does not cover)."""


def _homogeneous(M: pin.SE3) -> np.ndarray:
    return np.asarray(M.homogeneous, dtype=float).copy()


def _joint_kind(jm: pin.JointModel) -> tuple[int, np.ndarray]:
    """Kind and axis of a passive joint; NotPolynomial for kinds without a polynomial form."""
    name = jm.shortname()
    unit = {"X": np.array([1.0, 0, 0]), "Y": np.array([0, 1.0, 0]), "Z": np.array([0, 0, 1.0])}
    if name in ("JointModelRX", "JointModelRY", "JointModelRZ"):
        return REVOLUTE, unit[name[-1]]
    if name in ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ"):
        return REVOLUTE, unit[name[-1]]
    if name in ("JointModelRevoluteUnaligned", "JointModelRevoluteUnboundedUnaligned"):
        return REVOLUTE, np.array(jm.extract().axis, dtype=float)
    if name in ("JointModelPX", "JointModelPY", "JointModelPZ"):
        return PRISMATIC, unit[name[-1]]
    if name == "JointModelPrismaticUnaligned":
        return PRISMATIC, np.array(jm.extract().axis, dtype=float)
    if name == "JointModelSpherical":
        return SPHERICAL, np.zeros(3)
    if name == "JointModelFreeFlyer":
        return FREE_FLYER, np.zeros(3)
    raise NotPolynomial(f"joint kind {name} has no polynomial form")


def polynomial_form(mech: Mechanism, parameters: tuple[int, ...] | None = None) -> PolynomialForm:
    """The polynomial form of ``mech``'s closures with its actuators as parameters.

    Args:
        mech: the mechanism.
        parameters: the actuators (indices) taken as parameters, all by default; the others
            (redundant actuation) stay unknowns of the system (:attr:`PolynomialForm.checked`).

    Raises:
        NotPolynomial: a loop joint of another kind, or fewer independent closure entries
            than unknowns (the actuators do not fix the configuration).
    """
    model = mech.model
    gauges = {g.joint: g.value for g in mech.idle_gauges}
    closures = [c for c in mech.closures if not c.spec.name.startswith(GAUGE_PREFIX)]
    if not closures:
        raise NotPolynomial("no closures")
    chosen = tuple(range(mech.n_actuators)) if parameters is None else tuple(parameters)
    actuated = {mech.actuators[a].joint_id: i for i, a in enumerate(chosen)}
    all_actuated = {a.joint_id: i for i, a in enumerate(mech.actuators)}
    data = model.createData()
    pin.framesForwardKinematics(model, data, mech.q_ref)
    legs = _distance_legs(mech, data, closures, all_actuated, set(actuated), set(gauges))
    anchors: list[tuple[int, pin.SE3]] = []  # (parent joint, placement in it) of each closure point

    def anchor(joint: int, placement: pin.SE3) -> int:
        anchors.append((joint, placement))
        return len(anchors) - 1

    rows = []  # (code, anchor A, anchor B, axis, squared length, length anchor or -1)
    for c in closures:
        fa, fb = (anchor(model.frames[f].parentJoint, model.frames[f].placement) for f in c.frame_ids)
        if c.name in legs:
            leg = legs[c.name]
            fa, fb = anchor(leg.carrier, leg.centre), fb if leg.side == 0 else fa
            fl = -1 if leg.strut is None else anchor(leg.strut, leg.strut_point)
            rows.append((3, fa, fb, np.zeros(3), leg.length2, fl))
        else:
            code = {"point": 0, "weld": 1, "revolute": 2}[c.spec.type]
            rows.append((code, fa, fb, c.axis if c.axis is not None else np.zeros(3), 0.0, -1))
    used = {a for r in rows for a in (r[1], r[2], r[5]) if a >= 0}
    struts = {leg.strut for leg in legs.values() if leg.strut is not None}
    keep: set[int] = set()
    for a in used:
        j = anchors[a][0]
        while j > 0:
            keep.add(j)
            if j in struts:  # an actuated strut hangs from the world in the form (its length alone counts)
                break
            j = model.parents[j]
    joints = np.array(sorted(keep), dtype=int)
    index = {int(j): i for i, j in enumerate(joints)}
    if set(all_actuated) - keep:
        raise NotPolynomial("an actuated joint carries no closure")
    eliminated = sorted({int(j) for leg in legs.values() for j in leg.joints} - keep)
    k = len(joints)
    parent = np.full(k, -1, dtype=np.int64)
    kind = np.zeros(k, dtype=np.int64)
    offset = np.zeros(k, dtype=np.int64)
    axis = np.zeros((k, 3))
    placement = np.zeros((k, 4, 4))
    fixed = np.zeros((k, 4, 4))
    block_degree = np.zeros(k, dtype=np.int64)
    n = 0
    unit_offsets, unit_sizes = [], []
    checked: list[tuple[int, int, int]] = []  # redundant actuators left unknowns
    for i, j in enumerate(joints.tolist()):
        jm, name = model.joints[j], model.names[j]
        parent[i] = -1 if j in struts else index.get(int(model.parents[j]), -1)
        placement[i] = _homogeneous(model.jointPlacements[j])
        fixed[i] = _homogeneous(model.jointPlacements[j].inverse() * data.liMi[j])
        if j in actuated:
            jk, ax = _joint_kind(jm)
            if jk not in (REVOLUTE, PRISMATIC):
                raise NotPolynomial(f"actuated joint {name} is neither revolute nor prismatic")
            kind[i] = REVOLUTE_PARAM if jk == REVOLUTE else PRISMATIC_PARAM
            offset[i], axis[i] = actuated[j], ax
            continue
        if name in gauges:
            kind[i] = FIXED
            continue
        kind[i], axis[i] = _joint_kind(jm)
        offset[i] = n
        if kind[i] == REVOLUTE:
            unit_offsets.append(n)
            unit_sizes.append(2)
            block_degree[i] = 1
        elif kind[i] == PRISMATIC:
            block_degree[i] = 1
        else:
            quat = n + (3 if kind[i] == FREE_FLYER else 0)
            unit_offsets.append(quat)
            unit_sizes.append(4)
            block_degree[i] = 2
        if j in all_actuated:
            if kind[i] not in (REVOLUTE, PRISMATIC):
                raise NotPolynomial(f"actuated joint {name} is neither revolute nor prismatic")
            checked.append((all_actuated[j], n, int(kind[i] == REVOLUTE)))
        n += _SIZES[int(kind[i])]
    order = sorted(used)
    frame_joint = np.array([index.get(anchors[a][0], -1) for a in order], dtype=np.int64)
    frame_placement = np.array([_homogeneous(anchors[a][1]) for a in order])
    closure_kind = np.array([r[0] for r in rows], dtype=np.int64)
    closure_frames = np.array(
        [[order.index(r[1]), order.index(r[2]), order.index(r[5]) if r[5] >= 0 else -1] for r in rows],
        dtype=np.int64,
    )
    closure_axis = np.array([r[3] for r in rows])
    closure_length2 = np.array([r[4] for r in rows])
    sizes = [_ENTRIES[int(r[0])] for r in rows]
    entry_offset = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    n_entries = int(sum(sizes))
    n_unit = len(unit_offsets)
    n_comb = n - n_unit
    if n_comb <= 0:
        raise NotPolynomial("no unknown left to solve for")
    # degree of each entry: the largest path degree of the frames it involves
    path_degree = []
    for fj in frame_joint:
        d, i = 0, int(fj)
        while i >= 0:
            d += int(block_degree[i])
            i = int(parent[i])
        path_degree.append(d)
    entry_degree = np.zeros(n_entries, dtype=np.int64)
    for k in range(len(rows)):
        a, b, _ = closure_frames[k]
        start = entry_offset[k]
        if closure_kind[k] == 3:  # a squared distance (the strut's length is a parameter: degree 0)
            entry_degree[start] = 2 * max(path_degree[a], path_degree[b])
            continue
        entry_degree[start : start + 3] = max(path_degree[a], path_degree[b])
        entry_degree[start + 3 : start + sizes[k]] = path_degree[a] + path_degree[b]
    form = PolynomialForm(
        joints=joints,
        parent=parent,
        kind=kind,
        offset=offset,
        axis=axis,
        placement=placement,
        fixed=fixed,
        frame_joint=frame_joint,
        frame_placement=frame_placement,
        closure_kind=closure_kind,
        closure_frames=closure_frames,
        closure_axis=closure_axis,
        closure_length2=closure_length2,
        entry_offset=entry_offset,
        n_entries=n_entries,
        combination=np.zeros((n_comb, n_entries)),
        n=n,
        n_unit=n_unit,
        unit_offsets=np.array(unit_offsets, dtype=np.int64),
        unit_sizes=np.array(unit_sizes, dtype=np.int64),
        n_params=len(chosen),
        parameters=np.array(chosen, dtype=np.int64),
        checked=np.array(checked, dtype=np.int64).reshape(-1, 3),
        degrees=np.zeros(n, dtype=np.int64),
        eliminated_v=np.array([model.joints[j].idx_v for j in eliminated], dtype=np.int64),
        digest="",
        legs=tuple(
            LegAim(
                frame=int(c.frame_ids[found.side]),
                target=int(c.frame_ids[1 - found.side]),
                carrier=found.carrier,
                centre=_homogeneous(found.centre),
                joints=tuple(int(j) for j in reversed(found.joints)),
                axes=np.array([_joint_kind(model.joints[j])[1] for j in reversed(found.joints)]),
                q_index=tuple(int(model.joints[j].idx_q) for j in reversed(found.joints)),
                nq=tuple(int(model.joints[j].nq) for j in reversed(found.joints)),
            )
            for c in closures
            if (found := legs.get(c.name)) is not None
            and not set(found.joints) & keep
            and [_kind_or_none(model.joints[j]) for j in found.joints] in ([REVOLUTE, REVOLUTE], [SPHERICAL])
        ),
    )
    live = _live_entries(form)
    if live.sum() < n_comb:
        raise NotPolynomial(
            f"{int(live.sum())} independent closure entries for {n_comb} unknowns: the actuators do not fix "
            "the configuration"
        )
    if live.sum() == n_comb:  # square already: the live entries themselves, each of its own degree
        combination = np.eye(n_entries)[live]
        degrees = np.concatenate([np.full(n_unit, 2), entry_degree[live]])
    else:
        combination = np.random.default_rng(SEED).normal(size=(n_comb, n_entries)) * live
        degrees = np.concatenate([np.full(n_unit, 2), np.full(n_comb, int(entry_degree[live].max()))])
    h = hashlib.sha256()
    for arr in (parent, kind, offset, axis, placement, fixed, frame_joint, frame_placement, closure_kind):
        h.update(np.ascontiguousarray(arr).tobytes())
    for arr in (closure_frames, closure_axis, closure_length2, combination):
        h.update(np.ascontiguousarray(arr).tobytes())
    key = str(mech.n_actuators) if parameters is None else str(chosen)  # (all actuators: as before)
    h.update(f"{n} {n_unit} {key} {SEED}".encode())
    object.__setattr__(form, "combination", combination)
    object.__setattr__(form, "degrees", degrees)
    object.__setattr__(form, "digest", h.hexdigest())
    from .straight_line import straight_line

    object.__setattr__(form, "program", straight_line(form))
    return form


@dataclass(frozen=True)
class _Leg:
    """A closure reduced to a distance (see :func:`_distance_legs`)."""

    side: int  # the closure side the leg ends on
    carrier: int  # the joint carrying O
    centre: pin.SE3  # O's placement in it
    length2: float  # L^2 [m^2] of a rigid strut (0 with an actuated one)
    joints: list[int]  # the concurrent joints, eliminated
    strut: int | None  # the actuated prismatic joint between O and the closure point, if any
    strut_point: pin.SE3  # the closure point relative to O along the strut (in the form, from the world)


def _distance_legs(
    mech: Mechanism,
    data: pin.Data,
    closures: list,
    actuated: dict[int, int],
    parameters: set[int],
    gauged: set[str],
) -> dict[str, _Leg]:
    r"""Point closures whose one side ends in joints meeting at one point O, then a strut.

    Such a side (a universal or spherical joint, made of revolutes or a spherical joint, then a
    strut to the closure point) holds its closure point at a distance from O that its angles do
    not change: a constant L for a rigid strut; for a strut through an actuated prismatic joint
    (a parameter, as the U-P-S legs of a Gough-Stewart platform), :math:`|c + q e|` with
    :math:`c` the closure point at :math:`q = 0` relative to O and :math:`e` the slide's
    direction, both fixed in the body above the slide. The closure reduces to
    :math:`|p_B - O|^2 - L^2 = 0` (degree 2 in the other side's unknowns), with
    :math:`L^2 = |c + q e|^2` for the actuated strut (in the form, the slide hangs from the world
    and its closure point is placed at :math:`c`, so that the point's norm is the length). The
    concurrent joints leave the system (their angles are set again in closed form by
    :func:`aim_legs`). O is fixed
    in the body above them.
    """
    model = mech.model
    others: dict[str, set[int]] = {}
    for c in closures:  # joints each closure frame hangs from
        for f in c.frame_ids:
            j, chain = model.frames[f].parentJoint, set()
            while j > 0:
                chain.add(j)
                j = model.parents[j]
            others.setdefault(c.name, set()).update(chain)
    if mech.task_frame_id is not None:
        j, chain = model.frames[mech.task_frame_id].parentJoint, set()
        while j > 0:
            chain.add(j)
            j = model.parents[j]
        others["<task>"] = chain
    out = {}
    for c in closures:
        if c.spec.type != "point":
            continue
        for side in (0, 1):
            f = c.frame_ids[side]
            j, strut = model.frames[f].parentJoint, None
            if j in parameters and _kind_or_none(model.joints[j]) == PRISMATIC:
                strut, j = j, model.parents[j]
            block = []
            while j > 0 and j not in actuated and model.names[j] not in gauged:
                if _kind_or_none(model.joints[j]) not in (REVOLUTE, SPHERICAL):
                    break
                block.append(j)
                j = model.parents[j]
            mine = set(block) | ({strut} if strut is not None else set())
            if not block or any(mine & chain for name, chain in others.items() if name != c.name):
                continue
            lines = []
            for b in block:
                kind, ax = _joint_kind(model.joints[b])
                R = data.oMi[b].rotation
                for u in [ax] if kind == REVOLUTE else list(np.eye(3)):  # a ball: three axes through it
                    lines.append((data.oMi[b].translation, R @ u))
            if len(lines) < 2:  # one revolute: O alone is not fixed (the point circles about the axis)
                continue
            # least-squares meeting point of the axes
            A = sum(np.eye(3) - np.outer(u, u) for _, u in lines)
            rhs = sum((np.eye(3) - np.outer(u, u)) @ p for p, u in lines)
            O = np.linalg.lstsq(A, rhs, rcond=None)[0]
            if (
                max(np.linalg.norm((np.eye(3) - np.outer(u, u)) @ (O - p)) for p, u in lines)
                > CONCURRENT_AXES_TOL
            ):
                continue
            top = block[-1]
            carrier = int(model.parents[top])
            frame_of_top = data.oMi[carrier] * model.jointPlacements[top]
            centre = model.jointPlacements[top] * pin.SE3(np.eye(3), frame_of_top.actInv(O))
            length2, strut_point = float(np.sum((data.oMf[f].translation - O) ** 2)), pin.SE3.Identity()
            if strut is not None:  # |c + q e|^2: the point at q = 0, relative to O, in the slide's parent
                F, M = model.frames[f].placement, model.jointPlacements[strut]
                o = data.oMi[block[0]].actInv(O)
                length2, strut_point = 0.0, pin.SE3(F.rotation, F.translation - M.rotation.T @ o)
            out[c.name] = _Leg(side, carrier, centre, length2, block, strut, strut_point)
            break
    return out


def _kind_or_none(jm: pin.JointModel) -> int | None:
    try:
        return _joint_kind(jm)[0]
    except NotPolynomial:
        return None


def _live_entries(form: PolynomialForm) -> np.ndarray:
    """Mask of the closure entries that do not vanish identically, shape (n_entries,)."""
    from .evaluation import closure_entries

    rng = np.random.default_rng(SEED + 1)
    size = np.zeros(form.n_entries)
    for _ in range(3):
        x = rng.normal(size=form.n) + 1j * rng.normal(size=form.n)
        p = rng.normal(size=form.n_params) + 1j * rng.normal(size=form.n_params)
        e, de = closure_entries(form, x, p)
        size = np.maximum(size, np.abs(e) + np.abs(de).sum(axis=1))
    return size > HOMOTOPY_ZERO_ENTRY_RTOL * max(size.max(), 1.0)


def to_configuration(
    form: PolynomialForm, mech: Mechanism, x: np.ndarray, actuators: np.ndarray
) -> np.ndarray:
    """The tree configuration of each real solution ``x`` with the actuators at ``actuators``.

    ``x`` is one solution, shape (n,), or a stack of them, (N, n); the configurations come in the
    same shape with nq on the last axis. Joints off the loops keep their reference value;
    quaternions and (cos, sin) pairs are normalised.
    """
    model = mech.model
    X = np.real(x)
    rows = X.reshape(-1, form.n)
    q = np.tile(mech.q_ref, (len(rows), 1))
    for i, j in enumerate(form.joints.tolist()):
        jm, kd, o = model.joints[j], int(form.kind[i]), int(form.offset[i])
        iq = jm.idx_q
        if kd in (REVOLUTE, REVOLUTE_PARAM):
            angle = float(actuators[o]) if kd == REVOLUTE_PARAM else np.arctan2(rows[:, o + 1], rows[:, o])
            if jm.nq == 2:
                q[:, iq], q[:, iq + 1] = np.cos(angle), np.sin(angle)
            else:
                q[:, iq] = angle
        elif kd == PRISMATIC:
            q[:, iq] = rows[:, o]
        elif kd == PRISMATIC_PARAM:
            q[:, iq] = actuators[o]
        elif kd in (SPHERICAL, FREE_FLYER):
            t = 3 if kd == FREE_FLYER else 0
            quat = rows[:, o + t : o + t + 4]
            quat = quat / np.linalg.norm(quat, axis=1, keepdims=True)
            if t:
                q[:, iq : iq + 3] = rows[:, o : o + 3]
            q[:, iq + t : iq + t + 3] = quat[:, 1:]  # Pinocchio stores (x, y, z, w)
            q[:, iq + t + 3] = quat[:, 0]
    return q.reshape(*X.shape[:-1], model.nq)


def from_configuration(form: PolynomialForm, mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """The unknowns of a configuration ``q``, shape (n,) (the inverse of :func:`to_configuration`)."""
    model = mech.model
    x = np.zeros(form.n)
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    for i, j in enumerate(form.joints.tolist()):
        kd, o = int(form.kind[i]), int(form.offset[i])
        X = (model.jointPlacements[j].inverse() * data.liMi[j]).homogeneous
        if kd == REVOLUTE:
            R = X[:3, :3]
            a = form.axis[i]
            e = np.linalg.svd(np.eye(3) - np.outer(a, a))[0][:, 0]
            x[o], x[o + 1] = e @ R @ e, np.cross(e, R @ e) @ a
        elif kd == PRISMATIC:
            x[o] = form.axis[i] @ X[:3, 3]
        elif kd in (SPHERICAL, FREE_FLYER):
            t = 3 if kd == FREE_FLYER else 0
            quat = pin.Quaternion(X[:3, :3])
            if t:
                x[o : o + 3] = X[:3, 3]
            x[o + t : o + t + 4] = quat.w, quat.x, quat.y, quat.z
    return x


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross products of two (m, 3) arrays."""
    a0, a1, a2 = a.T
    b0, b1, b2 = b.T
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def _turns(u: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Per row, the turn about unit ``u`` taking ``x``'s part across ``u`` to ``y``'s [rad], shape (m,)."""
    xp = x - _dot(u, x)[:, None] * u
    yp = y - _dot(u, y)[:, None] * u
    return np.arctan2(_dot(u, _cross(xp, yp)), _dot(xp, yp))


def aim_pairs(u1: np.ndarray, u2: np.ndarray, v: np.ndarray, w: np.ndarray) -> np.ndarray:
    r"""Per row, both angle pairs with :math:`R(u_1, \theta_1) R(u_2, \theta_2) v = w`.

    Two rotations about axes through one point (Paden-Kahan subproblem 2): the middle vector
    :math:`c = R(u_2, \theta_2) v = R(u_1, -\theta_1) w` has :math:`u_1 \cdot c = u_1 \cdot w`,
    :math:`u_2 \cdot c = u_2 \cdot v` and :math:`|c| = |v|`, so
    :math:`c = \alpha u_1 + \beta u_2 \pm \gamma\, u_1 \times u_2`: the mirror pair of a universal
    joint (one pair twice where :math:`w` cannot be reached, :math:`\gamma` clipped at 0).

    Args:
        u1: the first (outer) unit axes, shape (m, 3).
        u2: the second unit axes, not parallel to ``u1``, shape (m, 3).
        v: the vector before the turns, shape (m, 3).
        w: the vector after them, shape (m, 3).

    Returns:
        The angles [rad], shape (2, m, 2): solution, row, (theta1, theta2).
    """
    m = len(u1)
    k = _dot(u1, u2)
    den = 1.0 - k * k
    a, b = _dot(u1, w), _dot(u2, v)
    alpha, beta = (a - k * b) / den, (b - k * a) / den
    gamma = np.sqrt(np.maximum(0.0, (_dot(v, v) - alpha * alpha - beta * beta - 2 * alpha * beta * k) / den))
    base = alpha[:, None] * u1 + beta[:, None] * u2
    n = gamma[:, None] * _cross(u1, u2)
    c = np.concatenate([base + n, base - n])  # the middle vector of both solutions
    first = _turns(np.concatenate([u1, u1]), c, np.concatenate([w, w]))
    second = _turns(np.concatenate([u2, u2]), np.concatenate([v, v]), c)
    return np.stack([first, second], axis=1).reshape(2, m, 2)


def aim_legs(
    form: PolynomialForm, mech: Mechanism, qs: np.ndarray, data: pin.Data | None = None
) -> tuple[np.ndarray, bool]:
    r"""Set the joints of the legs reduced to distances from the rest of each configuration, in closed form.

    Each leg's joints (a universal joint: two revolutes about axes through the leg's centre O,
    or one spherical joint) turn its closure point, at its strut length, about O onto the
    direction of the closure's other frame. For a universal joint, of the two angle pairs
    (:func:`aim_pairs`) the one nearest the configuration's values; for a spherical joint, the
    smallest turn from its value. At a root of the polynomial form the leg's point then meets
    the other frame: the closure holds to rounding.

    Args:
        form: the polynomial form.
        mech: its mechanism.
        qs: configurations with every joint but the legs' set (actuators included), shape (r, nq).
        data: Pinocchio data of ``mech.model`` to work in (a new one by default).

    Returns:
        The configurations with the legs aimed, shape (r, nq), and whether every eliminated
        leg was (False: a leg of another shape, or one not aimed; its joints keep their values).
    """
    model = mech.model
    out = np.array(qs, dtype=float, copy=True).reshape(-1, model.nq)
    done = form.eliminated_v.size == sum(len(leg.joints) for leg in form.legs)  # one column per joint
    if not form.legs or not len(out):
        return out, done
    zero = out.copy()
    for leg in form.legs:  # the legs' joints at their neutral value: rotations and axes read at zero
        for iq, nq in zip(leg.q_index, leg.nq, strict=True):
            zero[:, iq : iq + nq] = _NEUTRAL[nq]
    oR, op, at = _placements(mech, zero, {f for leg in form.legs for f in (leg.frame, leg.target)}, data)
    aimed: list[LegAim] = []  # the universal joints' legs, each over every configuration
    u1, u2, v, w, ref = [], [], [], [], []
    for leg in form.legs:
        origin = oR[:, leg.carrier] @ leg.centre[:3, 3] + op[:, leg.carrier]
        vl, wl = at[leg.frame] - origin, at[leg.target] - origin
        if len(leg.joints) == 1:  # a spherical joint: the smallest turn of its current value
            iq = leg.q_index[0]
            for i, Rj in enumerate(oR[:, leg.joints[0]]):
                now = pin.Quaternion(out[i, iq + 3], *out[i, iq : iq + 3]).normalized().toRotationMatrix()
                turn = pin.Quaternion.FromTwoVectors(Rj @ now @ Rj.T @ vl[i], wl[i]).toRotationMatrix()
                quat = pin.Quaternion(Rj.T @ turn @ Rj @ now).normalized()
                out[i, iq : iq + 4] = quat.x, quat.y, quat.z, quat.w
            continue
        aimed.append(leg)
        u1.append(oR[:, leg.joints[0]] @ leg.axes[0])
        u2.append(oR[:, leg.joints[1]] @ leg.axes[1])
        v.append(vl)
        w.append(wl)
        ref.append(
            np.stack([_angles(out, iq, nq) for iq, nq in zip(leg.q_index, leg.nq, strict=True)], axis=1)
        )
    if aimed:
        angles = aim_pairs(*(np.concatenate(a) for a in (u1, u2, v, w)))
        r = np.concatenate(ref)
        angles += 2 * np.pi * np.round((r - angles) / (2 * np.pi))  # each angle nearest its current value
        pick = np.abs(angles - r).sum(axis=2).argmin(axis=0)
        best = angles[pick, np.arange(len(r))].reshape(len(aimed), len(out), 2)
        done = done and bool(np.isfinite(best).all())
        for leg, pairs in zip(aimed, best, strict=True):
            ok = np.isfinite(pairs).all(axis=1)  # the configurations whose leg is aimed
            for iq, nq, angle in zip(leg.q_index, leg.nq, pairs[ok].T, strict=True):
                if nq == 2:
                    out[ok, iq], out[ok, iq + 1] = np.cos(angle), np.sin(angle)
                else:
                    out[ok, iq] = angle
    return out, done


def _placements(
    mech: Mechanism, qs: np.ndarray, frames: set[int], data: pin.Data | None
) -> tuple[np.ndarray, np.ndarray, dict[int, np.ndarray]]:
    """Joint rotations (r, njoints, 3, 3) and origins (r, njoints, 3) at each row of ``qs``; frame origins.

    ``frames`` are Pinocchio frame ids; their origins come as (r, 3) arrays. On the compiled
    kernels when they hold those frames, else by Pinocchio.
    """
    from ...kernels import kernel_of

    kernel = kernel_of(mech)
    if kernel is not None and frames <= set(kernel.frame_ids):
        placed = [kernel.placements(q) for q in qs]
        fp = np.array([p[3] for p in placed])
        at = {f: fp[:, kernel.frame_ids.index(f)] for f in frames}
        return np.array([p[0] for p in placed]), np.array([p[1] for p in placed]), at
    model = mech.model
    data = data if data is not None else model.createData()
    oR, op = np.empty((len(qs), model.njoints, 3, 3)), np.empty((len(qs), model.njoints, 3))
    at = {f: np.empty((len(qs), 3)) for f in frames}
    for i, q in enumerate(qs):
        pin.forwardKinematics(model, data, q)
        for j, M in enumerate(data.oMi):
            oR[i, j], op[i, j] = M.rotation, M.translation
        for f, where in at.items():
            where[i] = pin.updateFramePlacement(model, data, f).translation
    return oR, op, at


_NEUTRAL = {1: np.zeros(1), 2: np.array([1.0, 0.0]), 4: np.array([0.0, 0, 0, 1])}
"""Neutral configuration coordinates of a leg joint, by its nq (revolute, unbounded revolute, spherical)."""


def _angles(qs: np.ndarray, iq: int, nq: int) -> np.ndarray:
    """A revolute joint's angle in each row of ``qs`` [rad] (one coordinate, or (cos, sin) when unbounded)."""
    return np.arctan2(qs[:, iq + 1], qs[:, iq]) if nq == 2 else qs[:, iq]
