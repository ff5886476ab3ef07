r"""Compiled joint-space dynamics on the kernel's arrays: mass matrix, nonlinear effects, energy, drift.

World-frame spatial algebra over the tree (the kernel's joints are in topological order). A
spatial motion is held as ``(v_o, w)``: the linear velocity of the body point at the world
origin and the angular velocity, both world-aligned (the columns ``Sv``, ``Sw`` of
:func:`.compiled.forward`); a spatial force as ``(f, n_o)``, the force and its moment about
the world origin. Fixed at the origin, the spatial inertia of a body of mass :math:`m`, centre
of mass :math:`c` and rotational inertia :math:`I_c` about it (all in the world) is

.. math:: \mathcal I (v_o, \omega) = (m v_o + \omega \times h,\ h \times v_o + \bar I \omega),
          \qquad h = m c, \quad \bar I = I_c + m (c^T c\, 1 - c c^T),

and inertias of bodies add. The body velocities are :math:`V_j = V_{\lambda(j)} + S_j \dot q_j`
and, at :math:`\ddot q = 0`, the accelerations :math:`A_j = A_{\lambda(j)} + \dot S_j \dot q_j`
with :math:`\dot S_c = V \times S_c`, :math:`V` the velocity of the body the column is fixed
in (the joint's child, or the parent for a universal joint's first axis). Then

- the mass matrix by composite inertias (CRBA), :math:`M_{cd} = S_c^T \mathcal I^C_{j(d)} S_d`
  for :math:`c` on the path from :math:`j(d)` to the root, the armature on its diagonal
  (``pin.crba``);
- the nonlinear effects by the recursive Newton-Euler pass,
  :math:`F_j = \mathcal I_j (A_j - g) + V_j \times^* \mathcal I_j V_j` summed towards the root,
  :math:`h_c = S_c^T F_{j(c)}` (``pin.rnea(q, v, 0)``);
- the potential energy :math:`-\sum_j m_j\, g^T c_j` (``pin.computePotentialEnergy``);
- the closure drift :math:`\dot J_\phi v` from the frames' classical accelerations at
  :math:`\ddot q = 0`, row by row as :func:`plm_pin.core.closures.drift_from_data`.

:func:`sample` puts these together for one simulation sample (projection, accelerations,
closure forces, energy, task pose) as :class:`plm_pin.dynamics._constrained.ClosedChainDynamics`
does from Python. numba is imported only by the kernel modules.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .arrays import KernelArrays
from .compiled import (
    _EYE9,
    FREE_FLYER,
    PLANAR,
    POINT,
    SPHERICAL,
    TWIST,
    UNIVERSAL,
    WELD,
    _get,
    _mul,
    _mul_t,
    _mv,
    _t_mul,
    closure_rows,
    forward,
    frames,
    integrate,
    jlog3,
    log3,
    task_pose,
    unpack,
)

# statuses of a sample (what sample() reports)
DONE, SINGULAR, OFF_MANIFOLD, NON_FINITE = 0, 1, 2, 3


@njit(cache=True)
def joint_nv(kind: int) -> int:
    """Velocity columns of a joint of kind ``kind``."""
    if kind == SPHERICAL or kind == PLANAR:
        return 3
    if kind == FREE_FLYER:
        return 6
    if kind == UNIVERSAL:
        return 2
    return 1


@njit(cache=True)
def _cross(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float) -> tuple:
    """``a x b``."""
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, inline="always")
def body_inertias(
    k: KernelArrays, oR: np.ndarray, op: np.ndarray, bm: np.ndarray, bh: np.ndarray, bI: np.ndarray
) -> None:
    """Spatial inertia of each joint's body at the world origin: mass ``bm``, ``h = m c`` ``bh``, ``bI``.

    ``bI`` (nj, 3, 3) is the rotational inertia about the world origin, world-aligned.
    """
    mass, lever, rot = k.mass, k.lever, k.rot_inertia
    bm[0] = 0.0
    bh[0, 0] = bh[0, 1] = bh[0, 2] = 0.0
    for e in range(9):
        bI[0, e // 3, e % 3] = 0.0
    for j in range(1, mass.shape[0]):
        R = _get(oR, j)
        m = mass[j]
        c0, c1, c2 = _mv(R, lever[j, 0], lever[j, 1], lever[j, 2])
        c0, c1, c2 = c0 + op[j, 0], c1 + op[j, 1], c2 + op[j, 2]
        Ic = _mul_t(_mul(R, _get(rot, j)), R)
        cc = c0 * c0 + c1 * c1 + c2 * c2
        c = (c0, c1, c2)
        bm[j] = m
        bh[j, 0], bh[j, 1], bh[j, 2] = m * c0, m * c1, m * c2
        for a in range(3):
            for b in range(3):
                bI[j, a, b] = Ic[3 * a + b] + m * ((cc if a == b else 0.0) - c[a] * c[b])


@njit(cache=True)
def _apply(
    bm: np.ndarray, bh: np.ndarray, bI: np.ndarray, j: int,
    v0: float, v1: float, v2: float, w0: float, w1: float, w2: float,
) -> tuple:  # fmt: skip
    """The spatial force ``(f, n_o)`` of inertia ``j`` times the motion ``(v_o, w)``, as a 6-tuple."""
    m, h0, h1, h2 = bm[j], bh[j, 0], bh[j, 1], bh[j, 2]
    x0, x1, x2 = _cross(w0, w1, w2, h0, h1, h2)
    y0, y1, y2 = _cross(h0, h1, h2, v0, v1, v2)
    return (
        m * v0 + x0,
        m * v1 + x1,
        m * v2 + x2,
        y0 + bI[j, 0, 0] * w0 + bI[j, 0, 1] * w1 + bI[j, 0, 2] * w2,
        y1 + bI[j, 1, 0] * w0 + bI[j, 1, 1] * w1 + bI[j, 1, 2] * w2,
        y2 + bI[j, 2, 0] * w0 + bI[j, 2, 1] * w1 + bI[j, 2, 2] * w2,
    )


@njit(cache=True, inline="always")
def motions(
    k: KernelArrays, v: np.ndarray, Sw: np.ndarray, Sv: np.ndarray, V: np.ndarray, A: np.ndarray
) -> None:
    """Body velocities ``V`` (nj, 6) and accelerations ``A`` (nj, 6) at qdd = 0, no gravity."""
    parents, kinds, idx_v = k.parents, k.kinds, k.idx_v
    for d in range(6):
        V[0, d] = A[0, d] = 0.0
    for j in range(1, parents.shape[0]):
        par, kind, c0 = parents[j], kinds[j], idx_v[j]
        n = joint_nv(kind)
        for d in range(6):
            V[j, d] = V[par, d]
            A[j, d] = A[par, d]
        for c in range(c0, c0 + n):
            for d in range(3):
                V[j, d] += Sv[c, d] * v[c]
                V[j, 3 + d] += Sw[c, d] * v[c]
        for c in range(c0, c0 + n):
            b = par if kind == UNIVERSAL and c == c0 else j  # the body the column is fixed in
            vx, vy, vz, wx, wy, wz = V[b, 0], V[b, 1], V[b, 2], V[b, 3], V[b, 4], V[b, 5]
            s0, s1, s2 = Sv[c, 0], Sv[c, 1], Sv[c, 2]
            u0, u1, u2 = Sw[c, 0], Sw[c, 1], Sw[c, 2]
            x0, x1, x2 = _cross(wx, wy, wz, s0, s1, s2)
            y0, y1, y2 = _cross(vx, vy, vz, u0, u1, u2)
            z0, z1, z2 = _cross(wx, wy, wz, u0, u1, u2)
            qd = v[c]
            A[j, 0] += (x0 + y0) * qd
            A[j, 1] += (x1 + y1) * qd
            A[j, 2] += (x2 + y2) * qd
            A[j, 3] += z0 * qd
            A[j, 4] += z1 * qd
            A[j, 5] += z2 * qd


@njit(cache=True, inline="always")
def mass_matrix(
    k: KernelArrays, Sw: np.ndarray, Sv: np.ndarray, bm: np.ndarray, bh: np.ndarray, bI: np.ndarray,
    cm: np.ndarray, ch: np.ndarray, cI: np.ndarray, M: np.ndarray,
) -> None:  # fmt: skip
    """The joint-space mass matrix, armature on its diagonal, into ``M`` (nv, nv) by composite inertias.

    ``cm``, ``ch``, ``cI``: scratch of the shapes of ``bm``, ``bh``, ``bI``.
    """
    parents, kinds, idx_v, armature = k.parents, k.kinds, k.idx_v, k.armature
    M[:, :] = 0.0  # columns on different branches do not couple
    cm[:] = bm
    ch[:] = bh
    cI[:] = bI
    for j in range(parents.shape[0] - 1, 0, -1):
        c0 = idx_v[j]
        for c in range(c0, c0 + joint_nv(kinds[j])):
            F = _apply(cm, ch, cI, j, Sv[c, 0], Sv[c, 1], Sv[c, 2], Sw[c, 0], Sw[c, 1], Sw[c, 2])
            i = j
            while i > 0:
                d0 = idx_v[i]
                for d in range(d0, d0 + joint_nv(kinds[i])):
                    x = (
                        Sv[d, 0] * F[0] + Sv[d, 1] * F[1] + Sv[d, 2] * F[2]
                        + Sw[d, 0] * F[3] + Sw[d, 1] * F[4] + Sw[d, 2] * F[5]
                    )  # fmt: skip
                    M[d, c] = x
                    M[c, d] = x
                i = parents[i]
        par = parents[j]
        cm[par] += cm[j]
        for a in range(3):
            ch[par, a] += ch[j, a]
            for b in range(3):
                cI[par, a, b] += cI[j, a, b]
    for c in range(M.shape[0]):
        M[c, c] += armature[c]


@njit(cache=True, inline="always")
def nonlinear_effects(
    k: KernelArrays, Sw: np.ndarray, Sv: np.ndarray, V: np.ndarray, A: np.ndarray,
    bm: np.ndarray, bh: np.ndarray, bI: np.ndarray, F: np.ndarray, out: np.ndarray,
) -> None:  # fmt: skip
    """Nonlinear effects ``rnea(q, v, 0)`` into ``out`` (nv,); ``F``: (nj, 6) scratch."""
    parents, kinds, idx_v, g = k.parents, k.kinds, k.idx_v, k.gravity
    nj = parents.shape[0]
    for d in range(6):
        F[0, d] = 0.0
    for j in range(1, nj):
        f = _apply(
            bm,
            bh,
            bI,
            j,
            A[j, 0] - g[0],
            A[j, 1] - g[1],
            A[j, 2] - g[2],
            A[j, 3] - g[3],
            A[j, 4] - g[4],
            A[j, 5] - g[5],
        )
        p = _apply(bm, bh, bI, j, V[j, 0], V[j, 1], V[j, 2], V[j, 3], V[j, 4], V[j, 5])
        vx, vy, vz, wx, wy, wz = V[j, 0], V[j, 1], V[j, 2], V[j, 3], V[j, 4], V[j, 5]
        x0, x1, x2 = _cross(wx, wy, wz, p[0], p[1], p[2])  # (v, w) x* (f, n) = (w x f, w x n + v x f)
        y0, y1, y2 = _cross(wx, wy, wz, p[3], p[4], p[5])
        z0, z1, z2 = _cross(vx, vy, vz, p[0], p[1], p[2])
        F[j, 0], F[j, 1], F[j, 2] = f[0] + x0, f[1] + x1, f[2] + x2
        F[j, 3], F[j, 4], F[j, 5] = f[3] + y0 + z0, f[4] + y1 + z1, f[5] + y2 + z2
    for j in range(nj - 1, 0, -1):
        c0 = idx_v[j]
        for c in range(c0, c0 + joint_nv(kinds[j])):
            out[c] = (
                Sv[c, 0] * F[j, 0] + Sv[c, 1] * F[j, 1] + Sv[c, 2] * F[j, 2]
                + Sw[c, 0] * F[j, 3] + Sw[c, 1] * F[j, 4] + Sw[c, 2] * F[j, 5]
            )  # fmt: skip
        par = parents[j]
        for d in range(6):
            F[par, d] += F[j, d]


@njit(cache=True, inline="always")
def potential_energy(k: KernelArrays, bh: np.ndarray) -> float:
    """Gravitational potential energy [J], ``pin.computePotentialEnergy``, from the bodies' ``h = m c``."""
    g = k.gravity
    e = 0.0
    for j in range(1, bh.shape[0]):
        e -= bh[j, 0] * g[0] + bh[j, 1] * g[1] + bh[j, 2] * g[2]
    return e


