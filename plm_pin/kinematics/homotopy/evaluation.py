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

FAST = {"contract", "reassoc", "nsz", "arcp"}
"""LLVM fast-math flags of the kernels: reassociation and fused multiply-adds, but NaN and infinity
kept (a path going to infinity must be seen)."""


@njit(cache=True, inline="always")
def _quaternion(
    w: complex, x: complex, y: complex, z: complex, X: np.ndarray, i: int, dX: np.ndarray, d: int
) -> None:
    """Quadratic rotation of a quaternion into ``X[i, :3, :3]``, its 4 derivatives into ``dX[d:d + 4]``."""
    X[i, 0, 0], X[i, 0, 1], X[i, 0, 2] = (
        w * w + x * x - y * y - z * z,
        2 * (x * y - w * z),
        2 * (x * z + w * y),
    )
    X[i, 1, 0], X[i, 1, 1], X[i, 1, 2] = (
        2 * (x * y + w * z),
        w * w - x * x + y * y - z * z,
        2 * (y * z - w * x),
    )
    X[i, 2, 0], X[i, 2, 1], X[i, 2, 2] = (
        2 * (x * z - w * y),
        2 * (y * z + w * x),
        w * w - x * x - y * y + z * z,
    )
    # d/dw, d/dx, d/dy, d/dz
    dX[d, 0, 0], dX[d, 0, 1], dX[d, 0, 2] = 2 * w, -2 * z, 2 * y
    dX[d, 1, 0], dX[d, 1, 1], dX[d, 1, 2] = 2 * z, 2 * w, -2 * x
    dX[d, 2, 0], dX[d, 2, 1], dX[d, 2, 2] = -2 * y, 2 * x, 2 * w
    dX[d + 1, 0, 0], dX[d + 1, 0, 1], dX[d + 1, 0, 2] = 2 * x, 2 * y, 2 * z
    dX[d + 1, 1, 0], dX[d + 1, 1, 1], dX[d + 1, 1, 2] = 2 * y, -2 * x, -2 * w
    dX[d + 1, 2, 0], dX[d + 1, 2, 1], dX[d + 1, 2, 2] = 2 * z, 2 * w, -2 * x
    dX[d + 2, 0, 0], dX[d + 2, 0, 1], dX[d + 2, 0, 2] = -2 * y, 2 * x, 2 * w
    dX[d + 2, 1, 0], dX[d + 2, 1, 1], dX[d + 2, 1, 2] = 2 * x, 2 * y, 2 * z
    dX[d + 2, 2, 0], dX[d + 2, 2, 1], dX[d + 2, 2, 2] = -2 * w, 2 * z, -2 * y
    dX[d + 3, 0, 0], dX[d + 3, 0, 1], dX[d + 3, 0, 2] = -2 * z, -2 * w, 2 * x
    dX[d + 3, 1, 0], dX[d + 3, 1, 1], dX[d + 3, 1, 2] = 2 * w, -2 * z, 2 * y
    dX[d + 3, 2, 0], dX[d + 3, 2, 1], dX[d + 3, 2, 2] = 2 * x, 2 * y, 2 * z


@njit(cache=True, inline="always", fastmath=FAST)
def _mm_into(
    A: np.ndarray, a: int, B: np.ndarray, b: int, out: np.ndarray, o: int, rotates: bool, moves: bool
) -> None:
    """``out[o] = A[a] @ B[b]`` for stacks of complex 4 x 4 matrices, by plain loops.

    Every matrix here is a homogeneous transform (last row 0 0 0 1) or a derivative of one (last
    row 0), so the last rows' first three entries are zero and are not multiplied (43 products
    instead of 64). ``B[b]``'s upper-left 3 x 3 block is the identity unless ``rotates``, and its
    translation (first three entries of the last column) zero unless ``moves``: the products by
    those ones and zeros are skipped (the entries of ``A[a]`` they give are copied, the same
    numbers). Indices rather than views: a view costs a reference count in the compiled code, and
    the kernels take hundreds of products per evaluation.
    """
    for i in range(3):
        for j in range(3):
            if rotates:
                out[o, i, j] = A[a, i, 0] * B[b, 0, j] + A[a, i, 1] * B[b, 1, j] + A[a, i, 2] * B[b, 2, j]
            else:
                out[o, i, j] = A[a, i, j]
        if moves:
            t = A[a, i, 0] * B[b, 0, 3] + A[a, i, 1] * B[b, 1, 3] + A[a, i, 2] * B[b, 2, 3]
            out[o, i, 3] = t + A[a, i, 3] * B[b, 3, 3]
        else:
            out[o, i, 3] = A[a, i, 3] * B[b, 3, 3]
    for j in range(3):
        out[o, 3, j] = 0.0
    out[o, 3, 3] = A[a, 3, 3] * B[b, 3, 3]


