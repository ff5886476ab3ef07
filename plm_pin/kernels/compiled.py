r"""The compiled kernels: tree forward kinematics, closure and task rows, Newton, with numba.

The entry points take a :class:`~plm_pin.kernels.model.Kernel`'s arrays packed into one integer
and one float array (:func:`.arrays.pack`; two arrays to unbox per call) and read them back as
views (:func:`unpack`, passed on as ``k``); the inner functions work in place on buffers
allocated once per call, by index arithmetic on 3 x 3 matrices held as 9-tuples (no views,
no temporaries in the loops over joints and columns). The conventions are Pinocchio's:

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

from .arrays import HEADER, INT_FIELDS, KernelArrays
from .linear import Elimination, solve

# joint kinds (see plm_pin.kernels.model)
REVOLUTE, PRISMATIC, REVOLUTE_UNBOUNDED, SPHERICAL, FREE_FLYER, PLANAR, UNIVERSAL = 1, 2, 3, 4, 5, 6, 7
# closure kinds
POINT, REVOLUTE_CLOSURE, WELD, TWIST = 0, 1, 2, 3
# task kinds
NO_TASK, FRAME_TASK, JOINT_TASK = 0, 1, 2


@njit(cache=True)
def unpack(ints: np.ndarray, floats: np.ndarray) -> KernelArrays:
    """The :class:`KernelArrays` held by ``ints`` and ``floats`` (:func:`.arrays.pack`), as views."""
    nj, nf, nc, nv = ints[0], ints[1], ints[2], ints[3]
    o, g = HEADER, HEADER + len(INT_FIELDS) + 1
    return KernelArrays(
        ints[ints[o] : ints[o + 1]],
        ints[ints[o + 1] : ints[o + 2]],
        floats[ints[g] : ints[g + 1]].reshape((nj, 3, 3)),
        floats[ints[g + 1] : ints[g + 2]].reshape((nj, 3)),
        floats[ints[g + 2] : ints[g + 3]].reshape((nj, 3)),
        floats[ints[g + 3] : ints[g + 4]].reshape((nj, 3)),
        ints[ints[o + 2] : ints[o + 3]],
        ints[ints[o + 3] : ints[o + 4]],
        ints[ints[o + 4] : ints[o + 5]],
        floats[ints[g + 4] : ints[g + 5]].reshape((nf, 3, 3)),
        floats[ints[g + 5] : ints[g + 6]].reshape((nf, 3)),
        ints[ints[o + 5] : ints[o + 6]].reshape((nf, nv)),
        ints[ints[o + 6] : ints[o + 7]],
        ints[ints[o + 7] : ints[o + 8]],
        ints[ints[o + 8] : ints[o + 9]],
        ints[ints[o + 9] : ints[o + 10]],
        floats[ints[g + 6] : ints[g + 7]].reshape((nc, 3)),
        floats[ints[g + 7] : ints[g + 8]].reshape((nc, 3, 2)),
        ints[5],
        ints[6],
        ints[ints[o + 10] : ints[o + 11]],
        ints[ints[o + 11] : ints[o + 12]],
        ints[ints[o + 12] : ints[o + 13]],
        ints[ints[o + 13] : ints[o + 14]],
        ints[4],
        nv,
        floats[ints[g + 8] : ints[g + 9]],
        floats[ints[g + 9] : ints[g + 10]],
        ints[ints[o + 14] : ints[o + 15]],
        ints[ints[o + 15] : ints[o + 16]],
        ints[ints[o + 16] : ints[o + 17]],
        ints[ints[o + 17] : ints[o + 18]],
        ints[ints[o + 18] : ints[o + 19]],
        floats[ints[g + 10] : ints[g + 11]],
        floats[ints[g + 11] : ints[g + 12]].reshape((nj, 3)),
        floats[ints[g + 12] : ints[g + 13]].reshape((nj, 3, 3)),
        floats[ints[g + 13] : ints[g + 14]],
        floats[ints[g + 14] : ints[g + 15]],
    )


@njit(cache=True)
def elimination_of(k: KernelArrays) -> Elimination:
    """The kernel's :class:`~.linear.Elimination` (its five arrays)."""
    return Elimination(k.lu_order, k.lu_row_ptr, k.lu_rows, k.lu_col_ptr, k.lu_cols)


# 3 x 3 matrices are 9-tuples of floats (row-major) and vectors 3-tuples: no arrays, no views.


@njit(cache=True)
def _rot(x: float, y: float, z: float, c: float, s: float) -> tuple:
    """Rotation about the unit axis ``(x, y, z)`` of cosine ``c`` and sine ``s``."""
    t = 1.0 - c
    return (
        c + t * x * x,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        c + t * y * y,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        c + t * z * z,
    )


@njit(cache=True)
def _quat(x: float, y: float, z: float, w: float) -> tuple:
    """Rotation of the unit quaternion ``(x, y, z, w)`` (Pinocchio's order)."""
    tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    return (
        1.0 - (tyy + tzz),
        txy - twz,
        txz + twy,
        txy + twz,
        1.0 - (txx + tzz),
        tyz - twx,
        txz - twy,
        tyz + twx,
        1.0 - (txx + tyy),
    )


@njit(cache=True)
def _mul(A: tuple, B: tuple) -> tuple:
    """``A B``."""
    return (
        A[0] * B[0] + A[1] * B[3] + A[2] * B[6],
        A[0] * B[1] + A[1] * B[4] + A[2] * B[7],
        A[0] * B[2] + A[1] * B[5] + A[2] * B[8],
        A[3] * B[0] + A[4] * B[3] + A[5] * B[6],
        A[3] * B[1] + A[4] * B[4] + A[5] * B[7],
        A[3] * B[2] + A[4] * B[5] + A[5] * B[8],
        A[6] * B[0] + A[7] * B[3] + A[8] * B[6],
        A[6] * B[1] + A[7] * B[4] + A[8] * B[7],
        A[6] * B[2] + A[7] * B[5] + A[8] * B[8],
    )


@njit(cache=True)
def _mul_t(A: tuple, B: tuple) -> tuple:
    """``A B^T``."""
    return (
        A[0] * B[0] + A[1] * B[1] + A[2] * B[2],
        A[0] * B[3] + A[1] * B[4] + A[2] * B[5],
        A[0] * B[6] + A[1] * B[7] + A[2] * B[8],
        A[3] * B[0] + A[4] * B[1] + A[5] * B[2],
        A[3] * B[3] + A[4] * B[4] + A[5] * B[5],
        A[3] * B[6] + A[4] * B[7] + A[5] * B[8],
        A[6] * B[0] + A[7] * B[1] + A[8] * B[2],
        A[6] * B[3] + A[7] * B[4] + A[8] * B[5],
        A[6] * B[6] + A[7] * B[7] + A[8] * B[8],
    )