@njit(cache=True)
def _frame_motion(k: KernelArrays, f: int, fp: np.ndarray, V: np.ndarray, A: np.ndarray) -> tuple:
    """World-aligned velocity ``(v, w)`` and classical acceleration ``(a, alpha)`` of kernel frame ``f``."""
    j = k.f_joint[f]
    px, py, pz = fp[f, 0], fp[f, 1], fp[f, 2]
    w0, w1, w2 = V[j, 3], V[j, 4], V[j, 5]
    e0, e1, e2 = _cross(w0, w1, w2, px, py, pz)
    v0, v1, v2 = V[j, 0] + e0, V[j, 1] + e1, V[j, 2] + e2
    a0, a1, a2 = A[j, 3], A[j, 4], A[j, 5]
    x0, x1, x2 = _cross(a0, a1, a2, px, py, pz)
    y0, y1, y2 = _cross(w0, w1, w2, v0, v1, v2)
    return (
        (v0, v1, v2),
        (w0, w1, w2),
        (A[j, 0] + x0 + y0, A[j, 1] + x1 + y1, A[j, 2] + x2 + y2),
        (a0, a1, a2),
    )


@njit(cache=True)
def _jlog3_rate(theta: float, r: tuple, w: tuple) -> tuple:
    r"""The time derivative of ``Jlog3`` applied to ``w`` while the rotation moves at ``w`` (body frame).

    With :math:`J = \alpha I + [r]_\times / 2 + \beta r r^T` and :math:`\dot r = J w`:
    :math:`\dot J w = \dot\alpha w + \dot r \times w / 2 + \dot\beta (r^T w) r
    + \beta (\dot r^T w) r + \beta (r^T w) \dot r`, :math:`\dot\alpha = \alpha'(\theta)\, r^T \dot r / \theta`
    (likewise :math:`\beta`). Away from the identity only (the caller's test).
    """
    J = jlog3(theta, r[0], r[1], r[2])
    rd = _mv(J, w[0], w[1], w[2])
    st, ct = math.sin(theta), math.cos(theta)
    omc = 1.0 - ct
    beta = 1.0 / (theta * theta) - st / (2.0 * theta * omc)
    a1 = 0.5 * (st - theta) / (theta * omc)  # alpha'(theta) / theta
    b1 = -2.0 / theta**4 + (theta + st) / (2.0 * theta**3 * omc)  # beta'(theta) / theta
    rrd = r[0] * rd[0] + r[1] * rd[1] + r[2] * rd[2]
    rw = r[0] * w[0] + r[1] * w[1] + r[2] * w[2]
    rdw = rd[0] * w[0] + rd[1] * w[1] + rd[2] * w[2]
    x = _cross(rd[0], rd[1], rd[2], w[0], w[1], w[2])
    return (
        a1 * rrd * w[0] + 0.5 * x[0] + b1 * rrd * rw * r[0] + beta * rdw * r[0] + beta * rw * rd[0],
        a1 * rrd * w[1] + 0.5 * x[1] + b1 * rrd * rw * r[1] + beta * rdw * r[1] + beta * rw * rd[1],
        a1 * rrd * w[2] + 0.5 * x[2] + b1 * rrd * rw * r[2] + beta * rdw * r[2] + beta * rw * rd[2],
    )


