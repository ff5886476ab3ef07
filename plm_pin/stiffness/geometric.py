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

from ..kinematics.closures import HLOG3_MIN_ANGLE, Closure

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class _Structure:
    """The joint ancestry of a model (it depends on the tree only), with per-body column sets."""

    def __init__(
        self, parents: tuple[int, ...], joint_of_v: tuple[int, ...], first_v: tuple[int, ...]
    ) -> None:
        nj = len(parents)
        anc = np.zeros((nj, nj), dtype=bool)  # anc[a, b]: joint a is joint b or above it
        for b in range(nj):
            a = b
            while True:
                anc[a, b] = True
                if a == 0:
                    break
                a = parents[a]
        jv = np.array(joint_of_v, dtype=int)
        self.above = anc[np.ix_(jv, jv)]  # (nv, nv): [k, c]
        self.first_v = first_v
        self._bodies: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def body(self, joint: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Columns moving the body of ``joint``: mask (nv,), indices (n,), transposed ``above`` on them."""
        if joint not in self._bodies:
            mask = self.above[:, self.first_v[joint]] if joint else np.zeros(self.above.shape[0], dtype=bool)
            idx = np.flatnonzero(mask)
            self._bodies[joint] = (mask, idx, self.above[np.ix_(idx, idx)].T.astype(float))
        return self._bodies[joint]


@functools.cache
def _structure(
    model_id: int, parents: tuple[int, ...], joint_of_v: tuple[int, ...], first_v: tuple[int, ...]
) -> _Structure:
    del model_id
    return _Structure(parents, joint_of_v, first_v)


class TreeDerivatives:
    """Joint ancestry of a model and the world Jacobian columns at one configuration.

    Attributes:
        S: world twists of every velocity column, rows ``(v, omega)``, shape (6, nv).
    """

    def __init__(self, model: pin.Model, data: pin.Data) -> None:
        """Read the world Jacobian from ``data`` (after ``pin.computeJointJacobians``)."""
        joint_of_v = [0] * model.nv
        first_v = [0] * model.njoints
        for j in range(1, model.njoints):
            jm = model.joints[j]
            first_v[j] = jm.idx_v
            joint_of_v[jm.idx_v : jm.idx_v + jm.nv] = [j] * jm.nv
        self.model = model
        self._structure = _structure(id(model), tuple(model.parents), tuple(joint_of_v), tuple(first_v))
        self.S = np.array(data.J)  # (6, nv)

    def columns(self, joint: int) -> np.ndarray:
        """Mask of the velocity columns that move ``joint``'s body, shape (nv,)."""
        return self._structure.body(joint)[0]

    def dead_wrench(
        self, joint: int, f: np.ndarray, m: np.ndarray, p: np.ndarray, out: np.ndarray | None = None
    ) -> np.ndarray:
        r"""Derivative of the generalized force of a fixed world wrench on ``joint``'s body, shape (nv, nv).

        Args:
            joint: the body's joint index.
            f: force [N], world, shape (3,).
            m: moment [N m], world, shape (3,).
            p: point of application [m], world, shape (3,).
            out: an (nv, nv) array to add the derivative to (returned), instead of a new one.

        Returns:
            ``D[c, k]`` = :math:`\partial Q_c / \partial q_k`.
        """
        nv = self.model.nv
        D = np.zeros((nv, nv)) if out is None else out
        _, idx, mask = self._structure.body(joint)
        if idx.size == 0:
            return D
        V, W = self.S[:3, idx], self.S[3:, idx]  # (3, n): the columns moving the body
        F = pin.skew(f)
        # W . ad(S_k) S_c = v_c.(f x w_k) + w_c.(f x v_k) + w_c.(n x w_k), for k above c
        term = V.T @ (F @ W) + W.T @ (F @ V) + W.T @ (pin.skew(m - F @ p) @ W)  # p x f = -f x p
        term *= mask
        # + w_c . (dp_k x f), dp_k = v_k + w_k x p the point's motion
        term -= W.T @ (F @ (V - pin.skew(p) @ W))
        D[np.ix_(idx, idx)] += term
        return D

    def angular(self, joint: int) -> np.ndarray:
        """World angular Jacobian of ``joint``'s body, shape (3, nv)."""
        return self.S[3:] * self.columns(joint)


def closure_derivative(
    tree: TreeDerivatives, data: pin.Data, closures: Sequence[Closure], lam: np.ndarray
) -> np.ndarray:
    r"""Derivative of the cut-joint force :math:`J_\phi^T \lambda` at fixed :math:`\lambda`, shape (nv, nv).

    ``data`` must hold the frame placements of the configuration ``tree`` was read at.
    """
    model = tree.model
    D = np.zeros((model.nv, model.nv))
    for c in closures:
        fa, fb = c.frame_ids
        ja, jb = model.frames[fa].parentJoint, model.frames[fb].parentJoint
        oMa, oMb = data.oMf[fa], data.oMf[fb]
        lam_c = lam[c.rows]
        f = lam_c[:3]
        m = np.zeros(3)
        if c.spec.type != "point":
            m, dm = _closure_moment(c, tree, ja, jb, oMa.rotation, oMb.rotation, lam_c[3:])
            D += (tree.angular(jb) - tree.angular(ja)).T @ dm
        tree.dead_wrench(jb, f, m, oMb.translation, out=D)
        tree.dead_wrench(ja, -f, -m, oMa.translation, out=D)
    return D


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
        near = np.linalg.norm(pin.log3(R)) <= HLOG3_MIN_ANGLE
        dm = np.cross(wb.T, moment).T
        for k in range(rel.shape[1]):
            if not rel[:, k].any():
                continue
            dJ = 0.5 * pin.skew(rel[:, k]) if near else pin.Hlog3(R, rel[:, k])
            dm[:, k] += Rb @ dJ.T @ lam_r
        return moment, dm
    assert c.axis is not None and c.normal_basis is not None
    w = Rb @ c.axis
    a = Ra @ c.normal_basis @ lam_r
    moment = np.cross(w, a)
    dw = np.cross(wb.T, w).T
    da = np.cross(wa.T, a).T
    return moment, np.cross(dw.T, a).T + np.cross(w, da.T).T
