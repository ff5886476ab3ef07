r"""Predictor-corrector path tracking of a parameter homotopy, compiled with numba.

The homotopy moves the parameters on a straight line between two complex points,
:math:`P(t) = (1 - t) P_0 + t P_1`, :math:`t \in [0, 1]`, with :math:`P = (p, b)` the
actuator values and the offsets added to the equations (:mod:`.generic` uses the offsets;
a forward-kinematics call keeps them at zero). A path follows
:math:`\dot x = -F_x^{-1} (F_p \dot p + \dot b)`: a fourth-order Runge-Kutta predictor, then
at most :data:`CORRECTOR_STEPS` Newton corrections, accepted when they contract and stopped
when a correction, or the next one predicted from the contraction, is small (:func:`corrected`);
the next step aims the predictor's error at
:data:`~plm_pin.tolerances.HOMOTOPY_PREDICTOR_RTOL` (:func:`next_step`), and a rejected step
halves.

Endgame: a path whose norm passes :data:`HOMOTOPY_DIVERGED_NORM` goes to infinity (the target has
fewer finite solutions), and so does a path whose step is rejected while its norm grows like a
power of :math:`1/(1 - t)` over the last decades (:func:`_to_infinity`: near a root at infinity
the affine Jacobian is too ill-conditioned to follow the path much further); a path whose step
falls below :data:`HOMOTOPY_MIN_STEP` fails (a singular end or a near-collision); a path that reaches
:math:`t = 1` gets :data:`FINAL_NEWTON` Newton steps. Because the start point is generic
complex, the straight segment avoids the discriminant (a complex hypersurface) with probability
one, except possibly at :math:`t = 1` (the gamma trick in its parameter-space form).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...tolerances import (
    HOMOTOPY_CORRECTOR_TOL,
    HOMOTOPY_DIVERGED_NORM,
    HOMOTOPY_MIN_STEP,
    HOMOTOPY_PREDICTOR_RTOL,
    HOMOTOPY_ROOT_RTOL,
    HOMOTOPY_SINGULAR_COND,
)
from .straight_line import Program, system, workspace

REACHED, DIVERGED, FAILED, GROWING = 0, 1, 2, 3
"""Path end codes: reached t = 1, went to infinity (or handed over), tracker failure, and went to
infinity by the endgame's growth test (:func:`_to_infinity`)."""

CORRECTOR_STEPS = 3
MAX_STEP = 0.2
FINAL_NEWTON = 4
CONTRACTION_SAFETY = 4.0
"""Safety factor on the last step's Newton contraction constant when predicting a correction from one."""
HANDOFF_GROWTH = 1e3
"""Growth of a path's norm (times 1 + its start's) at which a forward-kinematics call's affine
tracking stops and the path is tracked again in projective coordinates (a path to infinity costs
the affine tracker 50 to 90 steps before it gives up, 20 to 25 with this)."""
ENDGAME_GROWTH = 2.0
"""Least growth of a path's norm per decade of 1 - t, over two decades, to call it diverging."""
ENDGAME_EXPONENT = 0.25
"""Least growth exponent w of a path's norm, like (1 - t)^(-w), at a rejected step, to call it diverging."""


@njit(cache=True)
def solve_linear(A: np.ndarray, y: np.ndarray, z: np.ndarray | None = None) -> bool:
    """Solve ``A u = y`` (complex, square) in place by LU with partial pivoting: ``y`` becomes ``u``.

    ``A`` is overwritten. A second right-hand side ``z`` is solved with the same factors. Returns
    False (and ``y``, ``z`` NaN) when a pivot is exactly zero. The pivot is the entry of largest
    squared modulus (no square root per candidate, as ``abs`` takes).
    """
    n = A.shape[0]
    for k in range(n):
        piv, best = k, A[k, k].real * A[k, k].real + A[k, k].imag * A[k, k].imag
        for r in range(k + 1, n):
            size = A[r, k].real * A[r, k].real + A[r, k].imag * A[r, k].imag
            if size > best:
                piv, best = r, size
        if A[piv, k] == 0:
            y[:] = np.nan
            if z is not None:
                z[:] = np.nan
            return False
        if piv != k:
            for c in range(n):
                A[k, c], A[piv, c] = A[piv, c], A[k, c]
            y[k], y[piv] = y[piv], y[k]
            if z is not None:
                z[k], z[piv] = z[piv], z[k]
        inv = 1.0 / A[k, k]
        for r in range(k + 1, n):
            f = A[r, k] * inv
            if f != 0:
                for c in range(k + 1, n):
                    A[r, c] -= f * A[k, c]
                y[r] -= f * y[k]
                if z is not None:
                    z[r] -= f * z[k]
    for k in range(n - 1, -1, -1):
        acc = y[k]
        for c in range(k + 1, n):
            acc -= A[k, c] * y[c]
        y[k] = acc / A[k, k]
        if z is not None:
            acc = z[k]
            for c in range(k + 1, n):
                acc -= A[k, c] * z[c]
            z[k] = acc / A[k, k]
    return True


