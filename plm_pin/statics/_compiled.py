r"""The balance factorisation of :func:`~plm_pin.statics.balance.balance_factors` in one compiled call.

The common case only: closure rows clearly of full rank (the QR of :math:`J_\phi^T`,
the exact 1-norm condition of :math:`R` above the threshold of
:func:`~plm_pin.statics.balance.closure_factors`) and a load the actuators resist. Anything
else returns a status and the caller takes the LAPACK path, which decides and words the
error. One call replaces a dozen LAPACK and numpy calls, whose Python overhead is most of
the cost on matrices of 9 to 30 columns. numba is imported only here.
"""

from __future__ import annotations

import numpy as np
from numba import njit

OK, FALLBACK = 0, 1
"""Status of :func:`factor`: done; or not the common case (the caller takes the LAPACK path)."""


@njit(cache=True)
def _upper_inverse(R: np.ndarray) -> np.ndarray:
    """Inverse of the upper-triangular ``R`` with a non-zero diagonal (back substitution)."""
    r = R.shape[0]
    X = np.zeros((r, r))
    for c in range(r):
        X[c, c] = 1.0 / R[c, c]
        for i in range(c - 1, -1, -1):
            s = 0.0
            for k in range(i + 1, c + 1):
                s += R[i, k] * X[k, c]
            X[i, c] = -s / R[i, i]
    return X


@njit(cache=True)
def _norm1(A: np.ndarray) -> float:
    return float(np.abs(A).sum(axis=0).max()) if A.size else 0.0


@njit(cache=True)
def _oriented(G: np.ndarray, tie: float) -> np.ndarray:
    """:func:`~plm_pin.statics.balance.oriented_internal_basis`, step for step."""
    n_act, k = G.shape
    if k == 0:
        return G.copy()
    if k == 1:
        g = np.abs(G[:, 0])
        top = g.max()
        pivot = 0
        for i in range(n_act):
            if g[i] >= (1.0 - tie) * top:
                pivot = i
                break
        return G.copy() if G[pivot, 0] > 0.0 else -G
    A = np.ascontiguousarray(G.T)
    rows = np.ascontiguousarray(G)
    shares = np.zeros(n_act)
    for i in range(n_act):
        shares[i] = rows[i] @ rows[i]
    Q = np.zeros((k, k))
    for j in range(k):
        top = shares.max()
        pivot = 0
        for i in range(n_act):
            if shares[i] >= (1.0 - tie) ** 2 * top:
                pivot = i
                break
        a = np.ascontiguousarray(A[:, pivot])
        w = a - Q @ (Q.T @ a)
        q = w / np.sqrt(w @ w)
        Q[:, j] = q
        shares = shares - (q @ A) ** 2
    return G @ Q