@njit(cache=True, inline="always")
def _translated_into(M: np.ndarray, X: np.ndarray, i: int, out: np.ndarray) -> None:
    """``out[i] = M[i] @ X[i]`` for a pure translation ``M[i]``: ``X[i]`` with ``M[i]``'s translation added.

    The same numbers as :func:`_mm_into` (its other products are by ones and zeros).
    """
    for r in range(4):
        for k in range(4):
            out[i, r, k] = X[i, r, k]
    for r in range(3):
        out[i, r, 3] += M[i, r, 3]


@njit(cache=True, inline="always", fastmath=FAST)
def _derivative_into(
    A: np.ndarray, a: int, rotates: bool, dX: np.ndarray, d: int, translation: bool, out: np.ndarray
) -> None:
    """``out[d] = A[a] @ dX[d]`` for a joint's local derivative ``dX[d]``, by its structure.

    A derivative along a translation coordinate has only its last column (the axis, first three
    entries); along a rotation coordinate (cos, sin, angle, quaternion) only its upper-left
    3 x 3 block. So the product is a rotation times a vector (9 products) or two 3 x 3 blocks (27),
    instead of a matrix product's 43; the zero parts are never written (the buffer starts at zero,
    and each slot keeps its structure). Unless ``rotates``, ``A[a]``'s rotation block is the
    identity (a joint on the world placed by a translation): the product is ``dX[d]``'s entries.
    """
    for r in range(3):
        if translation:
            if rotates:
                out[d, r, 3] = A[a, r, 0] * dX[d, 0, 3] + A[a, r, 1] * dX[d, 1, 3] + A[a, r, 2] * dX[d, 2, 3]
            else:
                out[d, r, 3] = dX[d, r, 3]
        else:
            for k in range(3):
                if rotates:
                    out[d, r, k] = (
                        A[a, r, 0] * dX[d, 0, k] + A[a, r, 1] * dX[d, 1, k] + A[a, r, 2] * dX[d, 2, k]
                    )
                else:
                    out[d, r, k] = dX[d, r, k]


@njit(cache=True, inline="always", fastmath=FAST)
def _mv_into(A: np.ndarray, a: int, S: np.ndarray, s: int, out: np.ndarray, o: int) -> None:
    """``out[o, :3, 3] = (A[a] @ S[s])[:3, 3]``: a transform (or its derivative) applied to a point.

    The point is the last column of ``S[s]`` (its fourth entry 1): 12 products instead of a
    matrix product's 43, for the closure frames whose rotation no closure reads.
    """
    for r in range(3):
        out[o, r, 3] = (
            A[a, r, 0] * S[s, 0, 3]
            + A[a, r, 1] * S[s, 1, 3]
            + A[a, r, 2] * S[s, 2, 3]
            + A[a, r, 3] * S[s, 3, 3]
        )


@njit(cache=True, inline="always", fastmath=FAST)
def _point_derivative_into(
    AdX: np.ndarray, d: int, translation: bool, S: np.ndarray, out: np.ndarray, o: int
) -> None:
    """``out[o, :3, 3] = (AdX[d] @ S[0])[:3, 3]`` for a derivative ``AdX[d]`` of :func:`_derivative_into`.

    As :func:`_mv_into`, by the derivative's structure: along a translation coordinate it is its
    last column (the point's fourth entry is 1), along a rotation one its 3 x 3 block times the
    point (9 products instead of 12; the terms left out are zero).
    """
    for r in range(3):
        if translation:
            out[o, r, 3] = AdX[d, r, 3]
        else:
            out[o, r, 3] = AdX[d, r, 0] * S[0, 0, 3] + AdX[d, r, 1] * S[0, 1, 3] + AdX[d, r, 2] * S[0, 2, 3]


