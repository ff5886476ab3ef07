r"""Compiled map metrics: :func:`plm_pin.workspace._batch.square_task_metrics` pose by pose, in numba.

For each stacked Jacobian :math:`A = [J_\phi; J_x]` of a batch, the velocity map :math:`S`
(:math:`A S = [0; I]` where :math:`A` is square, else :math:`A^T A S = J_x^T`) by an LU with
partial pivoting, its orthonormal basis :math:`N` by Gram-Schmidt (twice), :math:`T = J_x N`
and its inverse, :math:`C = N_a`, and the squared singular values of :math:`C T^{-1}`,
:math:`C`, :math:`J_\phi`, :math:`T^{-1}` and :math:`J_x` as the eigenvalues of their smaller
Gram matrices, each stage only where a metric asked for needs it. Those eigenvalues come from
Jacobi rotations on a 1 x 1 or 2 x 2 Gram, else from a Householder reduction to a tridiagonal
matrix and the implicit QL iteration with Wilkinson shifts (values only, no allocation). Both
are backward stable: each eigenvalue is exact for a symmetric matrix within a small multiple of
round-off of the Gram's norm, so it is accurate to
about :math:`\epsilon \lambda_{max}`, which :data:`plm_pin.tolerances.GRAM_RTOL` accounts for.
Closure rows that are exactly zero (the out-of-plane rows of a planar loop closed by 3-D point
closures) are dropped first: they change none of the values, and without them such a
system is often square, solved without the normal equations. The same values and the same
acceptance tests as the numpy path; a pose that fails them (or
whose QL iteration does not converge) is flagged for that path's SVD. numba is imported only
here; the functions compile on first use (cached on disk).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .linear import Elimination, dense_elimination, solve

METRIC_NAMES = ("manipulability", "condition_number", "constraint_margin", "inverse_margin", "direct_margin")
"""The columns of :func:`square_metrics`' output, in order."""


FLOAT_EPSILON = float(np.finfo(np.float64).eps)
"""Machine epsilon of float64, as a compile-time constant (``np.finfo`` in a loop costs a call)."""

JACOBI_MAX = 2
"""Largest Gram matrix whose eigenvalues are found by Jacobi rotations, else tridiagonal QL.

Measured per Gram (with its product): both 0.07 us at 2 x 2, but Jacobi 0.42 against QL
0.27 us at 3 x 3 and 2.9 against 1.4 us at 9 x 9."""


@njit(cache=True)
def _gram(M: np.ndarray, G: np.ndarray) -> int:
    """The smaller Gram matrix of ``M`` (r, c) into ``G[:n, :n]`` (both triangles); returns n = min(r, c)."""
    r, c = M.shape
    n = min(r, c)
    for a in range(n):
        for b in range(a + 1):
            s = 0.0
            if r <= c:
                for t in range(c):
                    s += M[a, t] * M[b, t]
            else:
                for t in range(r):
                    s += M[t, a] * M[t, b]
            G[a, b] = s
            G[b, a] = s
    return n


@njit(cache=True)
def _jacobi_eigenvalues(G: np.ndarray, n: int, out: np.ndarray) -> None:
    """Eigenvalues of the symmetric ``G[:n, :n]`` (overwritten) into ``out[:n]``: cyclic Jacobi."""
    eps = FLOAT_EPSILON
    for _ in range(64):
        off = 0.0
        total = 0.0
        for a in range(n):
            total += G[a, a] * G[a, a]
            for b in range(a + 1, n):
                off += G[a, b] * G[a, b]
        if off <= eps * eps * (total + off):
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                if G[p, q] == 0.0:
                    continue
                theta = (G[q, q] - G[p, p]) / (2.0 * G[p, q])
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                cs = 1.0 / math.sqrt(t * t + 1.0)
                sn = t * cs
                for i in range(n):
                    gp, gq = G[i, p], G[i, q]
                    G[i, p], G[i, q] = cs * gp - sn * gq, sn * gp + cs * gq
                for i in range(n):
                    gp, gq = G[p, i], G[q, i]
                    G[p, i], G[q, i] = cs * gp - sn * gq, sn * gp + cs * gq
    for a in range(n):
        out[a] = G[a, a]