@njit(cache=True, inline="always")
def drift(
    k: KernelArrays, fR: np.ndarray, fp: np.ndarray, V: np.ndarray, A: np.ndarray, series_angle: float,
    out: np.ndarray,
) -> None:  # fmt: skip
    r"""Closure drift :math:`\dot J_\phi v` into ``out`` (m,), (``closures.drift_from_data``).

    ``series_angle``: the weld rotation angle [rad] below which the second-order term of
    ``log3`` is left out (``LOG3_SERIES_ANGLE``, as the Python rows do).
    """
    c_kind, c_a, c_b, c_row, c_axis, c_E = k.c_kind, k.c_a, k.c_b, k.c_row, k.c_axis, k.c_E
    for i in range(c_kind.shape[0]):
        kind, s = c_kind[i], c_row[i]
        _, w_a, acc_a, al_a = _frame_motion(k, c_a[i], fp, V, A)
        _, w_b, acc_b, al_b = _frame_motion(k, c_b[i], fp, V, A)
        if kind != TWIST:
            out[s], out[s + 1], out[s + 2] = acc_b[0] - acc_a[0], acc_b[1] - acc_a[1], acc_b[2] - acc_a[2]
        if kind == POINT:
            continue
        dw = (w_b[0] - w_a[0], w_b[1] - w_a[1], w_b[2] - w_a[2])
        dal = (al_b[0] - al_a[0], al_b[1] - al_a[1], al_b[2] - al_a[2])
        Ra, Rb = _get(fR, c_a[i]), _get(fR, c_b[i])
        if kind == WELD:
            theta, l0, l1, l2 = log3(_t_mul(Ra, Rb))
            # r = log3(R_A^T R_B), r' = Jlog3 w_rel, w_rel = R_B^T dw, w_rel' = R_B^T (dalpha - w_b x dw)
            RbT = _t_mul(Rb, _EYE9)
            x = _cross(w_b[0], w_b[1], w_b[2], dw[0], dw[1], dw[2])
            w_rel = _mv(RbT, dw[0], dw[1], dw[2])
            d0, d1, d2 = _mv(RbT, dal[0] - x[0], dal[1] - x[1], dal[2] - x[2])
            g0, g1, g2 = _mv(jlog3(theta, l0, l1, l2), d0, d1, d2)
            if theta > series_angle:
                h0, h1, h2 = _jlog3_rate(theta, (l0, l1, l2), w_rel)
                g0, g1, g2 = g0 + h0, g1 + h1, g2 + h2
            out[s + 3], out[s + 4], out[s + 5] = g0, g1, g2
        elif kind == TWIST:
            x = _mv(Ra, c_E[i, 0, 1], c_E[i, 1, 1], c_E[i, 2, 1])
            y = _mv(Rb, c_E[i, 0, 0], c_E[i, 1, 0], c_E[i, 2, 0])
            dx = _cross(w_a[0], w_a[1], w_a[2], x[0], x[1], x[2])
            dy = _cross(w_b[0], w_b[1], w_b[2], y[0], y[1], y[2])
            p = _cross(al_a[0], al_a[1], al_a[2], x[0], x[1], x[2])
            e = _cross(w_a[0], w_a[1], w_a[2], dx[0], dx[1], dx[2])
            u = _cross(al_b[0], al_b[1], al_b[2], y[0], y[1], y[2])
            t = _cross(w_b[0], w_b[1], w_b[2], dy[0], dy[1], dy[2])
            out[s] = (
                (p[0] + e[0]) * y[0] + (p[1] + e[1]) * y[1] + (p[2] + e[2]) * y[2]
                + 2.0 * (dx[0] * dy[0] + dx[1] * dy[1] + dx[2] * dy[2])
                + x[0] * (u[0] + t[0]) + x[1] * (u[1] + t[1]) + x[2] * (u[2] + t[2])
            )  # fmt: skip
        else:  # revolute: E^T R_A^T (-w_a x (dw x w) + dalpha x w + dw x (w_b x w)), w = R_B u
            w = _mv(Rb, c_axis[i, 0], c_axis[i, 1], c_axis[i, 2])
            a = _cross(dw[0], dw[1], dw[2], w[0], w[1], w[2])
            a = _cross(w_a[0], w_a[1], w_a[2], a[0], a[1], a[2])
            b = _cross(dal[0], dal[1], dal[2], w[0], w[1], w[2])
            n = _cross(w_b[0], w_b[1], w_b[2], w[0], w[1], w[2])
            n = _cross(dw[0], dw[1], dw[2], n[0], n[1], n[2])
            t0, t1, t2 = -a[0] + b[0] + n[0], -a[1] + b[1] + n[1], -a[2] + b[2] + n[2]
            u0 = Ra[0] * t0 + Ra[3] * t1 + Ra[6] * t2
            u1 = Ra[1] * t0 + Ra[4] * t1 + Ra[7] * t2
            u2 = Ra[2] * t0 + Ra[5] * t1 + Ra[8] * t2
            for row in range(2):
                out[s + 3 + row] = c_E[i, 0, row] * u0 + c_E[i, 1, row] * u1 + c_E[i, 2, row] * u2


