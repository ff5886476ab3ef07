r"""Loop-closure residuals and their exact Jacobians.

A closure names two frames A and B that must coincide. With positions :math:`p`,
rotations :math:`R` and world angular velocities :math:`\omega` of the two frames:

- ``point`` (3 rows): :math:`\phi = p_B - p_A` (world) [m].
- ``revolute`` (5 rows): the point rows, then the axis :math:`u` (given in B's
  coordinates) seen from A must equal :math:`u`: :math:`E^T R_A^T R_B u = 0` with
  :math:`E` (3x2) an orthonormal basis of the plane normal to :math:`u`. Five rows that
  leave exactly the rotation about :math:`u` free, valid at any angle.
- ``weld`` (6 rows): the point rows, then :math:`\log_3(R_A^T R_B)` [rad].
- ``twist`` (1 row, the gauge of an idle spin, :mod:`plm_pin.core.idle`): with :math:`e_1, e_2`
  orthonormal, :math:`e_1 \times e_2 = u` (the axis, in B's coordinates),
  :math:`\phi = (R_A e_2)^T (R_B e_1)`, the sine of the rotation of B relative to A about
  :math:`u` when the frames coincide at rest; no point rows.

The Jacobians are exact derivatives of these residuals along the tangent space
(``pin.integrate`` convention), so they can be checked by finite differences. The
acceleration drift :math:`\dot J_\phi v` (what :math:`\ddot\phi` is when the joint
accelerations vanish) completes the second-order closure condition
:math:`J_\phi a + \dot J_\phi v = 0` of closed-chain dynamics.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..description.sidecar import ClosureSpec
from ..tolerances import LOG3_SERIES_ANGLE
from .scratch import placement_views

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class Closure:
    r"""A closure compiled against a Pinocchio model.

    Attributes:
        spec: the closure as described.
        frame_ids: Pinocchio frame indices of the two frames.
        rows: slice of this closure's rows in the stacked residual.
        axis: unit axis in B's coordinates (revolute and twist only).
        normal_basis: (3, 2) orthonormal basis normal to ``axis``, its columns :math:`e_1, e_2`
            with :math:`e_1 \times e_2` = ``axis`` (revolute and twist only).
    """

    spec: ClosureSpec
    frame_ids: tuple[int, int]
    rows: slice
    axis: np.ndarray | None = None
    normal_basis: np.ndarray | None = None

    @property
    def name(self) -> str:
        """The closure's name."""
        return self.spec.name

    @property
    def point_rows(self) -> int:
        """Number of point (translation) rows, first in :attr:`rows`: 3, or 0 for a twist."""
        return 0 if self.spec.type == "twist" else 3

    @property
    def rotation_rows(self) -> slice:
        """Slice of the rotation rows in the stacked residual (empty for a point closure)."""
        return slice(self.rows.start + self.point_rows, self.rows.stop)


def _normal_basis(u: np.ndarray) -> np.ndarray:
    helper = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    return np.column_stack([e1, e2])  # (3, 2)


def compile_closures(model: pin.Model, specs: Sequence[ClosureSpec]) -> tuple[Closure, ...]:
    """Resolve closure frame names to frame indices and assign residual rows.

    The frame names must already have been checked to exist in ``model``.
    """
    out = []
    start = 0
    for spec in specs:
        ids = (model.getFrameId(spec.frames[0]), model.getFrameId(spec.frames[1]))
        axis = basis = None
        if spec.type in ("revolute", "twist"):
            assert spec.axis is not None
            axis = np.array(spec.axis, dtype=float)
            basis = _normal_basis(axis)
            axis.setflags(write=False)
            basis.setflags(write=False)
        out.append(Closure(spec, ids, slice(start, start + spec.rows), axis, basis))
        start += spec.rows
    return tuple(out)


def closure_rows(closures: Sequence[Closure]) -> int:
    """Total number of residual rows."""
    return closures[-1].rows.stop if closures else 0


@dataclass(frozen=True)
class _Plan:
    """Constant maps that evaluate a closure tuple in a few vectorised numpy steps.

    Attributes:
        frames: distinct frame ids of the closures, in first-use order.
        angular: ``(closure, index of A, index of B)`` (indices in ``frames``) of the closures
            with rotation rows.
        difference: maps the stacked frame positions (3 per frame) to the residual, shape
            (m, 3 n_frames): +1 at B's and -1 at A's coordinate on each translation row
            (exact: no other term is added), zero rows at the rotation rows.
        frame_difference: the same on stacked frame Jacobians (6 rows per frame, of which the
            three translation rows are taken), shape (m, 6 n_frames).
    """

    frames: tuple[int, ...]
    angular: tuple[tuple[Closure, int, int], ...]
    difference: np.ndarray
    frame_difference: np.ndarray

    @classmethod
    def build(cls, closures: Sequence[Closure]) -> _Plan:
        """The plan of ``closures``."""
        frames = list(dict.fromkeys(f for c in closures for f in c.frame_ids))
        m, k = closure_rows(closures), len(frames)
        difference = np.zeros((m, k, 3))
        angular = []
        for c in closures:
            ia, ib = frames.index(c.frame_ids[0]), frames.index(c.frame_ids[1])
            for i in range(c.point_rows):
                difference[c.rows.start + i, ib, i] += 1.0
                difference[c.rows.start + i, ia, i] -= 1.0
            if c.spec.type != "point":
                angular.append((c, ia, ib))
        frame_difference = np.zeros((m, k, 6))
        frame_difference[:, :, :3] = difference
        return cls(
            tuple(frames), tuple(angular), difference.reshape(m, 3 * k), frame_difference.reshape(m, 6 * k)
        )