@njit(cache=True)
def _t_mul(A: tuple, B: tuple) -> tuple:
    """``A^T B``."""
    return (
        A[0] * B[0] + A[3] * B[3] + A[6] * B[6],
        A[0] * B[1] + A[3] * B[4] + A[6] * B[7],
        A[0] * B[2] + A[3] * B[5] + A[6] * B[8],
        A[1] * B[0] + A[4] * B[3] + A[7] * B[6],
        A[1] * B[1] + A[4] * B[4] + A[7] * B[7],
        A[1] * B[2] + A[4] * B[5] + A[7] * B[8],
        A[2] * B[0] + A[5] * B[3] + A[8] * B[6],
        A[2] * B[1] + A[5] * B[4] + A[8] * B[7],
        A[2] * B[2] + A[5] * B[5] + A[8] * B[8],
    )


@njit(cache=True)
def _mv(A: tuple, x: float, y: float, z: float) -> tuple:
    """``A (x, y, z)``."""
    return (A[0] * x + A[1] * y + A[2] * z, A[3] * x + A[4] * y + A[5] * z, A[6] * x + A[7] * y + A[8] * z)


@njit(cache=True)
def _get(M: np.ndarray, i: int) -> tuple:
    """``M[i]`` (a stack of 3 x 3 matrices) as a 9-tuple."""
    return (
        M[i, 0, 0],
        M[i, 0, 1],
        M[i, 0, 2],
        M[i, 1, 0],
        M[i, 1, 1],
        M[i, 1, 2],
        M[i, 2, 0],
        M[i, 2, 1],
        M[i, 2, 2],
    )


@njit(cache=True)
def _put(M: np.ndarray, i: int, T: tuple) -> None:
    """``M[i] = T``."""
    M[i, 0, 0], M[i, 0, 1], M[i, 0, 2] = T[0], T[1], T[2]
    M[i, 1, 0], M[i, 1, 1], M[i, 1, 2] = T[3], T[4], T[5]
    M[i, 2, 0], M[i, 2, 1], M[i, 2, 2] = T[6], T[7], T[8]


_EYE9 = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


@njit(cache=True)
def _column(
    W: tuple, p: tuple, wx: float, wy: float, wz: float, vx: float, vy: float, vz: float,
    Sw: np.ndarray, Sv: np.ndarray, col: int,
) -> None:  # fmt: skip
    """Velocity column ``col`` of a joint at world rotation ``W``, origin ``p``, local motion ``(w, v)``."""
    w0, w1, w2 = _mv(W, wx, wy, wz)
    t0, t1, t2 = _mv(W, vx, vy, vz)
    Sw[col, 0], Sw[col, 1], Sw[col, 2] = w0, w1, w2
    Sv[col, 0] = t0 - (w1 * p[2] - w2 * p[1])
    Sv[col, 1] = t1 - (w2 * p[0] - w0 * p[2])
    Sv[col, 2] = t2 - (w0 * p[1] - w1 * p[0])


