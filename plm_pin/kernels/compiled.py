r"""The compiled kernels: tree forward kinematics, closure and task rows, Newton, with numba.

Every function reads the constant arrays of a :class:`~plm_pin.kernels.model.Kernel` (passed
as ``k``) and works in place on caller-owned buffers, so a call allocates nothing
but its small temporaries. The conventions are Pinocchio's:

.. math:: {}^0M_j = {}^0M_{\lambda(j)}\, M_j^{place}\, M_j(q_j), \qquad
          {}^0M_f = {}^0M_{j(f)}\, M_f^{place},

a joint's velocity columns are its motion subspace seen in the world: angular
:math:`\omega = R_j s_\omega`, linear at the world origin :math:`R_j s_v - \omega \times p_j`,
so that the world-aligned (``LOCAL_WORLD_ALIGNED``) Jacobian of a frame at :math:`p_f` has
the columns :math:`(v_o + \omega \times p_f, \omega)` of the joints supporting it. Closure rows
are those of :mod:`plm_pin.core.closures`, task rows those of :class:`plm_pin.core.task.TaskTarget`,
and :func:`newton` is :func:`plm_pin.core.assembly.newton` step for step (Cholesky of the normal
equations, chord steps while the residual falls a hundredfold, one polishing step).

numba compiles these on first use and caches them on disk; numba is imported only here.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .arrays import KernelArrays

# joint kinds (see plm_pin.kernels.model)
REVOLUTE, PRISMATIC, REVOLUTE_UNBOUNDED, SPHERICAL, FREE_FLYER, PLANAR, UNIVERSAL = 1, 2, 3, 4, 5, 6, 7
# closure kinds
POINT, REVOLUTE_CLOSURE, WELD, TWIST = 0, 1, 2, 3
# task kinds
NO_TASK, FRAME_TASK, JOINT_TASK = 0, 1, 2


@njit(cache=True, inline="always")
def _rodrigues(a: np.ndarray, c: float, s: float, out: np.ndarray) -> None:
    """Rotation about the unit axis ``a`` of cosine ``c`` and sine ``s``, into ``out`` (3, 3)."""
    t = 1.0 - c
    x, y, z = a[0], a[1], a[2]
    out[0, 0] = c + t * x * x
    out[0, 1] = t * x * y - s * z
    out[0, 2] = t * x * z + s * y
    out[1, 0] = t * x * y + s * z
    out[1, 1] = c + t * y * y
    out[1, 2] = t * y * z - s * x
    out[2, 0] = t * x * z - s * y
    out[2, 1] = t * y * z + s * x
    out[2, 2] = c + t * z * z


@njit(cache=True, inline="always")
def _quat_matrix(x: float, y: float, z: float, w: float, out: np.ndarray) -> None:
    """Rotation of the unit quaternion ``(x, y, z, w)`` (Pinocchio's order), into ``out`` (3, 3)."""
    tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    out[0, 0] = 1.0 - (tyy + tzz)
    out[0, 1] = txy - twz
    out[0, 2] = txz + twy
    out[1, 0] = txy + twz
    out[1, 1] = 1.0 - (txx + tzz)
    out[1, 2] = tyz - twx
    out[2, 0] = txz - twy
    out[2, 1] = tyz + twx
    out[2, 2] = 1.0 - (txx + tyy)


@njit(cache=True, inline="always")
def _identity(out: np.ndarray) -> None:
    for i in range(3):
        for j in range(3):
            out[i, j] = 1.0 if i == j else 0.0


@njit(cache=True, inline="always")
def _mm3(A: np.ndarray, B: np.ndarray, out: np.ndarray) -> None:
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit(cache=True, inline="always")
def _mv3(A: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
    for i in range(3):
        out[i] = A[i, 0] * v[0] + A[i, 1] * v[1] + A[i, 2] * v[2]


@njit(cache=True, inline="always")
def forward(
    k: KernelArrays,
    q: np.ndarray,
    oR: np.ndarray,
    op: np.ndarray,
    Sw: np.ndarray,
    Sv: np.ndarray,
    columns: bool,
    mats: np.ndarray,
    vecs: np.ndarray,
) -> None:
    """World placements of every joint ``oR`` (nj, 3, 3), ``op`` (nj, 3) and their velocity columns.

    ``Sw`` (nv, 3) and ``Sv`` (nv, 3) receive each column's world angular velocity and the
    linear velocity of the point at the world origin (only with ``columns``). ``mats`` (>= 3, 3, 3)
    and ``vecs`` (>= 14, 3) are scratch.
    """
    parents, kinds, place_R, place_p, axis, axis2, idx_q, idx_v = (
        k.parents,
        k.kinds,
        k.place_R,
        k.place_p,
        k.axis,
        k.axis2,
        k.idx_q,
        k.idx_v,
    )
    _identity(oR[0])
    op[0] = 0.0
    Rj, R2, R1 = mats[0], mats[1], mats[2]
    pj, t = vecs[0], vecs[1]
    sw = vecs[2:8]  # local angular parts of the joint's columns
    sv = vecs[8:14]  # local linear parts
    for j in range(1, parents.shape[0]):
        kind, iq = kinds[j], idx_q[j]
        a = axis[j]
        pj[:] = 0.0
        sw[:] = 0.0
        sv[:] = 0.0
        n = 1
        if kind == REVOLUTE:
            _rodrigues(a, math.cos(q[iq]), math.sin(q[iq]), Rj)
            sw[0] = a
        elif kind == REVOLUTE_UNBOUNDED:
            _rodrigues(a, q[iq], q[iq + 1], Rj)
            sw[0] = a
        elif kind == PRISMATIC:
            _identity(Rj)
            pj[:] = a * q[iq]
            sv[0] = a
        elif kind == SPHERICAL:
            _quat_matrix(q[iq], q[iq + 1], q[iq + 2], q[iq + 3], Rj)
            n = 3
            for i in range(3):
                sw[i, i] = 1.0
        elif kind == FREE_FLYER:
            pj[0], pj[1], pj[2] = q[iq], q[iq + 1], q[iq + 2]
            _quat_matrix(q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6], Rj)
            n = 6
            for i in range(3):
                sv[i, i] = 1.0
                sw[3 + i, i] = 1.0
        elif kind == PLANAR:
            c, s = q[iq + 2], q[iq + 3]
            _identity(Rj)
            Rj[0, 0], Rj[0, 1], Rj[1, 0], Rj[1, 1] = c, -s, s, c
            pj[0], pj[1] = q[iq], q[iq + 1]
            n = 3
            sv[0, 0] = 1.0
            sv[1, 1] = 1.0
            sw[2, 2] = 1.0
        else:  # UNIVERSAL
            b = axis2[j]
            _rodrigues(a, math.cos(q[iq]), math.sin(q[iq]), R1)
            _rodrigues(b, math.cos(q[iq + 1]), math.sin(q[iq + 1]), R2)
            _mm3(R1, R2, Rj)
            n = 2
            for i in range(3):
                sw[0, i] = R2[0, i] * a[0] + R2[1, i] * a[1] + R2[2, i] * a[2]
            sw[1] = b
        par = parents[j]
        _mm3(oR[par], place_R[j], R1)  # parent's world rotation times the placement
        _mv3(oR[par], place_p[j], t)
        t += op[par]
        _mm3(R1, Rj, oR[j])
        _mv3(R1, pj, op[j])
        op[j] += t
        if not columns:
            continue
        R = oR[j]
        p = op[j]
        for c in range(n):
            col = idx_v[j] + c
            _mv3(R, sw[c], t)
            Sw[col] = t
            _mv3(R, sv[c], t)
            w = Sw[col]
            Sv[col, 0] = t[0] - (w[1] * p[2] - w[2] * p[1])
            Sv[col, 1] = t[1] - (w[2] * p[0] - w[0] * p[2])
            Sv[col, 2] = t[2] - (w[0] * p[1] - w[1] * p[0])


@njit(cache=True, inline="always")
def frames(k: KernelArrays, oR: np.ndarray, op: np.ndarray, fR: np.ndarray, fp: np.ndarray) -> None:
    """World placements ``fR`` (nf, 3, 3), ``fp`` (nf, 3) of the kernel's frames from the joints'."""
    f_joint, f_R, f_p = k.f_joint, k.f_R, k.f_p
    for f in range(f_joint.shape[0]):
        j = f_joint[f]
        _mm3(oR[j], f_R[f], fR[f])
        _mv3(oR[j], f_p[f], fp[f])
        fp[f] += op[j]


@njit(cache=True, inline="always")
def frame_jacobian(
    k: KernelArrays, f: int, fp: np.ndarray, Sw: np.ndarray, Sv: np.ndarray, out: np.ndarray
) -> None:
    """World-aligned Jacobian (6, nv) of kernel frame ``f`` (linear rows first), into ``out``."""
    support = k.support
    p = fp[f]
    for c in range(out.shape[1]):
        if support[f, c]:
            w = Sw[c]
            out[0, c] = Sv[c, 0] + w[1] * p[2] - w[2] * p[1]
            out[1, c] = Sv[c, 1] + w[2] * p[0] - w[0] * p[2]
            out[2, c] = Sv[c, 2] + w[0] * p[1] - w[1] * p[0]
            out[3, c], out[4, c], out[5, c] = w[0], w[1], w[2]
        else:
            out[:, c] = 0.0


@njit(cache=True)
def log3(R: np.ndarray, out: np.ndarray) -> float:
    """Pinocchio's ``log3`` of ``R`` into ``out`` (3,); returns the angle [rad]."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr >= 3.0:
        theta = 0.0
    elif tr <= -1.0:
        theta = math.pi
    else:
        theta = math.acos((tr - 1.0) / 2.0)
    if theta >= math.pi - 1e-2:  # near a half turn: from the diagonal (Pinocchio's branch)
        cphi = math.cos(theta - math.pi)
        beta = theta * theta / (1.0 + cphi)
        for i in range(3):
            d = (R[i, i] + cphi) * beta
            out[i] = math.sqrt(d) if d > 0.0 else 0.0
        if not R[2, 1] > R[1, 2]:
            out[0] = -out[0]
        if not R[0, 2] > R[2, 0]:
            out[1] = -out[1]
        if not R[1, 0] > R[0, 1]:
            out[2] = -out[2]
        return theta
    t = 0.5 * (theta / math.sin(theta) if theta > 1e-8 else 1.0)
    out[0] = t * (R[2, 1] - R[1, 2])
    out[1] = t * (R[0, 2] - R[2, 0])
    out[2] = t * (R[1, 0] - R[0, 1])
    return theta


@njit(cache=True)
def jlog3(theta: float, r: np.ndarray, out: np.ndarray) -> None:
    r"""Pinocchio's ``Jlog3`` at ``r`` (angle ``theta``): :math:`\alpha I + [r]_\times / 2 + \beta r r^T`."""
    if theta < 1e-4:  # Taylor series, error below 1e-17
        t2 = theta * theta
        alpha = 1.0 - t2 / 12.0 - t2 * t2 / 720.0
        beta = 1.0 / 12.0 + t2 / 720.0
    else:
        st, ct = math.sin(theta), math.cos(theta)
        st_1mct = st / (1.0 - ct)
        alpha = 0.5 * theta * st_1mct
        beta = 1.0 / (theta * theta) - st_1mct / (2.0 * theta)
    for i in range(3):
        for j in range(3):
            out[i, j] = beta * r[i] * r[j]
        out[i, i] += alpha
    out[0, 1] -= 0.5 * r[2]
    out[0, 2] += 0.5 * r[1]
    out[1, 0] += 0.5 * r[2]
    out[1, 2] -= 0.5 * r[0]
    out[2, 0] -= 0.5 * r[1]
    out[2, 1] += 0.5 * r[0]


@njit(cache=True)
def rpy(R: np.ndarray, out: np.ndarray) -> None:
    """Pinocchio's ``rpy.matrixToRpy`` of ``R`` into ``out`` (3,)."""
    m = math.sqrt(R[2, 1] * R[2, 1] + R[2, 2] * R[2, 2])
    p = math.atan2(-R[2, 0], m)
    if abs(abs(p) - 0.5 * math.pi) < 0.001:
        r = 0.0
        y = math.atan2(-R[0, 1], R[1, 1])
    else:
        y = math.atan2(R[1, 0], R[0, 0])
        r = math.atan2(R[2, 1], R[2, 2])
    out[0], out[1], out[2] = r, p, y


@njit(cache=True, inline="always")
def _wrap(a: float) -> float:
    return math.pi - (math.pi - a) % (2.0 * math.pi)


@njit(cache=True, inline="always")
def closure_rows(
    k: KernelArrays,
    fR: np.ndarray,
    fp: np.ndarray,
    Sw: np.ndarray,
    Sv: np.ndarray,
    r: np.ndarray,
    A: np.ndarray,
    jac: bool,
    mats: np.ndarray,
    vecs: np.ndarray,
    jacs: np.ndarray,
) -> None:
    """Closure residual into ``r`` (m,) and, with ``jac``, its Jacobian into ``A`` (m, nv).

    Scratch: ``mats`` (>= 5, 3, 3), ``vecs`` (>= 18, 3), ``jacs`` (>= 2, 6, nv).
    """
    c_kind, c_a, c_b, c_row, c_axis, c_E = k.c_kind, k.c_a, k.c_b, k.c_row, k.c_axis, k.c_E
    nv = A.shape[1]
    Ja, Jb, M, G = jacs[0], jacs[1], mats[3], mats[4]
    u, v, w, lg = vecs[14], vecs[15], vecs[16], vecs[17]
    for i in range(c_kind.shape[0]):
        kind, fa, fb, s = c_kind[i], c_a[i], c_b[i], c_row[i]
        Ra, Rb = fR[fa], fR[fb]
        E = c_E[i]
        if jac:
            frame_jacobian(k, fa, fp, Sw, Sv, Ja)
            frame_jacobian(k, fb, fp, Sw, Sv, Jb)
        if kind != TWIST:
            for d in range(3):
                r[s + d] = fp[fb, d] - fp[fa, d]
                if jac:
                    for c in range(nv):
                        A[s + d, c] = Jb[d, c] - Ja[d, c]
        if kind == POINT:
            continue
        n_rot = 1
        if kind == WELD:
            n_rot = 3
            for a_ in range(3):
                for b_ in range(3):
                    M[a_, b_] = Ra[0, a_] * Rb[0, b_] + Ra[1, a_] * Rb[1, b_] + Ra[2, a_] * Rb[2, b_]
            theta = log3(M, lg)
            r[s + 3 : s + 6] = lg
            if jac:
                jlog3(theta, lg, M)
                for a_ in range(3):  # G = Jlog3 R_B^T
                    for b_ in range(3):
                        G[a_, b_] = M[a_, 0] * Rb[b_, 0] + M[a_, 1] * Rb[b_, 1] + M[a_, 2] * Rb[b_, 2]
        elif kind == TWIST:
            _mv3(Ra, E[:, 1], u)  # x = R_A e2
            _mv3(Rb, E[:, 0], v)  # y = R_B e1
            r[s] = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
            G[0, 0] = v[1] * u[2] - v[2] * u[1]  # (y x x)^T
            G[0, 1] = v[2] * u[0] - v[0] * u[2]
            G[0, 2] = v[0] * u[1] - v[1] * u[0]
        else:  # revolute: E^T R_A^T R_B u, G = -E^T R_A^T [R_B u]x
            n_rot = 2
            _mv3(Rb, c_axis[i], w)
            for d in range(3):
                v[d] = Ra[0, d] * w[0] + Ra[1, d] * w[1] + Ra[2, d] * w[2]
            for e in range(2):
                r[s + 3 + e] = E[0, e] * v[0] + E[1, e] * v[1] + E[2, e] * v[2]
                _mv3(Ra, E[:, e], u)  # row e of E^T R_A^T, as a vector R_A E e
                # -(R_A E_e)^T [w]x = (w x R_A E_e)^T ... = -(u x w)^T... row: (u x w)^T negated
                G[e, 0] = -(u[1] * w[2] - u[2] * w[1])
                G[e, 1] = -(u[2] * w[0] - u[0] * w[2])
                G[e, 2] = -(u[0] * w[1] - u[1] * w[0])
        if jac:
            first = s if kind == TWIST else s + 3
            for e in range(n_rot):
                for c in range(nv):
                    A[first + e, c] = (
                        G[e, 0] * (Jb[3, c] - Ja[3, c])
                        + G[e, 1] * (Jb[4, c] - Ja[4, c])
                        + G[e, 2] * (Jb[5, c] - Ja[5, c])
                    )


@njit(cache=True, inline="always")
def task_pose(
    k: KernelArrays, q: np.ndarray, fR: np.ndarray, fp: np.ndarray, out: np.ndarray, ang: np.ndarray
) -> None:
    """Task coordinates (:meth:`plm_pin.core.task.Task.pose_from_data`) into ``out`` (n_task,).

    ``ang`` (3,) is scratch.
    """
    t_kind, t_frame, t_rows, t_jq, t_jkind = k.t_kind, k.t_frame, k.t_rows, k.t_jq, k.t_jkind
    if t_kind == FRAME_TASK:
        rpy(fR[t_frame], ang)
        for i in range(t_rows.shape[0]):
            row = t_rows[i]
            out[i] = fp[t_frame, row] if row < 3 else ang[row - 3]
    elif t_kind == JOINT_TASK:
        for i in range(t_jq.shape[0]):
            iq = t_jq[i]
            if t_jkind[i] == REVOLUTE:
                out[i] = _wrap(q[iq])
            elif t_jkind[i] == REVOLUTE_UNBOUNDED:
                out[i] = math.atan2(q[iq + 1], q[iq])
            else:
                out[i] = q[iq]


@njit(cache=True, inline="always")
def task_rows(
    k: KernelArrays,
    q: np.ndarray,
    fR: np.ndarray,
    fp: np.ndarray,
    Sw: np.ndarray,
    Sv: np.ndarray,
    x: np.ndarray,
    R_star: np.ndarray,
    r: np.ndarray,
    A: np.ndarray,
    jac: bool,
    mats: np.ndarray,
    vecs: np.ndarray,
    jacs: np.ndarray,
) -> None:
    """Task target rows (:class:`plm_pin.core.task.TaskTarget`) into ``r`` (n_task,), Jacobian into ``A``.

    Scratch: ``mats`` (>= 8, 3, 3), ``vecs`` (>= 20, 3), ``jacs`` (>= 3, 6, nv).
    """
    t_kind, t_frame, t_rows, t_jv = k.t_kind, k.t_frame, k.t_rows, k.t_jv
    n = r.shape[0]
    if t_kind == JOINT_TASK:
        task_pose(k, q, fR, fp, r, vecs[18])
        for i in range(n):
            d = r[i] - x[i]
            r[i] = d if k.t_jkind[i] == PRISMATIC else _wrap(d)
            if jac:
                A[i, :] = 0.0
                A[i, t_jv[i]] = 1.0
        return
    nv = A.shape[1]
    J = jacs[2]
    if jac:
        frame_jacobian(k, t_frame, fp, Sw, Sv, J)
    R = fR[t_frame]
    n_lin = 0
    n_ang = 0
    for i in range(n):
        if t_rows[i] < 3:
            n_lin += 1
        else:
            n_ang += 1
    for i in range(n_lin):
        row = t_rows[i]
        r[i] = fp[t_frame, row] - x[i]
        if jac:
            A[i] = J[row]
    if n_ang == 0:
        return
    lg, M, E, G = vecs[19], mats[5], mats[6], mats[7]
    if n_ang == 3:  # log3(R R*^T), Jacobian Jlog3(E) E^T J_w
        for a_ in range(3):
            for b_ in range(3):
                E[a_, b_] = R[a_, 0] * R_star[b_, 0] + R[a_, 1] * R_star[b_, 1] + R[a_, 2] * R_star[b_, 2]
        theta = log3(E, lg)
        r[n_lin : n_lin + 3] = lg
        if jac:
            jlog3(theta, lg, M)
            for a_ in range(3):
                for b_ in range(3):
                    G[a_, b_] = M[a_, 0] * E[b_, 0] + M[a_, 1] * E[b_, 1] + M[a_, 2] * E[b_, 2]
            for e in range(3):
                for c in range(nv):
                    A[n_lin + e, c] = G[e, 0] * J[3, c] + G[e, 1] * J[4, c] + G[e, 2] * J[5, c]
        return
    rpy(R, lg)
    for i in range(n_lin, n):
        r[i] = _wrap(lg[t_rows[i] - 3] - x[i])
    if jac:  # rows of the world roll-pitch-yaw Jacobian inverse times J_w
        sp, cp = math.sin(lg[1]), math.cos(lg[1])
        sy, cy = math.sin(lg[2]), math.cos(lg[2])
        tp = sp / cp
        M[0, 0], M[0, 1], M[0, 2] = cy / cp, sy / cp, 0.0
        M[1, 0], M[1, 1], M[1, 2] = -sy, cy, 0.0
        M[2, 0], M[2, 1], M[2, 2] = cy * tp, sy * tp, 1.0
        for i in range(n_lin, n):
            e = t_rows[i] - 3
            for c in range(nv):
                A[i, c] = M[e, 0] * J[3, c] + M[e, 1] * J[4, c] + M[e, 2] * J[5, c]


@njit(cache=True, inline="always")
def evaluate(
    k: KernelArrays,
    q: np.ndarray,
    x: np.ndarray,
    R_star: np.ndarray,
    with_task: bool,
    r: np.ndarray,
    A: np.ndarray,
    jac: bool,
    oR: np.ndarray,
    op: np.ndarray,
    fR: np.ndarray,
    fp: np.ndarray,
    Sw: np.ndarray,
    Sv: np.ndarray,
    mats: np.ndarray,
    vecs: np.ndarray,
    jacs: np.ndarray,
) -> None:
    """Residual ``[phi; task]`` into ``r`` and (``jac``) its Jacobian into ``A``, from ``q``.

    Scratch: ``mats`` (8, 3, 3), ``vecs`` (24, 3), ``jacs`` (3, 6, nv) (:func:`scratch`).
    """
    forward(k, q, oR, op, Sw, Sv, jac, mats, vecs)
    frames(k, oR, op, fR, fp)
    m = k.m
    closure_rows(k, fR, fp, Sw, Sv, r[:m], A[:m], jac, mats, vecs, jacs)
    if with_task:
        task_rows(k, q, fR, fp, Sw, Sv, x, R_star, r[m:], A[m:], jac, mats, vecs, jacs)


@njit(cache=True)
def scratch(nv: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The scratch arrays of :func:`evaluate` and :func:`integrate`: ``mats``, ``vecs``, ``jacs``."""
    return np.empty((8, 3, 3)), np.empty((24, 3)), np.empty((3, 6, nv))


@njit(cache=True, inline="always")
def integrate(
    k: KernelArrays, q: np.ndarray, v: np.ndarray, out: np.ndarray, mats: np.ndarray, vecs: np.ndarray
) -> None:
    """Pinocchio's ``integrate``: ``out`` = ``q`` moved by the tangent vector ``v`` (joint by joint).

    Scratch: ``mats`` (>= 1, 3, 3), ``vecs`` (>= 2, 3).
    """
    kinds, idx_q, idx_v = k.kinds, k.idx_q, k.idx_v
    out[:] = q
    R0, t, p = mats[0], vecs[0], vecs[1]
    for j in range(1, kinds.shape[0]):
        kind, iq, iv = kinds[j], idx_q[j], idx_v[j]
        if kind == REVOLUTE or kind == PRISMATIC:
            out[iq] = q[iq] + v[iv]
        elif kind == UNIVERSAL:
            out[iq] = q[iq] + v[iv]
            out[iq + 1] = q[iq + 1] + v[iv + 1]
        elif kind == REVOLUTE_UNBOUNDED or kind == PLANAR:
            o = 2 if kind == PLANAR else 0
            w = v[iv + o]
            ca, sa = q[iq + o], q[iq + o + 1]
            cw, sw = math.cos(w), math.sin(w)
            c1, s1 = cw * ca - sw * sa, sw * ca + cw * sa
            nrm = (3.0 - (c1 * c1 + s1 * s1)) / 2.0
            out[iq + o], out[iq + o + 1] = c1 * nrm, s1 * nrm
            if kind == PLANAR:  # M0 exp(v) in SE(2)
                vx, vy = v[iv], v[iv + 1]
                if abs(w) > 1e-8:
                    a, b = sw / w, (1.0 - cw) / w
                else:
                    a, b = 1.0 - w * w / 6.0, w / 2.0
                px, py = a * vx - b * vy, b * vx + a * vy
                out[iq] = q[iq] + ca * px - sa * py
                out[iq + 1] = q[iq + 1] + sa * px + ca * py
        else:  # SPHERICAL, FREE_FLYER: quaternion times exp3(w), translation + R0 V(w) v
            o = 3 if kind == FREE_FLYER else 0
            w0, w1, w2 = v[iv + o], v[iv + o + 1], v[iv + o + 2]
            th = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
            hs = math.sin(0.5 * th) / th if th > 1e-8 else 0.5 - th * th / 48.0
            ex, ey, ez, ew = hs * w0, hs * w1, hs * w2, math.cos(0.5 * th)
            x, y, z, w = q[iq + o], q[iq + o + 1], q[iq + o + 2], q[iq + o + 3]
            nx = w * ex + x * ew + y * ez - z * ey
            ny = w * ey - x * ez + y * ew + z * ex
            nz = w * ez + x * ey - y * ex + z * ew
            nw = w * ew - x * ex - y * ey - z * ez
            nrm = math.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
            out[iq + o], out[iq + o + 1], out[iq + o + 2], out[iq + o + 3] = (
                nx / nrm,
                ny / nrm,
                nz / nrm,
                nw / nrm,
            )
            if kind == FREE_FLYER:
                _quat_matrix(x, y, z, w, R0)
                if th > 1e-8:
                    c1 = (1.0 - math.cos(th)) / (th * th)
                    c2 = (th - math.sin(th)) / (th * th * th)
                else:
                    c1, c2 = 0.5 - th * th / 24.0, 1.0 / 6.0 - th * th / 120.0
                l0, l1, l2 = v[iv], v[iv + 1], v[iv + 2]
                a0, a1, a2 = w1 * l2 - w2 * l1, w2 * l0 - w0 * l2, w0 * l1 - w1 * l0  # w x lin
                b0, b1, b2 = w1 * a2 - w2 * a1, w2 * a0 - w0 * a2, w0 * a1 - w1 * a0  # w x (w x lin)
                p[0], p[1], p[2] = l0 + c1 * a0 + c2 * b0, l1 + c1 * a1 + c2 * b1, l2 + c1 * a2 + c2 * b2
                _mv3(R0, p, t)
                for d in range(3):
                    out[iq + d] = q[iq + d] + t[d]


@njit(cache=True)
def _cholesky_solve(N: np.ndarray, b: np.ndarray) -> bool:
    """Cholesky-factor ``N`` in place (lower), solve ``N x = b`` in ``b``; False if not positive definite."""
    n = N.shape[0]
    for j in range(n):
        d = N[j, j]
        for p in range(j):
            d -= N[j, p] * N[j, p]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        N[j, j] = d
        for i in range(j + 1, n):
            s = N[i, j]
            for p in range(j):
                s -= N[i, p] * N[j, p]
            N[i, j] = s / d
    _cholesky_back(N, b)
    return True


@njit(cache=True)
def _cholesky_back(L: np.ndarray, b: np.ndarray) -> None:
    """Solve ``L L^T x = b`` in ``b`` with a factor from :func:`_cholesky_solve`."""
    n = L.shape[0]
    for i in range(n):
        s = b[i]
        for p in range(i):
            s -= L[i, p] * b[p]
        b[i] = s / L[i, i]
    for i in range(n - 1, -1, -1):
        s = b[i]
        for p in range(i + 1, n):
            s -= L[p, i] * b[p]
        b[i] = s / L[i, i]


@njit(cache=True)
def newton(
    k: KernelArrays,
    free: np.ndarray,
    x: np.ndarray,
    R_star: np.ndarray,
    with_task: bool,
    tol: float,
    round_off: float,
    max_iterations: int,
    stall_ratio: float,
    chord_ratio: float,
    polish: bool,
    q: np.ndarray,
    r: np.ndarray,
    pose: np.ndarray,
) -> int:
    """:func:`plm_pin.core.assembly.newton` moving the ``free`` columns: iterations, or -1.

    ``q`` holds the start; on success it holds the solution, ``r`` its residual ``[phi; task]``
    and ``pose`` its task coordinates (:func:`task_pose`).
    """
    nj, nv, nf = k.parents.shape[0], k.nv, k.f_joint.shape[0]
    n, nfree = r.shape[0], free.shape[0]
    A = np.empty((n, nv))
    Af = np.empty((n, nfree))
    N = np.empty((nfree, nfree))
    b = np.empty(nfree)
    step = np.zeros(nv)
    oR, op = np.empty((nj, 3, 3)), np.empty((nj, 3))
    fR, fp = np.empty((max(nf, 1), 3, 3)), np.empty((max(nf, 1), 3))
    Sw, Sv = np.empty((nv, 3)), np.empty((nv, 3))
    mats, vecs, jacs = scratch(nv)
    q_next = np.empty(q.shape[0])
    factorised = fresh = False
    polished = not polish
    err_prev = np.inf
    for iteration in range(max_iterations + 1):
        evaluate(k, q, x, R_star, with_task, r, A, False, oR, op, fR, fp, Sw, Sv, mats, vecs, jacs)
        err = 0.0
        for i in range(n):
            err = max(err, abs(r[i]))
        if err <= tol:
            if polished or err < round_off:
                task_pose(k, q, fR, fp, pose, vecs[18])
                return iteration
            polished = True
            refresh = not factorised
        elif iteration == max_iterations:
            return -1
        elif polish and err < chord_ratio * err_prev:
            refresh = not factorised
        elif err < stall_ratio * err_prev or not fresh:
            refresh = True
        else:
            return -1
        if refresh:
            evaluate(k, q, x, R_star, with_task, r, A, True, oR, op, fR, fp, Sw, Sv, mats, vecs, jacs)
            for i in range(n):
                for c in range(nfree):
                    Af[i, c] = A[i, free[c]]
            for a_ in range(nfree):
                for c in range(a_ + 1):
                    s = 0.0
                    for i in range(n):
                        s += Af[i, a_] * Af[i, c]
                    N[a_, c] = s
                    N[c, a_] = s
            factorised = True
        for c in range(nfree):
            s = 0.0
            for i in range(n):
                s += Af[i, c] * r[i]
            b[c] = s
        if refresh:
            if not _cholesky_solve(N, b):
                return -1
        else:
            _cholesky_back(N, b)
        for c in range(nfree):
            step[free[c]] = -b[c]
        fresh = refresh
        integrate(k, q, step, q_next, mats, vecs)
        q[:] = q_next
        err_prev = err
    return -1


@njit(cache=True)
def batch_newton(
    k: KernelArrays,
    Q: np.ndarray,
    X: np.ndarray,
    R_stars: np.ndarray,
    tol: float,
    max_iterations: int,
    stall: float,
    ok: np.ndarray,
    A_out: np.ndarray,
    R_out: np.ndarray,
) -> None:
    """Gauss-Newton on closures and task at each pose of a batch, from its row of ``Q`` (solved in place).

    Every iteration takes a fresh Jacobian; a pose fails when its residual does not fall
    below ``stall`` times the previous one, when the normal matrix is not positive definite,
    or after ``max_iterations``; no polishing step. Where a pose converges, ``ok`` is True,
    ``A_out`` holds the inverse-kinematics Jacobian (closure rows, then the task frame's
    world-aligned twist rows) and ``R_out`` the world rotation of every joint.

    Args:
        k: the kernel arrays (a frame task).
        Q: starting configurations, solved in place, shape (B, nq).
        X: task targets, shape (B, n_task).
        R_stars: target rotations of tasks with all three angles (else any), shape (B, 3, 3).
        tol: residual tolerance [m, rad].
        max_iterations: iteration cap.
        stall: the residual ratio below which an iteration must go.
        ok: out, shape (B,).
        A_out: out, shape (B, m + n_task, nv).
        R_out: out, shape (B, nj, 3, 3).
    """
    nj, nv, nf, m = k.parents.shape[0], k.nv, k.f_joint.shape[0], k.m
    n = m + X.shape[1]
    A = np.empty((n, nv))
    r = np.empty(n)
    N = np.empty((nv, nv))
    b = np.empty(nv)
    oR, op = np.empty((nj, 3, 3)), np.empty((nj, 3))
    fR, fp = np.empty((max(nf, 1), 3, 3)), np.empty((max(nf, 1), 3))
    Sw, Sv = np.empty((nv, 3)), np.empty((nv, 3))
    mats, vecs, jacs = scratch(nv)
    q_next = np.empty(Q.shape[1])
    for p in range(Q.shape[0]):
        q = Q[p]
        ok[p] = False
        err_prev = np.inf
        for iteration in range(max_iterations + 1):
            evaluate(k, q, X[p], R_stars[p], True, r, A, True, oR, op, fR, fp, Sw, Sv, mats, vecs, jacs)
            err = 0.0
            for i in range(n):
                err = max(err, abs(r[i]))
            if err <= tol:
                ok[p] = True
                A_out[p, :m] = A[:m]
                frame_jacobian(k, k.t_frame, fp, Sw, Sv, jacs[2])
                for i in range(n - m):
                    A_out[p, m + i] = jacs[2][k.t_rows[i]]
                R_out[p] = oR
                break
            if math.isnan(err) or not err < stall * err_prev or iteration == max_iterations:
                break
            for a_ in range(nv):
                s = 0.0
                for i in range(n):
                    s += A[i, a_] * r[i]
                b[a_] = s
                for c in range(a_ + 1):
                    s = 0.0
                    for i in range(n):
                        s += A[i, a_] * A[i, c]
                    N[a_, c] = s
                    N[c, a_] = s
            if not _cholesky_solve(N, b):
                break
            for c in range(nv):
                b[c] = -b[c]
            integrate(k, q, b, q_next, mats, vecs)
            q[:] = q_next
            err_prev = err
