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

The compiled kernels write into one workspace per certificate (:func:`workspace`), take
``nextafter`` as an operation on the bits (the same result, without a library call), and
multiply by an exact factor (placement, axis, combination, Y) with two products instead of four
(the same bounds).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core.typing.templates import Signature
from numba.extending import intrinsic

from ...tolerances import HOMOTOPY_MAX_BOX_RTOL
from .form import (
    FIXED,
    FREE_FLYER,
    PRISMATIC,
    PRISMATIC_PARAM,
    REVOLUTE,
    REVOLUTE_PARAM,
    SPHERICAL,
    PolynomialForm,
)

BOX_GROWTH = (4.0, 64.0, 1024.0)
"""Half-widths of the boxes tried, in order, as multiples of the Newton enclosure's size."""


_FLOAT_EPSILON = float(np.finfo(np.float64).eps)  # machine epsilon (IEEE doubles), not a tolerance
_TINY = float(np.nextafter(0.0, 1.0))  # the smallest positive (subnormal) double
_NEG_ZERO = int(np.array(-0.0).view(np.int64))  # the bits of -0.0, +inf and -inf
_POS_INF = int(np.array(np.inf).view(np.int64))
_NEG_INF = int(np.array(-np.inf).view(np.int64))


@intrinsic
def _bits(typingctx: object, v: types.Type) -> tuple[Signature, Callable[..., ir.Value]]:
    """The IEEE 754 bits of a double as an int64 (a bit cast, no conversion)."""

    def codegen(
        context: object, builder: ir.IRBuilder, signature: Signature, args: list[ir.Value]
    ) -> ir.Value:
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def _double(typingctx: object, b: types.Type) -> tuple[Signature, Callable[..., ir.Value]]:
    """The double whose IEEE 754 bits are the int64 ``b``."""

    def codegen(
        context: object, builder: ir.IRBuilder, signature: Signature, args: list[ir.Value]
    ) -> ir.Value:
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


@njit(cache=True)
def _up(v: float) -> float:
    """``nextafter(v, inf)``, bit for bit, without the library call (the kernels take thousands).

    The next double up has the next integer as bits for a positive double (+0 included: its
    successor is the least subnormal), the previous one for a negative double; -0 goes to the
    least subnormal and infinity stays (a NaN stays a NaN).
    """
    b: int = _bits(v)  # type: ignore[call-arg]
    if b == _NEG_ZERO:
        return _TINY
    if b == _POS_INF:
        return v
    return _double(b + ((b >> 63) | 1))


@njit(cache=True)
def _dn(v: float) -> float:
    """``nextafter(v, -inf)``, bit for bit: the mirror image of :func:`_up`."""
    b: int = _bits(v)  # type: ignore[call-arg]
    if b == 0:
        return -_TINY
    if b == _NEG_INF:
        return v
    return _double(b - ((b >> 63) | 1))


@njit(cache=True)
def _mul2(alo: float, ahi: float, blo: float, bhi: float) -> tuple[float, float]:
    """``[alo, ahi] [blo, bhi]`` rounded outward."""
    p1, p2, p3, p4 = alo * blo, alo * bhi, ahi * blo, ahi * bhi
    return _dn(min(min(p1, p2), min(p3, p4))), _up(max(max(p1, p2), max(p3, p4)))


@njit(cache=True)
def _add2(alo: float, ahi: float, blo: float, bhi: float) -> tuple[float, float]:
    return _dn(alo + blo), _up(ahi + bhi)


@njit(cache=True)
def _fma2(lo: float, hi: float, alo: float, ahi: float, blo: float, bhi: float) -> tuple[float, float]:
    """``[lo, hi] + [alo, ahi] [blo, bhi]``; an exact zero factor leaves the sum unchanged, exactly."""
    if (alo == 0.0 and ahi == 0.0) or (blo == 0.0 and bhi == 0.0):
        return lo, hi
    plo, phi = _mul2(alo, ahi, blo, bhi)
    return _dn(lo + plo), _up(hi + phi)


@njit(cache=True)
def _pfma2(lo: float, hi: float, y: float, blo: float, bhi: float) -> tuple[float, float]:
    """:func:`_fma2` by the point ``y``: of the four products two pairs are equal, so two are taken."""
    if y == 0.0 or (blo == 0.0 and bhi == 0.0):
        return lo, hi
    p, q = y * blo, y * bhi
    return _dn(lo + _dn(min(p, q))), _up(hi + _up(max(p, q)))


@njit(cache=True)
def _mm_into(A: np.ndarray, a: int, B: np.ndarray, b: int, out: np.ndarray, o: int) -> None:
    """``out[o] = A[a] B[b]`` for stacks of interval 4 x 4 matrices, shape (., 4, 4, 2).

    Each entry sums its terms in order; a row's four entries are carried together (four
    independent chains of roundings for the processor to overlap).
    """
    for i in range(4):
        l0, h0, l1, h1, l2, h2, l3, h3 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        for r in range(4):
            alo, ahi = A[a, i, r, 0], A[a, i, r, 1]
            if alo == 0.0 and ahi == 0.0:
                continue  # an exact zero factor: every sum of the row is unchanged, exactly
            l0, h0 = _fma2(l0, h0, alo, ahi, B[b, r, 0, 0], B[b, r, 0, 1])
            l1, h1 = _fma2(l1, h1, alo, ahi, B[b, r, 1, 0], B[b, r, 1, 1])
            l2, h2 = _fma2(l2, h2, alo, ahi, B[b, r, 2, 0], B[b, r, 2, 1])
            l3, h3 = _fma2(l3, h3, alo, ahi, B[b, r, 3, 0], B[b, r, 3, 1])
        out[o, i, 0, 0], out[o, i, 0, 1], out[o, i, 1, 0], out[o, i, 1, 1] = l0, h0, l1, h1
        out[o, i, 2, 0], out[o, i, 2, 1], out[o, i, 3, 0], out[o, i, 3, 1] = l2, h2, l3, h3


