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
def _skew(a: np.ndarray) -> np.ndarray:
    K = np.zeros((3, 3), dtype=np.complex128)
    K[0, 1], K[0, 2], K[1, 2] = -a[2], a[1], -a[0]
    K[1, 0], K[2, 0], K[2, 1] = a[2], -a[1], a[0]
    return K


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


@njit(cache=True)
def _local(
    kind: int, axis: np.ndarray, fixed: np.ndarray, v: np.ndarray, X: np.ndarray, dX: np.ndarray
) -> int:
    """Local transform of one joint from its coordinates ``v`` into ``X``, derivatives into ``dX``.

    Returns the number of coordinates (derivatives written).
    """
    X[:, :] = 0.0
    X[3, 3] = 1.0
    if kind == REVOLUTE or kind == REVOLUTE_PARAM:
        K = _skew(axis.astype(np.complex128))
        K2 = _mm(K, K)
        if kind == REVOLUTE:
            c, s = v[0], v[1]
        else:
            c, s = np.cos(v[0]), np.sin(v[0])
        for r in range(3):
            for k in range(3):
                X[r, k] = (1.0 if r == k else 0.0) + s * K[r, k] + (1.0 - c) * K2[r, k]
        dX[:2] = 0.0
        if kind == REVOLUTE:
            dX[0, :3, :3] = -K2
            dX[1, :3, :3] = K
            return 2
        dX[0, :3, :3] = c * K + s * K2
        return 1
    if kind == PRISMATIC or kind == PRISMATIC_PARAM:
        for r in range(3):
            X[r, r] = 1.0
            X[r, 3] = v[0] * axis[r]
        dX[0] = 0.0
        for r in range(3):
            dX[0, r, 3] = axis[r]
        return 1
    if kind == SPHERICAL or kind == FREE_FLYER:
        t = 3 if kind == FREE_FLYER else 0
        dR = np.zeros((4, 3, 3), dtype=np.complex128)
        R = np.zeros((3, 3), dtype=np.complex128)
        _quaternion(v[t], v[t + 1], v[t + 2], v[t + 3], R, dR)
        X[:3, :3] = R
        dX[: t + 4] = 0.0
        for r in range(t):
            X[r, 3] = v[r]
            dX[r, r, 3] = 1.0
        for k in range(4):
            dX[t + k, :3, :3] = dR[k]
        return t + 4
    X[:, :] = fixed
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
    Mc = placement.astype(np.complex128)
    Fc = fixed.astype(np.complex128)
    for i in range(k):
        kd = kind[i]
        if kd == REVOLUTE_PARAM or kd == PRISMATIC_PARAM:
            v = p[offset[i] : offset[i] + 1]
            col[i] = n + offset[i]
        else:
            v = x[offset[i] : offset[i] + 7] if kd != 0 else x[:0]
            col[i] = offset[i]
        ncoord[i] = _local(kd, axis[i], Fc[i], v, Xs[i], dXs[i])
        if parent[i] >= 0:
            A[i] = _mm(T[parent[i]], Mc[i])
        else:
            A[i] = Mc[i]
        T[i] = _mm(A[i], Xs[i])
    AdX = np.zeros((k, 7, 4, 4), dtype=np.complex128)  # A_j dX_j, shared by the frames below joint j
    for i in range(k):
        for c in range(ncoord[i]):
            AdX[i, c] = _mm(A[i], dXs[i, c])
    nf = frame_joint.shape[0]
    Tf = np.zeros((nf, 4, 4), dtype=np.complex128)
    dTf = np.zeros((nf, nc, 4, 4), dtype=np.complex128)
    for f in range(nf):
        S = frame_placement[f].astype(np.complex128)
        i = frame_joint[f]
        Tf[f] = _mm(T[i], S) if i >= 0 else S
        while i >= 0:
            for c in range(ncoord[i]):
                dTf[f, col[i] + c] = _mm(AdX[i, c], S)
            S = _mm(_mm(Mc[i], Xs[i]), S)
            i = parent[i]
    e = np.zeros(n_entries, dtype=np.complex128)
    de = np.zeros((n_entries, nc), dtype=np.complex128)
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
        RaT, Rb = Tf[a, :3, :3].T.copy(), Tf[b, :3, :3].copy()
        E = _mm(RaT, Rb)
        if closure_kind[c] == 1:
            for r in range(3):
                for s in range(3):
                    e[o + 3 + 3 * r + s] = E[r, s] - (1.0 if r == s else 0.0)
            for j in range(nc):
                dE = _mm(dTf[a, j, :3, :3].T, Rb) + _mm(RaT, dTf[b, j, :3, :3])
                for r in range(3):
                    for s in range(3):
                        de[o + 3 + 3 * r + s, j] = dE[r, s]
        else:
            u = closure_axis[c].astype(np.complex128)
            Eu = _mm(E, u.reshape(3, 1)).ravel()
            for r in range(3):
                e[o + 3 + r] = Eu[r] - u[r]
            for j in range(nc):
                dEu = _mm(_mm(dTf[a, j, :3, :3].T, Rb) + _mm(RaT, dTf[b, j, :3, :3]), u.reshape(3, 1)).ravel()
                for r in range(3):
                    de[o + 3 + r, j] = dEu[r]
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