@njit(cache=True, inline="always")
def _copy_into(A: np.ndarray, a: int, out: np.ndarray, o: int) -> None:
    """``out[o] = A[a]`` for stacks of 4 x 4 matrices."""
    for i in range(4):
        for j in range(4):
            out[o, i, j] = A[a, i, j]


@njit(cache=True, inline="always")
def _skew_entry(axis: np.ndarray, i: int, r: int, k: int) -> float:
    """Entry (r, k) of the cross-product matrix of ``axis[i]``."""
    if r == k:
        return 0.0
    if r == 0:
        return -axis[i, 2] if k == 1 else axis[i, 1]
    if r == 1:
        return axis[i, 2] if k == 0 else -axis[i, 0]
    return -axis[i, 1] if k == 0 else axis[i, 0]


@njit(cache=True, inline="always")
def _constant_local(
    kind: int, axis: np.ndarray, fixed: np.ndarray, i: int, X: np.ndarray, dX: np.ndarray, G: np.ndarray
) -> None:
    r"""The entries of joint ``i``'s ``X[i]`` and ``dX[7 i:]`` that do not depend on its coordinates.

    Written once into zeroed buffers (:func:`_local` writes the others at each evaluation): the
    ones, a fixed joint's transform, the derivatives of a revolute joint in (cos, sin)
    (:math:`-K^2` and :math:`K`), of a prismatic joint (its axis) and of a free-flyer's
    translation; and a revolute joint's :math:`K = [a]_\times` and :math:`K^2 = a a^T - (a^T a) I`
    into ``G[i, 0]`` and ``G[i, 1]``.
    """
    d = 7 * i
    X[i, 3, 3] = 1.0
    if kind == FIXED:
        for r in range(3):
            for k in range(4):
                X[i, r, k] = fixed[i, r, k]
    if kind == REVOLUTE or kind == REVOLUTE_PARAM:
        aa = axis[i, 0] * axis[i, 0] + axis[i, 1] * axis[i, 1] + axis[i, 2] * axis[i, 2]
        for r in range(3):
            for k in range(3):
                G[i, 0, r, k] = _skew_entry(axis, i, r, k)
                G[i, 1, r, k] = axis[i, r] * axis[i, k] - (aa if r == k else 0.0)
                if kind == REVOLUTE:
                    dX[d, r, k] = -G[i, 1, r, k]
                    dX[d + 1, r, k] = G[i, 0, r, k]
    elif kind == PRISMATIC or kind == PRISMATIC_PARAM:
        for r in range(3):
            X[i, r, r] = 1.0
            dX[d, r, 3] = axis[i, r]
    elif kind == FREE_FLYER:
        for r in range(3):
            dX[d + r, r, 3] = 1.0


@njit(cache=True, inline="always", fastmath=FAST)
def _local(
    kind: int,
    axis: np.ndarray,
    G: np.ndarray,
    i: int,
    v: np.ndarray,
    o: int,
    X: np.ndarray,
    dX: np.ndarray,
) -> None:
    r"""Local transform of joint ``i`` from ``v[o:]`` into ``X[i]``, its derivatives into ``dX[7 i:]``.

    The entries that depend on the coordinates; :func:`_constant_local` wrote the others. A
    revolute joint about the unit axis :math:`a`: :math:`R = I + s K + (1 - c) K^2` (``G[i]``).
    """
    d = 7 * i
    if kind == REVOLUTE or kind == REVOLUTE_PARAM:
        if kind == REVOLUTE:
            c, s = v[o], v[o + 1]
        else:
            c, s = np.cos(v[o]), np.sin(v[o])
        for r in range(3):
            for k in range(3):
                X[i, r, k] = (1.0 if r == k else 0.0) + s * G[i, 0, r, k] + (1.0 - c) * G[i, 1, r, k]
                if kind == REVOLUTE_PARAM:
                    dX[d, r, k] = c * G[i, 0, r, k] + s * G[i, 1, r, k]
    elif kind == PRISMATIC or kind == PRISMATIC_PARAM:
        for r in range(3):
            X[i, r, 3] = v[o] * axis[i, r]
    elif kind == SPHERICAL or kind == FREE_FLYER:
        t = 3 if kind == FREE_FLYER else 0
        _quaternion(v[o + t], v[o + t + 1], v[o + t + 2], v[o + t + 3], X, i, dX, d + t)
        for r in range(t):
            X[i, r, 3] = v[o + r]