@njit(cache=True)
def _mm_point_left(P: np.ndarray, p: int, B: np.ndarray, b: int, out: np.ndarray, o: int) -> None:
    """``out[o] = P[p] B[b]`` for a stack ``P`` of exact (float) 4 x 4 matrices, as :func:`_mm_into`."""
    for i in range(4):
        l0, h0, l1, h1, l2, h2, l3, h3 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        for r in range(4):
            y = P[p, i, r]
            if y == 0.0:
                continue
            l0, h0 = _pfma2(l0, h0, y, B[b, r, 0, 0], B[b, r, 0, 1])
            l1, h1 = _pfma2(l1, h1, y, B[b, r, 1, 0], B[b, r, 1, 1])
            l2, h2 = _pfma2(l2, h2, y, B[b, r, 2, 0], B[b, r, 2, 1])
            l3, h3 = _pfma2(l3, h3, y, B[b, r, 3, 0], B[b, r, 3, 1])
        out[o, i, 0, 0], out[o, i, 0, 1], out[o, i, 1, 0], out[o, i, 1, 1] = l0, h0, l1, h1
        out[o, i, 2, 0], out[o, i, 2, 1], out[o, i, 3, 0], out[o, i, 3, 1] = l2, h2, l3, h3


@njit(cache=True)
def _mm_point_right(A: np.ndarray, a: int, P: np.ndarray, p: int, out: np.ndarray, o: int) -> None:
    """``out[o] = A[a] P[p]`` for a stack ``P`` of exact (float) 4 x 4 matrices, as :func:`_mm_into`."""
    for i in range(4):
        l0, h0, l1, h1, l2, h2, l3, h3 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        for r in range(4):
            alo, ahi = A[a, i, r, 0], A[a, i, r, 1]
            if alo == 0.0 and ahi == 0.0:
                continue
            l0, h0 = _pfma2(l0, h0, P[p, r, 0], alo, ahi)
            l1, h1 = _pfma2(l1, h1, P[p, r, 1], alo, ahi)
            l2, h2 = _pfma2(l2, h2, P[p, r, 2], alo, ahi)
            l3, h3 = _pfma2(l3, h3, P[p, r, 3], alo, ahi)
        out[o, i, 0, 0], out[o, i, 0, 1], out[o, i, 1, 0], out[o, i, 1, 1] = l0, h0, l1, h1
        out[o, i, 2, 0], out[o, i, 2, 1], out[o, i, 3, 0], out[o, i, 3, 1] = l2, h2, l3, h3


@njit(cache=True)
def _mv_into(A: np.ndarray, a: int, B: np.ndarray, b: int, out: np.ndarray, o: int) -> None:
    """``out[o, :, 3] = A[a] B[b, :, 3]``: the last column alone (a point carried by a transform)."""
    l0, h0, l1, h1, l2, h2, l3, h3 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for r in range(4):
        blo, bhi = B[b, r, 3, 0], B[b, r, 3, 1]
        if blo == 0.0 and bhi == 0.0:
            continue
        l0, h0 = _fma2(l0, h0, A[a, 0, r, 0], A[a, 0, r, 1], blo, bhi)
        l1, h1 = _fma2(l1, h1, A[a, 1, r, 0], A[a, 1, r, 1], blo, bhi)
        l2, h2 = _fma2(l2, h2, A[a, 2, r, 0], A[a, 2, r, 1], blo, bhi)
        l3, h3 = _fma2(l3, h3, A[a, 3, r, 0], A[a, 3, r, 1], blo, bhi)
    out[o, 0, 3, 0], out[o, 0, 3, 1], out[o, 1, 3, 0], out[o, 1, 3, 1] = l0, h0, l1, h1
    out[o, 2, 3, 0], out[o, 2, 3, 1], out[o, 3, 3, 0], out[o, 3, 3, 1] = l2, h2, l3, h3


