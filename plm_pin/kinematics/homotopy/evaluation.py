r"""Compiled evaluation of the polynomial system and its Jacobians over complex numbers.

Forward kinematics of the kept joints with complex :math:`4 \times 4` transforms: each
joint's world transform :math:`T_j = T_{parent(j)} M_j X_j(x_j)`; a closure frame's
derivative along a coordinate of joint :math:`j` on its path is
:math:`T_{parent(j)} M_j\, \partial X_j\, S_{j,f}`, with :math:`S_{j,f}` the transform from
joint :math:`j`'s moving frame to the frame (a suffix product, so no inverse is taken).
numba compiles it on first use (cached on disk); numba is imported only here.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .form import FREE_FLYER, PRISMATIC, PRISMATIC_PARAM, REVOLUTE, REVOLUTE_PARAM, SPHERICAL, PolynomialForm


@njit(cache=True, inline="always")
def _mm(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Product of two small complex matrices by plain loops (BLAS calls cost more at 4 x 4)."""
    m, k, n = A.shape[0], A.shape[1], B.shape[1]
    out = np.zeros((m, n), dtype=np.complex128)
    for i in range(m):
        for r in range(k):
            a = A[i, r]
            if a != 0:
                for j in range(n):
                    out[i, j] += a * B[r, j]
    return out


@njit(cache=True)
def _quaternion(w: complex, x: complex, y: complex, z: complex, R: np.ndarray, dR: np.ndarray) -> None:
    """Homogeneous quadratic rotation of a quaternion into ``R`` and its 4 derivatives into ``dR``."""
    R[0, 0], R[0, 1], R[0, 2] = w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)
    R[1, 0], R[1, 1], R[1, 2] = 2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)
    R[2, 0], R[2, 1], R[2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z
    # d/dw, d/dx, d/dy, d/dz
    dR[0, 0, 0], dR[0, 0, 1], dR[0, 0, 2] = 2 * w, -2 * z, 2 * y
    dR[0, 1, 0], dR[0, 1, 1], dR[0, 1, 2] = 2 * z, 2 * w, -2 * x
    dR[0, 2, 0], dR[0, 2, 1], dR[0, 2, 2] = -2 * y, 2 * x, 2 * w
    dR[1, 0, 0], dR[1, 0, 1], dR[1, 0, 2] = 2 * x, 2 * y, 2 * z
    dR[1, 1, 0], dR[1, 1, 1], dR[1, 1, 2] = 2 * y, -2 * x, -2 * w
    dR[1, 2, 0], dR[1, 2, 1], dR[1, 2, 2] = 2 * z, 2 * w, -2 * x
    dR[2, 0, 0], dR[2, 0, 1], dR[2, 0, 2] = -2 * y, 2 * x, 2 * w
    dR[2, 1, 0], dR[2, 1, 1], dR[2, 1, 2] = 2 * x, 2 * y, 2 * z
    dR[2, 2, 0], dR[2, 2, 1], dR[2, 2, 2] = -2 * w, 2 * z, -2 * y
    dR[3, 0, 0], dR[3, 0, 1], dR[3, 0, 2] = -2 * z, -2 * w, 2 * x
    dR[3, 1, 0], dR[3, 1, 1], dR[3, 1, 2] = 2 * w, -2 * z, 2 * y
    dR[3, 2, 0], dR[3, 2, 1], dR[3, 2, 2] = 2 * x, 2 * y, 2 * z


@njit(cache=True, inline="always")
def _mm_into(A: np.ndarray, B: np.ndarray, out: np.ndarray) -> None:
    """``out = A @ B`` for small complex matrices, by plain loops (no allocation)."""
    m, k, n = A.shape[0], A.shape[1], B.shape[1]
    for i in range(m):
        for j in range(n):
            acc = 0j
            for r in range(k):
                acc += A[i, r] * B[r, j]
            out[i, j] = acc


@njit(cache=True, inline="always")
def _skew_entry(a: np.ndarray, r: int, k: int) -> float:
    """Entry (r, k) of the cross-product matrix of ``a``."""
    if r == k:
        return 0.0
    if r == 0:
        return -a[2] if k == 1 else a[1]
    if r == 1:
        return a[2] if k == 0 else -a[0]
    return -a[1] if k == 0 else a[0]


@njit(cache=True)
def _local(
    kind: int, axis: np.ndarray, fixed: np.ndarray, v: np.ndarray, X: np.ndarray, dX: np.ndarray
) -> int:
    r"""Local transform of one joint from its coordinates ``v`` into ``X``, derivatives into ``dX``.

    Returns the number of coordinates (derivatives written). A revolute joint about the unit
    axis :math:`a`: :math:`R = I + s K + (1 - c) K^2`, :math:`K = [a]_\times`,
    :math:`K^2 = a a^T - (a^T a) I`.
    """
    X[:, :] = 0.0
    X[3, 3] = 1.0
    if kind == REVOLUTE or kind == REVOLUTE_PARAM:
        if kind == REVOLUTE:
            c, s = v[0], v[1]
        else:
            c, s = np.cos(v[0]), np.sin(v[0])
        aa = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]
        dX[0] = 0.0
        if kind == REVOLUTE:
            dX[1] = 0.0
        for r in range(3):
            for k in range(3):
                K = _skew_entry(axis, r, k)
                K2 = axis[r] * axis[k] - (aa if r == k else 0.0)
                X[r, k] = (1.0 if r == k else 0.0) + s * K + (1.0 - c) * K2
                if kind == REVOLUTE:
                    dX[0, r, k] = -K2
                    dX[1, r, k] = K
                else:
                    dX[0, r, k] = c * K + s * K2
        return 2 if kind == REVOLUTE else 1
    if kind == PRISMATIC or kind == PRISMATIC_PARAM:
        dX[0] = 0.0
        for r in range(3):
            X[r, r] = 1.0
            X[r, 3] = v[0] * axis[r]
            dX[0, r, 3] = axis[r]
        return 1
    if kind == SPHERICAL or kind == FREE_FLYER:
        t = 3 if kind == FREE_FLYER else 0
        dX[: t + 4] = 0.0
        _quaternion(v[t], v[t + 1], v[t + 2], v[t + 3], X[:3, :3], dX[t : t + 4, :3, :3])
        for r in range(t):
            X[r, 3] = v[r]
            dX[r, r, 3] = 1.0
        return t + 4
    for r in range(4):
        for k in range(4):
            X[r, k] = fixed[r, k]
    return 0