@njit(cache=True)
def workspace(
    n: int,
    npar: int,
    parent: np.ndarray,
    kind: np.ndarray,
    offset: np.ndarray,
    axis: np.ndarray,
    placement: np.ndarray,
    fixed: np.ndarray,
    frame_joint: np.ndarray,
    closure_kind: np.ndarray,
    closure_frames: np.ndarray,
    n_entries: int,
) -> tuple:
    """The buffers :func:`generic_system` writes into, allocated once per batch of evaluations.

    Also what does not change from one evaluation to the next: the local transforms' entries that
    do not depend on the coordinates (:func:`_constant_local`), and the structure: the derivative
    column of each joint, the number of its coordinates, which columns a closure frame depends on
    (a column off a frame's path stays zero, as do the entries of a derivative matrix a joint
    kind never writes), per joint whether :math:`M_j` and :math:`X_j` rotate and move (their
    rotation block is not the identity, their translation not zero: the ``rotates`` and
    ``moves`` of :func:`_mm_into`; most placements are pure translations, a revolute or spherical
    joint does not move, a prismatic one does not rotate), per joint coordinate whether its
    derivative is along a translation (else a rotation), and which closure frames are read as
    points (their origin alone: point and distance closures).
    """
    k, nf, nc = kind.shape[0], frame_joint.shape[0], n + npar
    ncoord = np.zeros(k, dtype=np.int64)
    col = np.zeros(k, dtype=np.int64)
    for i in range(k):
        kd = kind[i]
        col[i] = n + offset[i] if kd == REVOLUTE_PARAM or kd == PRISMATIC_PARAM else offset[i]
        if kd == REVOLUTE:
            ncoord[i] = 2
        elif kd == SPHERICAL:
            ncoord[i] = 4
        elif kd == FREE_FLYER:
            ncoord[i] = 7
        elif kd == PRISMATIC or kd == PRISMATIC_PARAM or kd == REVOLUTE_PARAM:
            ncoord[i] = 1
    # (M_j rotates, M_j moves, X_j rotates, X_j moves) per joint; per joint coordinate, whether its
    # derivative is along a translation (else a rotation)
    rigid = np.zeros((k, 4), dtype=np.bool_)
    translation = np.zeros(7 * k, dtype=np.bool_)
    for i in range(k):
        kd = kind[i]
        slides = kd == PRISMATIC or kd == PRISMATIC_PARAM
        rigid[i, 0] = np.any(placement[i, :3, :3] != np.eye(3))
        rigid[i, 1] = np.any(placement[i, :3, 3] != 0.0)
        if kd == FIXED:
            rigid[i, 2] = np.any(fixed[i, :3, :3] != np.eye(3))
            rigid[i, 3] = np.any(fixed[i, :3, 3] != 0.0)
        else:
            rigid[i, 2] = not slides
            rigid[i, 3] = slides or kd == FREE_FLYER
        for c in range(ncoord[i]):
            translation[7 * i + c] = slides or (kd == FREE_FLYER and c < 3)
    point = np.ones(nf, dtype=np.bool_)  # only the frame's origin is read (point and distance closures)
    for c in range(closure_kind.shape[0]):
        if closure_kind[c] == 1 or closure_kind[c] == 2:
            point[closure_frames[c, 0]] = point[closure_frames[c, 1]] = False
    on_path = np.zeros((nf, nc), dtype=np.bool_)
    for f in range(nf):
        i = frame_joint[f]
        while i >= 0:
            for c in range(ncoord[i]):
                on_path[f, col[i] + c] = True
            i = parent[i]
    c16 = np.complex128
    X = np.zeros((k, 4, 4), dtype=c16)
    dX = np.zeros((7 * k, 4, 4), dtype=c16)
    G = np.zeros((k, 2, 3, 3))
    for i in range(k):
        _constant_local(kind[i], axis, fixed, i, X, dX, G)
    return (
        ncoord,
        col,
        on_path,
        placement.astype(c16),  # M: joint placements
        X,  # local transforms
        dX,  # their derivatives, 7 per joint
        np.zeros((k, 4, 4), dtype=c16),  # T: world transform after the joint
        np.zeros((k, 4, 4), dtype=c16),  # A: world transform of the joint frame before X_j
        np.zeros((k, 4, 4), dtype=c16),  # MX: M_j X_j
        np.zeros((7 * k, 4, 4), dtype=c16),  # AdX: A_j dX_j, shared by the frames below joint j
        np.zeros((nf, 4, 4), dtype=c16),  # Tf: closure frames
        np.zeros((nf * nc, 4, 4), dtype=c16),  # dTf: their derivatives, nc per frame (zero off the path)
        np.zeros(n_entries, dtype=c16),  # e
        np.zeros((n_entries, nc), dtype=c16),  # de
        np.zeros(n, dtype=c16),  # F
        np.zeros((n, nc), dtype=c16),  # J = [F_x F_p]
        np.zeros((2, 4, 4), dtype=c16),  # S: suffix products (two slots)
        np.zeros((3, 3), dtype=c16),  # E
        rigid,  # (M_j rotates, M_j moves, X_j rotates, X_j moves) per joint
        translation,  # per joint coordinate: its derivative is along a translation
        G,  # a revolute joint's K and K^2
        point,  # per closure frame: only its origin is read
    )