@njit(cache=True)
def terms(
    ints: np.ndarray, floats: np.ndarray, q: np.ndarray, v: np.ndarray, series_angle: float,
    M: np.ndarray, nle: np.ndarray, gamma: np.ndarray,
) -> float:  # fmt: skip
    """The dynamics terms at ``(q, v)`` on the packed arrays (``series_angle``: :func:`drift`'s).

    Writes the mass matrix into ``M`` (nv, nv), the nonlinear effects into ``nle`` (nv,) and the
    closure drift into ``gamma`` (m,).

    Returns:
        The potential energy [J].
    """
    k = unpack(ints, floats)
    nj, nf, nv = k.parents.shape[0], max(k.f_joint.shape[0], 1), k.nv
    oR, op, fR, fp = np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((nf, 3, 3)), np.empty((nf, 3))
    Sw, Sv = np.empty((nv, 3)), np.empty((nv, 3))
    forward(k, q, oR, op, Sw, Sv, True)
    frames(k, oR, op, fR, fp)
    bm, bh, bI = np.empty(nj), np.empty((nj, 3)), np.empty((nj, 3, 3))
    body_inertias(k, oR, op, bm, bh, bI)
    mass_matrix(k, Sw, Sv, bm, bh, bI, np.empty(nj), np.empty((nj, 3)), np.empty((nj, 3, 3)), M)
    V, A = np.empty((nj, 6)), np.empty((nj, 6))
    motions(k, v, Sw, Sv, V, A)
    nonlinear_effects(k, Sw, Sv, V, A, bm, bh, bI, np.empty((nj, 6)), nle)
    drift(k, fR, fp, V, A, series_angle, gamma)
    return potential_energy(k, bh)