@njit(cache=True)
def _local(
    kind: int,
    axis: np.ndarray,
    fixed: np.ndarray,
    i: int,
    v: np.ndarray,
    o: int,
    X: np.ndarray,
    dX: np.ndarray,
    K2: np.ndarray,
) -> None:
    """Interval local transform of joint ``i`` from the intervals ``v[o:]`` into ``X[i]``.

    Its derivatives go into ``dX[o:]`` (the joint's unknowns); ``K2[i]`` is a revolute joint's
    :math:`K^2` (:func:`workspace`).
    """
    d = o  # the joint's first unknown: its derivatives' slot (unused by parameters)
    for r in range(4):
        for k in range(4):
            X[i, r, k, 0] = X[i, r, k, 1] = 0.0
    X[i, 3, 3, 0] = X[i, 3, 3, 1] = 1.0
    if kind == REVOLUTE or kind == REVOLUTE_PARAM:
        for r in range(3):
            for k in range(3):
                lo, hi = 0.0, 0.0
                for t in range(3):
                    b = _skew_entry(axis, i, t, k)
                    lo, hi = _pfma2(lo, hi, _skew_entry(axis, i, r, t), b, b)
                K2[r, k, 0], K2[r, k, 1] = lo, hi
        clo, chi, slo, shi = v[o, 0], v[o, 1], v[o + 1, 0], v[o + 1, 1]
        omlo, omhi = _dn(1.0 - chi), _up(1.0 - clo)
        for r in range(3):
            for k in range(3):
                kk = _skew_entry(axis, i, r, k)
                alo, ahi = _mul2(slo, shi, kk, kk)
                blo, bhi = _mul2(omlo, omhi, K2[r, k, 0], K2[r, k, 1])
                lo, hi = _add2(alo, ahi, blo, bhi)
                if r == k:
                    lo, hi = _add2(lo, hi, 1.0, 1.0)
                X[i, r, k, 0], X[i, r, k, 1] = lo, hi
        if kind == REVOLUTE:
            for c in range(2):
                for r in range(4):
                    for k in range(4):
                        dX[d + c, r, k, 0] = dX[d + c, r, k, 1] = 0.0
            for r in range(3):
                for k in range(3):
                    dX[d, r, k, 0], dX[d, r, k, 1] = -K2[r, k, 1], -K2[r, k, 0]
                    dX[d + 1, r, k, 0] = dX[d + 1, r, k, 1] = _skew_entry(axis, i, r, k)
        return
    if kind == PRISMATIC or kind == PRISMATIC_PARAM:
        for r in range(3):
            X[i, r, r, 0] = X[i, r, r, 1] = 1.0
            X[i, r, 3, 0], X[i, r, 3, 1] = _mul2(v[o, 0], v[o, 1], axis[i, r], axis[i, r])
        if kind == PRISMATIC:
            for r in range(4):
                for k in range(4):
                    dX[d, r, k, 0] = dX[d, r, k, 1] = 0.0
            for r in range(3):
                dX[d, r, 3, 0] = dX[d, r, 3, 1] = axis[i, r]
        return
    if kind == SPHERICAL or kind == FREE_FLYER:
        t = 3 if kind == FREE_FLYER else 0
        q = o + t
        wl, wh, xl, xh = v[q, 0], v[q, 1], v[q + 1, 0], v[q + 1, 1]
        yl, yh, zl, zh = v[q + 2, 0], v[q + 2, 1], v[q + 3, 0], v[q + 3, 1]
        wwl, wwh = _mul2(wl, wh, wl, wh)
        xxl, xxh = _mul2(xl, xh, xl, xh)
        yyl, yyh = _mul2(yl, yh, yl, yh)
        zzl, zzh = _mul2(zl, zh, zl, zh)
        xyl, xyh = _mul2(xl, xh, yl, yh)
        wzl, wzh = _mul2(wl, wh, zl, zh)
        xzl, xzh = _mul2(xl, xh, zl, zh)
        wyl, wyh = _mul2(wl, wh, yl, yh)
        yzl, yzh = _mul2(yl, yh, zl, zh)
        wxl, wxh = _mul2(wl, wh, xl, xh)
        # diagonal: (a + b) - (c + d)
        al, ah = _add2(wwl, wwh, xxl, xxh)
        bl, bh = _add2(yyl, yyh, zzl, zzh)
        X[i, 0, 0, 0], X[i, 0, 0, 1] = _add2(al, ah, -bh, -bl)
        al, ah = _add2(wwl, wwh, yyl, yyh)
        bl, bh = _add2(xxl, xxh, zzl, zzh)
        X[i, 1, 1, 0], X[i, 1, 1, 1] = _add2(al, ah, -bh, -bl)
        al, ah = _add2(wwl, wwh, zzl, zzh)
        bl, bh = _add2(xxl, xxh, yyl, yyh)
        X[i, 2, 2, 0], X[i, 2, 2, 1] = _add2(al, ah, -bh, -bl)
        # off the diagonal: 2 (a +- b), the doubling exact
        al, ah = _add2(xyl, xyh, -wzh, -wzl)
        X[i, 0, 1, 0], X[i, 0, 1, 1] = 2.0 * al, 2.0 * ah
        al, ah = _add2(xyl, xyh, wzl, wzh)
        X[i, 1, 0, 0], X[i, 1, 0, 1] = 2.0 * al, 2.0 * ah
        al, ah = _add2(xzl, xzh, wyl, wyh)
        X[i, 0, 2, 0], X[i, 0, 2, 1] = 2.0 * al, 2.0 * ah
        al, ah = _add2(xzl, xzh, -wyh, -wyl)
        X[i, 2, 0, 0], X[i, 2, 0, 1] = 2.0 * al, 2.0 * ah
        al, ah = _add2(yzl, yzh, -wxh, -wxl)
        X[i, 1, 2, 0], X[i, 1, 2, 1] = 2.0 * al, 2.0 * ah
        al, ah = _add2(yzl, yzh, wxl, wxh)
        X[i, 2, 1, 0], X[i, 2, 1, 1] = 2.0 * al, 2.0 * ah
        for c in range(t + 4):
            for r in range(4):
                for k in range(4):
                    dX[d + c, r, k, 0] = dX[d + c, r, k, 1] = 0.0
        for r in range(t):
            X[i, r, 3, 0], X[i, r, 3, 1] = v[o + r, 0], v[o + r, 1]
            dX[d + r, r, 3, 0] = dX[d + r, r, 3, 1] = 1.0
        # the derivatives 2 w, 2 x, ... (exact), as in .evaluation._quaternion
        e = d + t
        _set2(dX, e, 0, 0, 2.0 * wl, 2.0 * wh)
        _set2(dX, e, 0, 1, -2.0 * zh, -2.0 * zl)
        _set2(dX, e, 0, 2, 2.0 * yl, 2.0 * yh)
        _set2(dX, e, 1, 0, 2.0 * zl, 2.0 * zh)
        _set2(dX, e, 1, 1, 2.0 * wl, 2.0 * wh)
        _set2(dX, e, 1, 2, -2.0 * xh, -2.0 * xl)
        _set2(dX, e, 2, 0, -2.0 * yh, -2.0 * yl)
        _set2(dX, e, 2, 1, 2.0 * xl, 2.0 * xh)
        _set2(dX, e, 2, 2, 2.0 * wl, 2.0 * wh)
        e += 1
        _set2(dX, e, 0, 0, 2.0 * xl, 2.0 * xh)
        _set2(dX, e, 0, 1, 2.0 * yl, 2.0 * yh)
        _set2(dX, e, 0, 2, 2.0 * zl, 2.0 * zh)
        _set2(dX, e, 1, 0, 2.0 * yl, 2.0 * yh)
        _set2(dX, e, 1, 1, -2.0 * xh, -2.0 * xl)
        _set2(dX, e, 1, 2, -2.0 * wh, -2.0 * wl)
        _set2(dX, e, 2, 0, 2.0 * zl, 2.0 * zh)
        _set2(dX, e, 2, 1, 2.0 * wl, 2.0 * wh)
        _set2(dX, e, 2, 2, -2.0 * xh, -2.0 * xl)
        e += 1
        _set2(dX, e, 0, 0, -2.0 * yh, -2.0 * yl)
        _set2(dX, e, 0, 1, 2.0 * xl, 2.0 * xh)
        _set2(dX, e, 0, 2, 2.0 * wl, 2.0 * wh)
        _set2(dX, e, 1, 0, 2.0 * xl, 2.0 * xh)
        _set2(dX, e, 1, 1, 2.0 * yl, 2.0 * yh)
        _set2(dX, e, 1, 2, 2.0 * zl, 2.0 * zh)
        _set2(dX, e, 2, 0, -2.0 * wh, -2.0 * wl)
        _set2(dX, e, 2, 1, 2.0 * zl, 2.0 * zh)
        _set2(dX, e, 2, 2, -2.0 * yh, -2.0 * yl)
        e += 1
        _set2(dX, e, 0, 0, -2.0 * zh, -2.0 * zl)
        _set2(dX, e, 0, 1, -2.0 * wh, -2.0 * wl)
        _set2(dX, e, 0, 2, 2.0 * xl, 2.0 * xh)
        _set2(dX, e, 1, 0, 2.0 * wl, 2.0 * wh)
        _set2(dX, e, 1, 1, -2.0 * zh, -2.0 * zl)
        _set2(dX, e, 1, 2, 2.0 * yl, 2.0 * yh)
        _set2(dX, e, 2, 0, 2.0 * xl, 2.0 * xh)
        _set2(dX, e, 2, 1, 2.0 * yl, 2.0 * yh)
        _set2(dX, e, 2, 2, 2.0 * zl, 2.0 * zh)
        return
    for r in range(4):
        for k in range(4):
            X[i, r, k, 0] = X[i, r, k, 1] = fixed[i, r, k]


