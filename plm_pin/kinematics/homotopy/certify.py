r"""Interval certificates: a Krawczyk test that a box holds exactly one real solution.

For the square real system :math:`F(x) = 0` (the polynomial form at real actuator values),
an approximate root :math:`\tilde x`, a box :math:`X \ni \tilde x` and any matrix :math:`Y`
(here the inverse of :math:`F_x(\tilde x)`), the Krawczyk operator

.. math:: K(X) = \tilde x - Y F(\tilde x) + (I - Y F_x(X)) (X - \tilde x)

evaluated in interval arithmetic, if it lies in the interior of :math:`X`, proves that
:math:`X` holds exactly one root of :math:`F` (Krawczyk 1969; Moore, Kearfott & Cloud,
*Introduction to Interval Analysis*, 2009, thm. 8.2), and that :math:`F_x` is non-singular
on it. :math:`F(\tilde x)` and the interval Jacobian :math:`F_x(X)` come from the same
forward kinematics as :mod:`.evaluation`, carried out on intervals: every sum and product
is rounded outward by one ``nextafter`` step on each side (an IEEE operation in
round-to-nearest errs by at most half an ulp), the axes, placements and the random
combination are the exact floating-point numbers of the form, and the cosine and sine of
an actuated angle are widened by two ulps on each side (libm's error is below one ulp).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...tolerances import HOMOTOPY_MAX_BOX_RTOL
from .form import FREE_FLYER, PRISMATIC, PRISMATIC_PARAM, REVOLUTE, REVOLUTE_PARAM, SPHERICAL, PolynomialForm

BOX_GROWTH = (4.0, 64.0, 1024.0)
"""Half-widths of the boxes tried, in order, as multiples of the Newton enclosure's size."""


@njit(cache=True)
def _dn(v: float) -> float:
    return np.nextafter(v, -np.inf)


@njit(cache=True)
def _up(v: float) -> float:
    return np.nextafter(v, np.inf)


@njit(cache=True)
def _mul2(alo: float, ahi: float, blo: float, bhi: float) -> tuple[float, float]:
    p1, p2, p3, p4 = alo * blo, alo * bhi, ahi * blo, ahi * bhi
    return _dn(min(min(p1, p2), min(p3, p4))), _up(max(max(p1, p2), max(p3, p4)))


@njit(cache=True)
def _add(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty(2)
    out[0], out[1] = _dn(a[0] + b[0]), _up(a[1] + b[1])
    return out


@njit(cache=True)
def _mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    p1, p2, p3, p4 = a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]
    out = np.empty(2)
    out[0] = _dn(min(min(p1, p2), min(p3, p4)))
    out[1] = _up(max(max(p1, p2), max(p3, p4)))
    return out


@njit(cache=True)
def _point(M: np.ndarray) -> np.ndarray:
    """A float array as degenerate intervals, shape (..., 2)."""
    out = np.empty((*M.shape, 2))
    out[..., 0] = M
    out[..., 1] = M
    return out