_PLANS: dict[int, tuple[Sequence[Closure], _Plan]] = {}


def _plan(closures: Sequence[Closure]) -> _Plan:
    """The plan of a closure sequence, built once per sequence object (kept alive with its plan)."""
    hit = _PLANS.get(id(closures))
    if hit is not None and hit[0] is closures:
        return hit[1]
    plan = _Plan.build(closures)
    if len(_PLANS) >= 256:  # sequences built on the fly (one leg's closures): bound the cache
        _PLANS.clear()
    _PLANS[id(closures)] = (closures, plan)
    return plan


class BoundClosures:
    """Closures bound to one Pinocchio data: residual and Jacobian with few Python calls.

    The frame placements are read through live views (:func:`~plm_pin.core.scratch.placement_views`),
    the translation rows of every closure come from one product with a constant matrix of
    +1 / -1. Solvers bind once per solve and evaluate at each pass; the results are those of
    :func:`residual_from_placements` and :func:`jacobian_from_data`, which bind per call.
    """

    __slots__ = ("_R", "_data", "_plan", "_t", "closures", "rows")

    def __init__(self, data: pin.Data, closures: Sequence[Closure]) -> None:
        """Bind ``closures`` to ``data`` (the views are made once per data and closure frames)."""
        self.closures = closures
        self.rows = closure_rows(closures)
        self._plan = plan = _plan(closures)
        self._data = data  # the views point into it: keep it alive with them
        self._t, self._R = placement_views(data, plan.frames)

    def residual(self, out: np.ndarray) -> np.ndarray:
        """Stacked residual from the placements in the bound data, written into ``out`` (m,)."""
        if not self.rows:
            return out
        plan = self._plan
        np.matmul(plan.difference, np.concatenate(self._t), out=out)
        R = self._R
        for c, ia, ib in plan.angular:
            Ra, Rb = R[ia], R[ib]
            start, stop = c.rows.start, c.rows.stop
            if c.spec.type == "weld":
                out[start + 3 : stop] = pin.log3(Ra.T @ Rb)
            elif c.spec.type == "twist":
                assert c.normal_basis is not None
                out[start] = (Ra @ c.normal_basis[:, 1]) @ (Rb @ c.normal_basis[:, 0])
            else:
                assert c.axis is not None and c.normal_basis is not None
                out[start + 3 : stop] = c.normal_basis.T @ (Ra.T @ (Rb @ c.axis))
        return out

    def jacobian(self, model: pin.Model, out: np.ndarray) -> np.ndarray:
        """Jacobian from the joint Jacobians and placements in the bound data, into ``out`` (m, nv)."""
        if not self.rows:
            return out
        plan, data = self._plan, self._data
        Js = np.array([pin.getFrameJacobian(model, data, f, _LWA) for f in plan.frames])  # (n_frames, 6, nv)
        np.matmul(plan.frame_difference, Js.reshape(-1, model.nv), out=out)
        for c, ia, ib in plan.angular:
            # rows times the world angular velocity of B relative to A
            out[c.rotation_rows] = angular_rows(c, data) @ (Js[ib, 3:] - Js[ia, 3:])
        return out


def residual_from_placements(
    data: pin.Data, closures: Sequence[Closure], out: np.ndarray | None = None
) -> np.ndarray:
    """Stacked residual from frame placements already updated in ``data``, shape (m,).

    Written into ``out`` (shape (m,)) when given, for solvers that reuse their buffers.
    """
    phi = np.empty(closure_rows(closures)) if out is None else out
    if not closures:
        return phi
    return BoundClosures(data, closures).residual(phi)


def residual(model: pin.Model, data: pin.Data, closures: Sequence[Closure], q: np.ndarray) -> np.ndarray:
    r"""Closure residual :math:`\phi(q)`, shape (m,)."""
    pin.framesForwardKinematics(model, data, q)
    return residual_from_placements(data, closures)


def jacobian(model: pin.Model, data: pin.Data, closures: Sequence[Closure], q: np.ndarray) -> np.ndarray:
    r"""Closure Jacobian :math:`J_\phi = \partial\phi/\partial q` on the tangent space, shape (m, nv)."""
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    return jacobian_from_data(model, data, closures)


def jacobian_from_data(
    model: pin.Model, data: pin.Data, closures: Sequence[Closure], out: np.ndarray | None = None
) -> np.ndarray:
    """Closure Jacobian from joint Jacobians and frame placements already in ``data``, shape (m, nv).

    Written into ``out`` (shape (m, nv)) when given, for solvers that reuse their buffers.
    """
    J = np.empty((closure_rows(closures), model.nv)) if out is None else out
    if not closures:
        return J
    return BoundClosures(data, closures).jacobian(model, J)