@njit(cache=True, inline="always")
def forward(
    k: KernelArrays,
    q: np.ndarray,
    oR: np.ndarray,
    op: np.ndarray,
    Sw: np.ndarray,
    Sv: np.ndarray,
    columns: bool,
) -> None:
    """World placements of every joint ``oR`` (nj, 3, 3), ``op`` (nj, 3) and their velocity columns.

    ``Sw`` (nv, 3) and ``Sv`` (nv, 3) receive each column's world angular velocity and the
    linear velocity of the point at the world origin (only with ``columns``).
    """
    parents, kinds, place_R, place_p, axis, axis2, idx_q = (
        k.parents,
        k.kinds,
        k.place_R,
        k.place_p,
        k.axis,
        k.axis2,
        k.idx_q,
    )
    _put(oR, 0, _EYE9)
    op[0, 0] = op[0, 1] = op[0, 2] = 0.0
    for j in range(1, parents.shape[0]):
        kind, iq = kinds[j], idx_q[j]
        ax, ay, az = axis[j, 0], axis[j, 1], axis[j, 2]
        px = py = pz = 0.0
        u0 = u1 = u2 = 0.0  # a universal joint's first axis, seen after its second rotation
        if kind == REVOLUTE:
            Rj = _rot(ax, ay, az, math.cos(q[iq]), math.sin(q[iq]))
        elif kind == REVOLUTE_UNBOUNDED:
            Rj = _rot(ax, ay, az, q[iq], q[iq + 1])
        elif kind == PRISMATIC:
            Rj = _EYE9
            px, py, pz = ax * q[iq], ay * q[iq], az * q[iq]
        elif kind == SPHERICAL:
            Rj = _quat(q[iq], q[iq + 1], q[iq + 2], q[iq + 3])
        elif kind == FREE_FLYER:
            px, py, pz = q[iq], q[iq + 1], q[iq + 2]
            Rj = _quat(q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6])
        elif kind == PLANAR:
            c, s = q[iq + 2], q[iq + 3]
            Rj = (c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
            px, py = q[iq], q[iq + 1]
        else:  # UNIVERSAL
            R2 = _rot(axis2[j, 0], axis2[j, 1], axis2[j, 2], math.cos(q[iq + 1]), math.sin(q[iq + 1]))
            Rj = _mul(_rot(ax, ay, az, math.cos(q[iq]), math.sin(q[iq])), R2)
            u0 = R2[0] * ax + R2[3] * ay + R2[6] * az
            u1 = R2[1] * ax + R2[4] * ay + R2[7] * az
            u2 = R2[2] * ax + R2[5] * ay + R2[8] * az
        par = parents[j]
        P = _get(oR, par)
        PR = _mul(P, _get(place_R, j))  # parent's world rotation times the placement
        t0, t1, t2 = _mv(P, place_p[j, 0], place_p[j, 1], place_p[j, 2])
        W = _mul(PR, Rj)
        _put(oR, j, W)
        d0, d1, d2 = _mv(PR, px, py, pz)
        p = (d0 + t0 + op[par, 0], d1 + t1 + op[par, 1], d2 + t2 + op[par, 2])
        op[j, 0], op[j, 1], op[j, 2] = p
        if not columns:
            continue
        col = k.idx_v[j]
        if kind == REVOLUTE or kind == REVOLUTE_UNBOUNDED:
            _column(W, p, ax, ay, az, 0.0, 0.0, 0.0, Sw, Sv, col)
        elif kind == PRISMATIC:
            _column(W, p, 0.0, 0.0, 0.0, ax, ay, az, Sw, Sv, col)
        elif kind == SPHERICAL:
            _column(W, p, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, Sw, Sv, col)
            _column(W, p, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, Sw, Sv, col + 1)
            _column(W, p, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, Sw, Sv, col + 2)
        elif kind == FREE_FLYER:
            _column(W, p, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, Sw, Sv, col)
            _column(W, p, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, Sw, Sv, col + 1)
            _column(W, p, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, Sw, Sv, col + 2)
            _column(W, p, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, Sw, Sv, col + 3)
            _column(W, p, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, Sw, Sv, col + 4)
            _column(W, p, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, Sw, Sv, col + 5)
        elif kind == PLANAR:
            _column(W, p, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, Sw, Sv, col)
            _column(W, p, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, Sw, Sv, col + 1)
            _column(W, p, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, Sw, Sv, col + 2)
        else:  # UNIVERSAL
            _column(W, p, u0, u1, u2, 0.0, 0.0, 0.0, Sw, Sv, col)
            _column(W, p, axis2[j, 0], axis2[j, 1], axis2[j, 2], 0.0, 0.0, 0.0, Sw, Sv, col + 1)


@njit(cache=True, inline="always")
def frames(k: KernelArrays, oR: np.ndarray, op: np.ndarray, fR: np.ndarray, fp: np.ndarray) -> None:
    """World placements ``fR`` (nf, 3, 3), ``fp`` (nf, 3) of the kernel's frames from the joints'."""
    f_joint, f_R, f_p = k.f_joint, k.f_R, k.f_p
    for f in range(f_joint.shape[0]):
        j = f_joint[f]
        R = _get(oR, j)
        _put(fR, f, _mul(R, _get(f_R, f)))
        t0, t1, t2 = _mv(R, f_p[f, 0], f_p[f, 1], f_p[f, 2])
        fp[f, 0], fp[f, 1], fp[f, 2] = t0 + op[j, 0], t1 + op[j, 1], t2 + op[j, 2]


@njit(cache=True)
def _linear(Sw: np.ndarray, Sv: np.ndarray, c: int, x: float, y: float, z: float) -> tuple:
    r"""Velocity of the point ``(x, y, z)`` under velocity column ``c``: :math:`v_o + \omega \times p`."""
    w0, w1, w2 = Sw[c, 0], Sw[c, 1], Sw[c, 2]
    return Sv[c, 0] + w1 * z - w2 * y, Sv[c, 1] + w2 * x - w0 * z, Sv[c, 2] + w0 * y - w1 * x


@njit(cache=True)
def frame_jacobian(
    k: KernelArrays, f: int, fp: np.ndarray, Sw: np.ndarray, Sv: np.ndarray, out: np.ndarray
) -> None:
    """World-aligned Jacobian (6, nv) of kernel frame ``f`` (linear rows first), into ``out``."""
    support = k.support
    x, y, z = fp[f, 0], fp[f, 1], fp[f, 2]
    for c in range(out.shape[1]):
        if support[f, c]:
            out[0, c], out[1, c], out[2, c] = _linear(Sw, Sv, c, x, y, z)
            out[3, c], out[4, c], out[5, c] = Sw[c, 0], Sw[c, 1], Sw[c, 2]
        else:
            for d in range(6):
                out[d, c] = 0.0


@njit(cache=True)
def log3(R: tuple) -> tuple:
    """Pinocchio's ``log3`` of ``R``: the angle [rad] and the rotation vector ``(theta, r0, r1, r2)``."""
    tr = R[0] + R[4] + R[8]
    if tr >= 3.0:
        theta = 0.0
    elif tr <= -1.0:
        theta = math.pi
    else:
        theta = math.acos((tr - 1.0) / 2.0)
    if theta >= math.pi - 1e-2:  # near a half turn: from the diagonal (Pinocchio's branch)
        cphi = math.cos(theta - math.pi)
        beta = theta * theta / (1.0 + cphi)
        d0, d1, d2 = (R[0] + cphi) * beta, (R[4] + cphi) * beta, (R[8] + cphi) * beta
        r0 = math.sqrt(d0) if d0 > 0.0 else 0.0
        r1 = math.sqrt(d1) if d1 > 0.0 else 0.0
        r2 = math.sqrt(d2) if d2 > 0.0 else 0.0
        if not R[7] > R[5]:
            r0 = -r0
        if not R[2] > R[6]:
            r1 = -r1
        if not R[3] > R[1]:
            r2 = -r2
        return theta, r0, r1, r2
    t = 0.5 * (theta / math.sin(theta) if theta > 1e-8 else 1.0)
    return theta, t * (R[7] - R[5]), t * (R[2] - R[6]), t * (R[3] - R[1])


@njit(cache=True)
def jlog3(theta: float, r0: float, r1: float, r2: float) -> tuple:
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
    return (
        alpha + beta * r0 * r0,
        beta * r0 * r1 - 0.5 * r2,
        beta * r0 * r2 + 0.5 * r1,
        beta * r1 * r0 + 0.5 * r2,
        alpha + beta * r1 * r1,
        beta * r1 * r2 - 0.5 * r0,
        beta * r2 * r0 - 0.5 * r1,
        beta * r2 * r1 + 0.5 * r0,
        alpha + beta * r2 * r2,
    )


@njit(cache=True)
def rpy(R: tuple) -> tuple:
    """Pinocchio's ``rpy.matrixToRpy`` of ``R``: ``(roll, pitch, yaw)``."""
    m = math.sqrt(R[7] * R[7] + R[8] * R[8])
    p = math.atan2(-R[6], m)
    if abs(abs(p) - 0.5 * math.pi) < 0.001:
        return 0.0, p, math.atan2(-R[1], R[4])
    return math.atan2(R[7], R[8]), p, math.atan2(R[3], R[0])


@njit(cache=True)
def _wrap(a: float) -> float:
    return math.pi - (math.pi - a) % (2.0 * math.pi)


@njit(cache=True)
def _angular_rows(
    k: KernelArrays, fa: int, fb: int, G: tuple, n_rows: int, first: int, Sw: np.ndarray, A: np.ndarray
) -> None:
    """Rows ``first``... of ``A``: ``n_rows`` rows of ``G`` (3 x 3) times the angular rows of J_B - J_A."""
    support = k.support
    for c in range(A.shape[1]):
        s = support[fb, c] - support[fa, c]
        w0, w1, w2 = s * Sw[c, 0], s * Sw[c, 1], s * Sw[c, 2]
        for e in range(n_rows):
            A[first + e, c] = G[3 * e] * w0 + G[3 * e + 1] * w1 + G[3 * e + 2] * w2


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
) -> None:
    """Closure residual into ``r[:m]`` and, with ``jac``, its Jacobian into ``A[:m]`` (nv columns)."""
    c_kind, c_a, c_b, c_row, c_axis, c_E, support = (
        k.c_kind,
        k.c_a,
        k.c_b,
        k.c_row,
        k.c_axis,
        k.c_E,
        k.support,
    )
    nv = A.shape[1]
    for i in range(c_kind.shape[0]):
        kind, fa, fb, s = c_kind[i], c_a[i], c_b[i], c_row[i]
        if kind != TWIST:
            ax, ay, az = fp[fa, 0], fp[fa, 1], fp[fa, 2]
            bx, by, bz = fp[fb, 0], fp[fb, 1], fp[fb, 2]
            r[s], r[s + 1], r[s + 2] = bx - ax, by - ay, bz - az
            if jac:
                for c in range(nv):
                    sa, sb = support[fa, c], support[fb, c]
                    if sa and sb:  # the column moves both: omega x (p_B - p_A)
                        w0, w1, w2 = Sw[c, 0], Sw[c, 1], Sw[c, 2]
                        dx, dy, dz = bx - ax, by - ay, bz - az
                        A[s, c], A[s + 1, c], A[s + 2, c] = (
                            w1 * dz - w2 * dy,
                            w2 * dx - w0 * dz,
                            w0 * dy - w1 * dx,
                        )
                    elif sb:
                        A[s, c], A[s + 1, c], A[s + 2, c] = _linear(Sw, Sv, c, bx, by, bz)
                    elif sa:
                        v0, v1, v2 = _linear(Sw, Sv, c, ax, ay, az)
                        A[s, c], A[s + 1, c], A[s + 2, c] = -v0, -v1, -v2
                    else:
                        A[s, c] = A[s + 1, c] = A[s + 2, c] = 0.0
        if kind == POINT:
            continue
        Ra, Rb = _get(fR, fa), _get(fR, fb)
        if kind == WELD:
            theta, l0, l1, l2 = log3(_t_mul(Ra, Rb))
            r[s + 3], r[s + 4], r[s + 5] = l0, l1, l2
            if jac:  # Jlog3 R_B^T
                _angular_rows(k, fa, fb, _mul_t(jlog3(theta, l0, l1, l2), Rb), 3, s + 3, Sw, A)
        elif kind == TWIST:
            u0, u1, u2 = _mv(Ra, c_E[i, 0, 1], c_E[i, 1, 1], c_E[i, 2, 1])  # x = R_A e2
            v0, v1, v2 = _mv(Rb, c_E[i, 0, 0], c_E[i, 1, 0], c_E[i, 2, 0])  # y = R_B e1
            r[s] = u0 * v0 + u1 * v1 + u2 * v2
            if jac:  # (y x x)^T
                G = (v1 * u2 - v2 * u1, v2 * u0 - v0 * u2, v0 * u1 - v1 * u0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
                _angular_rows(k, fa, fb, G, 1, s, Sw, A)
        else:  # revolute: E^T R_A^T R_B u, rows -(R_A E_e x R_B u)^T
            w0, w1, w2 = _mv(Rb, c_axis[i, 0], c_axis[i, 1], c_axis[i, 2])
            v0 = Ra[0] * w0 + Ra[3] * w1 + Ra[6] * w2
            v1 = Ra[1] * w0 + Ra[4] * w1 + Ra[7] * w2
            v2 = Ra[2] * w0 + Ra[5] * w1 + Ra[8] * w2
            for e in range(2):
                r[s + 3 + e] = c_E[i, 0, e] * v0 + c_E[i, 1, e] * v1 + c_E[i, 2, e] * v2
            if jac:
                a0, a1, a2 = _mv(Ra, c_E[i, 0, 0], c_E[i, 1, 0], c_E[i, 2, 0])
                b0, b1, b2 = _mv(Ra, c_E[i, 0, 1], c_E[i, 1, 1], c_E[i, 2, 1])
                G = (
                    -(a1 * w2 - a2 * w1),
                    -(a2 * w0 - a0 * w2),
                    -(a0 * w1 - a1 * w0),
                    -(b1 * w2 - b2 * w1),
                    -(b2 * w0 - b0 * w2),
                    -(b0 * w1 - b1 * w0),
                    0.0,
                    0.0,
                    0.0,
                )
                _angular_rows(k, fa, fb, G, 2, s + 3, Sw, A)


@njit(cache=True, inline="always")
def task_pose(k: KernelArrays, q: np.ndarray, fR: np.ndarray, fp: np.ndarray, out: np.ndarray) -> None:
    """Task coordinates (:meth:`plm_pin.core.task.Task.pose_from_data`) into ``out`` (n_task,)."""
    t_kind, t_frame, t_rows, t_jq, t_jkind = k.t_kind, k.t_frame, k.t_rows, k.t_jq, k.t_jkind
    if t_kind == FRAME_TASK:
        ang = rpy(_get(fR, t_frame))
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
) -> None:
    """Task target rows (:class:`plm_pin.core.task.TaskTarget`) into ``r[m:]``, Jacobian into ``A[m:]``."""
    t_kind, t_frame, t_rows, t_jv, t_jkind, support = (
        k.t_kind,
        k.t_frame,
        k.t_rows,
        k.t_jv,
        k.t_jkind,
        k.support,
    )
    m, nv = k.m, A.shape[1]
    n = r.shape[0] - m
    if t_kind == JOINT_TASK:
        for i in range(n):
            iq = k.t_jq[i]
            if t_jkind[i] == REVOLUTE:
                d = _wrap(q[iq]) - x[i]
            elif t_jkind[i] == REVOLUTE_UNBOUNDED:
                d = math.atan2(q[iq + 1], q[iq]) - x[i]
            else:
                d = q[iq] - x[i]
            r[m + i] = d if t_jkind[i] == PRISMATIC else _wrap(d)
            if jac:
                for c in range(nv):
                    A[m + i, c] = 0.0
                A[m + i, t_jv[i]] = 1.0
        return
    f = t_frame
    px, py, pz = fp[f, 0], fp[f, 1], fp[f, 2]
    n_lin = 0
    for i in range(n):
        if t_rows[i] < 3:
            n_lin += 1
    for i in range(n_lin):
        row = t_rows[i]
        r[m + i] = fp[f, row] - x[i]
        if jac:
            for c in range(nv):
                A[m + i, c] = _linear(Sw, Sv, c, px, py, pz)[row] if support[f, c] else 0.0
    n_ang = n - n_lin
    if n_ang == 0:
        return
    R = _get(fR, f)
    first = m + n_lin
    if n_ang == 3:  # log3(R R*^T), Jacobian Jlog3(E) E^T J_w
        E = _mul_t(
            R,
            (
                R_star[0, 0],
                R_star[0, 1],
                R_star[0, 2],
                R_star[1, 0],
                R_star[1, 1],
                R_star[1, 2],
                R_star[2, 0],
                R_star[2, 1],
                R_star[2, 2],
            ),
        )
        theta, l0, l1, l2 = log3(E)
        r[first], r[first + 1], r[first + 2] = l0, l1, l2
        if jac:
            G = _mul_t(jlog3(theta, l0, l1, l2), E)
            for c in range(nv):
                if support[f, c]:
                    w0, w1, w2 = Sw[c, 0], Sw[c, 1], Sw[c, 2]
                    for e in range(3):
                        A[first + e, c] = G[3 * e] * w0 + G[3 * e + 1] * w1 + G[3 * e + 2] * w2
                else:
                    A[first, c] = A[first + 1, c] = A[first + 2, c] = 0.0
        return
    ang = rpy(R)
    for i in range(n_lin, n):
        r[m + i] = _wrap(ang[t_rows[i] - 3] - x[i])
    if jac:  # rows of the world roll-pitch-yaw Jacobian inverse times J_w
        sp, cp = math.sin(ang[1]), math.cos(ang[1])
        sy, cy = math.sin(ang[2]), math.cos(ang[2])
        tp = sp / cp
        M = (cy / cp, sy / cp, 0.0, -sy, cy, 0.0, cy * tp, sy * tp, 1.0)
        for i in range(n_lin, n):
            e = t_rows[i] - 3
            for c in range(nv):
                if support[f, c]:
                    A[m + i, c] = M[3 * e] * Sw[c, 0] + M[3 * e + 1] * Sw[c, 1] + M[3 * e + 2] * Sw[c, 2]
                else:
                    A[m + i, c] = 0.0


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
) -> None:
    """Residual ``[phi; task]`` into ``r`` and (``jac``) its Jacobian into ``A``, from ``q``."""
    forward(k, q, oR, op, Sw, Sv, jac)
    frames(k, oR, op, fR, fp)
    closure_rows(k, fR, fp, Sw, Sv, r, A, jac)
    if with_task:
        task_rows(k, q, fR, fp, Sw, Sv, x, R_star, r, A, jac)


