r"""Path tracking in projective coordinates: where a path that leaves every bound really ends.

A path of the affine tracker (:mod:`.tracking`) whose norm grows past every bound either goes to
infinity (the target has fewer finite roots than the generic parameter: a non-generic target,
such as a Delta whose three arms are at one angle, where base and platform hexagons are similar)
or to a large but finite root. In affine coordinates the two look alike; in projective
coordinates they do not. With :math:`x = z / z_0` and each equation homogenised,
:math:`G_i(z) = z_0^{d_i} F_i(z / z_0)` (:math:`d_i` its degree, :attr:`PolynomialForm.degrees`),
and a random affine chart :math:`a \cdot z = 1` closing the system, a path to infinity is a
bounded path whose :math:`z_0` tends to zero. Its end is then read off :math:`z_0` at
:math:`t = 1`: zero (relative to :math:`|z|`, :data:`~plm_pin.tolerances.HOMOTOPY_INFINITY_RTOL`)
is a root at infinity, anything else the finite root :math:`z / z_0`. A path whose :math:`z_0`
falls that low after :data:`ENDGAME_T`, or whose step fails there (a root at infinity is often
singular), is at infinity too.

The homogenised system is evaluated through the affine one at :math:`x = z / z_0`: its terms
then carry the same rounding as a direct homogeneous evaluation (the factors
:math:`z_0^{d_i}` scale them back), as long as :math:`z_0 \ne 0`, which the end point of a
path at infinity approaches but never reaches at :math:`t < 1`.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit

from ...tolerances import (
    HOMOTOPY_CORRECTOR_TOL,
    HOMOTOPY_ENDGAME_MIN_STEP,
    HOMOTOPY_INFINITY_RTOL,
    HOMOTOPY_MIN_STEP,
    HOMOTOPY_ROOT_RTOL,
    HOMOTOPY_SINGULAR_COND,
)
from .form import PolynomialForm
from .straight_line import Program, system, workspace
from .threads import over_threads
from .tracking import (
    CORRECTOR_STEPS,
    FAILED,
    FINAL_NEWTON,
    MAX_STEP,
    REACHED,
    condition_number,
    corrected,
    path_norm,
    solve_linear,
)

AT_INFINITY = 3
"""Path end code: the path went to a root at infinity (:math:`z_0 = 0` at :math:`t = 1`)."""
ENDGAME_T = 0.99
"""From this :math:`t` on, a path whose :math:`z_0` falls to
:data:`~plm_pin.tolerances.HOMOTOPY_INFINITY_RTOL` is at infinity, without tracking on to
:math:`t = 1` (earlier, a path may pass near infinity and come back)."""


@njit(cache=True)
def _homogeneous(z, p, ws, program, degrees, chart, zero_b, x, G, H):  # type: ignore[no-untyped-def]
    """``G`` = the homogenised system at ``z`` (n + 1,), ``H`` = its Jacobian ``[G_z G_p]``."""
    n = x.shape[0]
    z0 = z[0]
    for j in range(n):
        x[j] = z[j + 1] / z0
    F, J = system(x, p, zero_b, ws, program)
    npar = p.shape[0]
    for i in range(n):
        d = degrees[i]
        s = z0 ** (d - 1)
        G[i] = s * z0 * F[i]
        acc = d * F[i]
        for j in range(n):
            H[i, j + 1] = s * J[i, j]
            acc -= x[j] * J[i, j]
        H[i, 0] = s * acc
        for k in range(npar):
            H[i, n + 1 + k] = s * z0 * J[i, n + k]
    acc = -1.0 + 0j
    for j in range(n + 1):
        acc += chart[j] * z[j]
        H[n, j] = chart[j]
    G[n] = acc
    for k in range(npar):
        H[n, n + 1 + k] = 0.0


@njit(cache=True)
def _step(z, p, dp, ws, program, degrees, chart, zero_b, x, G, H, A, newton, velocity):  # type: ignore[no-untyped-def]
    """``newton`` = the Newton step, ``velocity`` = the tangent dz/dt at ``(z, p)``; one factorisation."""
    _homogeneous(z, p, ws, program, degrees, chart, zero_b, x, G, H)
    m = z.shape[0]
    for i in range(m):
        newton[i] = -G[i]
        acc = 0.0j
        for k in range(dp.shape[0]):
            acc -= H[i, m + k] * dp[k]
        velocity[i] = acc
        for j in range(m):
            A[i, j] = H[i, j]
    solve_linear(A, newton, velocity)


@njit(cache=True)
def track_projective(
    x0: np.ndarray,
    t0: float,
    p0: np.ndarray,
    p1: np.ndarray,
    chart: np.ndarray,
    degrees: np.ndarray,
    program: Program,
) -> tuple[np.ndarray, int, float]:
    """Track the root ``x0`` (n,) of the closures at ``p0 + t0 (p1 - p0)`` to ``p1`` in the chart ``chart``.

    Returns:
        The end ``z = (z_0, z_1, ..., z_n)`` (n + 1,), its code: REACHED (a finite root
        ``z[1:] / z[0]``), AT_INFINITY, or FAILED (the step fell below the smallest), and the
        :math:`t` it got to.
    """
    n = x0.shape[0]
    m = n + 1
    ws = workspace(n, p0.shape[0], program)
    zero_b = np.zeros(n, dtype=np.complex128)
    x = np.empty(n, dtype=np.complex128)
    G = np.empty(m, dtype=np.complex128)
    H = np.empty((m, m + p0.shape[0]), dtype=np.complex128)
    A = np.empty((m, m), dtype=np.complex128)
    z = np.empty(m, dtype=np.complex128)
    z[0] = 1.0
    z[1:] = x0
    scale = chart[0] * z[0]
    for j in range(n):
        scale += chart[j + 1] * z[j + 1]
    z /= scale
    y, zs, d = np.empty_like(z), np.empty_like(z), np.empty_like(z)
    k1, k2, k3, k4, v = (
        np.empty_like(z),
        np.empty_like(z),
        np.empty_like(z),
        np.empty_like(z),
        np.empty_like(z),
    )
    dp = p1 - p0
    pt = p0 + t0 * dp
    t, h = t0, 0.1 * (1.0 - t0)  # a path resumed near its end starts at the scale of what is left
    steps, streak = 0, 0
    omega = np.inf  # Newton's contraction constant, from the last step (:func:`~.tracking.corrected`)
    _step(z, pt, dp, ws, program, degrees, chart, zero_b, x, G, H, A, d, k1)
    code = REACHED
    while t < 1.0:
        if steps > 5000:
            code = FAILED
            break
        h = min(h, 1.0 - t)
        steps += 1
        th = t + 0.5 * h
        for i in range(m):
            zs[i] = z[i] + 0.5 * h * k1[i]
        pt[:] = p0 + th * dp
        _step(zs, pt, dp, ws, program, degrees, chart, zero_b, x, G, H, A, d, k2)
        for i in range(m):
            zs[i] = z[i] + 0.5 * h * k2[i]
        _step(zs, pt, dp, ws, program, degrees, chart, zero_b, x, G, H, A, d, k3)
        for i in range(m):
            zs[i] = z[i] + h * k3[i]
        pt[:] = p0 + (t + h) * dp
        _step(zs, pt, dp, ws, program, degrees, chart, zero_b, x, G, H, A, d, k4)
        ok = True
        for i in range(m):
            y[i] = z[i] + (h / 6.0) * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            ok = ok and np.isfinite(y[i].real) and np.isfinite(y[i].imag)
        last = np.inf
        if ok:
            converged = False
            for _ in range(CORRECTOR_STEPS):
                _step(y, pt, dp, ws, program, degrees, chart, zero_b, x, G, H, A, d, v)
                nd = path_norm(d)
                if not np.isfinite(nd) or nd > 0.5 * last:
                    break
                for i in range(m):
                    y[i] += d[i]
                if last < np.inf:
                    omega = nd / (last * last)
                if corrected(nd, last, omega, HOMOTOPY_CORRECTOR_TOL * path_norm(y)):
                    converged = True
                    break
                last = nd
            ok = converged or last <= 1e-6 * path_norm(y)
        if ok:
            z[:] = y
            k1[:] = v
            t += h
            streak += 1
            if streak >= 3:
                h = min(2.0 * h, MAX_STEP)
                streak = 0
            if t >= ENDGAME_T and abs(z[0]) <= HOMOTOPY_INFINITY_RTOL * path_norm(z):
                return z, AT_INFINITY, t
        else:
            h *= 0.5
            streak = 0
            # past ENDGAME_T a step that small is given up too: near a singular end, such as a root at
            # infinity, the corrector stalls at any step, and halving on only costs evaluations
            if h < HOMOTOPY_MIN_STEP or (t >= ENDGAME_T and h < HOMOTOPY_ENDGAME_MIN_STEP * (1.0 - t)):
                code = FAILED
                break
    if code == REACHED:
        for _ in range(FINAL_NEWTON):
            _step(z, p1, dp, ws, program, degrees, chart, zero_b, x, G, H, A, d, v)
            if not np.isfinite(path_norm(d)):
                break
            for i in range(m):
                z[i] += d[i]
    if t >= ENDGAME_T and abs(z[0]) <= HOMOTOPY_INFINITY_RTOL * path_norm(
        z
    ):  # or stopped by a singular end there
        code = AT_INFINITY
    return z, code, t


@njit(cache=True, nogil=True)
def track_projective_all(
    X0: np.ndarray,
    T0: np.ndarray,
    p0: np.ndarray,
    p1: np.ndarray,
    chart: np.ndarray,
    degrees: np.ndarray,
    program: Program,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`track_projective` from each row of ``X0`` (N, n) at its ``T0`` (N,): ends (N, n + 1), codes."""
    N, n = X0.shape
    Z = np.empty((N, n + 1), dtype=np.complex128)
    codes = np.empty(N, dtype=np.int64)
    for i in range(N):
        Z[i], codes[i], _ = track_projective(X0[i], T0[i], p0, p1, chart, degrees, program)
    return Z, codes