@njit(cache=True)
def _velocity(x, p, b, dp, db, ws, program, out):  # type: ignore[no-untyped-def]
    """``out`` = the path's tangent dx/dt at (x, p, b)."""
    _, J = system(x, p, b, ws, program)
    n = x.shape[0]
    for i in range(n):
        acc = -db[i]
        for j in range(dp.shape[0]):
            acc -= J[i, n + j] * dp[j]
        out[i] = acc
    solve_linear(J[:, :n], out)


@njit(cache=True)
def _newton(x, p, b, ws, program, out):  # type: ignore[no-untyped-def]
    """``out`` = the Newton step at (x, p, b)."""
    F, J = system(x, p, b, ws, program)
    for i in range(x.shape[0]):
        out[i] = -F[i]
    solve_linear(J[:, : x.shape[0]], out)


@njit(cache=True)
def _newton_velocity(x, p, b, dp, db, ws, program, out, velocity):  # type: ignore[no-untyped-def]
    """``out`` = the Newton step and ``velocity`` = the path's tangent at (x, p, b), one factorisation."""
    F, J = system(x, p, b, ws, program)
    n = x.shape[0]
    for i in range(n):
        out[i] = -F[i]
        acc = -db[i]
        for j in range(dp.shape[0]):
            acc -= J[i, n + j] * dp[j]
        velocity[i] = acc
    solve_linear(J[:, :n], out, velocity)