@njit(cache=True)
def placements(
    ints: np.ndarray,
    floats: np.ndarray,
    q: np.ndarray,
    oR: np.ndarray,
    op: np.ndarray,
    fR: np.ndarray,
    fp: np.ndarray,
) -> None:
    """World placements of every joint and kernel frame at ``q`` (:func:`forward`, :func:`frames`)."""
    k = unpack(ints, floats)
    Sw = np.empty((0, 3))
    forward(k, q, oR, op, Sw, Sw, False)
    frames(k, oR, op, fR, fp)


@njit(cache=True)
def rows(
    ints: np.ndarray,
    floats: np.ndarray,
    q: np.ndarray,
    x: np.ndarray,
    R_star: np.ndarray,
    with_task: bool,
    r: np.ndarray,
    A: np.ndarray,
) -> None:
    """:func:`evaluate` with its Jacobian, on the packed arrays."""
    k = unpack(ints, floats)
    nj, nf, nv = k.parents.shape[0], max(k.f_joint.shape[0], 1), k.nv
    oR, op, fR, fp = np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((nf, 3, 3)), np.empty((nf, 3))
    evaluate(k, q, x, R_star, with_task, r, A, True, oR, op, fR, fp, np.empty((nv, 3)), np.empty((nv, 3)))


@njit(cache=True, inline="always")
def integrate(k: KernelArrays, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
    """Pinocchio's ``integrate``: ``out`` = ``q`` moved by the tangent vector ``v`` (joint by joint)."""
    kinds, idx_q, idx_v = k.kinds, k.idx_q, k.idx_v
    out[:] = q
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
                if th > 1e-8:
                    c1 = (1.0 - math.cos(th)) / (th * th)
                    c2 = (th - math.sin(th)) / (th * th * th)
                else:
                    c1, c2 = 0.5 - th * th / 24.0, 1.0 / 6.0 - th * th / 120.0
                l0, l1, l2 = v[iv], v[iv + 1], v[iv + 2]
                a0, a1, a2 = w1 * l2 - w2 * l1, w2 * l0 - w0 * l2, w0 * l1 - w1 * l0  # w x lin
                b0, b1, b2 = w1 * a2 - w2 * a1, w2 * a0 - w0 * a2, w0 * a1 - w1 * a0  # w x (w x lin)
                t0, t1, t2 = _mv(
                    _quat(x, y, z, w), l0 + c1 * a0 + c2 * b0, l1 + c1 * a1 + c2 * b1, l2 + c1 * a2 + c2 * b2
                )
                out[iq] = q[iq] + t0
                out[iq + 1] = q[iq + 1] + t1
                out[iq + 2] = q[iq + 2] + t2


@njit(cache=True, inline="always")
def normalize(k: KernelArrays, q: np.ndarray) -> None:
    """Scale ``q``'s quaternions and (cos, sin) pairs back to unit norm, in place (extrapolated starts).

    :func:`forward` reads an unbounded revolute's or a planar joint's pair as it is, so a pair
    off the unit circle would place the joint with a scaled rotation.
    """
    for j in range(1, k.kinds.shape[0]):
        kind = k.kinds[j]
        if kind == FREE_FLYER:
            iq, n = k.idx_q[j] + 3, 4
        elif kind == SPHERICAL:
            iq, n = k.idx_q[j], 4
        elif kind == PLANAR:
            iq, n = k.idx_q[j] + 2, 2
        elif kind == REVOLUTE_UNBOUNDED:
            iq, n = k.idx_q[j], 2
        else:
            continue
        s = 0.0
        for t in range(n):
            s += q[iq + t] * q[iq + t]
        s = math.sqrt(s)
        for t in range(n):
            q[iq + t] /= s


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
    ints: np.ndarray,
    floats: np.ndarray,
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
    info: np.ndarray,
) -> int:
    """:func:`plm_pin.core.assembly.newton` moving the ``free`` columns: iterations, or -1.

    ``q`` holds the start; on success it holds the solution, ``r`` its residual ``[phi; task]``,
    ``pose`` its task coordinates (:func:`task_pose`) and ``info`` (2,) the largest absolute
    residual and 1.0 if ``q`` is within the model's position limits (else 0.0).
    """
    k = unpack(ints, floats)
    nj, nv, nf = k.parents.shape[0], k.nv, max(k.f_joint.shape[0], 1)
    n, nfree = r.shape[0], free.shape[0]
    A = np.empty((n, nv))
    Af = np.empty((n, nfree))
    N = np.empty((nfree, nfree))
    b = np.empty(nfree)
    step = np.zeros(nv)
    oR, op, fR, fp = np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((nf, 3, 3)), np.empty((nf, 3))
    Sw, Sv = np.empty((nv, 3)), np.empty((nv, 3))
    q_next = np.empty(q.shape[0])
    factorised = fresh = again = False
    polished = not polish
    err_prev = np.inf
    iteration = 0
    # The first step needs a Jacobian whatever the residual (none is factorised yet): it comes
    # with the first pass, spent in vain only when the start is already solved. Later passes
    # take one only when the step asks for it, at the same q again (``again``).
    jac = True  # one call site of the inlined evaluate: each one costs seconds of compile
    while True:
        evaluate(k, q, x, R_star, with_task, r, A, jac, oR, op, fR, fp, Sw, Sv)
        if not again:
            err = 0.0
            for i in range(n):
                err = max(err, abs(r[i]))
            if err <= tol:
                if polished or err < round_off:
                    task_pose(k, q, fR, fp, pose)
                    inside = 1.0
                    for i in range(q.shape[0]):
                        if not k.lower[i] <= q[i] <= k.upper[i]:
                            inside = 0.0
                    info[0], info[1] = err, inside
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
            if refresh and not jac:
                jac = again = True
                continue
        if jac:  # this q's Jacobian: a fresh normal matrix
            jac, again, refresh, factorised = False, False, True, True
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
        integrate(k, q, step, q_next)
        q[:] = q_next
        err_prev = err
        iteration += 1