@njit(cache=True)
def homogeneous_at(
    z: np.ndarray, p: np.ndarray, chart: np.ndarray, degrees: np.ndarray, program: Program
) -> tuple[np.ndarray, np.ndarray]:
    """The homogenised system (n + 1,) and its Jacobian in ``z`` (n + 1, n + 1) at ``z``, ``p``."""
    m = z.shape[0]
    n = m - 1
    ws = workspace(n, p.shape[0], program)
    G = np.empty(m, dtype=np.complex128)
    H = np.empty((m, m + p.shape[0]), dtype=np.complex128)
    x = np.empty(n, dtype=np.complex128)
    _homogeneous(z, p, ws, program, degrees, chart, np.zeros(n, dtype=np.complex128), x, G, H)
    return G, H[:, :m].copy()


def chart(n: int) -> np.ndarray:
    """The fixed random affine chart :math:`a` (n + 1,) of the projective tracking (seeded, unit norm)."""
    return _chart(n).copy()


@functools.cache
def _chart(n: int) -> np.ndarray:
    from .polynomial import SEED

    rng = np.random.default_rng(SEED + 3)
    a = rng.normal(size=n + 1) + 1j * rng.normal(size=n + 1)
    return a / np.linalg.norm(a)


def projective_ends(
    form: PolynomialForm, X0: np.ndarray, T0: np.ndarray, p0: np.ndarray, p1: np.ndarray
) -> tuple[np.ndarray, int, int, np.ndarray]:
    """Track paths from ``p0`` to ``p1`` in projective coordinates, from ``X0`` (N, n) at ``T0`` (N,).

    A row is a point of its path at :math:`t` = ``T0``: a generic root (:math:`t = 0`), or where the
    affine tracker gave the path up.

    Returns:
        The finite non-singular ends (k, n) (their affine coordinates), the numbers of paths
        that went to infinity and that ended singular, and which paths failed (N,).
    """
    if not len(X0):
        return np.zeros((0, form.n), dtype=np.complex128), 0, 0, np.zeros(0, dtype=bool)
    a = chart(form.n)
    program = form.program
    Z, codes = over_threads(
        track_projective_all, (np.ascontiguousarray(X0), T0), p0, p1, a, form.degrees, program
    )
    roots = []
    infinity = singular = 0
    failed = np.zeros(len(Z), dtype=bool)
    for i, (z, code) in enumerate(zip(Z, codes, strict=True)):
        if code == AT_INFINITY:
            infinity += 1
            continue
        if code != REACHED or not np.all(np.isfinite(z)):
            failed[i] = True
            continue
        G, Gz = homogeneous_at(z, p1, a, form.degrees, program)
        rows = np.linalg.norm(
            Gz, axis=1
        )  # scaled to unit norm: the homogenised equations' scales are arbitrary
        if np.abs(G).max() > HOMOTOPY_ROOT_RTOL * (1.0 + np.abs(z).max()):
            failed[i] = True
        elif not np.all(rows > 0) or not condition_number(Gz / rows[:, None]) <= HOMOTOPY_SINGULAR_COND:
            singular += 1
        else:
            roots.append(z[1:] / z[0])
    return np.array(roots, dtype=np.complex128).reshape(-1, form.n), infinity, singular, failed