@njit(cache=True)
def _set2(A: np.ndarray, a: int, r: int, k: int, lo: float, hi: float) -> None:
    A[a, r, k, 0], A[a, r, k, 1] = lo, hi


@njit(cache=True)
def _skew_entry(axis: np.ndarray, i: int, r: int, k: int) -> float:
    """Entry (r, k) of the cross-product matrix of ``axis[i]``."""
    if r == k:
        return 0.0
    if r == 0:
        return -axis[i, 2] if k == 1 else axis[i, 1]
    if r == 1:
        return axis[i, 2] if k == 0 else -axis[i, 0]
    return -axis[i, 1] if k == 0 else axis[i, 0]


# the buffers of a workspace, by position
_NCOORD, _STATIC, _X, _DX, _T, _A, _MX, _ADX, _TF, _DTF, _POINT, _S, _E, _K2 = range(14)
_DE3, _ENT, _DENT, _F, _J, _XI, _FX, _JMID, _LU, _PIV, _Y, _ROW, _D = range(14, 27)


@njit(cache=True)
def workspace(n: int, args: tuple) -> tuple:
    """The buffers of :func:`interval_system` and the Krawczyk test, allocated once per certificate.

    Also the static structure: the number of coordinates of each joint and which closure frames
    are read only at their origin (point and distance closures).
    """
    parent, kind, frame_joint = args[0], args[1], args[6]
    closure_kind, closure_frames, combination = args[8], args[9], args[13]
    k, nf, m = kind.shape[0], frame_joint.shape[0], combination.shape[1]
    ncoord = np.zeros(k, dtype=np.int64)
    for i in range(k):
        kd = kind[i]
        if kd == REVOLUTE:
            ncoord[i] = 2
        elif kd == PRISMATIC:
            ncoord[i] = 1
        elif kd == SPHERICAL:
            ncoord[i] = 4
        elif kd == FREE_FLYER:
            ncoord[i] = 7
    flags = np.ones(nf + k, dtype=np.bool_)
    point = flags[:nf]
    static = flags[nf:]  # X_j, M_j X_j, A_j, T_j depend on neither x nor (but for M_j X_j) the path
    for i in range(k):
        kd = kind[i]
        static[i] = (kd == FIXED or kd == REVOLUTE_PARAM or kd == PRISMATIC_PARAM) and (
            parent[i] < 0 or static[parent[i]]
        )
    for c in range(closure_kind.shape[0]):
        if closure_kind[c] == 1 or closure_kind[c] == 2:
            point[closure_frames[c, 0]] = False
            point[closure_frames[c, 1]] = False
    # one allocation, carved into the buffers (all written before read but dTf)
    q = 4 * 4 * 2  # one interval 4 x 4 matrix
    size = (4 * k + 2 * n + nf + nf * n + 2) * q + 3 * 18 + 2 * m + 2 * m * n + 10 * n + 2 * n * n + 3 * n * n
    buf = np.empty(size)
    o = 0
    # (a reshape costs more than an index: the buffers of one shape are carved as one stack)
    stack = buf[o : o + 4 * k * q].reshape((4, k, 4, 4, 2))
    X = stack[0]  # local transforms
    T = stack[1]  # world transform after the joint
    A = stack[2]  # world transform of the joint frame before X_j
    MX = stack[3]  # M_j X_j, shared by the frames below joint j
    o += 4 * k * q
    stack = buf[o : o + 2 * n * q].reshape((2, n, 4, 4, 2))
    dX = stack[0]  # derivatives of X_j, at the joint's unknowns
    AdX = stack[1]  # A_j dX_j, shared likewise
    o += 2 * n * q
    Tf = buf[o : o + nf * q].reshape((nf, 4, 4, 2))  # closure frames
    o += nf * q
    dTf = buf[o : o + nf * n * q].reshape((nf * n, 4, 4, 2))  # their derivatives, n per frame
    dTf[:] = 0.0  # zero off the frame's path
    o += nf * n * q
    S = buf[o : o + 2 * q].reshape((2, 4, 4, 2))  # suffix products (two slots)
    o += 2 * q
    small = buf[o : o + 54].reshape((3, 3, 3, 2))
    E = small[0]  # R_A^T R_B
    dE = small[1]  # a derivative of E
    K2 = small[2]  # K^2 of a revolute joint
    o += 54
    e = buf[o : o + 2 * m].reshape((m, 2))  # closure entries
    o += 2 * m
    de = buf[o : o + 2 * m * n].reshape((m, n, 2))  # their derivatives
    o += 2 * m * n
    vectors = buf[o : o + 10 * n].reshape((5, n, 2))
    F = vectors[0]
    xi = vectors[1]  # the box (or the point) evaluated
    Fx = vectors[2]  # F at the point, kept for the Krawczyk test
    row = vectors[3]  # a row of Y F_x(X)
    D = vectors[4]  # X - x
    o += 10 * n
    J = buf[o : o + 2 * n * n].reshape((n, n, 2))  # F_x
    o += 2 * n * n
    squares = buf[o : o + 3 * n * n].reshape((3, n, n))
    Jmid = squares[0]  # the midpoint Jacobian
    LU = squares[1]  # its LU factors
    Y = squares[2]  # its inverse
    piv = np.empty(n, dtype=np.int64)  # the row pivots
    return (
        ncoord,
        static,
        X,
        dX,
        T,
        A,
        MX,
        AdX,
        Tf,
        dTf,
        point,
        S,
        E,
        K2,
        dE,
        e,
        de,
        F,
        J,
        xi,
        Fx,
        Jmid,
        LU,
        piv,
        Y,
        row,
        D,
    )


