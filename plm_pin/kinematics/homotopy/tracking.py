r"""Predictor-corrector path tracking of a parameter homotopy, compiled with numba.

The homotopy moves the parameters on a straight line between two complex points,
:math:`P(t) = (1 - t) P_0 + t P_1`, :math:`t \in [0, 1]`, with :math:`P = (p, b)` the
actuator values and the offsets added to the equations (:mod:`.generic` uses the offsets;
a forward-kinematics call keeps them at zero). A path follows
:math:`\dot x = -F_x^{-1} (F_p \dot p + \dot b)`: a fourth-order Runge-Kutta predictor, then
at most :data:`CORRECTOR_STEPS` Newton corrections, accepted when they contract; the step
doubles after three accepted steps in a row and halves on a rejected one.

Endgame: a path whose norm passes :data:`HOMOTOPY_DIVERGED_NORM` goes to infinity (the target has
fewer finite solutions); a path whose step falls below :data:`MIN_STEP` fails (a singular
end or a near-collision); a path that reaches :math:`t = 1` gets :data:`FINAL_NEWTON` Newton
steps. Because the start point is generic complex, the straight segment avoids the
discriminant (a complex hypersurface) with probability one, except possibly at
:math:`t = 1` (the gamma trick in its parameter-space form).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...tolerances import HOMOTOPY_CORRECTOR_TOL, HOMOTOPY_DIVERGED_NORM
from .evaluation import system

REACHED, DIVERGED, FAILED = 0, 1, 2
"""Path end codes: reached t = 1, went to infinity, tracker failure."""

CORRECTOR_STEPS = 3
MIN_STEP = 1e-9  # TOLERANCE -> tolerances.py
"""Smallest step in t [-] before a path is declared failed."""
MAX_STEP = 0.2
FINAL_NEWTON = 4


@njit(cache=True)
def solve_linear(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``A y = b`` (complex, square) by LU with partial pivoting (``A`` is overwritten)."""
    n = A.shape[0]
    y = b.copy()
    for k in range(n):
        piv, best = k, abs(A[k, k])
        for r in range(k + 1, n):
            if abs(A[r, k]) > best:
                piv, best = r, abs(A[r, k])
        if best == 0.0:
            y[:] = np.nan
            return y
        if piv != k:
            for c in range(n):
                A[k, c], A[piv, c] = A[piv, c], A[k, c]
            y[k], y[piv] = y[piv], y[k]
        inv = 1.0 / A[k, k]
        for r in range(k + 1, n):
            f = A[r, k] * inv
            if f != 0:
                for c in range(k + 1, n):
                    A[r, c] -= f * A[k, c]
                y[r] -= f * y[k]
    for k in range(n - 1, -1, -1):
        acc = y[k]
        for c in range(k + 1, n):
            acc -= A[k, c] * y[c]
        y[k] = acc / A[k, k]
    return y


@njit(cache=True)
def _velocity(x, p, b, dp, db, args):  # type: ignore[no-untyped-def]
    _, Jx, Jp = system(x, p, b, *args)
    rhs = -db.copy()
    for i in range(Jp.shape[0]):
        for j in range(Jp.shape[1]):
            rhs[i] -= Jp[i, j] * dp[j]
    return solve_linear(Jx, rhs)


@njit(cache=True)
def _newton(x, p, b, args):  # type: ignore[no-untyped-def]
    F, Jx, _ = system(x, p, b, *args)
    return solve_linear(Jx, -F)


@njit(cache=True)
def track(
    x0: np.ndarray, p0: np.ndarray, b0: np.ndarray, p1: np.ndarray, b1: np.ndarray, args: tuple
) -> tuple[np.ndarray, int, int]:
    """Track one solution ``x0`` of the system at ``(p0, b0)`` to ``(p1, b1)``.

    Returns:
        The end point, its code (REACHED, DIVERGED, FAILED) and the number of steps.
    """
    x = x0.copy()
    dp, db = p1 - p0, b1 - b0
    t, h = 0.0, 0.1
    steps, streak = 0, 0
    while t < 1.0:
        if steps > 5000:
            return x, FAILED, steps
        h = min(h, 1.0 - t)
        steps += 1
        # RK4 predictor
        k1 = _velocity(x, p0 + t * dp, b0 + t * db, dp, db, args)
        k2 = _velocity(x + 0.5 * h * k1, p0 + (t + 0.5 * h) * dp, b0 + (t + 0.5 * h) * db, dp, db, args)
        k3 = _velocity(x + 0.5 * h * k2, p0 + (t + 0.5 * h) * dp, b0 + (t + 0.5 * h) * db, dp, db, args)
        k4 = _velocity(x + h * k3, p0 + (t + h) * dp, b0 + (t + h) * db, dp, db, args)
        y = x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        pt, bt = p0 + (t + h) * dp, b0 + (t + h) * db
        ok = bool(np.all(np.isfinite(y)))
        last: float = np.inf
        if ok:
            converged = False
            for _ in range(CORRECTOR_STEPS):
                d = _newton(y, pt, bt, args)
                nd = float(np.linalg.norm(d))
                if not np.isfinite(nd) or nd > 0.5 * last:
                    break
                y += d
                last = nd
                if nd <= HOMOTOPY_CORRECTOR_TOL * (1.0 + np.linalg.norm(y)):
                    converged = True
                    break
            ok = converged or last <= 1e-6 * (1.0 + float(np.linalg.norm(y)))
        if ok:
            x = y
            t += h
            streak += 1
            if streak >= 3:
                h = min(2.0 * h, MAX_STEP)
                streak = 0
            if np.linalg.norm(x) > HOMOTOPY_DIVERGED_NORM:
                return x, DIVERGED, steps
        else:
            h *= 0.5
            streak = 0
            if h < MIN_STEP:
                if np.linalg.norm(x) > 1e3 * (1.0 + np.linalg.norm(x0)):
                    return x, DIVERGED, steps
                return x, FAILED, steps
    for _ in range(FINAL_NEWTON):
        d = _newton(x, p1, b1, args)
        if not np.all(np.isfinite(d)):
            break
        x = x + d
    return x, REACHED, steps


@njit(cache=True)
def track_all(
    X0: np.ndarray, p0: np.ndarray, b0: np.ndarray, p1: np.ndarray, b1: np.ndarray, args: tuple
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Track every row of ``X0`` (shape (N, n)): end points (N, n), codes (N,), steps (N,)."""
    N = X0.shape[0]
    out = np.empty_like(X0)
    codes = np.empty(N, dtype=np.int64)
    steps = np.empty(N, dtype=np.int64)
    for i in range(N):
        out[i], codes[i], steps[i] = track(X0[i], p0, b0, p1, b1, args)
    return out, codes, steps