@njit(cache=True)
def _entries(
    x: np.ndarray,
    p: np.ndarray,
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
    n_entries: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Closure entries (m,) and their derivatives along (x, p), shape (m, n + n_params)."""
    n, npar, k = x.shape[0], p.shape[0], kind.shape[0]
    nc = n + npar
    Xs = np.zeros((k, 4, 4), dtype=np.complex128)
    dXs = np.zeros((k, 7, 4, 4), dtype=np.complex128)
    ncoord = np.zeros(k, dtype=np.int64)
    col = np.zeros(k, dtype=np.int64)  # first derivative column of each joint
    T = np.zeros((k, 4, 4), dtype=np.complex128)  # world transform after the joint
    A = np.zeros((k, 4, 4), dtype=np.complex128)  # world transform of the joint frame before X_j
    MX = np.zeros((k, 4, 4), dtype=np.complex128)  # M_j X_j
    AdX = np.zeros((k, 7, 4, 4), dtype=np.complex128)  # A_j dX_j, shared by the frames below joint j
    Mc = placement.astype(np.complex128)
    for i in range(k):
        kd = kind[i]
        if kd == REVOLUTE_PARAM or kd == PRISMATIC_PARAM:
            v = p[offset[i] : offset[i] + 1]
            col[i] = n + offset[i]
        else:
            v = x[offset[i] : offset[i] + 7]
            col[i] = offset[i]
        ncoord[i] = _local(kd, axis[i], fixed[i], v, Xs[i], dXs[i])
        if parent[i] >= 0:
            _mm_into(T[parent[i]], Mc[i], A[i])
        else:
            A[i] = Mc[i]
        _mm_into(A[i], Xs[i], T[i])
        _mm_into(Mc[i], Xs[i], MX[i])
        for c in range(ncoord[i]):
            _mm_into(A[i], dXs[i, c], AdX[i, c])
    nf = frame_joint.shape[0]
    Tf = np.zeros((nf, 4, 4), dtype=np.complex128)
    dTf = np.zeros((nf, nc, 4, 4), dtype=np.complex128)
    S = np.empty((4, 4), dtype=np.complex128)
    S2 = np.empty((4, 4), dtype=np.complex128)
    for f in range(nf):
        for r in range(4):
            for q in range(4):
                S[r, q] = frame_placement[f, r, q]
        i = frame_joint[f]
        if i >= 0:
            _mm_into(T[i], S, Tf[f])
        else:
            Tf[f] = S
        while i >= 0:
            for c in range(ncoord[i]):
                _mm_into(AdX[i, c], S, dTf[f, col[i] + c])
            _mm_into(MX[i], S, S2)
            S[:, :] = S2
            i = parent[i]
    e = np.zeros(n_entries, dtype=np.complex128)
    de = np.zeros((n_entries, nc), dtype=np.complex128)
    E = np.empty((3, 3), dtype=np.complex128)
    for c in range(closure_kind.shape[0]):
        a, b, o = closure_frames[c, 0], closure_frames[c, 1], entry_offset[c]
        if closure_kind[c] == 3:  # |p_B - p_A|^2 - L^2
            e[o] = -closure_length2[c]
            for r in range(3):
                d = Tf[b, r, 3] - Tf[a, r, 3]
                e[o] += d * d
                for j in range(nc):
                    de[o, j] += 2.0 * d * (dTf[b, j, r, 3] - dTf[a, j, r, 3])
            continue
        for r in range(3):
            e[o + r] = Tf[b, r, 3] - Tf[a, r, 3]
            for j in range(nc):
                de[o + r, j] = dTf[b, j, r, 3] - dTf[a, j, r, 3]
        if closure_kind[c] == 0:
            continue
        # E = R_A^T R_B and its derivatives dR_A^T R_B + R_A^T dR_B, entry by entry
        for r in range(3):
            for q in range(3):
                acc = 0j
                for t in range(3):
                    acc += Tf[a, t, r] * Tf[b, t, q]
                E[r, q] = acc
        u = closure_axis[c]
        if closure_kind[c] == 1:
            for r in range(3):
                for q in range(3):
                    e[o + 3 + 3 * r + q] = E[r, q] - (1.0 if r == q else 0.0)
        else:
            for r in range(3):
                e[o + 3 + r] = E[r, 0] * u[0] + E[r, 1] * u[1] + E[r, 2] * u[2] - u[r]
        for j in range(nc):
            for r in range(3):
                for q in range(3):
                    acc = 0j
                    for t in range(3):
                        acc += dTf[a, j, t, r] * Tf[b, t, q] + Tf[a, t, r] * dTf[b, j, t, q]
                    E[r, q] = acc
            if closure_kind[c] == 1:
                for r in range(3):
                    for q in range(3):
                        de[o + 3 + 3 * r + q, j] = E[r, q]
            else:
                for r in range(3):
                    de[o + 3 + r, j] = E[r, 0] * u[0] + E[r, 1] * u[1] + E[r, 2] * u[2]
    return e, de


@njit(cache=True)
def system(
    x: np.ndarray,
    p: np.ndarray,
    b: np.ndarray,
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
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Square system :math:`F(x; p) + b`, its Jacobians along x (n, n) and p (n, n_params)."""
    n, npar = x.shape[0], p.shape[0]
    e, de = _entries(
        x,
        p,
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
        combination.shape[1],
    )
    F = np.zeros(n, dtype=np.complex128)
    J = np.zeros((n, n + npar), dtype=np.complex128)
    nu = unit_offsets.shape[0]
    for u in range(nu):
        o = unit_offsets[u]
        acc = -1.0 + 0j
        for r in range(unit_sizes[u]):
            acc += x[o + r] * x[o + r]
            J[u, o + r] = 2.0 * x[o + r]
        F[u] = acc
    C = combination.astype(np.complex128)
    F[nu:] = _mm(C, e.reshape(-1, 1)).ravel()
    J[nu:] = _mm(C, de)
    F += b
    return F, J[:, :n].copy(), J[:, n:].copy()


def closure_entries(form: PolynomialForm, x: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closure entries at complex ``x``, ``p`` (m,) and their derivatives along (x, p), (m, n + n_params)."""
    return _entries(
        np.asarray(x, dtype=np.complex128),
        np.asarray(p, dtype=np.complex128),
        form.parent,
        form.kind,
        form.offset,
        form.axis,
        form.placement,
        form.fixed,
        form.frame_joint,
        form.frame_placement,
        form.closure_kind,
        form.closure_frames,
        form.closure_axis,
        form.closure_length2,
        form.entry_offset,
        form.n_entries,
    )


def evaluate(
    form: PolynomialForm, x: np.ndarray, p: np.ndarray, b: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Square system at complex ``x``, ``p`` (plus offsets ``b``): F (n,), F_x (n, n), F_p (n, n_params)."""
    bb = np.zeros(form.n, dtype=np.complex128) if b is None else np.asarray(b, dtype=np.complex128)
    return system(
        np.asarray(x, dtype=np.complex128), np.asarray(p, dtype=np.complex128), bb, *form.kernel_args()
    )