@njit(cache=True)
def _system_into(
    xi: np.ndarray, pi: np.ndarray, ws: tuple, values: bool | np.bool_, again: bool | np.bool_, args: tuple
) -> None:
    """:func:`interval_system` into the buffers ``F`` and ``F_x`` of ``ws`` (:func:`workspace`).

    ``args``: the form's arrays (:meth:`~.form.PolynomialForm.kernel_args`). Without ``values``,
    ``F_x`` alone (``F`` is left unset); ``again``: ``ws`` holds a pass with the same parameters
    (:func:`_joints`). Its callers pass the flags as ``np.bool_(True)`` or ``np.bool_(False)``:
    numba compiles a function once per literal argument, and a bare ``True`` would compile the
    system (and everything it calls) once per combination of flags, about half a minute each.
    """
    (
        parent,
        kind,
        offset,
        axis,
        placement,
        fixed,
        frame_joint,
        frame_placement,
        closure_kind,
        closure_frames,
        closure_axis,
        closure_length2,
        entry_offset,
        combination,
        unit_offsets,
        unit_sizes,
    ) = args
    n = xi.shape[0]
    _joints(xi, pi.reshape(-1, 2), ws, parent, kind, offset, axis, placement, fixed, again)
    _frames(n, ws, parent, offset, frame_joint, frame_placement)
    _closures(n, ws, closure_kind, closure_frames, closure_axis, closure_length2, entry_offset, values)
    _combine(xi, ws, combination, unit_offsets, unit_sizes, values)


@njit(cache=True)
def _joints(
    xi: np.ndarray,
    pflat: np.ndarray,
    ws: tuple,
    parent: np.ndarray,
    kind: np.ndarray,
    offset: np.ndarray,
    axis: np.ndarray,
    placement: np.ndarray,
    fixed: np.ndarray,
    again: bool | np.bool_,
) -> None:
    """Each joint's local transform and derivatives, its world transform and the products below it.

    ``pflat``: the parameters' intervals, parameter o's at rows 2 o and 2 o + 1. ``again``: ``ws``
    holds a pass with the same parameters, whose transforms that do not depend on x are kept.
    """
    ncoord, static, X, dX, T, A, MX, AdX, K2 = (
        ws[_NCOORD],
        ws[_STATIC],
        ws[_X],
        ws[_DX],
        ws[_T],
        ws[_A],
        ws[_MX],
        ws[_ADX],
        ws[_K2],
    )
    for i in range(kind.shape[0]):
        kd = kind[i]
        if again and static[i]:
            continue
        if kd == REVOLUTE_PARAM or kd == PRISMATIC_PARAM:
            if not again:
                _local(kd, axis, fixed, i, pflat, 2 * offset[i], X, dX, K2)
                _mm_point_left(placement, i, X, i, MX, i)
        elif kd != FIXED or not again:
            _local(kd, axis, fixed, i, xi, offset[i], X, dX, K2)
            _mm_point_left(placement, i, X, i, MX, i)
        if parent[i] >= 0:
            _mm_point_right(T, parent[i], placement, i, A, i)
            _mm_into(A, i, X, i, T, i)
        else:  # on the world: A = M, T = M X
            for r in range(4):
                for q in range(4):
                    A[i, r, q, 0] = A[i, r, q, 1] = placement[i, r, q]
            _copy_into(MX, i, T, i)
        for c in range(ncoord[i]):
            _mm_into(A, i, dX, offset[i] + c, AdX, offset[i] + c)


@njit(cache=True)
def _frames(
    n: int,
    ws: tuple,
    parent: np.ndarray,
    offset: np.ndarray,
    frame_joint: np.ndarray,
    frame_placement: np.ndarray,
) -> None:
    """Each closure frame's transform ``Tf`` and its derivatives ``dTf`` along the unknowns."""
    ncoord, T, MX, AdX, Tf, dTf, point, S = (
        ws[_NCOORD],
        ws[_T],
        ws[_MX],
        ws[_ADX],
        ws[_TF],
        ws[_DTF],
        ws[_POINT],
        ws[_S],
    )
    for f in range(frame_joint.shape[0]):
        for r in range(4):
            for q in range(4):
                S[0, r, q, 0] = S[0, r, q, 1] = frame_placement[f, r, q]
        i = frame_joint[f]
        if point[f]:  # the origin alone: the same operations on the last column
            if i >= 0:
                _mv_into(T, i, S, 0, Tf, f)
            else:
                for r in range(4):
                    Tf[f, r, 3, 0], Tf[f, r, 3, 1] = S[0, r, 3, 0], S[0, r, 3, 1]
            while i >= 0:
                for c in range(ncoord[i]):
                    _mv_into(AdX, offset[i] + c, S, 0, dTf, f * n + offset[i] + c)
                if parent[i] < 0:
                    break  # (no joint above to carry the suffix to)
                _mv_into(MX, i, S, 0, S, 1)
                for r in range(4):
                    S[0, r, 3, 0], S[0, r, 3, 1] = S[1, r, 3, 0], S[1, r, 3, 1]
                i = parent[i]
            continue
        if i >= 0:
            _mm_into(T, i, S, 0, Tf, f)
        else:
            _copy_into(S, 0, Tf, f)
        while i >= 0:
            for c in range(ncoord[i]):
                _mm_into(AdX, offset[i] + c, S, 0, dTf, f * n + offset[i] + c)
            if parent[i] < 0:
                break
            _mm_into(MX, i, S, 0, S, 1)
            _copy_into(S, 1, S, 0)
            i = parent[i]