@njit(cache=True)
def assemble(
    ints: np.ndarray,
    floats: np.ndarray,
    free: np.ndarray,
    x: np.ndarray,
    R_star: np.ndarray,
    with_task: bool,
    tol: float,
    rcond: float,
    round_off: float,
    max_iterations: int,
    q: np.ndarray,
    r: np.ndarray,
) -> int:
    """:func:`plm_pin.core.assembly.assemble` (Levenberg-Marquardt) moving the ``free`` columns.

    Step for step the Python one: the minimum-norm damped step from the SVD of the free
    columns' Jacobian, singular values at most ``max(rcond s_1, tol max(s_1, 1))`` left out,
    damping ``mu0 |r|^2`` raised tenfold on a rejected step (up to 30 times) and lowered tenfold
    on an accepted one, one polishing step once within ``tol``.

    ``q`` holds the start and ends at the last iterate, ``r`` its residual ``[phi; task]``.

    Returns:
        The iterations taken, or -1 when the largest absolute residual is above ``tol``.
    """
    k = unpack(ints, floats)
    nj, nv, nf = k.parents.shape[0], k.nv, max(k.f_joint.shape[0], 1)
    n, nfree = r.shape[0], free.shape[0]
    A = np.empty((n, nv))
    Jf = np.empty((n, nfree))
    r_new, q_new = np.empty(n), np.empty(q.shape[0])
    step, c = np.zeros(nv), np.empty(min(n, nfree))
    oR, op, fR, fp = np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((nf, 3, 3)), np.empty((nf, 3))
    Sw, Sv = np.empty((nv, 3)), np.empty((nv, 3))
    U, s, Vt = np.empty((n, 0)), np.empty(0), np.empty((0, nfree))
    cost = mu0 = floor = 1.0
    iterations, polish, tries = 0, 1, 0
    phase = 0  # 0: residual at q, 1: Jacobian at q, 2: residual at the trial q_new
    while n:
        trial = phase == 2
        # one call site of the inlined evaluate (each costs seconds of compile)
        evaluate(k, q_new if trial else q, x, R_star, with_task, r_new if trial else r, A, phase == 1,
                 oR, op, fR, fp, Sw, Sv)  # fmt: skip
        check = True  # else take a step with the current damping
        if phase == 1:  # the SVD of the free columns, and the residual's components on it
            for i in range(n):
                for j in range(nfree):
                    Jf[i, j] = A[i, free[j]]
            U, s, Vt = np.linalg.svd(Jf, full_matrices=False)
            floor = max(rcond * s[0], tol * max(s[0], 1.0)) if s.size else 0.0
            if s.size == 0 or not s[0] > floor:
                break
            for i in range(s.shape[0]):
                u = 0.0
                for a in range(n):
                    u += U[a, i] * r[a]
                c[i] = u
            tries = 0
            check = False
        elif phase == 2:
            cost_new = 0.0
            for i in range(n):
                cost_new += r_new[i] * r_new[i]
            if cost_new < cost:
                q[:] = q_new
                r[:] = r_new
                cost = cost_new
                mu0 = max(mu0 / 10.0, 1e-12)
            else:
                mu0 *= 10.0
                tries += 1
                if tries == 30:
                    break
                check = False
        else:
            cost = 0.0
            for i in range(n):
                cost += r[i] * r[i]
        if check:
            err = 0.0
            for i in range(n):
                err = max(err, abs(r[i]))
            if iterations >= max_iterations:
                break
            if err <= tol:
                if polish == 0 or err < round_off:
                    break
                polish -= 1
            iterations += 1
            phase = 1
            continue
        mu = mu0 * cost
        step[:] = 0.0
        for i in range(s.shape[0]):
            if s[i] > floor:
                g = s[i] / (s[i] * s[i] + mu) * c[i]
                for j in range(nfree):
                    step[free[j]] -= g * Vt[i, j]
        integrate(k, q, step, q_new)
        phase = 2
    err = 0.0
    for i in range(n):
        err = max(err, abs(r[i]))
    return iterations if err <= tol else -1