@njit(cache=True)
def _matmul(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Interval matrix product, A (m, k, 2), B (k, n, 2)."""
    m, k, n = A.shape[0], A.shape[1], B.shape[1]
    out = np.zeros((m, n, 2))
    for i in range(m):
        for j in range(n):
            lo, hi = 0.0, 0.0
            for r in range(k):
                alo, ahi, blo, bhi = A[i, r, 0], A[i, r, 1], B[r, j, 0], B[r, j, 1]
                if (alo == 0.0 and ahi == 0.0) or (blo == 0.0 and bhi == 0.0):
                    continue  # an exact zero term: the sum is unchanged, exactly
                plo, phi = _mul2(alo, ahi, blo, bhi)
                lo, hi = _dn(lo + plo), _up(hi + phi)
            out[i, j, 0], out[i, j, 1] = lo, hi
    return out


@njit(cache=True)
def _neg(a: np.ndarray) -> np.ndarray:
    out = np.empty_like(a)
    out[..., 0] = -a[..., 1]
    out[..., 1] = -a[..., 0]
    return out


@njit(cache=True)
def _madd(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Element-wise interval sum of two arrays of intervals."""
    out = np.empty_like(A)
    flat_a, flat_b, flat_o = A.reshape(-1, 2), B.reshape(-1, 2), out.reshape(-1, 2)
    for i in range(flat_a.shape[0]):
        flat_o[i] = _add(flat_a[i], flat_b[i])
    return out


@njit(cache=True)
def _transpose(A: np.ndarray) -> np.ndarray:
    out = np.empty((A.shape[1], A.shape[0], 2))
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            out[j, i] = A[i, j]
    return out


@njit(cache=True)
def _local(
    kind: int, axis: np.ndarray, fixed: np.ndarray, v: np.ndarray, X: np.ndarray, dX: np.ndarray
) -> int:
    """Interval local transform of one joint (coordinates ``v`` (k, 2)) and its derivatives."""
    X[:] = 0.0
    X[3, 3] = 1.0
    one = np.ones(2)
    if kind == REVOLUTE or kind == REVOLUTE_PARAM:
        K = np.zeros((3, 3))
        K[0, 1], K[0, 2], K[1, 2] = -axis[2], axis[1], -axis[0]
        K[1, 0], K[2, 0], K[2, 1] = axis[2], -axis[1], axis[0]
        Ki = _point(K)
        K2 = _matmul(Ki, Ki)
        c, s = v[0], v[1]
        omc = np.empty(2)
        omc[0], omc[1] = _dn(1.0 - c[1]), _up(1.0 - c[0])
        for r in range(3):
            for k in range(3):
                e = _add(_mul(s, Ki[r, k]), _mul(omc, K2[r, k]))
                if r == k:
                    e = _add(e, one)
                X[r, k] = e
        if kind == REVOLUTE:
            dX[0] = 0.0
            dX[1] = 0.0
            dX[0, :3, :3] = _neg(K2)
            dX[1, :3, :3] = Ki
            return 2
        return 0
    if kind == PRISMATIC or kind == PRISMATIC_PARAM:
        for r in range(3):
            X[r, r] = one
            X[r, 3] = _mul(v[0], _point(axis[r : r + 1])[0])
        if kind == PRISMATIC:
            dX[0] = 0.0
            for r in range(3):
                dX[0, r, 3] = axis[r]
            return 1
        return 0
    if kind == SPHERICAL or kind == FREE_FLYER:
        t = 3 if kind == FREE_FLYER else 0
        w, x, y, z = v[t], v[t + 1], v[t + 2], v[t + 3]
        ww, xx, yy, zz = _mul(w, w), _mul(x, x), _mul(y, y), _mul(z, z)
        xy, wz, xz, wy, yz, wx = _mul(x, y), _mul(w, z), _mul(x, z), _mul(w, y), _mul(y, z), _mul(w, x)
        X[0, 0] = _add(_add(ww, xx), _neg(_add(yy, zz)))
        X[1, 1] = _add(_add(ww, yy), _neg(_add(xx, zz)))
        X[2, 2] = _add(_add(ww, zz), _neg(_add(xx, yy)))
        X[0, 1] = 2.0 * _add(xy, _neg(wz))
        X[1, 0] = 2.0 * _add(xy, wz)
        X[0, 2] = 2.0 * _add(xz, wy)
        X[2, 0] = 2.0 * _add(xz, _neg(wy))
        X[1, 2] = 2.0 * _add(yz, _neg(wx))
        X[2, 1] = 2.0 * _add(yz, wx)
        for k in range(t + 4):
            dX[k] = 0.0
        for r in range(t):
            X[r, 3] = v[r]
            dX[r, r, 3] = 1.0
        w2, x2, y2, z2 = 2.0 * w, 2.0 * x, 2.0 * y, 2.0 * z  # exact
        mw, mx, my, mz = _neg(w2), _neg(x2), _neg(y2), _neg(z2)
        rows = (
            ((w2, mz, y2), (z2, w2, mx), (my, x2, w2)),
            ((x2, y2, z2), (y2, mx, mw), (z2, w2, mx)),
            ((my, x2, w2), (x2, y2, z2), (mw, z2, my)),
            ((mz, mw, x2), (w2, mz, y2), (x2, y2, z2)),
        )
        for k in range(4):
            for r in range(3):
                for c in range(3):
                    dX[t + k, r, c] = rows[k][r][c]
        return t + 4
    X[:] = _point(fixed)
    return 0


@njit(cache=True)
def interval_system(
    xi: np.ndarray,
    pi: np.ndarray,
    parent: np.ndarray,
    kind: np.ndarray,
    offset: np.ndarray,
    axis: np.ndarray,
    placement: np.ndarray,
    fixed: np.ndarray,
    frame_joint: np.ndarray,
    frame_placement: np.ndarray,
    closure_kind: np.ndarray,
    closure_frames: np.ndarray,
    closure_axis: np.ndarray,
    closure_length2: np.ndarray,
    entry_offset: np.ndarray,
    combination: np.ndarray,
    unit_offsets: np.ndarray,
    unit_sizes: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Enclosures of F (n, 2) and F_x (n, n, 2) over the box ``xi`` (n, 2).

    ``pi`` holds the parameters as intervals: (cos, sin) of each actuated angle, or the
    displacement twice, shape (n_params, 2, 2).
    """
    n, k = xi.shape[0], kind.shape[0]
    Xs = np.zeros((k, 4, 4, 2))
    dXs = np.zeros((k, 7, 4, 4, 2))
    ncoord = np.zeros(k, dtype=np.int64)
    T = np.zeros((k, 4, 4, 2))
    A = np.zeros((k, 4, 4, 2))
    MX = np.zeros((k, 4, 4, 2))  # M_i X_i, shared by the frames below joint i
    AdX = np.zeros((k, 7, 4, 4, 2))  # A_i dX_i, likewise
    for i in range(k):
        kd = kind[i]
        if kd == REVOLUTE_PARAM or kd == PRISMATIC_PARAM:
            v = pi[offset[i]]
        elif kd == 0:
            v = xi[:0]
        else:
            v = xi[offset[i] : offset[i] + 7]
        ncoord[i] = _local(kd, axis[i], fixed[i], v, Xs[i], dXs[i])
        Mi = _point(placement[i])
        A[i] = _matmul(T[parent[i]], Mi) if parent[i] >= 0 else Mi
        T[i] = _matmul(A[i], Xs[i])
        MX[i] = _matmul(Mi, Xs[i])
        for c in range(ncoord[i]):
            AdX[i, c] = _matmul(A[i], dXs[i, c])
    nf = frame_joint.shape[0]
    Tf = np.zeros((nf, 4, 4, 2))
    dTf = np.zeros((nf, n, 4, 4, 2))
    for f in range(nf):
        point = True  # only the frame's origin is read (point and distance closures)
        for c in range(closure_kind.shape[0]):
            if (closure_kind[c] == 1 or closure_kind[c] == 2) and (
                closure_frames[c, 0] == f or closure_frames[c, 1] == f
            ):
                point = False
        # the origin alone is the last column of each product: the same operations on one column
        S = _point(frame_placement[f]) if not point else _point(frame_placement[f][:, 3:4].copy())
        i = frame_joint[f]
        if i >= 0:
            P = _matmul(T[i], S)
        else:
            P = S
        if point:
            Tf[f, :, 3] = P[:, 0]
        else:
            Tf[f] = P
        while i >= 0:
            for c in range(ncoord[i]):
                P = _matmul(AdX[i, c], S)
                if point:
                    dTf[f, offset[i] + c, :, 3] = P[:, 0]
                else:
                    dTf[f, offset[i] + c] = P
            S = _matmul(MX[i], S)
            i = parent[i]
    m = combination.shape[1]
    e = np.zeros((m, 2))
    de = np.zeros((m, n, 2))
    for c in range(closure_kind.shape[0]):
        a, b, o = closure_frames[c, 0], closure_frames[c, 1], entry_offset[c]
        if closure_kind[c] == 3:  # |p_B - p_A|^2 - L^2, L^2 = |p_L|^2 for an actuated strut L
            acc = np.empty(2)
            acc[0], acc[1] = -closure_length2[c], -closure_length2[c]
            g = closure_frames[c, 2]
            for r in range(3):
                d = _add(Tf[b, r, 3], _neg(Tf[a, r, 3]))
                acc = _add(acc, _mul(d, d))
                if g >= 0:  # the strut hangs from the world on a parameter: no x-derivative
                    acc = _add(acc, _neg(_mul(Tf[g, r, 3], Tf[g, r, 3])))
                for j in range(n):
                    dd = _add(dTf[b, j, r, 3], _neg(dTf[a, j, r, 3]))
                    de[o, j] = _add(de[o, j], 2.0 * _mul(d, dd))
            e[o] = acc
            continue
        for r in range(3):
            e[o + r] = _add(Tf[b, r, 3], _neg(Tf[a, r, 3]))
            for j in range(n):
                de[o + r, j] = _add(dTf[b, j, r, 3], _neg(dTf[a, j, r, 3]))
        if closure_kind[c] == 0:
            continue
        RaT, Rb = _transpose(Tf[a, :3, :3]), Tf[b, :3, :3].copy()
        E = _matmul(RaT, Rb)
        if closure_kind[c] == 1:
            for r in range(3):
                for s in range(3):
                    e[o + 3 + 3 * r + s] = E[r, s] if r != s else _add(E[r, s], -np.ones(2))
            for j in range(n):
                dE = _madd(_matmul(_transpose(dTf[a, j, :3, :3]), Rb), _matmul(RaT, dTf[b, j, :3, :3].copy()))
                for r in range(3):
                    for s in range(3):
                        de[o + 3 + 3 * r + s, j] = dE[r, s]
        else:
            u = _point(closure_axis[c].reshape(3, 1))
            Eu = _matmul(E, u)
            for r in range(3):
                e[o + 3 + r] = _add(Eu[r, 0], _neg(u[r, 0]))
            for j in range(n):
                dE = _madd(_matmul(_transpose(dTf[a, j, :3, :3]), Rb), _matmul(RaT, dTf[b, j, :3, :3].copy()))
                dEu = _matmul(dE, u)
                for r in range(3):
                    de[o + 3 + r, j] = dEu[r, 0]
    F = np.zeros((n, 2))
    J = np.zeros((n, n, 2))
    nu = unit_offsets.shape[0]
    for q in range(nu):
        o = unit_offsets[q]
        acc = -np.ones(2)
        for r in range(unit_sizes[q]):
            xr = xi[o + r]
            sq = np.empty(2)  # the square of an interval (tighter than a product)
            lo2, hi2 = xr[0] * xr[0], xr[1] * xr[1]
            if xr[0] <= 0.0 <= xr[1]:
                sq[0], sq[1] = 0.0, _up(max(lo2, hi2))
            else:
                sq[0], sq[1] = _dn(min(lo2, hi2)), _up(max(lo2, hi2))
            acc = _add(acc, sq)
            J[q, o + r] = 2.0 * xr
        F[q] = acc
    C = _point(combination)
    F[nu:] = _matmul(C, e.reshape(m, 1, 2)).reshape(n - nu, 2)
    for j in range(n):
        col = _matmul(C, de[:, j].copy().reshape(m, 1, 2))
        for r in range(n - nu):
            J[nu + r, j] = col[r, 0]
    return F, J


@njit(cache=True)
def krawczyk(x: np.ndarray, radius: float, pi: np.ndarray, args: tuple, Fx: np.ndarray) -> bool:
    """Whether the box ``x +- radius (1 + abs(x))`` provably holds exactly one root (Krawczyk test).

    ``Fx`` is the enclosure of F at the point ``x`` (:func:`interval_system`), shape (n, 2).
    """
    n = x.shape[0]
    box = np.empty((n, 2))
    for i in range(n):
        r = radius * (1.0 + abs(x[i]))
        box[i, 0], box[i, 1] = _dn(x[i] - r), _up(x[i] + r)
    _, JX = interval_system(box, pi, *args)
    Jmid = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            Jmid[i, j] = 0.5 * (JX[i, j, 0] + JX[i, j, 1])
    Y = np.linalg.inv(Jmid)
    Yi = _point(Y)
    YF = _matmul(Yi, Fx.reshape(n, 1, 2)).reshape(n, 2)
    M = _neg(_matmul(Yi, JX))
    for i in range(n):
        M[i, i] = _add(M[i, i], np.ones(2))
    d = np.empty((n, 1, 2))
    for i in range(n):
        d[i, 0, 0], d[i, 0, 1] = _dn(box[i, 0] - x[i]), _up(box[i, 1] - x[i])
    Md = _matmul(M, d).reshape(n, 2)
    for i in range(n):
        lo = _dn(_dn(x[i] - YF[i, 1]) + Md[i, 0])
        hi = _up(_up(x[i] - YF[i, 0]) + Md[i, 1])
        if not (box[i, 0] < lo and hi < box[i, 1]):
            return False
    return True


def parameter_intervals(form: PolynomialForm, actuators: np.ndarray) -> np.ndarray:
    """Actuator values as the interval parameters of :func:`interval_system`, shape (n_params, 2, 2)."""
    pi = np.zeros((form.n_params, 2, 2))
    for i, kd in enumerate(form.kind):
        if kd == REVOLUTE_PARAM:
            o, a = int(form.offset[i]), float(actuators[int(form.offset[i])])
            for slot, value in ((0, np.cos(a)), (1, np.sin(a))):
                pi[o, slot] = (
                    np.nextafter(np.nextafter(value, -np.inf), -np.inf),
                    np.nextafter(np.nextafter(value, np.inf), np.inf),
                )
        elif kd == PRISMATIC_PARAM:
            o = int(form.offset[i])
            pi[o, 0] = pi[o, 1] = float(actuators[o])
    return pi


@njit(cache=True)
def newton_size(x: np.ndarray, pi: np.ndarray, args: tuple) -> tuple[float, np.ndarray]:
    r"""Size of the Newton enclosure at ``x``: the largest :math:`|Y F([\tilde x])|` (a float bound).

    The Krawczyk box must hold this (the root lies about one Newton step away, plus the rounding
    of :math:`F`, magnified by the conditioning), and should not be much larger (the interval
    Jacobian over a wide box stops the contraction). A fixed width fails one way or the other on
    an ill-conditioned root. Infinite when the Jacobian is singular. Also returns the enclosure of
    F at ``x`` (the Krawczyk test's).
    """
    n = x.shape[0]
    Fx, Jx = interval_system(_point(x), pi, *args)
    Jmid = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            Jmid[i, j] = 0.5 * (Jx[i, j, 0] + Jx[i, j, 1])
    if np.linalg.matrix_rank(Jmid) < n:
        return np.inf, Fx
    Y = np.linalg.inv(Jmid)
    out = 0.0
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += abs(Y[i, j]) * max(abs(Fx[j, 0]), abs(Fx[j, 1]))
        out = max(out, acc)
    return out, Fx


def certify(
    form: PolynomialForm, x: np.ndarray, actuators: np.ndarray, pi: np.ndarray | None = None
) -> float | None:
    """Half-width (relative, times 1 + abs(x)) of a box around real ``x`` proven to hold one root, or None.

    The boxes tried are :data:`BOX_GROWTH` times the Newton enclosure's size (:func:`newton_size`),
    at most :data:`~plm_pin.tolerances.HOMOTOPY_MAX_BOX_RTOL`. ``pi``: the actuators'
    :func:`parameter_intervals`, when the caller has them.
    """
    if pi is None:
        pi = parameter_intervals(form, actuators)
    args = form.kernel_args()
    x = np.asarray(x, dtype=float)
    size, Fx = newton_size(x, pi, args)
    size = max(size, float(np.finfo(float).eps))
    for growth in BOX_GROWTH:
        radius = growth * size
        if not radius <= HOMOTOPY_MAX_BOX_RTOL:
            break
        if krawczyk(x, radius, pi, args, Fx):
            return radius
    return None