@njit(cache=True)
def _tridiagonal_eigenvalues(G: np.ndarray, n: int, d: np.ndarray, e: np.ndarray) -> bool:
    """Eigenvalues of the symmetric ``G[:n, :n]`` (overwritten) into ``d[:n]``; False if QL did not converge.

    ``e`` (at least n) is scratch.

    Householder reflections reduce ``G`` to a tridiagonal matrix (diagonal ``d``, subdiagonal
    ``e``), whose eigenvalues the implicit QL iteration with Wilkinson shifts finds, values
    only, in the root-free form of Pal, Walker and Kahan (on the squares of ``e``, as LAPACK's
    ``dsterf``: no square root per rotation, 7 % cheaper than ``tql1``'s on the 9 x 9 Gram
    of the 3D4M), deflating from the end of the diagonal with the smaller entry (``dsterf``'s
    choice, fewer rotations there). Both are backward stable: the values are exact for a
    symmetric matrix within a few round-offs of ``|G|``. An off-diagonal entry is dropped once
    below round-off of the tridiagonal's norm (not of its neighbours), which keeps that bound
    and saves the sweeps a relative test would spend on the zero eigenvalues of a
    rank-deficient Gram. Without LAPACK's scaling, ``|G|`` must lie between 1e-150 and 1e150
    (its squares stay normal), far from a Jacobian's Gram.
    """
    eps = FLOAT_EPSILON
    for k in range(n - 2):  # reflect x = G[k+1:, k] onto alpha e_0 by I - v v^T / h, v = x - alpha e_0
        xx = 0.0
        for i in range(k + 1, n):
            xx += G[i, k] * G[i, k]
        if xx == 0.0:
            e[k] = 0.0
            continue
        x0 = G[k + 1, k]
        alpha = -math.sqrt(xx) if x0 >= 0.0 else math.sqrt(xx)  # v_0 = x_0 - alpha: no cancellation
        h = xx - x0 * alpha  # v^T v / 2
        for i in range(k + 1, n):  # v into e[k+1:] (free until step i)
            e[i] = G[i, k]
        e[k + 1] = x0 - alpha
        vp = 0.0
        for i in range(k + 1, n):  # p = A22 v / h into d[k+1:]
            s = 0.0
            for j in range(k + 1, n):
                s += G[i, j] * e[j]
            s /= h
            d[i] = s
            vp += e[i] * s
        kk = vp / (2.0 * h)
        for i in range(k + 1, n):  # w = p - (v^T p / 2h) v
            d[i] -= kk * e[i]
        for i in range(k + 1, n):  # A22 <- H A22 H = A22 - v w^T - w v^T
            vi, wi = e[i], d[i]
            for j in range(k + 1, n):
                G[i, j] -= vi * d[j] + wi * e[j]
        e[k] = alpha
    for i in range(n):
        d[i] = G[i, i]
    if n >= 2:
        e[n - 2] = G[n - 1, n - 2]
    e[n - 1] = 0.0
    if abs(d[n - 1]) < abs(d[0]):  # deflate from the smaller end, as dsterf (QR on this order)
        for i in range(n // 2):
            d[i], d[n - 1 - i] = d[n - 1 - i], d[i]
        for i in range((n - 1) // 2):
            e[i], e[n - 2 - i] = e[n - 2 - i], e[i]
    norm = 0.0
    for i in range(n):
        norm = max(norm, abs(d[i]) + abs(e[i]) + (abs(e[i - 1]) if i > 0 else 0.0))
    small2 = (eps * norm) ** 2
    for i in range(n - 1):  # Pal-Walker-Kahan: the iteration runs on the squares of e
        e[i] = e[i] * e[i]
    for l in range(n):  # QL: deflate at the first negligible e[m] from l, chase the bulge from m up
        converged = False
        for _ in range(30 * n):
            m = l
            while m < n - 1 and e[m] > small2:
                m += 1
            if m == l:
                converged = True
                break
            p = d[l]
            rte = math.sqrt(e[l])
            sigma = (d[l + 1] - p) / (2.0 * rte)
            r = math.sqrt(sigma * sigma + 1.0)
            sigma = p - rte / (sigma + (r if sigma >= 0.0 else -r))  # Wilkinson shift
            c, s = 1.0, 0.0
            gamma = d[m] - sigma
            p = gamma * gamma
            for i in range(m - 1, l - 1, -1):  # root-free: no square root per rotation
                bb = e[i]
                r = p + bb
                if i != m - 1:
                    e[i + 1] = s * r
                oldc = c
                c = p / r
                s = bb / r
                oldgam = gamma
                alpha = d[i]
                gamma = c * (alpha - sigma) - s * oldgam
                d[i + 1] = oldgam + (alpha - gamma)
                p = gamma * gamma / c if c != 0.0 else oldc * bb
            e[l] = s * p
            d[l] = sigma + gamma
        if not converged:
            return False
    return True


@njit(cache=True)
def _finite(X: np.ndarray) -> bool:
    """Whether every entry of ``X`` (2-D) is finite, without the temporary of ``np.isfinite``."""
    for i in range(X.shape[0]):
        for j in range(X.shape[1]):
            if not math.isfinite(X[i, j]):
                return False
    return True


@njit(cache=True)
def _gram_eigenvalues(M: np.ndarray, G: np.ndarray, work: np.ndarray, out: np.ndarray) -> int:
    """Squared singular values of ``M`` (r, c), descending, into ``out``; returns n = min(r, c).

    Eigenvalues of the smaller Gram matrix (in the scratch ``G``, ``work`` of at least n) by
    cyclic Jacobi rotations up to :data:`JACOBI_MAX` rows, tridiagonal QL above, clipped at
    zero; NaN if the QL iteration did not converge (the caller's tests then reject the pose).
    """
    n = _gram(M, G)
    if n <= JACOBI_MAX:
        _jacobi_eigenvalues(G, n, out)
    elif not _tridiagonal_eigenvalues(G, n, out, work):
        out[:n] = np.nan
        return n
    for a in range(n):  # insertion sort, descending
        v = max(out[a], 0.0)
        b = a
        while b > 0 and out[b - 1] < v:
            out[b] = out[b - 1]
            b -= 1
        out[b] = v
    return n


@njit(cache=True)
def _frobenius(M: np.ndarray) -> float:
    """Frobenius norm of ``M`` (2-D): a bound of its largest singular value from above."""
    s = 0.0
    for i in range(M.shape[0]):
        for j in range(M.shape[1]):
            s += M[i, j] * M[i, j]
    return math.sqrt(s)


@njit(cache=True)
def square_metrics(
    A: np.ndarray,
    m: int,
    actuated_v: np.ndarray,
    mobility: int,
    e: Elimination,
    wanted: np.ndarray,
    factor_rcond: float,
    gram_rtol: float,
    inverse_rtol: float,
    out: np.ndarray,
    good: np.ndarray,
) -> None:
    r"""The map metrics of each stacked Jacobian ``A[p] = [J_phi; J_x]`` (B, m + k, nv), k = ``mobility``.

    Where ``A[p]`` is square (on its nonzero rows) and neither margin of :math:`C` or
    :math:`T` is asked for, :math:`J_{ce} = S_a` itself: :math:`J_x S = I` makes
    :math:`T^{-1} = R` and :math:`C T^{-1} = N_a R`. Its pose is accepted when
    :math:`1 / (|S|_F |J_x|_F) >` ``factor_rcond``, which bounds the condition number of
    :math:`S` (:math:`\sigma_{min}(S) \ge 1 / \sigma_{max}(J_x)`) and so implies both tests of
    the basis route (a pose between the two goes to the SVD path, with the same values).

    Only the stages the ``wanted`` metrics need run: the velocity map and its basis for all but
    the constraint margin, :math:`T^{-1}` for :math:`J_{ce}` and the inverse margin, the Gram
    eigenvalues of :math:`C T^{-1}` for the manipulability and condition number, of
    :math:`C` for the direct margin, of :math:`J_\phi` for the constraint margin, of
    :math:`T^{-1}` and :math:`J_x` for the inverse margin. Without the inverse margin, the test
    that :math:`T` is regular takes the Frobenius norms (each a bound of the largest singular
    value from above, so the margin tested is at most the true one: a pose passing it passes
    the exact test). Each pose is tested only on what it computes.

    Args:
        A: stacked Jacobians, shape (B, m + k, nv).
        m: closure rows.
        actuated_v: velocity indices of the actuators, shape (n_act,).
        mobility: DOF (= k).
        e: the structural pattern of ``A[p]`` (:class:`.linear.Elimination`; the square
            solves' cost, not their values, depends on it).
        wanted: which metrics to compute, one flag per :data:`METRIC_NAMES` entry, shape (5,).
        factor_rcond: smallest accepted ratio of the velocity map's QR diagonal.
        gram_rtol: smallest accepted ratio of squared singular values (the Gram's accuracy).
        inverse_rtol: smallest accepted inverse margin.
        out: the metrics (:data:`METRIC_NAMES`), shape (B, 5); the columns not wanted are left as they are.
        good: out, whether the pose passed every test (else its row of ``out`` is meaningless).
    """
    B, n, nv = A.shape
    k, na = mobility, actuated_v.shape[0]
    w_ce = wanted[0] or wanted[1]  # the singular values of J_ce = C T^-1
    w_phi, w_inverse, w_direct = wanted[2], wanted[3], wanted[4]
    w_t = w_ce or w_inverse  # T^-1
    w_basis = w_t or w_direct  # the velocity map and its basis N
    direct = w_ce and not (w_inverse or w_direct)  # J_ce read from the velocity map where A is square
    M = np.empty((nv, nv))
    S = np.empty((nv, k))
    N = np.empty((nv, k))
    d = np.empty(k)
    T = np.empty((k, k))
    T_inv = np.empty((k, k))
    C = np.empty((na, k))
    CT = np.empty((na, k))
    big = max(n, nv)
    F, RHS = np.empty((big, nv)), np.empty((big, k))
    pivots, step = np.empty(nv, dtype=np.int64), np.empty(big, dtype=np.int64)
    dense_v, dense_k = dense_elimination(nv, nv), dense_elimination(k, k)
    G = np.empty((big, big))
    work = np.empty(big)
    s_ce, s_c, s_phi, s_t, s_x = np.empty(big), np.empty(big), np.empty(big), np.empty(big), np.empty(big)
    rank = nv - k
    live = np.empty((n, nv))
    m_all = m
    for p in range(B):
        good[p] = False
        m = 0  # A without its zero closure rows (a planar loop's out-of-plane ones): the same metrics
        for i in range(m_all):
            zero = True
            for c in range(nv):
                if A[p, i, c] != 0.0:
                    zero = False
                    break
            if not zero:
                live[m] = A[p, i]
                m += 1
        for j in range(k):
            live[m + j] = A[p, m_all + j]
        Ap = live[: m + k]
        shortcut = direct and m + k == nv
        if w_basis:
            if m + k == nv:  # A S = [0; I], on A's nonzero rows
                RHS[:, :] = 0.0
                for j in range(k):
                    RHS[m_all + j, j] = 1.0
                solved = solve(A[p], e, F, pivots, step, RHS, S)
            else:  # A^T A S = J_x^T
                for a in range(nv):
                    for b in range(a + 1):
                        s = 0.0
                        for i in range(m + k):
                            s += Ap[i, a] * Ap[i, b]
                        M[a, b] = s
                        M[b, a] = s
                    for j in range(k):
                        RHS[a, j] = Ap[m + j, a]
                solved = solve(M, dense_v, F, pivots, step, RHS, S)
            if not solved or not _finite(S):
                continue
        if shortcut:
            # J_x S = I exactly (A square), so J_ce = C T^-1 = N_a R = S_a, with no basis; and
            # cond(S) <= |S| |J_x|: a pose passing this test passes the basis' and T's tests
            if not 1.0 / (_frobenius(S) * _frobenius(Ap[m:])) > factor_rcond:
                continue
            for a in range(na):
                for b in range(k):
                    CT[a, b] = S[actuated_v[a], b]
        elif w_basis:
            for j in range(k):  # Gram-Schmidt, twice
                for c in range(nv):
                    N[c, j] = S[c, j]
                for _ in range(2):
                    for i in range(j):
                        s = 0.0
                        for c in range(nv):
                            s += N[c, i] * N[c, j]
                        for c in range(nv):
                            N[c, j] -= s * N[c, i]
                s = 0.0
                for c in range(nv):
                    s += N[c, j] * N[c, j]
                d[j] = math.sqrt(s)
                if d[j] > 0.0:
                    for c in range(nv):
                        N[c, j] /= d[j]
            if not d.min() > factor_rcond * d.max():
                continue
        inverse = 0.0
        if w_t and not shortcut:
            for a in range(k):
                for b in range(k):
                    s = 0.0
                    for c in range(nv):
                        s += Ap[m + a, c] * N[c, b]
                    T[a, b] = s
                    RHS[a, b] = 1.0 if a == b else 0.0
            if not solve(T, dense_k, F, pivots, step, RHS[:k], T_inv):
                continue
            if w_inverse:
                _gram_eigenvalues(T_inv, G, work, s_t)
                _gram_eigenvalues(Ap[m:], G, work, s_x)
                inverse = 1.0 / (math.sqrt(s_t[0]) * math.sqrt(s_x[0]))
                tested = inverse
            else:
                tested = 1.0 / (_frobenius(T_inv) * _frobenius(Ap[m:]))
            if not tested > inverse_rtol:
                continue
        if w_ce or w_direct:
            for a in range(na):
                for b in range(k):
                    C[a, b] = N[actuated_v[a], b]
        n_ce = n_c = 0
        if w_ce:
            if not shortcut:
                for a in range(na):
                    for b in range(k):
                        s = 0.0
                        for c in range(k):
                            s += C[a, c] * T_inv[c, b]
                        CT[a, b] = s
            n_ce = _gram_eigenvalues(CT, G, work, s_ce)
            if not s_ce[n_ce - 1] > gram_rtol * s_ce[0]:
                continue
        if w_direct:
            n_c = _gram_eigenvalues(C, G, work, s_c)
            if not s_c[n_c - 1] > gram_rtol * s_c[0]:
                continue
        if w_phi:
            s_phi[:] = 0.0  # (fewer live rows than the rank: the rank-th value is zero)
            if m > 0:
                _gram_eigenvalues(Ap[:m], G, work, s_phi)
            if not s_phi[rank - 1] > gram_rtol * s_phi[0]:
                continue
        if w_ce:
            w = 1.0
            for i in range(n_ce):
                w *= math.sqrt(s_ce[i])
            out[p, 0] = w
            out[p, 1] = math.sqrt(s_ce[0]) / math.sqrt(s_ce[n_ce - 1])
        if w_phi:
            out[p, 2] = math.sqrt(s_phi[rank - 1] / s_phi[0])
        if w_inverse:
            out[p, 3] = inverse
        if w_direct:
            out[p, 4] = math.sqrt(s_c[n_c - 1])
        good[p] = True