@njit(cache=True)
def _closures(
    n: int,
    ws: tuple,
    closure_kind: np.ndarray,
    closure_frames: np.ndarray,
    closure_axis: np.ndarray,
    closure_length2: np.ndarray,
    entry_offset: np.ndarray,
    values: bool | np.bool_,
) -> None:
    """The closure entries ``e`` (unless not ``values``) and their derivatives ``de`` from the frames."""
    Tf, dTf, E, dE, e, de = ws[_TF], ws[_DTF], ws[_E], ws[_DE3], ws[_ENT], ws[_DENT]
    for c in range(closure_kind.shape[0]):
        a, b, o = closure_frames[c, 0], closure_frames[c, 1], entry_offset[c]
        if closure_kind[c] == 3:  # |p_B - p_A|^2 - L^2, L^2 = |p_L|^2 for an actuated strut L
            lo, hi = -closure_length2[c], -closure_length2[c]
            g = closure_frames[c, 2]
            for j in range(n):
                de[o, j, 0] = de[o, j, 1] = 0.0
            for r in range(3):
                dl, dh = _add2(Tf[b, r, 3, 0], Tf[b, r, 3, 1], -Tf[a, r, 3, 1], -Tf[a, r, 3, 0])
                pl, ph = _mul2(dl, dh, dl, dh)
                lo, hi = _add2(lo, hi, pl, ph)
                if g >= 0:  # the strut hangs from the world on a parameter: no x-derivative
                    pl, ph = _mul2(Tf[g, r, 3, 0], Tf[g, r, 3, 1], Tf[g, r, 3, 0], Tf[g, r, 3, 1])
                    lo, hi = _add2(lo, hi, -ph, -pl)
                for j in range(n):
                    ua, ub = a * n + j, b * n + j
                    ddl, ddh = _add2(dTf[ub, r, 3, 0], dTf[ub, r, 3, 1], -dTf[ua, r, 3, 1], -dTf[ua, r, 3, 0])
                    pl, ph = _mul2(dl, dh, ddl, ddh)
                    de[o, j, 0], de[o, j, 1] = _add2(de[o, j, 0], de[o, j, 1], 2.0 * pl, 2.0 * ph)
            e[o, 0], e[o, 1] = lo, hi
            continue
        for r in range(3):
            e[o + r, 0], e[o + r, 1] = _add2(Tf[b, r, 3, 0], Tf[b, r, 3, 1], -Tf[a, r, 3, 1], -Tf[a, r, 3, 0])
            for j in range(n):
                ua, ub = a * n + j, b * n + j
                de[o + r, j, 0], de[o + r, j, 1] = _add2(
                    dTf[ub, r, 3, 0], dTf[ub, r, 3, 1], -dTf[ua, r, 3, 1], -dTf[ua, r, 3, 0]
                )
        if closure_kind[c] == 0:
            continue
        # E = R_A^T R_B and its derivatives dR_A^T R_B + R_A^T dR_B
        for r in range(3):
            for s in range(3):
                lo, hi = 0.0, 0.0
                for t in range(3):
                    lo, hi = _fma2(lo, hi, Tf[a, t, r, 0], Tf[a, t, r, 1], Tf[b, t, s, 0], Tf[b, t, s, 1])
                E[r, s, 0], E[r, s, 1] = lo, hi
        if not values:
            pass
        elif closure_kind[c] == 1:
            for r in range(3):
                for s in range(3):
                    lo, hi = E[r, s, 0], E[r, s, 1]
                    if r == s:
                        lo, hi = _add2(lo, hi, -1.0, -1.0)
                    e[o + 3 + 3 * r + s, 0], e[o + 3 + 3 * r + s, 1] = lo, hi
        else:
            for r in range(3):
                lo, hi = _axis_product(E, r, closure_axis, c)
                u = closure_axis[c, r]
                e[o + 3 + r, 0], e[o + 3 + r, 1] = _add2(lo, hi, -u, -u)
        for j in range(n):
            ua, ub = a * n + j, b * n + j
            for r in range(3):
                for s in range(3):
                    lo, hi = 0.0, 0.0
                    for t in range(3):
                        lo, hi = _fma2(
                            lo, hi, dTf[ua, t, r, 0], dTf[ua, t, r, 1], Tf[b, t, s, 0], Tf[b, t, s, 1]
                        )
                    lo2, hi2 = 0.0, 0.0
                    for t in range(3):
                        lo2, hi2 = _fma2(
                            lo2, hi2, Tf[a, t, r, 0], Tf[a, t, r, 1], dTf[ub, t, s, 0], dTf[ub, t, s, 1]
                        )
                    dE[r, s, 0], dE[r, s, 1] = _add2(lo, hi, lo2, hi2)
            if closure_kind[c] == 1:
                for r in range(3):
                    for s in range(3):
                        de[o + 3 + 3 * r + s, j, 0], de[o + 3 + 3 * r + s, j, 1] = dE[r, s, 0], dE[r, s, 1]
            else:
                for r in range(3):
                    de[o + 3 + r, j, 0], de[o + 3 + r, j, 1] = _axis_product(dE, r, closure_axis, c)


@njit(cache=True)
def _combine(
    xi: np.ndarray,
    ws: tuple,
    combination: np.ndarray,
    unit_offsets: np.ndarray,
    unit_sizes: np.ndarray,
    values: bool | np.bool_,
) -> None:
    """The unit equations and the random combination of the entries: ``F`` (if ``values``) and ``F_x``."""
    e, de, F, J = ws[_ENT], ws[_DENT], ws[_F], ws[_J]
    n = xi.shape[0]
    nu, m = unit_offsets.shape[0], e.shape[0]
    for q in range(nu):
        o = unit_offsets[q]
        for j in range(n):
            J[q, j, 0] = J[q, j, 1] = 0.0
        lo, hi = -1.0, -1.0
        for r in range(unit_sizes[q]):
            xl, xh = xi[o + r, 0], xi[o + r, 1]
            J[q, o + r, 0], J[q, o + r, 1] = 2.0 * xl, 2.0 * xh
            if not values:
                continue
            l2, h2 = xl * xl, xh * xh  # the square of an interval (tighter than a product)
            if xl <= 0.0 <= xh:
                lo, hi = _add2(lo, hi, 0.0, _up(max(l2, h2)))
            else:
                lo, hi = _add2(lo, hi, _dn(min(l2, h2)), _up(max(l2, h2)))
        F[q, 0], F[q, 1] = lo, hi
    for i in range(n - nu):
        if values:
            lo, hi = 0.0, 0.0
            for r in range(m):
                lo, hi = _pfma2(lo, hi, combination[i, r], e[r, 0], e[r, 1])
            F[nu + i, 0], F[nu + i, 1] = lo, hi
        for j in range(n):
            J[nu + i, j, 0] = J[nu + i, j, 1] = 0.0
        for r in range(m):  # the row's n sums side by side
            w = combination[i, r]
            if w == 0.0:
                continue
            for j in range(n):
                J[nu + i, j, 0], J[nu + i, j, 1] = _pfma2(
                    J[nu + i, j, 0], J[nu + i, j, 1], w, de[r, j, 0], de[r, j, 1]
                )