@njit(cache=True)
def _at(t: float, a0: np.ndarray, da: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``out = a0 + t da``."""
    for i in range(a0.shape[0]):
        out[i] = a0[i] + t * da[i]
    return out


@njit(cache=True)
def path_norm(v: np.ndarray) -> float:
    """Euclidean norm of a complex vector (no temporary, unlike ``np.linalg.norm``)."""
    acc = 0.0
    for i in range(v.shape[0]):
        acc += v[i].real * v[i].real + v[i].imag * v[i].imag
    return np.sqrt(acc)


@njit(cache=True)
def corrected(nd: float, last: float, omega: float, small: float) -> bool:
    """Whether the corrector has converged after a correction of norm ``nd`` (``last``: the one before).

    It has when ``nd`` is below ``small``, or the next correction will be: by this step's
    contraction (``nd / last``) or, after the first correction (``last`` inf), by Newton's quadratic
    contraction with the constant ``omega`` measured at the last step (times :data:`CONTRACTION_SAFETY`;
    inf while unmeasured, so a path's first step always takes two corrections).
    """
    next_one = nd * (nd / last) if last < np.inf else CONTRACTION_SAFETY * omega * nd * nd
    return nd <= small or next_one <= small


@njit(cache=True)
def next_step(h: float, first: float, size: float) -> float:
    """The step after an accepted step ``h`` whose first correction (the predictor's error) was ``first``.

    The predictor's error is of fifth order in the step: the next one aims it at
    :data:`~plm_pin.tolerances.HOMOTOPY_PREDICTOR_RTOL` times ``size`` (the path's scale), growing at
    most twofold and shrinking at most by half, and at most :data:`MAX_STEP`.
    """
    goal = HOMOTOPY_PREDICTOR_RTOL * size
    grow = 2.0 if first <= goal / 32.0 else max(0.5, 0.8 * (goal / first) ** 0.2)
    return min(grow * h, MAX_STEP)


@njit(cache=True)
def _to_infinity(x: np.ndarray, v: np.ndarray, rest: float, gap: float, marks: np.ndarray) -> bool:
    r"""Whether a path whose step was rejected at :math:`1 - t` = ``rest`` is going to infinity.

    Near a root at infinity the affine Jacobian grows ill-conditioned (like a power of
    :math:`|x|`), so the corrector stalls long before :data:`HOMOTOPY_DIVERGED_NORM`. The path
    goes to infinity when it grows like :math:`(1 - t)^{-w}`: its norm grew at least
    :data:`ENDGAME_GROWTH` times over each of the last two decades of :math:`1 - t`, or its square
    over the last one (``marks``: the norms where :math:`1 - t` passed ``100 gap``, ``10 gap`` and
    ``gap``), is still above the last mark, and the tangent ``v`` still gives the exponent
    :math:`w = (1 - t)\,\mathrm{Re}(x^H v) / |x|^2 \ge` :data:`ENDGAME_EXPONENT`. A path to a
    finite root, regular or singular, has a norm that settles (:math:`w \to 0`, or
    :math:`w < 0` toward the origin).
    """
    if gap > 1e-3 or not (np.isfinite(marks[0]) and np.isfinite(marks[1])):
        return False
    size = path_norm(x)
    last = marks[2] / marks[1]  # growth over the last decade
    steady = marks[1] >= ENDGAME_GROWTH * marks[0] or last >= ENDGAME_GROWTH**2
    if size < marks[2] or last < ENDGAME_GROWTH or not steady:
        return False
    acc = 0.0
    for i in range(x.shape[0]):
        acc += x[i].real * v[i].real + x[i].imag * v[i].imag
    return rest * acc / (size * size) >= ENDGAME_EXPONENT


@njit(cache=True)
def track(
    x0: np.ndarray,
    p0: np.ndarray,
    b0: np.ndarray,
    p1: np.ndarray,
    b1: np.ndarray,
    ws: tuple,
    program: Program,
    handoff: float = np.inf,
) -> tuple[np.ndarray, int, int, float]:
    """Track one solution ``x0`` of the system at ``(p0, b0)`` to ``(p1, b1)``.

    ``ws`` is the program's workspace (:func:`~.straight_line.workspace`); the path's own buffers are
    allocated once here, so no step allocates.

    A path whose norm passes ``handoff`` times ``1 + |x0|`` stops as DIVERGED too (for the
    projective tracker to take over, :mod:`.projective`).

    Returns:
        The end point, its code (REACHED, DIVERGED, FAILED, GROWING), the number of steps and
        the :math:`t` of the end point (1, or where the path was given up: a point on the path
        there, for the projective tracker to go on from).
    """
    n = x0.shape[0]
    x = x0.copy()
    y = np.empty_like(x)
    xs = np.empty_like(x)
    d = np.empty_like(x)
    k1, k2, k3, k4 = np.empty_like(x), np.empty_like(x), np.empty_like(x), np.empty_like(x)
    v = np.empty_like(x)  # the tangent at the last corrector's point
    fresh = False  # whether k1 holds the tangent at x (from the corrector of the step that reached it)
    dp, db = p1 - p0, b1 - b0
    pt, bt = np.empty_like(p0), np.empty_like(b0)
    t, h = 0.0, 0.1
    steps = 0
    omega = np.inf  # Newton's contraction constant at the last step: |next correction| ~ omega |correction|^2
    norm0 = path_norm(x0)
    # the norm where 1 - t last passed a power of ten, and at the two passes before (endgame)
    gap, marks = 1.0, np.array([np.nan, np.nan, norm0])
    while t < 1.0:
        if steps > 5000:
            return x, FAILED, steps, t
        h = min(h, 1.0 - t)
        steps += 1
        # RK4 predictor
        if not fresh:
            _velocity(x, _at(t, p0, dp, pt), _at(t, b0, db, bt), dp, db, ws, program, k1)
        th = t + 0.5 * h
        for i in range(n):
            xs[i] = x[i] + 0.5 * h * k1[i]
        _velocity(xs, _at(th, p0, dp, pt), _at(th, b0, db, bt), dp, db, ws, program, k2)
        for i in range(n):
            xs[i] = x[i] + 0.5 * h * k2[i]
        _velocity(xs, pt, bt, dp, db, ws, program, k3)
        for i in range(n):
            xs[i] = x[i] + h * k3[i]
        _velocity(xs, _at(t + h, p0, dp, pt), _at(t + h, b0, db, bt), dp, db, ws, program, k4)
        ok = True
        for i in range(n):
            y[i] = x[i] + (h / 6.0) * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            ok = ok and np.isfinite(y[i].real) and np.isfinite(y[i].imag)
        last: float = np.inf
        first = np.inf  # the first correction: the predictor's error
        if ok:
            converged = False
            for _ in range(CORRECTOR_STEPS):
                _newton_velocity(y, pt, bt, dp, db, ws, program, d, v)
                nd = path_norm(d)
                if not np.isfinite(nd) or nd > 0.5 * last:
                    break
                for i in range(n):
                    y[i] += d[i]
                if last < np.inf:
                    omega = nd / (last * last)
                else:
                    first = nd
                if corrected(nd, last, omega, HOMOTOPY_CORRECTOR_TOL * (1.0 + path_norm(y))):
                    converged = True
                    break
                last = nd
            ok = converged or last <= 1e-6 * (1.0 + path_norm(y))
        if ok:  # the next step's first tangent: the last corrector's, a correction below tolerance away
            x[:] = y
            k1[:] = v
            fresh = True
            t += h
            h = next_step(h, first, 1.0 + path_norm(x))
            if path_norm(x) > HOMOTOPY_DIVERGED_NORM or path_norm(x) > handoff * (1.0 + norm0):
                return x, DIVERGED, steps, t
            if 1.0 - t <= 0.1 * gap:
                gap = 1.0 - t
                marks[0], marks[1], marks[2] = marks[1], marks[2], path_norm(x)
        else:
            fresh = True  # k1 (at x) still holds
            if _to_infinity(x, k1, 1.0 - t, gap, marks):  # no use halving the step down to HOMOTOPY_MIN_STEP
                return x, GROWING, steps, t
            h *= 0.5
            if h < HOMOTOPY_MIN_STEP:
                if path_norm(x) > 1e3 * (1.0 + norm0):
                    return x, DIVERGED, steps, t
                return x, FAILED, steps, t
    for _ in range(FINAL_NEWTON):
        _newton(x, p1, b1, ws, program, d)
        if not np.isfinite(path_norm(d)):
            break
        for i in range(n):
            x[i] += d[i]
    return x, REACHED, steps, 1.0


@njit(cache=True, nogil=True)
def track_all(
    X0: np.ndarray,
    p0: np.ndarray,
    b0: np.ndarray,
    p1: np.ndarray,
    b1: np.ndarray,
    program: Program,
    handoff: float = np.inf,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Track every row of ``X0`` (shape (N, n)): end points (N, n), codes, steps and end t (N,) each.

    ``handoff`` as in :func:`track`.
    """
    N = X0.shape[0]
    ws = workspace(X0.shape[1], p0.shape[0], program)
    out = np.empty_like(X0)
    codes = np.empty(N, dtype=np.int64)
    steps = np.empty(N, dtype=np.int64)
    ends = np.empty(N)
    for i in range(N):
        out[i], codes[i], steps[i], ends[i] = track(X0[i], p0, b0, p1, b1, ws, program, handoff)
    return out, codes, steps, ends


@njit(cache=True)
def condition_number(A: np.ndarray) -> float:
    r"""The 1-norm condition number :math:`\|A\|_1 \|A^{-1}\|_1` of a square complex matrix.

    By an LU inverse: 2 to 6 us on the 4 to 12 unknowns here, where the 2-norm's SVD takes 6 to 30
    (the two are within a factor n of each other). Infinite where ``A`` is not finite or is singular.
    """
    if not np.all(np.isfinite(A)):
        return np.inf
    try:
        B = np.linalg.inv(A)
    except Exception:  # exactly singular
        return np.inf
    size = np.abs(A).sum(axis=0).max() * np.abs(B).sum(axis=0).max()
    return size if np.isfinite(size) else np.inf


@njit(cache=True)
def clean_ends(
    X: np.ndarray, codes: np.ndarray, p: np.ndarray, b: np.ndarray, program: Program
) -> np.ndarray:
    """Which rows of ``X`` (N, n) end their paths cleanly, in one compiled call: shape (N,).

    A clean end reached t = 1 (its code is :data:`REACHED`) at a finite root: the square system
    there is within :data:`~plm_pin.tolerances.HOMOTOPY_ROOT_RTOL` times 1 + its largest entry of
    zero, and F_x's :func:`condition_number` is at most
    :data:`~plm_pin.tolerances.HOMOTOPY_SINGULAR_COND`.
    """
    N, n = X.shape
    ws = workspace(n, p.shape[0], program)
    clean = np.zeros(N, dtype=np.bool_)
    for k in range(N):
        if codes[k] != REACHED or not np.all(np.isfinite(X[k])):
            continue
        F, J = system(X[k], p, b, ws, program)
        if np.abs(F).max() <= HOMOTOPY_ROOT_RTOL * (1.0 + np.abs(X[k]).max()):
            clean[k] = condition_number(np.ascontiguousarray(J[:, :n])) <= HOMOTOPY_SINGULAR_COND
    return clean


@njit(cache=True)
def real_newton(X0: np.ndarray, p: np.ndarray, program: Program) -> np.ndarray:
    """Each row of ``X0`` (N, n) refined by at most three Newton steps on the real system, from its real part.

    At real parameters ``p``, in one compiled call; a row stops early when a step is below 1e-15
    relative. Returns the refined rows, shape (N, n).
    """
    N, n = X0.shape
    ws = workspace(n, p.shape[0], program)
    out = np.empty((N, n))
    xc = np.empty(n, dtype=np.complex128)
    pc = p.astype(np.complex128)
    b = np.zeros(n, dtype=np.complex128)
    A = np.empty((n, n))
    r = np.empty(n)
    for k in range(N):
        x = out[k]
        for i in range(n):
            x[i] = X0[k, i].real
        for _ in range(3):
            for i in range(n):
                xc[i] = x[i]
            F, J = system(xc, pc, b, ws, program)
            for i in range(n):
                r[i] = -F[i].real
                for j in range(n):
                    A[i, j] = J[i, j].real
            step = np.linalg.solve(A, r)
            big, size = 0.0, 0.0
            for i in range(n):
                x[i] += step[i]
                big = max(big, abs(step[i]))
            for i in range(n):
                size = max(size, abs(x[i]))
            if big < 1e-15 * (1.0 + size):
                break
    return out
