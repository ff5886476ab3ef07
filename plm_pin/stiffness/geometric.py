r"""Geometric stiffness: how the generalized forces of fixed loads change with the configuration.

A force :math:`f` and a moment :math:`m` fixed in the world, applied to a body at a point
:math:`p(q)`, exert the generalized force :math:`Q_c = S_c^T W` with the world twist
:math:`S_c` of each column the body depends on and the wrench about the world origin
:math:`W = (f, p \times f + m)`. Its derivative along a tangent direction :math:`k` is
exact in closed form: a column moves with every joint above it,
:math:`\partial S_c / \partial q_k = \mathrm{ad}(S_k) S_c` (Pinocchio's tangent convention:
a joint's motion subspace is fixed in its own frame), and the point moves with
:math:`\partial p / \partial q_k = v_k + \omega_k \times p`:

.. math::

    \frac{\partial Q_c}{\partial q_k} = W^T \mathrm{ad}(S_k) S_c
    + \omega_c^T \left(\frac{\partial p}{\partial q_k} \times f\right).

The cut-joint forces :math:`\lambda` of a closure are such loads (force :math:`\lambda` on
frame B, its opposite on frame A); the rotation rows of weld and revolute closures add the
change of the map from :math:`\lambda_{rot}` to the moment (:func:`closure_derivative`).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..core.closures import Closure
from ..tolerances import LOG3_SERIES_ANGLE

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


_SKEW = np.array([pin.skew(e).ravel() for e in np.eye(3)])  # row k: the cross-product matrix of e_k


def _skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices of the rows of ``v``, shape (n, 3, 3)."""
    return (v @ _SKEW).reshape(-1, 3, 3)


class _Structure:
    """The joint ancestry of a model (it depends on the tree only), with the columns moving each body."""

    def __init__(self, parents: tuple[int, ...], nvs: tuple[int, ...]) -> None:
        nj = len(parents)
        anc = np.zeros((nj, nj), dtype=bool)  # anc[a, b]: joint a is joint b or above it
        for b in range(nj):
            a = b
            while True:
                anc[a, b] = True
                if a == 0:
                    break
                a = parents[a]
        jv = np.repeat(np.arange(nj), nvs)  # the joint of each velocity column
        above = anc[np.ix_(jv, jv)]  # (nv, nv): [k, c], column k is column c's joint or above it
        self.below = above.T.astype(float)  # [c, k]
        self.moves = anc[jv].T.astype(float)  # [j, c]: column c moves the body of joint j (none the world's)


@functools.cache
def _structure(parents: tuple[int, ...], nvs: tuple[int, ...]) -> _Structure:
    return _Structure(parents, nvs)


class TreeDerivatives:
    """Joint ancestry of a model and the world Jacobian columns at one configuration.

    Attributes:
        S: world twists of every velocity column, rows ``(v, omega)``, shape (6, nv).
    """

    def __init__(self, model: pin.Model, data: pin.Data) -> None:
        """Read the world Jacobian from ``data`` (after ``pin.computeJointJacobians``)."""
        self.model = model
        self._structure = _structure(tuple(model.parents), tuple(model.nvs))
        self.S = np.array(data.J)  # (6, nv)

    def columns(self, joint: int) -> np.ndarray:
        """Mask of the velocity columns that move ``joint``'s body (1 or 0), shape (nv,)."""
        return self._structure.moves[joint]

    def dead_wrenches(self, joints: Sequence[int], f: np.ndarray, m: np.ndarray, p: np.ndarray) -> np.ndarray:
        r"""Derivative of the generalized force of fixed world wrenches on bodies, summed, shape (nv, nv).

        Args:
            joints: each wrench's body, by joint index, length n.
            f: forces [N], world, shape (n, 3).
            m: moments [N m], world, shape (n, 3).
            p: points of application [m], world, shape (n, 3).

        Returns:
            ``D[c, k]`` = :math:`\sum_i \partial Q_{i,c} / \partial q_k`.
        """
        n, nv = len(joints), self.model.nv
        if n == 0:
            return np.zeros((nv, nv))
        Sb = self.S[None] * self._structure.moves[list(joints)][:, None, :]  # (n, 6, nv): each body's columns
        F, P = _skew(f), _skew(p)
        # W . ad(S_k) S_c = v_c.(f x w_k) + w_c.(f x v_k) + w_c.(n x w_k), for k above c; n = m + p x f
        G = np.zeros((n, 6, 6))
        G[:, :3, 3:] = F
        G[:, 3:, :3] = F
        G[:, 3:, 3:] = _skew(m + (P @ f[:, :, None])[:, :, 0])
        # + w_c . (dp_k x f), dp_k = v_k + w_k x p the point's motion, for every k moving the body
        E = np.zeros((n, 6, 6))
        E[:, 3:, :3] = -F
        E[:, 3:, 3:] = F @ P
        X = Sb.transpose(2, 0, 1).reshape(nv, 6 * n)  # [S_1^T ... S_n^T]
        above = X @ (G @ Sb).reshape(6 * n, nv)
        return above * self._structure.below + X @ (E @ Sb).reshape(6 * n, nv)

    def angular(self, joint: int) -> np.ndarray:
        """World angular Jacobian of ``joint``'s body, shape (3, nv)."""
        return self.S[3:] * self.columns(joint)