@njit(cache=True)
def _axis_product(E: np.ndarray, r: int, closure_axis: np.ndarray, c: int) -> tuple[float, float]:
    """Row ``r`` of the interval matrix ``E`` (3, 3, 2) times the exact axis ``closure_axis[c]``."""
    lo, hi = 0.0, 0.0
    for s in range(3):
        lo, hi = _pfma2(lo, hi, closure_axis[c, s], E[r, s, 0], E[r, s, 1])
    return lo, hi


@njit(cache=True)
def _copy_into(A: np.ndarray, a: int, out: np.ndarray, o: int) -> None:
    """``out[o] = A[a]`` for stacks of interval 4 x 4 matrices."""
    for i in range(4):
        for j in range(4):
            out[o, i, j, 0], out[o, i, j, 1] = A[a, i, j, 0], A[a, i, j, 1]


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
    displacement twice, shape (n_params, 2, 2). Allocates a :func:`workspace` (the certificate
    reuses one).
    """
    args = (
        parent,
        kind,
        offset,
        axis,
        placement,
        fixed,
        frame_joint,
        frame_placement,
        closure_kind,
        closure_frames,
        closure_axis,
        closure_length2,
        entry_offset,
        combination,
        unit_offsets,
        unit_sizes,
    )
    ws = workspace(xi.shape[0], args)
    _system_into(xi, pi, ws, np.bool_(True), np.bool_(False), args)
    return ws[_F], ws[_J]


@njit(cache=True)
def _inverse(A: np.ndarray, LU: np.ndarray, piv: np.ndarray, Y: np.ndarray) -> bool:
    """``Y`` = the inverse of ``A`` (n, n) by one LU factorisation with partial pivoting (into ``LU``).

    False, ``Y`` unset, when a pivot is zero or not finite (``A`` singular, or not finite).
    """
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            LU[i, j] = A[i, j]
    for kk in range(n):
        p, big = kk, abs(LU[kk, kk])
        for i in range(kk + 1, n):
            if abs(LU[i, kk]) > big:
                p, big = i, abs(LU[i, kk])
        if not (0.0 < big < np.inf):
            return False
        piv[kk] = p
        if p != kk:
            for j in range(n):
                LU[kk, j], LU[p, j] = LU[p, j], LU[kk, j]
        inv = 1.0 / LU[kk, kk]
        for i in range(kk + 1, n):
            f = LU[i, kk] * inv
            LU[i, kk] = f
            if f != 0.0:
                for j in range(kk + 1, n):
                    LU[i, j] -= f * LU[kk, j]
    # Y = U^-1 L^-1 P, by row operations on the rows of P
    for i in range(n):
        for j in range(n):
            Y[i, j] = 1.0 if i == j else 0.0
    for kk in range(n):
        p = piv[kk]
        if p != kk:
            for j in range(n):
                Y[kk, j], Y[p, j] = Y[p, j], Y[kk, j]
    for i in range(1, n):
        for t in range(i):
            f = LU[i, t]
            if f != 0.0:
                for j in range(n):
                    Y[i, j] -= f * Y[t, j]
    for i in range(n - 1, -1, -1):
        for t in range(i + 1, n):
            f = LU[i, t]
            if f != 0.0:
                for j in range(n):
                    Y[i, j] -= f * Y[t, j]
        d = LU[i, i]
        for j in range(n):
            Y[i, j] /= d
    return True


@njit(cache=True)
def _midpoint_inverse(
    J: np.ndarray, Jmid: np.ndarray, LU: np.ndarray, piv: np.ndarray, Y: np.ndarray
) -> bool:
    """The inverse of the midpoint of the interval matrix ``J`` (n, n, 2) into ``ws``'s ``Y``."""
    n = J.shape[0]
    for i in range(n):
        for j in range(n):
            Jmid[i, j] = 0.5 * (J[i, j, 0] + J[i, j, 1])
    return _inverse(Jmid, LU, piv, Y)


@njit(cache=True)
def _newton_size(x: np.ndarray, pi: np.ndarray, args: tuple, ws: tuple) -> float:
    """:func:`newton_size` in the buffers of ``ws``; F at ``x`` is left in its ``Fx``."""
    n = x.shape[0]
    xi, Fx = ws[_XI], ws[_FX]
    for i in range(n):
        xi[i, 0] = xi[i, 1] = x[i]
    _system_into(xi, pi, ws, np.bool_(True), np.bool_(False), args)
    F = ws[_F]
    for i in range(n):
        Fx[i, 0], Fx[i, 1] = F[i, 0], F[i, 1]
    if not _midpoint_inverse(ws[_J], ws[_JMID], ws[_LU], ws[_PIV], ws[_Y]):
        return np.inf
    Jmid, Y = ws[_JMID], ws[_Y]
    # numerically singular as numpy's matrix_rank has it (sigma_min <= n eps sigma_max), with the
    # 1-norm condition number (exact here, from the inverse) standing for the 2-norm one
    na, ny = 0.0, 0.0
    for j in range(n):
        sa, sy = 0.0, 0.0
        for i in range(n):
            sa += abs(Jmid[i, j])
            sy += abs(Y[i, j])
        na, ny = max(na, sa), max(ny, sy)
    if not (na * ny * n * _FLOAT_EPSILON < 1.0):
        return np.inf
    out = 0.0
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += abs(Y[i, j]) * max(abs(Fx[j, 0]), abs(Fx[j, 1]))
        out = max(out, acc)
    return out