@njit(cache=True)
def factor(
    J: np.ndarray,
    act_v: np.ndarray,
    tau: np.ndarray,
    singular_rtol: float,
    closure_tol: float,
    equilibrium_rtol: float,
    tie: float,
) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""``(status, N, lambda_map, C, P, G)`` of :func:`~plm_pin.statics.balance.balance_factors`.

    ``status`` is :data:`OK`, or :data:`FALLBACK` with empty arrays: closure rows not clearly
    of full rank or none left free, or a load on feasible motions the actuators do not hold.
    """
    m, nv = J.shape
    n_act = act_v.shape[0]
    empty = np.zeros((0, 0))
    keep = np.zeros(m, dtype=np.bool_)
    for i in range(m):
        for c in range(nv):
            if J[i, c] != 0.0:
                keep[i] = True
                break
    rows = np.flatnonzero(keep)
    r = rows.shape[0]
    if r == 0 or r > nv:
        return FALLBACK, empty, empty, empty, empty, empty
    At = np.zeros((nv, nv))  # J^T padded with zero columns: the same reflectors, and the full Q
    for j in range(r):
        At[:, j] = J[rows[j]]
    Q, Rfull = np.linalg.qr(At)  # LAPACK geqrf + orgqr, as closure_factors
    R = np.ascontiguousarray(Rfull[:r, :r])
    for j in range(r):
        if R[j, j] == 0.0:
            return FALLBACK, empty, empty, empty, empty, empty
    Rinv = _upper_inverse(R)
    if 1.0 / (_norm1(R) * _norm1(Rinv)) <= 1e3 * max(singular_rtol, closure_tol):
        return FALLBACK, empty, empty, empty, empty, empty
    lambda_map = np.zeros((m, nv))
    L = np.ascontiguousarray(Rinv) @ np.ascontiguousarray(Q[:, :r].T)
    for j in range(r):
        lambda_map[rows[j]] = L[j]
    N0 = np.ascontiguousarray(Q[:, r:])
    k0 = nv - r
    if k0 == 0:
        return FALLBACK, empty, empty, empty, empty, empty
    C0 = np.empty((n_act, k0))
    for i in range(n_act):
        C0[i] = N0[act_v[i]]
    U, s, Vt_any = np.linalg.svd(C0)
    Vt = np.ascontiguousarray(Vt_any)  # numba types LAPACK's outputs as any layout
    top = s[0] if s.shape[0] else 1.0
    rank = 0
    for v in s:
        if v > singular_rtol * top:
            rank += 1
    b = N0.T @ tau
    scale = max(np.abs(tau).max() if tau.shape[0] else 0.0, 1e-300)
    for i in range(rank, k0):
        if abs(Vt[i] @ b) > equilibrium_rtol * scale:
            return FALLBACK, empty, empty, empty, empty, empty
    N = N0 @ np.ascontiguousarray(Vt.T)
    P = (U[:, :rank] / s[:rank]) @ np.ascontiguousarray(N[:, :rank].T)
    G = _oriented(np.ascontiguousarray(U[:, rank:]), tie)
    C = np.empty((n_act, k0))
    for i in range(n_act):
        C[i] = N[act_v[i]]
    return OK, N, lambda_map, C, P, G


@njit(cache=True)
def point_closure_rows(
    Jw: np.ndarray,
    t: np.ndarray,
    support: np.ndarray,
    plus: np.ndarray,
    minus: np.ndarray,
    axis: np.ndarray,
    tol: float,
    J: np.ndarray,
) -> bool:
    r"""Jacobian of point closures into ``J`` from Pinocchio's joint Jacobians; whether they close to ``tol``.

    Pinocchio's arithmetic, step for step: the world-aligned Jacobian of frame ``f`` at column
    ``c`` of its joint's support is :math:`(v - p_f \times \omega, \omega)` (``getFrameJacobian``
    with ``LOCAL_WORLD_ALIGNED``), zero elsewhere; a closure row is the difference of its two
    frames' rows, and its residual the difference of their positions (the products of
    :class:`~plm_pin.core.closures.BoundClosures` with its +1 / -1 maps: one rounding each).

    Args:
        Jw: ``data.J``, the joint Jacobians in the world frame, shape (6, nv).
        t: positions of the closure frames, shape (n_frames, 3) [m].
        support: whether column ``c`` moves frame ``f``, shape (n_frames, nv).
        plus: frame B of each row (index in the frames), shape (m,).
        minus: frame A of each row, shape (m,).
        axis: the coordinate (0, 1, 2) of each row, shape (m,).
        tol: largest residual of a closed configuration [m].
        J: output, shape (m, nv).
    """
    m, nv = J.shape
    closed = True
    for r in range(m):
        b, a, i = plus[r], minus[r], axis[r]
        phi = t[b, i] - t[a, i]
        if not abs(phi) <= tol:  # NaN: not closed
            closed = False
        i1, i2 = (i + 1) % 3, (i + 2) % 3  # (p x w)_i = p_i1 w_i2 - p_i2 w_i1
        for c in range(nv):
            vb = Jw[i, c] - (t[b, i1] * Jw[3 + i2, c] - t[b, i2] * Jw[3 + i1, c]) if support[b, c] else 0.0
            va = Jw[i, c] - (t[a, i1] * Jw[3 + i2, c] - t[a, i2] * Jw[3 + i1, c]) if support[a, c] else 0.0
            d = vb - va
            J[r, c] = d if d != 0.0 else 0.0  # a zero is +0, as the sum of the +1 / -1 product
    return closed