def closure_derivative(
    tree: TreeDerivatives, data: pin.Data, closures: Sequence[Closure], lam: np.ndarray
) -> np.ndarray:
    r"""Derivative of the cut-joint force :math:`J_\phi^T \lambda` at fixed :math:`\lambda`, shape (nv, nv).

    ``data`` must hold the frame placements of the configuration ``tree`` was read at.
    """
    model, frames, oMf = tree.model, tree.model.frames, data.oMf
    D = np.zeros((model.nv, model.nv))
    fa, fb = [c.frame_ids[0] for c in closures], [c.frame_ids[1] for c in closures]
    ja, jb = [frames[i].parentJoint for i in fa], [frames[i].parentJoint for i in fb]
    p = np.array([oMf[i].translation for i in fb + fa]).reshape(-1, 3)  # on B, then on A
    f = np.array([lam[c.rows.start : c.rows.start + 3] if c.point_rows else np.zeros(3) for c in closures])
    f = f.reshape(len(closures), 3)
    m = np.zeros_like(f)
    for i, c in enumerate(closures):
        if c.spec.type != "point":
            m[i], dm = _closure_moment(
                c, tree, ja[i], jb[i], oMf[fa[i]].rotation, oMf[fb[i]].rotation, lam[c.rotation_rows]
            )
            D += (tree.angular(jb[i]) - tree.angular(ja[i])).T @ dm
    return D + tree.dead_wrenches(jb + ja, np.vstack([f, -f]), np.vstack([m, -m]), p)


def _closure_moment(
    c: Closure, tree: TreeDerivatives, ja: int, jb: int, Ra: np.ndarray, Rb: np.ndarray, lam_r: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Moment on B of the rotation rows' forces, and its derivative at fixed forces, (3,), (3, nv)."""
    wa, wb = tree.angular(ja), tree.angular(jb)  # (3, nv)
    if c.spec.type == "weld":
        R = Ra.T @ Rb
        Jl = pin.Jlog3(R)
        moment = Rb @ Jl.T @ lam_r
        rel = Rb.T @ (wb - wa)  # (3, nv): relative rotation rates in B's coordinates
        near = np.linalg.norm(pin.log3(R)) <= LOG3_SERIES_ANGLE
        dm = np.cross(wb.T, moment).T
        for k in range(rel.shape[1]):
            if not rel[:, k].any():
                continue
            dJ = 0.5 * pin.skew(rel[:, k]) if near else pin.Hlog3(R, rel[:, k])
            dm[:, k] += Rb @ dJ.T @ lam_r
        return moment, dm
    assert c.axis is not None and c.normal_basis is not None
    if c.spec.type == "twist":  # moment lam (y x x), y = R_B e1 and x = R_A e2 turning with B and A
        x, y = Ra @ c.normal_basis[:, 1], Rb @ c.normal_basis[:, 0]
        dx, dy = np.cross(wa.T, x).T, np.cross(wb.T, y).T  # (3, nv)
        return lam_r[0] * np.cross(y, x), lam_r[0] * (np.cross(dy.T, x).T + np.cross(y, dx.T).T)
    w = Rb @ c.axis
    a = Ra @ c.normal_basis @ lam_r
    moment = np.cross(w, a)
    dw = np.cross(wb.T, w).T
    da = np.cross(wa.T, a).T
    return moment, np.cross(dw.T, a).T + np.cross(w, da.T).T