@njit(cache=True)
def _gauss_newton_step(
    A: np.ndarray,
    r: np.ndarray,
    e: Elimination,
    F: np.ndarray,
    N: np.ndarray,
    b: np.ndarray,
    x: np.ndarray,
    pivots: np.ndarray,
    step: np.ndarray,
) -> bool:
    """The Gauss-Newton step :math:`(A^T A)^{-1} A^T r` into ``x`` (nv, 1); False if singular.

    Where ``A`` (n, nv) has as many nonzero rows as columns (its exactly zero rows are a planar loop's
    out-of-plane closure rows), the step is :math:`A^{-1} r` on those rows, solved by the LU
    of :mod:`.linear` on the kernel's pattern ``e``; else by the Cholesky factor of the normal
    equations. ``F`` (n, nv), ``N`` (nv, nv), ``b`` (n, 1), ``pivots`` (nv,) and ``step``
    (n,) are scratch.
    """
    n, nv = A.shape
    live = 0
    for i in range(n):
        for c in range(nv):
            if A[i, c] != 0.0:
                live += 1
                break
    if live == nv:
        for i in range(n):
            b[i, 0] = r[i]
        return solve(A, e, F, pivots, step, b, x)
    for a_ in range(nv):
        s = 0.0
        for i in range(n):
            s += A[i, a_] * r[i]
        x[a_, 0] = s
        for c in range(a_ + 1):
            s = 0.0
            for i in range(n):
                s += A[i, a_] * A[i, c]
            N[a_, c] = s
            N[c, a_] = s
    return _cholesky_solve(N, x[:, 0])