@njit(cache=True)
def workspace_for(n: int, npar: int, args: tuple) -> tuple:
    """:func:`workspace` for ``n`` unknowns and ``npar`` parameters of the form packed in ``args``."""
    parent, kind, offset, axis, placement, fixed, frame_joint = args[:7]
    closure_kind, closure_frames, combination = args[8], args[9], args[13]
    return workspace(
        n,
        npar,
        parent,
        kind,
        offset,
        axis,
        placement,
        fixed,
        frame_joint,
        closure_kind,
        closure_frames,
        combination.shape[1],
    )


@njit(cache=True, fastmath=FAST)
def _entries(
    x: np.ndarray,
    p: np.ndarray,
    ws: tuple,
    parent: np.ndarray,
    kind: np.ndarray,
    offset: np.ndarray,
    axis: np.ndarray,
    frame_joint: np.ndarray,
    frame_placement: np.ndarray,
    closure_kind: np.ndarray,
    closure_frames: np.ndarray,
    closure_axis: np.ndarray,
    closure_length2: np.ndarray,
    entry_offset: np.ndarray,
) -> None:
    """Closure entries ``e`` (m,) and their derivatives ``de`` along (x, p) (m, n + n_params), into ``ws``."""
    (
        ncoord,
        col,
        on_path,
        M,
        X,
        dX,
        T,
        A,
        MX,
        AdX,
        Tf,
        dTf,
        e,
        de,
        _,
        _,
        S,
        E,
        rigid,
        translation,
        G,
        point,
    ) = ws
    k = kind.shape[0]
    nc = de.shape[1]
    for i in range(k):
        kd = kind[i]
        if kd == REVOLUTE_PARAM or kd == PRISMATIC_PARAM:
            _local(kd, axis, G, i, p, offset[i], X, dX)
        else:
            _local(kd, axis, G, i, x, offset[i], X, dX)
        if rigid[i, 0]:
            _mm_into(M, i, X, i, MX, i, rigid[i, 2], rigid[i, 3])
        else:
            _translated_into(M, X, i, MX)
        if parent[i] >= 0:
            _mm_into(T, parent[i], M, i, A, i, rigid[i, 0], rigid[i, 1])
            _mm_into(A, i, X, i, T, i, rigid[i, 2], rigid[i, 3])
        else:  # on the world: T = M X
            _copy_into(M, i, A, i)
            _copy_into(MX, i, T, i)
        turned = parent[i] >= 0 or rigid[i, 0]  # A_j's rotation block is not the identity
        for c in range(ncoord[i]):
            _derivative_into(A, i, turned, dX, 7 * i + c, translation[7 * i + c], AdX)
    nf = frame_joint.shape[0]
    for f in range(nf):
        for r in range(4):
            for q in range(4):
                S[0, r, q] = frame_placement[f, r, q]
        i = frame_joint[f]
        if point[f]:  # the origin alone, carried up the path by matrix-vector products
            if i >= 0:
                _mv_into(T, i, S, 0, Tf, f)
            else:
                _copy_into(S, 0, Tf, f)
            while i >= 0:
                for c in range(ncoord[i]):
                    dc = 7 * i + c
                    _point_derivative_into(AdX, dc, translation[dc], S, dTf, f * nc + col[i] + c)
                if parent[i] < 0:  # (the suffix on the world is not read)
                    break
                _mv_into(MX, i, S, 0, S, 1)
                for r in range(3):
                    S[0, r, 3] = S[1, r, 3]
                i = parent[i]
            continue
        if i >= 0:
            _mm_into(T, i, S, 0, Tf, f, True, True)
        else:
            _copy_into(S, 0, Tf, f)
        while i >= 0:
            for c in range(ncoord[i]):
                _mm_into(AdX, 7 * i + c, S, 0, dTf, f * nc + col[i] + c, True, True)
            if parent[i] < 0:
                break
            _mm_into(MX, i, S, 0, S, 1, True, True)
            _copy_into(S, 1, S, 0)
            i = parent[i]
    for c in range(closure_kind.shape[0]):
        a, b, o = closure_frames[c, 0], closure_frames[c, 1], entry_offset[c]
        if closure_kind[c] == 3:  # |p_B - p_A|^2 - L^2, L^2 = |p_L|^2 for an actuated strut L
            e[o] = -closure_length2[c]
            g = closure_frames[c, 2]
            for j in range(nc):
                de[o, j] = 0.0
            for r in range(3):
                d = Tf[b, r, 3] - Tf[a, r, 3]
                e[o] += d * d
                for j in range(nc):
                    if on_path[a, j] or on_path[b, j]:
                        de[o, j] += 2.0 * d * (dTf[b * nc + j, r, 3] - dTf[a * nc + j, r, 3])
                if g >= 0:
                    e[o] -= Tf[g, r, 3] * Tf[g, r, 3]
                    for j in range(nc):
                        if on_path[g, j]:
                            de[o, j] -= 2.0 * Tf[g, r, 3] * dTf[g * nc + j, r, 3]
            continue
        for r in range(3):
            e[o + r] = Tf[b, r, 3] - Tf[a, r, 3]
            for j in range(nc):
                if on_path[a, j] or on_path[b, j]:
                    de[o + r, j] = dTf[b * nc + j, r, 3] - dTf[a * nc + j, r, 3]
        if closure_kind[c] == 0:
            continue
        # E = R_A^T R_B and its derivatives dR_A^T R_B + R_A^T dR_B, entry by entry
        for r in range(3):
            for q in range(3):
                acc = 0j
                for t in range(3):
                    acc += Tf[a, t, r] * Tf[b, t, q]
                E[r, q] = acc
        if closure_kind[c] == 1:
            for r in range(3):
                for q in range(3):
                    e[o + 3 + 3 * r + q] = E[r, q] - (1.0 if r == q else 0.0)
        else:
            for r in range(3):
                e[o + 3 + r] = (
                    E[r, 0] * closure_axis[c, 0]
                    + E[r, 1] * closure_axis[c, 1]
                    + E[r, 2] * closure_axis[c, 2]
                    - closure_axis[c, r]
                )
        for j in range(nc):
            if not (on_path[a, j] or on_path[b, j]):
                continue
            for r in range(3):
                for q in range(3):
                    acc = 0j
                    for t in range(3):
                        acc += dTf[a * nc + j, t, r] * Tf[b, t, q] + Tf[a, t, r] * dTf[b * nc + j, t, q]
                    E[r, q] = acc
            if closure_kind[c] == 1:
                for r in range(3):
                    for q in range(3):
                        de[o + 3 + 3 * r + q, j] = E[r, q]
            else:
                for r in range(3):
                    de[o + 3 + r, j] = (
                        E[r, 0] * closure_axis[c, 0]
                        + E[r, 1] * closure_axis[c, 1]
                        + E[r, 2] * closure_axis[c, 2]
                    )