@njit(cache=True)
def newton_size(x: np.ndarray, pi: np.ndarray, args: tuple) -> tuple[float, np.ndarray]:
    r"""Size of the Newton enclosure at ``x``: the largest :math:`|Y F([\tilde x])|` (a float bound).

    The Krawczyk box must hold this (the root lies about one Newton step away, plus the rounding
    of :math:`F`, magnified by the conditioning), and should not be much larger (the interval
    Jacobian over a wide box stops the contraction). A fixed width fails one way or the other on
    an ill-conditioned root. Infinite when the Jacobian is singular: a zero or non-finite pivot
    of the LU factorisation of its midpoint, or a condition number (1-norm) of at least
    :math:`1 / (n \varepsilon)`, numpy's numerical rank threshold. Also returns the enclosure
    of F at ``x`` (the Krawczyk test's).
    """
    ws = workspace(x.shape[0], args)
    size = _newton_size(x, pi, args, ws)
    return size, ws[_FX]


@njit(cache=True)
def _krawczyk(
    x: np.ndarray,
    radius: float,
    pi: np.ndarray,
    args: tuple,
    Fx: np.ndarray,
    ws: tuple,
    reuse: bool | np.bool_,
) -> bool:
    r""":func:`krawczyk` in the buffers of ``ws`` (``Fx`` may be one of them: it is only read).

    ``reuse``: ``ws`` holds :func:`_newton_size`'s pass at ``x`` with the same ``pi``; Y is its
    inverse of :math:`F_x(\tilde x)`, and the transforms that do not depend on x are kept.
    Otherwise Y is the inverse of the midpoint of :math:`F_x(X)`.
    """
    n = x.shape[0]
    box = ws[_XI]
    for i in range(n):
        r = radius * (1.0 + abs(x[i]))
        box[i, 0], box[i, 1] = _dn(x[i] - r), _up(x[i] + r)
    _system_into(box, pi, ws, np.bool_(False), reuse, args)
    JX = ws[_J]
    if not reuse and not _midpoint_inverse(JX, ws[_JMID], ws[_LU], ws[_PIV], ws[_Y]):
        return False
    Y, row, d = ws[_Y], ws[_ROW], ws[_D]
    for j in range(n):
        d[j, 0], d[j, 1] = _dn(box[j, 0] - x[j]), _up(box[j, 1] - x[j])  # X - x
    for i in range(n):
        # row i of K(X) = x - Y F(x) + (I - Y F_x(X)) (X - x)
        yl, yh = 0.0, 0.0
        for t in range(n):
            yl, yh = _pfma2(yl, yh, Y[i, t], Fx[t, 0], Fx[t, 1])
        for j in range(n):
            row[j, 0] = row[j, 1] = 0.0
        for t in range(n):  # row i of Y F_x(X), its n sums side by side
            y = Y[i, t]
            if y == 0.0:
                continue
            for j in range(n):
                row[j, 0], row[j, 1] = _pfma2(row[j, 0], row[j, 1], y, JX[t, j, 0], JX[t, j, 1])
        ml, mh = 0.0, 0.0
        for j in range(n):
            lo, hi = -row[j, 1], -row[j, 0]
            if i == j:
                lo, hi = _add2(lo, hi, 1.0, 1.0)
            ml, mh = _fma2(ml, mh, lo, hi, d[j, 0], d[j, 1])
        lo = _dn(_dn(x[i] - yh) + ml)
        hi = _up(_up(x[i] - yl) + mh)
        if not (box[i, 0] < lo and hi < box[i, 1]):
            return False
    return True


@njit(cache=True)
def krawczyk(x: np.ndarray, radius: float, pi: np.ndarray, args: tuple, Fx: np.ndarray) -> bool:
    """Whether the box ``x +- radius (1 + abs(x))`` provably holds exactly one root (Krawczyk test).

    ``Fx`` is the enclosure of F at the point ``x`` (:func:`interval_system`), shape (n, 2).
    Y is the inverse of the midpoint of the interval Jacobian (any matrix keeps the test
    rigorous); the test fails when that midpoint is singular.
    """
    return _krawczyk(x, radius, pi, args, Fx, workspace(x.shape[0], args), np.bool_(False))


@njit(cache=True)
def _certify(
    X: np.ndarray,
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
) -> np.ndarray:
    r""":func:`certify`'s radii for every row of ``X``, in one compiled call with one workspace.

    NaN where not certified. Y is the Newton step's inverse of :math:`F_x(\tilde x)`, for every box.
    Each row's test starts with its own Newton pass, which writes every buffer the test reads (the
    workspace carries nothing from one row to the next). The form's arrays come one by one (a call
    with a tuple of arrays costs more to dispatch).
    """
    args = (
        parent,
        kind,
        offset,
        axis,
        placement,
        fixed,
        frame_joint,
        frame_placement,
        closure_kind,
        closure_frames,
        closure_axis,
        closure_length2,
        entry_offset,
        combination,
        unit_offsets,
        unit_sizes,
    )
    radii = np.full(X.shape[0], np.nan)
    ws = workspace(X.shape[1], args)
    for k in range(X.shape[0]):
        x = X[k]
        size = max(_newton_size(x, pi, args, ws), _FLOAT_EPSILON)
        for g in BOX_GROWTH:
            radius = g * size
            if not radius <= HOMOTOPY_MAX_BOX_RTOL:
                break
            if _krawczyk(x, radius, pi, args, ws[_FX], ws, np.bool_(True)):
                radii[k] = radius
                break
    return radii


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


def certify(
    form: PolynomialForm, X: np.ndarray, actuators: np.ndarray, pi: np.ndarray | None = None
) -> np.ndarray:
    """Per row of real ``X`` (N, n): the half-width of a box proven to hold exactly one root, or NaN.

    The half-width is relative (times 1 + abs(x)). The boxes tried are :data:`BOX_GROWTH` times the
    Newton enclosure's size (:func:`newton_size`), at most
    :data:`~plm_pin.tolerances.HOMOTOPY_MAX_BOX_RTOL`; every row in one compiled call. ``pi``: the
    actuators' :func:`parameter_intervals`, when the caller has them.
    """
    if pi is None:
        pi = parameter_intervals(form, actuators)
    X = np.ascontiguousarray(X, dtype=float).reshape(-1, form.n)
    return _certify(X, np.ascontiguousarray(pi, dtype=float), *form.kernel_args())