@njit(cache=True)
def _newton_batch(
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

    Each start's quaternions and (cos, sin) pairs are first put back to unit norm (:func:`normalize`).

    Every iteration takes a fresh Jacobian; a pose fails when its residual does not fall
    below ``stall`` times the previous one, when its step's matrix is singular
    (:func:`_gauss_newton_step`), or after ``max_iterations``; no polishing step. Where a
    pose converges, ``ok`` is True, ``A_out`` holds the inverse-kinematics Jacobian (closure
    rows, then the task frame's world-aligned twist rows) and ``R_out`` the world rotation of
    every joint.

    Args:
        k: the kernel's arrays (a frame task).
        Q: starting configurations, solved in place, shape (B, nq).
        X: task targets, shape (B, n_task).
        R_stars: target rotations of tasks with all three angles (else any), shape (B, 3, 3),
            or one for every pose, shape (1, 3, 3).
        tol: residual tolerance [m, rad].
        max_iterations: iteration cap.
        stall: the residual ratio below which an iteration must go.
        ok: out, shape (B,).
        A_out: out, shape (B, m + n_task, nv).
        R_out: out, shape (B, nj, 3, 3).
    """
    nj, nv, nf, m = k.parents.shape[0], k.nv, max(k.f_joint.shape[0], 1), k.m
    n = m + X.shape[1]
    A, r, N, J = np.empty((n, nv)), np.empty(n), np.empty((nv, nv)), np.empty((6, nv))
    F, b, x, step = np.empty((n, nv)), np.empty((n, 1)), np.empty((nv, 1)), np.empty(nv)
    pivots, rows_step = np.empty(nv, dtype=np.int64), np.empty(n, dtype=np.int64)
    e = elimination_of(k)
    oR, op, fR, fp = np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((nf, 3, 3)), np.empty((nf, 3))
    Sw, Sv = np.empty((nv, 3)), np.empty((nv, 3))
    q_next = np.empty(Q.shape[1])
    for p in range(Q.shape[0]):
        q = Q[p]
        normalize(k, q)
        R_star = R_stars[p] if R_stars.shape[0] > 1 else R_stars[0]
        ok[p] = False
        err_prev = np.inf
        for iteration in range(max_iterations + 1):
            evaluate(k, q, X[p], R_star, True, r, A, True, oR, op, fR, fp, Sw, Sv)
            err = 0.0
            for i in range(n):
                err = max(err, abs(r[i]))
            if err <= tol:
                ok[p] = True
                A_out[p, :m] = A[:m]
                frame_jacobian(k, k.t_frame, fp, Sw, Sv, J)
                for i in range(n - m):
                    for c in range(nv):
                        A_out[p, m + i, c] = J[k.t_rows[i], c]
                R_out[p] = oR
                break
            if math.isnan(err) or not err < stall * err_prev or iteration == max_iterations:
                break
            if not _gauss_newton_step(A, r, e, F, N, b, x, pivots, rows_step):
                break
            for c in range(nv):
                step[c] = -x[c, 0]
            integrate(k, q, step, q_next)
            q[:] = q_next
            err_prev = err


@njit(cache=True)
def _leg_determinant(M: np.ndarray, n: int) -> float:
    """Determinant of ``M[:n, :n]``: by cofactors up to 3 x 3 (as the numpy path), else by LU in ``M``."""
    if n == 1:
        return M[0, 0]
    if n == 2:
        return M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
    if n == 3:
        a, b, c = M[0, 0], M[0, 1], M[0, 2]
        d, e, f = M[1, 0], M[1, 1], M[1, 2]
        g, h, i = M[2, 0], M[2, 1], M[2, 2]
        return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    det = 1.0
    for j in range(n):  # Gaussian elimination with partial pivoting
        pivot = j
        for i in range(j + 1, n):
            if abs(M[i, j]) > abs(M[pivot, j]):
                pivot = i
        if M[pivot, j] == 0.0:
            return 0.0
        if pivot != j:
            for c in range(n):
                M[j, c], M[pivot, c] = M[pivot, c], M[j, c]
            det = -det
        det *= M[j, j]
        for i in range(j + 1, n):
            f = M[i, j] / M[j, j]
            for c in range(j + 1, n):
                M[i, c] -= f * M[j, c]
    return det


@njit(cache=True)
def _leg_modes(
    k: KernelArrays,
    A_ik: np.ndarray,
    oR: np.ndarray,
    legs: np.ndarray,
    turns: np.ndarray,
    generic: np.ndarray,
    rtol: float,
    M: np.ndarray,
    mode: np.ndarray,
) -> None:
    """Working mode into ``mode`` (n_legs,) from the IK Jacobian ``A_ik`` and joint rotations ``oR``.

    As :func:`plm_pin.workspace._batch.batch_modes` with :meth:`BatchKinematics.turns
    <plm_pin.workspace._batch.BatchKinematics.turns>`: per square leg, the sign of its block's
    determinant, each passive revolute column negated where its world axis points away from the
    leg's generic axis seen from the leg's root joint; 0 at or below ``rtol`` times Hadamard's
    bound. ``legs``, ``turns`` and ``generic`` as :func:`walk_rows_step` takes them; ``M`` is scratch.
    """
    size = (legs.shape[1] - 1) // 2
    for leg in range(legs.shape[0]):
        n = legs[leg, 0]
        bound = 1.0
        for b in range(n):
            s = 0.0
            for a in range(n):
                M[a, b] = A_ik[legs[leg, 1 + a], legs[leg, 1 + size + b]]
                s += M[a, b] * M[a, b]
            bound *= math.sqrt(s)
        det = _leg_determinant(M, n)
        for t in range(turns.shape[0]):
            if turns[t, 0] != leg:
                continue
            j, root = turns[t, 2], turns[t, 3]
            w = _mv(_get(oR, j), k.axis[j, 0], k.axis[j, 1], k.axis[j, 2])  # the revolute's world axis
            g = _mv(_get(oR, root), generic[t, 0], generic[t, 1], generic[t, 2])
            if w[0] * g[0] + w[1] * g[1] + w[2] * g[2] < 0.0:
                det = -det
        mode[leg] = 0 if abs(det) <= rtol * bound else (1 if det > 0.0 else -1)


@njit(cache=True)
def batch_newton_modes(
    ints: np.ndarray,
    floats: np.ndarray,
    legs: np.ndarray,
    turns: np.ndarray,
    generic: np.ndarray,
    rtol: float,
    Q: np.ndarray,
    X: np.ndarray,
    R_stars: np.ndarray,
    tol: float,
    max_iterations: int,
    stall: float,
    ok: np.ndarray,
    A_out: np.ndarray,
    modes: np.ndarray,
) -> None:
    """:func:`_newton_batch`, and the working mode (:func:`_leg_modes`) of each pose that converges.

    Arguments as :func:`_newton_batch`'s (the packed arrays, without the joint rotations) and, for the modes,
    ``legs``, ``turns``, ``generic`` and ``rtol`` as :func:`walk_rows_step` takes them;
    ``modes`` is out, shape (B, n_legs).
    """
    k = unpack(ints, floats)
    R = np.empty((Q.shape[0], k.parents.shape[0], 3, 3))
    _newton_batch(k, Q, X, R_stars, tol, max_iterations, stall, ok, A_out, R)
    size = (legs.shape[1] - 1) // 2
    M = np.empty((size, size))
    for p in range(Q.shape[0]):
        if ok[p]:
            _leg_modes(k, A_out[p], R[p], legs, turns, generic, rtol, M, modes[p])


@njit(cache=True)
def _predict(Q: np.ndarray, p0: int, p1: int, p2: int, out: np.ndarray) -> None:
    """The next point of a line of equally spaced solutions, by polynomial extrapolation, into ``out``.

    The solutions are ``Q[p0]``, ``Q[p1]``, ``Q[p2]``, nearest first; -1 where absent (from the
    last one given on).
    """
    for t in range(out.shape[0]):
        if p2 >= 0:
            out[t] = 3.0 * Q[p0, t] - 3.0 * Q[p1, t] + Q[p2, t]
        elif p1 >= 0:
            out[t] = 2.0 * Q[p0, t] - Q[p1, t]
        else:
            out[t] = Q[p0, t]


@njit(cache=True)
def _compatible(mode: np.ndarray, wanted: np.ndarray) -> bool:
    """Whether working mode ``mode`` is ``wanted`` (a zero sign on either side matches either)."""
    for leg in range(mode.shape[0]):
        if not (mode[leg] == wanted[leg] or mode[leg] == 0 or wanted[leg] == 0):
            return False
    return True


@njit(cache=True)
def walk_line(
    ints: np.ndarray,
    floats: np.ndarray,
    legs: np.ndarray,
    turns: np.ndarray,
    generic: np.ndarray,
    wanted: np.ndarray,
    rtol: float,
    poses: np.ndarray,
    R_stars: np.ndarray,
    Q: np.ndarray,
    reached: np.ndarray,
    modes: np.ndarray,
    start: int,
    step: int,
    tol: float,
    max_iterations: int,
    stall: float,
    index: np.ndarray,
    A_out: np.ndarray,
) -> int:
    """Walk one side of a line of poses from a solved point: each next point predicted, solved, kept.

    The walk starts at point ``start`` (reached) and goes by ``step`` (+1 or -1). Each point is
    predicted by polynomial extrapolation from up to three points before it on this walk (the
    start included), its quaternions and (cos, sin) pairs put back to unit norm, solved by
    :func:`_newton_batch`'s Newton and kept (written into ``Q``, ``modes``, ``reached``; its
    flat index and IK Jacobian into ``index`` and ``A_out``) if its working mode
    (:func:`_leg_modes`) is compatible with ``wanted``. The walk ends at the line's end, at a
    reached point, or at the first point that fails either test.

    Arguments as :func:`walk_rows_step` takes them, for the line's points alone.

    Returns:
        The number of points kept (the walk stopped at point ``start + step * (count + 1)``).
    """
    k = unpack(ints, floats)
    nj, nq = k.parents.shape[0], Q.shape[1]
    three_angles = R_stars.shape[0] > 1
    q, X = np.empty((1, nq)), np.empty((1, poses.shape[1]))
    ok = np.empty(1, dtype=np.bool_)
    A = np.empty((1, A_out.shape[1], A_out.shape[2]))
    R = np.empty((1, nj, 3, 3))
    size = (legs.shape[1] - 1) // 2
    M = np.empty((size, size))
    mode = np.empty(legs.shape[0], dtype=np.int8)
    count = 0
    p = start + step
    while 0 <= p < reached.shape[0] and not reached[p]:
        p0 = p - step
        _predict(Q, p0, p0 - step if count >= 1 else -1, p0 - 2 * step if count >= 2 else -1, q[0])
        X[0] = poses[p]
        _newton_batch(
            k, q, X, R_stars[p : p + 1] if three_angles else R_stars, tol, max_iterations, stall, ok, A, R
        )
        if not ok[0]:
            break
        _leg_modes(k, A[0], R[0], legs, turns, generic, rtol, M, mode)
        if not _compatible(mode, wanted):
            break
        Q[p] = q[0]
        modes[p] = mode
        reached[p] = True
        index[count] = p
        A_out[count] = A[0]
        count += 1
        p += step
    return count


@njit(cache=True)
def walk_rows_step(
    ints: np.ndarray,
    floats: np.ndarray,
    legs: np.ndarray,
    turns: np.ndarray,
    generic: np.ndarray,
    wanted: np.ndarray,
    rtol: float,
    poses: np.ndarray,
    R_stars: np.ndarray,
    Q: np.ndarray,
    reached: np.ndarray,
    modes: np.ndarray,
    n1: int,
    fronts: np.ndarray,
    lagging: bool,
    tol: float,
    max_iterations: int,
    stall: float,
    index: np.ndarray,
    A_out: np.ndarray,
) -> int:
    """One step of the row walk on a row-major grid of ``n1`` columns: the next row of each side.

    Each side's next row (``fronts``, the upward side first, the downward one unless
    ``lagging``) is predicted per column solved on the row before it, by polynomial
    extrapolation from up to three rows before it on its side, solved in one batch by
    :func:`_newton_batch`'s Newton and kept where it converges in a working mode
    (:func:`_leg_modes`) compatible with ``wanted`` (equal signs, or a zero on either side):
    its configuration, mode and ``reached`` written into the grid, its flat index and IK
    Jacobian into ``index`` and ``A_out``. A side ends (its front set to -1) past the grid's
    edge or after a row with no solved point.

    Args:
        ints: the packed integer arrays of the kernel (a frame task).
        floats: its packed float arrays.
        legs: per square leg, its block size ``n`` then its ``n`` sign rows and ``n`` velocity
            columns, each padded to the largest block, shape (n_legs, 1 + 2 * size).
        turns: per passive revolute to orient: its leg, its column in the leg's block, its joint
            and the leg's root joint, shape (n_axes, 4).
        generic: the generic axis of each, in the root joint's frame, shape (n_axes, 3).
        wanted: the working mode to keep, shape (n_legs,).
        rtol: a leg block is singular at or below this times Hadamard's bound.
        poses: task targets of the grid, shape (n_points, n_task).
        R_stars: their rotations where the task holds all three angles, shape (n_points, 3, 3),
            else one ignored rotation, shape (1, 3, 3).
        Q: configurations of the grid (in and out), shape (n_points, nq).
        reached: solved points (in and out), shape (n_points,).
        modes: their working modes (out where reached), shape (n_points, n_legs).
        n1: columns of the grid.
        fronts: the next row of the upward and the downward side (-1 once ended), updated, (2,).
        lagging: the downward side waits this step.
        tol: residual tolerance [m, rad].
        max_iterations: Newton iteration cap.
        stall: the residual ratio below which an iteration must go.
        index: out, flat indices of the points kept, shape (>= 2 * n1,).
        A_out: out, their IK Jacobians, shape (>= 2 * n1, m + n_task, nv).

    Returns:
        The number of points kept, or -1 when neither side had a row to walk.
    """
    k = unpack(ints, floats)
    nj, nq, n_task = k.parents.shape[0], Q.shape[1], poses.shape[1]
    n0 = reached.shape[0] // n1
    three_angles = R_stars.shape[0] > 1
    # one side's row: the columns tried, their starts, targets and solutions
    cols = np.empty(n1, dtype=np.int64)
    Qb, Xb = np.empty((n1, nq)), np.empty((n1, n_task))
    Rb = np.empty((n1 if three_angles else 1, 3, 3))
    ok = np.empty(n1, dtype=np.bool_)
    Ab = np.empty((n1, A_out.shape[1], A_out.shape[2]))
    Rj = np.empty((n1, nj, 3, 3))
    if not three_angles:
        Rb[0] = R_stars[0]
    M = np.empty(((legs.shape[1] - 1) // 2, (legs.shape[1] - 1) // 2))
    mode = np.empty(legs.shape[0], dtype=np.int8)
    count = 0
    walked = False
    for side in range(2):
        direction = 1 - 2 * side
        i = fronts[side]
        if side == 1 and lagging:
            continue
        ended = not 0 <= i < n0
        if not ended:
            ended = True
            for c in range(n1):
                if reached[(i - direction) * n1 + c]:
                    ended = False
                    break
        if ended:
            fronts[side] = -1
            continue
        walked = True
        fronts[side] = i + direction
        b0, b1, b2 = i - direction, i - 2 * direction, i - 3 * direction
        nb = 0
        for c in range(n1):
            p0 = b0 * n1 + c
            if not reached[p0]:
                continue
            two = 0 <= b1 < n0 and reached[b1 * n1 + c]
            three = two and 0 <= b2 < n0 and reached[b2 * n1 + c]
            _predict(Q, p0, b1 * n1 + c if two else -1, b2 * n1 + c if three else -1, Qb[nb])
            p = i * n1 + c
            Xb[nb] = poses[p]
            if three_angles:
                Rb[nb] = R_stars[p]
            cols[nb] = c
            nb += 1
        _newton_batch(
            k, Qb[:nb], Xb[:nb], Rb[:nb] if three_angles else Rb, tol, max_iterations, stall, ok, Ab, Rj
        )
        for e in range(nb):
            if not ok[e]:
                continue
            _leg_modes(k, Ab[e], Rj[e], legs, turns, generic, rtol, M, mode)
            if not _compatible(mode, wanted):
                continue
            p = i * n1 + cols[e]
            Q[p] = Qb[e]
            modes[p] = mode
            reached[p] = True
            index[count] = p
            A_out[count] = Ab[e]
            count += 1
    return count if walked else -1


@njit(cache=True)
def integrate_packed(
    ints: np.ndarray, floats: np.ndarray, q: np.ndarray, v: np.ndarray, out: np.ndarray
) -> None:
    """:func:`integrate` on the packed arrays."""
    integrate(unpack(ints, floats), q, v, out)