@njit(cache=True, fastmath=FAST)
def generic_system(
    x: np.ndarray,
    p: np.ndarray,
    b: np.ndarray,
    ws: tuple,
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
    r"""Square system :math:`F(x; p) + b` (n,) and its Jacobian :math:`[F_x\ F_p]` (n, n + n_params).

    From the form's joints, frames and closures at each call: the definition of the system, which
    :mod:`.straight_line` traces once into the program the trackers run. Both results are buffers
    of ``ws`` (:func:`workspace`), overwritten by the next call.
    """
    _entries(
        x,
        p,
        ws,
        parent,
        kind,
        offset,
        axis,
        frame_joint,
        frame_placement,
        closure_kind,
        closure_frames,
        closure_axis,
        closure_length2,
        entry_offset,
    )
    e, de, F, J = ws[12], ws[13], ws[14], ws[15]
    nu, m, nc = unit_offsets.shape[0], e.shape[0], J.shape[1]
    for u in range(nu):
        o = unit_offsets[u]
        acc = -1.0 + 0j
        for j in range(nc):  # (the caller may have factored J in place)
            J[u, j] = 0.0
        for r in range(unit_sizes[u]):
            acc += x[o + r] * x[o + r]
            J[u, o + r] = 2.0 * x[o + r]
        F[u] = acc + b[u]
    for i in range(combination.shape[0]):  # rows of C @ e and C @ de, skipping C's zeros (a selection)
        acc = b[nu + i]
        for j in range(nc):
            J[nu + i, j] = 0.0
        for r in range(m):
            w = combination[i, r]
            if w != 0.0:
                acc += w * e[r]
                for j in range(nc):
                    J[nu + i, j] += w * de[r, j]
        F[nu + i] = acc
    return F, J


@njit(cache=True)
def entries_at(X: np.ndarray, p: np.ndarray, args: tuple) -> np.ndarray:
    """Closure entries at every row of complex ``X`` (N, n) and parameters ``p``: shape (N, n_entries).

    In one compiled call; ``args`` is the form's :meth:`~.form.PolynomialForm.kernel_args`.
    """
    (
        parent,
        kind,
        offset,
        axis,
        _placement,
        _fixed,
        frame_joint,
        frame_placement,
        closure_kind,
        closure_frames,
        closure_axis,
        closure_length2,
        entry_offset,
        _combination,
        _unit_offsets,
        _unit_sizes,
    ) = args  # not read: the placements and fixed transforms (in the workspace), the square system's arrays
    N, n = X.shape
    ws = workspace_for(n, p.shape[0], args)
    e = ws[12]
    out = np.empty((N, e.shape[0]), dtype=np.complex128)
    for k in range(N):
        _entries(
            X[k],
            p,
            ws,
            parent,
            kind,
            offset,
            axis,
            frame_joint,
            frame_placement,
            closure_kind,
            closure_frames,
            closure_axis,
            closure_length2,
            entry_offset,
        )
        out[k] = e
    return out


_WORKSPACES: dict[tuple[str, int], tuple] = {}


def _workspace(form: PolynomialForm) -> tuple:
    """The buffers of ``form``'s evaluations from Python, made once per form (per thread)."""
    import threading

    if not form.digest:  # a form being built
        return _new_workspace(form)
    key = (form.digest, threading.get_ident())
    ws = _WORKSPACES.get(key)
    if ws is None:
        ws = _WORKSPACES[key] = _new_workspace(form)
    return ws


def _new_workspace(form: PolynomialForm) -> tuple:
    return workspace(
        form.n,
        form.n_params,
        form.parent,
        form.kind,
        form.offset,
        form.axis,
        form.placement,
        form.fixed,
        form.frame_joint,
        form.closure_kind,
        form.closure_frames,
        form.n_entries,
    )


def closure_entries(form: PolynomialForm, x: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closure entries at complex ``x``, ``p`` (m,) and their derivatives along (x, p), (m, n + n_params)."""
    ws = _workspace(form)
    _entries(
        np.asarray(x, dtype=np.complex128),
        np.asarray(p, dtype=np.complex128),
        ws,
        form.parent,
        form.kind,
        form.offset,
        form.axis,
        form.frame_joint,
        form.frame_placement,
        form.closure_kind,
        form.closure_frames,
        form.closure_axis,
        form.closure_length2,
        form.entry_offset,
    )
    return ws[12].copy(), ws[13].copy()


def evaluate(
    form: PolynomialForm, x: np.ndarray, p: np.ndarray, b: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Square system at complex ``x``, ``p`` (plus offsets ``b``): F (n,), F_x (n, n), F_p (n, n_params)."""
    bb = np.zeros(form.n, dtype=np.complex128) if b is None else np.asarray(b, dtype=np.complex128)
    F, J = generic_system(
        np.asarray(x, dtype=np.complex128),
        np.asarray(p, dtype=np.complex128),
        bb,
        _workspace(form),
        *form.kernel_args(),
    )
    return F.copy(), J[:, : form.n].copy(), J[:, form.n :].copy()