def angular_rows(c: Closure, data: pin.Data) -> np.ndarray:
    r"""Map :math:`G` from relative angular velocity to rotation rows of a closure.

    :math:`\dot\phi_{rot} = G (\omega_B - \omega_A)`, world angular velocities, frame placements
    already in ``data``; shape (3, 3) for a weld, (2, 3) for a revolute closure, (1, 3) for a twist
    (:math:`(R_B e_1 \times R_A e_2)^T`). By duality,
    rotation-row forces :math:`\lambda_{rot}` are the moment :math:`G^T \lambda_{rot}` [N m] on B
    (its opposite on A).
    """
    Ra = data.oMf[c.frame_ids[0]].rotation
    Rb = data.oMf[c.frame_ids[1]].rotation
    if c.spec.type == "weld":
        return pin.Jlog3(Ra.T @ Rb) @ Rb.T
    assert c.axis is not None and c.normal_basis is not None
    if c.spec.type == "twist":
        return np.cross(Rb @ c.normal_basis[:, 0], Ra @ c.normal_basis[:, 1])[None, :]
    return -c.normal_basis.T @ Ra.T @ pin.skew(Rb @ c.axis)


def drift_from_data(
    model: pin.Model, data: pin.Data, closures: Sequence[Closure], out: np.ndarray | None = None
) -> np.ndarray:
    r"""Closure acceleration drift :math:`\dot J_\phi(q, v)\, v`, shape (m,).

    ``data`` must hold the kinematics of ``(q, v, 0)``: call
    ``pin.forwardKinematics(model, data, q, v, 0 * v)`` then ``pin.updateFramePlacements``.
    The result is :math:`\ddot\phi` at zero joint acceleration, exact everywhere (off the
    closure manifold too), so that :math:`J_\phi a + \dot J_\phi v = \ddot\phi`.
    Written into ``out`` (shape (m,)) when given.
    """
    gamma = np.empty(closure_rows(closures)) if out is None else out
    for c in closures:
        fa, fb = c.frame_ids
        acc_a = pin.getFrameClassicalAcceleration(model, data, fa, _LWA)
        acc_b = pin.getFrameClassicalAcceleration(model, data, fb, _LWA)
        start, stop = c.rows.start, c.rows.stop
        kind = c.spec.type
        if kind != "twist":
            gamma[start : start + 3] = acc_b.linear - acc_a.linear
        if kind == "point":
            continue
        w_a = pin.getFrameVelocity(model, data, fa, _LWA).angular
        w_b = pin.getFrameVelocity(model, data, fb, _LWA).angular
        dw, dalpha = w_b - w_a, acc_b.angular - acc_a.angular
        Ra, Rb = data.oMf[fa].rotation, data.oMf[fb].rotation
        if kind == "weld":
            # r = log3(R_A^T R_B), r' = Jlog3 w_rel with w_rel = R_B^T dw (B's coordinates)
            R = Ra.T @ Rb
            w_rel = Rb.T @ dw
            dw_rel = Rb.T @ (dalpha - np.cross(w_b, dw))
            gamma[start + 3 : stop] = pin.Jlog3(R) @ dw_rel
            if np.linalg.norm(pin.log3(R)) > LOG3_SERIES_ANGLE:  # Hlog3 is NaN near the identity, where
                gamma[start + 3 : stop] += pin.Hlog3(R, w_rel) @ w_rel  # this term is O(angle |w|^2)
        elif kind == "twist":
            # r = x . y, x = R_A e2, y = R_B e1: r'' = x'' . y + 2 x' . y' + x . y'', with
            # x' = w_a x x, x'' = alpha_a x x + w_a x (w_a x x) (y likewise with B)
            assert c.normal_basis is not None
            x, y = Ra @ c.normal_basis[:, 1], Rb @ c.normal_basis[:, 0]
            dx, dy = np.cross(w_a, x), np.cross(w_b, y)
            ddx = np.cross(acc_a.angular, x) + np.cross(w_a, dx)
            ddy = np.cross(acc_b.angular, y) + np.cross(w_b, dy)
            gamma[start] = ddx @ y + 2.0 * (dx @ dy) + x @ ddy
        else:
            # r = E^T R_A^T w with w = R_B u: r'' = E^T R_A^T (-w_a x (dw x w) + dalpha x w + dw x (w_b x w))
            assert c.axis is not None and c.normal_basis is not None
            w = Rb @ c.axis
            acc = -np.cross(w_a, np.cross(dw, w)) + np.cross(dalpha, w) + np.cross(dw, np.cross(w_b, w))
            gamma[start + 3 : stop] = c.normal_basis.T @ (Ra.T @ acc)
    return gamma


def drift(
    model: pin.Model, data: pin.Data, closures: Sequence[Closure], q: np.ndarray, v: np.ndarray
) -> np.ndarray:
    r"""Closure acceleration drift :math:`\dot J_\phi(q, v)\, v`, shape (m,); see :func:`drift_from_data`."""
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.updateFramePlacements(model, data)
    return drift_from_data(model, data, closures)