@njit(cache=True)
def _distance(k: KernelArrays, r: np.ndarray) -> float:
    """Closure distance of ``r``: the largest norm of a closure's point rows [m] or other rows [rad]."""
    c_kind, c_row = k.c_kind, k.c_row
    nc, m = c_kind.shape[0], k.m
    out = 0.0
    for i in range(nc):
        s = c_row[i]
        stop = c_row[i + 1] if i + 1 < nc else m
        p = 0 if c_kind[i] == TWIST else 3
        a = 0.0
        for e in range(s, s + p):
            a += r[e] * r[e]
        b = 0.0
        for e in range(s + p, stop):
            b += r[e] * r[e]
        out = max(out, a, b)
    return math.sqrt(out)


@njit(cache=True)
def _finite(x: np.ndarray) -> bool:
    for e in x.flat:
        if not math.isfinite(e):
            return False
    return True


@njit(cache=True)
def _rank_lost(s: np.ndarray, rank: int, rank_rtol: float) -> bool:
    """Whether the ``rank``-th singular value of ``s`` (descending) is lost: a constraint singularity."""
    return rank > 0 and s[rank - 1] <= rank_rtol * max(s[0], 1.0)


@njit(cache=True)
def samples(
    ints: np.ndarray, floats: np.ndarray, Y: np.ndarray, origin: np.ndarray, euclidean: bool,
    tau: np.ndarray, rank: int, tol: float, velocity_tol: float, rank_rtol: float, series_angle: float,
    Q: np.ndarray, Vel: np.ndarray, Acc: np.ndarray, Lam: np.ndarray, after: np.ndarray,
    before: np.ndarray, energy: np.ndarray, potential: np.ndarray, X: np.ndarray,
) -> tuple:  # fmt: skip
    r"""Project and evaluate the states ``Y`` (n, 2 nv) in turn, as the Python sample path does.

    Each row holds the chart coordinates (the configuration when ``euclidean``, else its
    tangent at ``origin``) and the velocities. The configuration moves by one minimum-norm
    Gauss-Newton step when its closure distance passes ``tol``; the velocity is projected by the
    least-kinetic-energy saddle system when the configuration moved or :math:`|J_\phi v|`
    passes ``velocity_tol``; then the KKT solve with :math:`W = V_r^T` gives the accelerations
    and minimum-norm closure forces. Into row ``i`` of ``Q``, ``Vel``, ``Acc``, ``Lam``,
    ``after`` (closure distance), ``before`` (before the projection), ``energy`` (kinetic plus
    potential), ``potential`` and ``X`` (task pose).

    Returns:
        ``(i, status)``: the samples done, and why the next one needs the Python path
        (:data:`SINGULAR`, :data:`OFF_MANIFOLD` after one step, :data:`NON_FINITE`); ``DONE``
        when all are.
    """
    k = unpack(ints, floats)
    nj, nf, nv, m = k.parents.shape[0], max(k.f_joint.shape[0], 1), k.nv, k.m
    oR, op, fR, fp = np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((nf, 3, 3)), np.empty((nf, 3))
    Sw, Sv = np.empty((nv, 3)), np.empty((nv, 3))
    bm, bh, bI = np.empty(nj), np.empty((nj, 3)), np.empty((nj, 3, 3))
    cm, ch, cI = np.empty(nj), np.empty((nj, 3)), np.empty((nj, 3, 3))
    V, A, F = np.empty((nj, 6)), np.empty((nj, 6)), np.empty((nj, 6))
    r, J = np.empty(m), np.empty((m, nv))
    M, h, gamma = np.empty((nv, nv)), np.empty(nv), np.empty(m)
    K, rhs = np.zeros((nv + rank, nv + rank)), np.empty(nv + rank)
    q, dq = np.empty(Q.shape[1]), np.empty(nv)
    for i in range(Y.shape[0]):
        y = Y[i]
        if not _finite(y):
            return i, NON_FINITE
        if euclidean:
            q[:] = y[:nv]
        else:
            integrate(k, origin, y[:nv], q)
        v = y[nv:].copy()
        forward(k, q, oR, op, Sw, Sv, True)
        frames(k, oR, op, fR, fp)
        closure_rows(k, fR, fp, Sw, Sv, r, J, True)
        d_before = d_after = _distance(k, r)
        moved = d_before > tol
        if moved:
            U, s, Vt = np.linalg.svd(J, full_matrices=False)
            if _rank_lost(s, rank, rank_rtol):
                return i, SINGULAR
            for c in range(nv):
                dq[c] = 0.0
            for e in range(rank):
                x = 0.0
                for row in range(m):
                    x += U[row, e] * r[row]
                x /= s[e]
                for c in range(nv):
                    dq[c] -= Vt[e, c] * x
            q0 = q.copy()
            integrate(k, q0, dq, q)
            forward(k, q, oR, op, Sw, Sv, True)
            frames(k, oR, op, fR, fp)
            closure_rows(k, fR, fp, Sw, Sv, r, J, True)
            d_after = _distance(k, r)
            if d_after > tol:
                return i, OFF_MANIFOLD
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        if _rank_lost(s, rank, rank_rtol):
            return i, SINGULAR
        Vt = np.ascontiguousarray(Vt)  # (LAPACK's layout) for the product below
        body_inertias(k, oR, op, bm, bh, bI)
        mass_matrix(k, Sw, Sv, bm, bh, bI, cm, ch, cI, M)
        K[:nv, :nv] = M
        for e in range(rank):
            for c in range(nv):
                K[c, nv + e] = -Vt[e, c]
                K[nv + e, c] = Vt[e, c]
        rate = np.max(np.abs(J @ v)) if m else 0.0  # the largest closure rate
        if moved or rate > velocity_tol:  # min |v+ - v|_M on W v+ = 0
            rhs[:nv] = 0.0
            rhs[nv : nv + rank] = -(Vt[:rank] @ v)
            sol = np.linalg.solve(K, rhs)
            for c in range(nv):
                v[c] += sol[c]
        motions(k, v, Sw, Sv, V, A)
        nonlinear_effects(k, Sw, Sv, V, A, bm, bh, bI, F, h)
        drift(k, fR, fp, V, A, series_angle, gamma)
        for c in range(nv):
            rhs[c] = tau[c] - h[c]
        for e in range(rank):
            x = 0.0
            for row in range(m):
                x += U[row, e] * gamma[row]
            rhs[nv + e] = -x / s[e]
        sol = np.linalg.solve(K, rhs)
        for row in range(m):
            x = 0.0
            for e in range(rank):
                x += U[row, e] * (sol[nv + e] / s[e])
            Lam[i, row] = x
        Acc[i, :] = sol[:nv]
        if not (_finite(Acc[i]) and _finite(Lam[i])):
            return i, NON_FINITE
        kinetic = 0.0
        for a in range(nv):
            x = 0.0
            for b in range(nv):
                x += M[a, b] * v[b]
            kinetic += v[a] * x
        pot = potential_energy(k, bh)
        Q[i, :] = q
        Vel[i, :] = v
        after[i], before[i] = d_after, d_before
        energy[i], potential[i] = 0.5 * kinetic + pot, pot
        if X.shape[1]:
            task_pose(k, q, fR, fp, X[i])
    return Y.shape[0], DONE
