r"""Closed-chain forward dynamics at one state: accelerations, closure forces, velocity projection.

The tree's equations of motion with the closures as constraints (index-1 form):

.. math::
    M(q)\, a + h(q, v) = \tau + J_\phi^T \lambda, \qquad J_\phi a + \dot J_\phi v = 0,

:math:`M` the joint-space mass matrix with the armature (reflected rotor inertia) on its
diagonal, :math:`h` the Coriolis, centrifugal and gravity terms (gravity from
``model.gravity``), :math:`\tau` the applied generalized forces, :math:`\lambda` the closure
forces in the rows of :mod:`plm_pin.core.closures` (force on the second frame of a
closure, its opposite on the first: the convention of :mod:`plm_pin.statics`).

Two solvers give the same :math:`a`:

- ``"kkt"`` (ours, any closure type): only :math:`r = n_v - \text{mobility}` rows of
  :math:`J_\phi` are independent (planar point closures have zero rows), so the rows are
  reduced by the SVD :math:`J_\phi = U \Sigma V^T` to :math:`W = V_r^T`, orthonormal, and
  the regular saddle-point system

  .. math::
      \begin{bmatrix} M & -W^T \\ W & 0 \end{bmatrix}
      \begin{bmatrix} a \\ \mu \end{bmatrix} =
      \begin{bmatrix} \tau - h \\ -\Sigma_r^{-1} U_r^T \dot J_\phi v \end{bmatrix},
      \qquad \lambda = U_r \Sigma_r^{-1} \mu

  is solved: :math:`\lambda` is the minimum-norm closure force (none on redundant rows).
- ``"pinocchio"`` (point and weld closures): ``pin.constraintDynamics`` with legacy
  ``RigidConstraintModel`` s, ``CONTACT_3D`` world-aligned for a point closure and
  ``CONTACT_6D`` local for a weld, no Baumgarte correction, proximal iterations. Its
  multipliers are brought to our rows through the generalized force they exert,
  :math:`J_\phi^T \lambda = J_{pin}^T \lambda_{pin}` (minimum-norm solution). Where its proximal
  iterations do not converge within their cap (ill-conditioned closures, near a constraint
  singularity, where the answer would be inexact and an adaptive integrator would crawl), the
  accelerations come from the KKT solve instead.

**Constraint singularities on the way through.** Where two sheets of the closure manifold
cross (the 3D4M's two rods of a leg pair hanging straight down: a mirrored and a coincident
sheet meet), the closure Jacobian loses a rank: its r-th singular value :math:`\sigma_r`
passes through zero, linearly in time, each time the legs swing through. On the sheet the
motion is on, the accelerations stay bounded and continuous: differentiating
:math:`J_\phi v = 0` along it gives :math:`u_r^T \dot J_\phi v = -\sigma_r v_r^T a`, so the
drift row tends to zero with :math:`\sigma_r` and their ratio stays finite; the joint-space
closure force :math:`J_\phi^T \lambda = M a + h - \tau` stays finite too, while the cut
forces along the vanishing row grow like :math:`1/\sigma_r` (a self-stress of the aligned rods
whose lever arm vanishes). At a state *off* the manifold the drift row does not vanish, and
the index-1 solve amplifies the state's error by :math:`1/\sigma_r`; an integrator's stages
near the crossing are such states. :meth:`ClosedChainDynamics.stage_rates` therefore
evaluates the rates of a stage at its projection onto the closures, where the ratio is exact.

At the crossing itself (:math:`\sigma_r \le` ``RANK_RTOL`` :math:`\sigma_1`) the lost row
:math:`u` is dropped from the solve (a least-squares KKT) when the motion is defined there, and
the step stops with :class:`~plm_pin.exceptions.SingularConfiguration` when it is not. The
motion is defined when (i) the lost row is **consistent**, :math:`u^T \dot J_\phi v = 0`
(else no finite force keeps the loops closed: :math:`J_\phi a = -\dot J_\phi v` has no
solution), and (ii) the velocity picks **one** sheet: the closures allow the velocities of the
tangent cone :math:`\{w : J_\phi w = 0,\ Q(w) = u^T \dot J_\phi(w) w = 0\}` (second-order
analysis of the singular point), a union of the sheets' tangent spaces; :math:`v` lies on one
sheet only when it is a regular point of that cone, :math:`\nabla Q(v) \ne 0` on the null
space of :math:`J_\phi`. At rest (:math:`v = 0`) or with :math:`v` on the intersection of the
sheets, the continuation is not determined by the model (a bifurcation), and the run stops.

After an integration step the state is projected back onto the closures
(:meth:`ClosedChainDynamics.project`). The velocity projection onto :math:`J_\phi v = 0` is
the one of least kinetic energy change, :math:`\min \|v^+ - v\|_M`, solved with the same
saddle-point matrix for both solvers (Pinocchio 4.1's ``impulseDynamics`` with constraint
models leaves :math:`J_\phi v^+ \ne 0` for closures between two moving bodies): it never
adds energy and removes only the part of :math:`v` that violates the closures.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from .._linalg import lu_solve, thin_svd
from ..core import closures as _closures
from ..core.assembly import assemble
from ..core.closures import Closure
from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput, SingularConfiguration
from ..statics.balance import AnyLoad, Load
from ..tolerances import CROSSING_WATCH_RTOL, LOST_ROW_DRIFT_RTOL, RANK_RTOL, SHEET_GRADIENT_RTOL

SOLVERS = ("auto", "kkt", "pinocchio")
"""Solver choices; ``auto`` is ``pinocchio`` when every closure is a point or a weld, else ``kkt``."""

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_PIN_CONTACT = {
    "point": (pin.ContactType.CONTACT_3D, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED),
    "weld": (pin.ContactType.CONTACT_6D, pin.ReferenceFrame.LOCAL),
}
PROJECTION_ITERATIONS = 20
"""Iteration cap of the position projection."""

_PROXIMAL = (1e-12, 1e-10, 20)
"""Pinocchio proximal settings: absolute accuracy, regularization mu, iteration cap."""

STAGE_ITERATIONS = 2
"""Gauss-Newton steps that put an integrator's stage on the closures before its rates are taken.

From a stage error e, one step leaves e^2/sigma_r (sigma_r: the smallest kept closure singular
value), two leave e^4/sigma_r^3: below round-off for the stages of a step near a crossing.
"""


class ReducedRows(NamedTuple):
    r"""The independent closure rows at one configuration, from the SVD :math:`J_\phi = U \Sigma V^T`.

    Attributes:
        U: the first r left singular vectors, shape (m, r).
        s: the first r singular values, shape (r,).
        W: the first r right singular vectors as rows, :math:`V_r^T`, orthonormal, shape (r, nv).
    """

    U: np.ndarray
    s: np.ndarray
    W: np.ndarray


class Projection(NamedTuple):
    """A state projected onto the closures, with what the projection computed at the result.

    Attributes:
        q: projected configuration, shape (nq,).
        v: projected joint velocities, shape (nv,).
        before: closure distance before the projection [m, rad].
        after: closure distance of ``q`` [m, rad].
        rows: the reduced closure rows at ``q``, or None when the projection did not need them.
        jacobian: the closure Jacobian at ``q`` (None without closures), shape (m, nv).
    """

    q: np.ndarray
    v: np.ndarray
    before: float
    after: float
    rows: ReducedRows | None
    jacobian: np.ndarray | None = None


class ClosureDistance:
    """Closure distance of a residual: the largest norm of a closure's point rows [m] or other rows [rad].

    The Euclidean gap of each closure, not the largest entry (which can be up to sqrt(3) times smaller).
    """

    def __init__(self, closures: Sequence[Closure]) -> None:
        """Group the residual rows of ``closures``: point rows, then rotation rows, of each."""
        groups: list[int] = []
        for i, c in enumerate(closures):
            n = c.rows.stop - c.rows.start
            groups += [2 * i] * c.point_rows + [2 * i + 1] * (n - c.point_rows)
        self._groups = np.array(groups, dtype=int)
        self._n = 2 * len(closures)
        # point and weld closures only: the groups are consecutive blocks of three rows
        self._blocks = all(c.rows.stop - c.rows.start in (3, 6) for c in closures)

    def __call__(self, phi: np.ndarray) -> float:
        """The closure distance of ``phi`` [m, rad] (0 without closures)."""
        if not phi.size:
            return 0.0
        if phi.size == 3 and self._blocks:
            return math.sqrt(float(phi @ phi))
        if self._blocks:
            P = phi.reshape(-1, 3)
            return math.sqrt(float(np.max(np.einsum("ij,ij->i", P, P))))
        return float(np.sqrt(np.max(np.bincount(self._groups, phi * phi, minlength=self._n))))


def resolve_solver(mech: Mechanism, solver: str) -> str:
    """The solver to use for ``mech``: ``solver`` checked, ``auto`` resolved.

    Raises:
        InvalidInput: unknown solver, or ``pinocchio`` with a revolute closure.
    """
    if solver not in SOLVERS:
        raise InvalidInput(f"solver {solver!r} is not one of {list(SOLVERS)}")
    unsupported = [c.name for c in mech.closures if c.spec.type not in _PIN_CONTACT]
    if solver == "pinocchio" and unsupported:
        raise InvalidInput(
            f"solver 'pinocchio' supports point and weld closures only; {unsupported} are revolute "
            "(5 rows); use solver 'kkt' or 'auto'"
        )
    if solver == "auto":
        return "pinocchio" if mech.closures and not unsupported else "kkt"
    return solver


class ClosedChainDynamics:
    r"""Forward dynamics of one mechanism under a constant wrench, state by state.

    Holds its own Pinocchio data (the mechanism's scratch data is left alone).

    Attributes:
        solver: ``"kkt"`` or ``"pinocchio"``.
        rank: number of independent closure rows, :math:`n_v - \text{mobility}`.
    """

    def __init__(self, mech: Mechanism, solver: str, load: AnyLoad | None) -> None:
        """Prepare the solver ``solver`` (``auto``, ``kkt`` or ``pinocchio``) for ``mech`` and ``load``."""
        self.solver = resolve_solver(mech, solver)
        self.model = model = mech.model
        self.closures = mech.closures
        self.data = model.createData()
        self.rank = mech.nv - mech.mobility
        self.distance = ClosureDistance(mech.closures)
        self.load = load
        self._name = mech.name
        self._all_columns = np.arange(mech.nv)
        self._bound = _closures.BoundClosures(self.data, self.closures)  # few Python calls per pass
        self._scratch = model.createData()  # for the drift at other velocities (constraint singularities)
        self._K = np.zeros((2 * mech.nv, 2 * mech.nv))  # saddle-point matrix, its top-left (nv + r) block
        if self.solver == "pinocchio":
            self._pin_data = model.createData()
            self._cms = pin.StdVec_RigidConstraintModel()
            self._cds = pin.StdVec_RigidConstraintData()
            for c in mech.closures:
                fa, fb = (model.frames[i] for i in c.frame_ids)
                kind, frame = _PIN_CONTACT[c.spec.type]
                self._cms.append(
                    pin.RigidConstraintModel(
                        kind, model, fa.parentJoint, fa.placement, fb.parentJoint, fb.placement, frame
                    )
                )
            for cm in self._cms:  # append stores a copy: create the datas from the stored models
                self._cds.append(cm.createData())
            pin.initConstraintDynamics(model, self._pin_data, self._cms, self._cds)
            self._settings = pin.ProximalSettings(*_PROXIMAL)

    # ------------------------------------------------------------- terms
    def _mass_and_jacobian(self) -> tuple[np.ndarray, np.ndarray]:
        """M and J_phi from ``self.data`` after computeAllTerms, or crba and joint Jacobians.

        The Python bindings of ``crba`` and ``computeAllTerms`` return the whole symmetric
        mass matrix, armature on the diagonal (Pinocchio 4.1).
        """
        pin.updateFramePlacements(self.model, self.data)
        return self.data.M.copy(), self._jacobian_from_data()

    def _wrench_force(self, data: pin.Data) -> np.ndarray | None:
        """Generalized force of the wrench from joint Jacobians and placements in ``data``, (nv,)."""
        if self.load is None:
            return None
        return self.load.generalized_force(self.model, data)

    def _split(self, J: np.ndarray) -> tuple[ReducedRows, np.ndarray]:
        """The closure Jacobian's independent rows, and the left singular vectors of rows lost here.

        Returns:
            ``U_r``, ``Sigma_r``, ``W = V_r^T`` of the rows kept, and the left singular vectors of
            the independent rows whose singular value vanishes (a constraint singularity),
            shape (m, d); d = 0 away from one.
        """
        U, s, Vt = thin_svd(J)
        r = self.rank
        kept = r
        if r and s[r - 1] <= RANK_RTOL * max(s[0], 1.0):
            kept = int(np.sum(s[:r] > RANK_RTOL * max(s[0], 1.0)))
        return ReducedRows(U[:, :kept], s[:kept], Vt[:kept]), U[:, kept:r]

    def _reduced_rows(
        self, J: np.ndarray, through: tuple[np.ndarray, np.ndarray] | None = None
    ) -> ReducedRows:
        """``U_r``, ``Sigma_r`` and ``W = V_r^T`` of the closure Jacobian's independent rows.

        ``through``: the state ``(q, v)`` on the closures that ``J`` belongs to, to pass a
        constraint singularity where the motion is defined (module docstring): the lost rows
        are dropped then.

        Raises:
            SingularConfiguration: when the r-th singular value vanishes (constraint singularity),
                without ``through`` or where the motion is not defined.
        """
        rows, lost = self._split(J)
        if lost.shape[1]:
            if through is None:
                s = np.linalg.svd(J, compute_uv=False)
                raise SingularConfiguration(
                    f"{self._name}: constraint singularity: closure Jacobian singular values {s.tolist()}, "
                    f"{self.rank} independent rows expected (mobility {self.model.nv - self.rank})"
                )
            self._check_through(*through, lost, rows.W, J)
        return rows

    def _drift(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        r"""The acceleration drift :math:`\dot J_\phi(q, v) v` (m,), computed in a scratch data."""
        data = self._scratch
        pin.forwardKinematics(self.model, data, q, v, np.zeros(self.model.nv))
        pin.updateFramePlacements(self.model, data)
        return _closures.drift_from_data(self.model, data, self.closures)

    def _check_through(
        self, q: np.ndarray, v: np.ndarray, lost: np.ndarray, Wk: np.ndarray, J: np.ndarray
    ) -> None:
        r"""Raise unless the motion through this constraint singularity is defined (module docstring).

        Args:
            q: configuration on the closures, shape (nq,).
            v: joint velocities, shape (nv,).
            lost: left singular vectors of the rows lost here, shape (m, d).
            Wk: the kept rows :math:`V_k^T`, shape (k, nv).
            J: the closure Jacobian, for the message, shape (m, nv).
        """
        gamma = self._drift(q, v)
        s = np.linalg.svd(J, compute_uv=False)
        where = f"{self._name}: constraint singularity (closure Jacobian singular values {s.tolist()})"
        lost_drift = float(np.max(np.abs(lost.T @ gamma)))
        scale = float(np.max(np.abs(gamma), initial=0.0))
        if lost_drift > LOST_ROW_DRIFT_RTOL * scale:
            raise SingularConfiguration(
                f"{where}: the motion is not defined here: the acceleration constraint along the lost "
                f"closure row is inconsistent (drift {lost_drift:.3g}, {lost_drift / scale:.3g} of the "
                f"drift's size, more than {LOST_ROW_DRIFT_RTOL:g}): no finite closure force keeps the loops "
                "closed"
            )
        # Q(w) = lost^T gamma(q, w) is quadratic in w: its gradient at v along n is
        # lost^T (gamma(v + n) - gamma(v - n)) / 2, exactly; n spans the null space of the kept rows
        N = np.linalg.svd(Wk)[2][Wk.shape[0] :] if Wk.size else np.eye(self.model.nv)
        size = float(np.linalg.norm(v))
        drift = self._drift
        grad = np.array([lost.T @ (drift(q, v + size * n) - drift(q, v - size * n)) / 2 for n in N])
        form = np.array([lost.T @ drift(q, size * n) for n in N])
        if size == 0.0 or np.max(np.abs(grad)) <= SHEET_GRADIENT_RTOL * 2 * np.max(np.abs(form)):
            raise SingularConfiguration(
                f"{where}: the motion is not defined here: the velocity (|v| = {size:.3g}) lies where "
                "sheets of the closure manifold meet (at rest, or moving along their intersection), so "
                "the model does not say which one the mechanism follows"
            )

    def _saddle(self, M: np.ndarray, W: np.ndarray, top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
        """Solve ``[[M, -W^T], [W, 0]] [x; mu] = [top; bottom]``, returning ``(x, mu)`` stacked."""
        nv, r = M.shape[0], W.shape[0]
        K = self._K[: nv + r, : nv + r]
        K[:nv, :nv] = M
        K[:nv, nv:] = -W.T
        K[nv:, :nv] = W
        return lu_solve(K, np.concatenate([top, bottom]))

    def residual_from_data(self) -> np.ndarray:
        """Closure residual (m,) from the frame placements in ``self.data``."""
        return self._bound.residual(np.empty(self._bound.rows))

    def _jacobian_from_data(self) -> np.ndarray:
        """Closure Jacobian (m, nv) from the joint Jacobians and placements in ``self.data``."""
        return self._bound.jacobian(self.model, np.empty((self._bound.rows, self.model.nv)))

    def _closure_terms(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closure residual (m,) and Jacobian (m, nv) at ``q``; leaves placements and Jacobians in data."""
        pin.computeJointJacobians(self.model, self.data, q)  # placements too
        pin.updateFramePlacements(self.model, self.data)
        return self.residual_from_data(), self._jacobian_from_data()

    # ------------------------------------------------------------ public
    def kkt(
        self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, rows: ReducedRows | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Our KKT solve: joint accelerations (nv,) and minimum-norm closure forces (m,).

        ``rows``: the reduced closure rows at ``q`` when already known (from :meth:`project`).

        Raises:
            SingularConfiguration: at a constraint singularity where the motion is not defined.
        """
        model, data = self.model, self.data
        pin.computeAllTerms(model, data, q, v)
        M, J = self._mass_and_jacobian()
        rhs = tau - data.nle
        w = self._wrench_force(data)
        if w is not None:
            rhs += w
        if not self.closures:
            return lu_solve(M, rhs), np.zeros(0)
        gamma = _closures.drift_from_data(model, data, self.closures)
        Ur, sr, W = self._reduced_rows(J, (q, v)) if rows is None else rows
        sol = self._saddle(M, W, rhs, -(Ur.T @ gamma) / sr)
        nv = model.nv
        return sol[:nv], Ur @ (sol[nv:] / sr)

    def _pinocchio_acceleration(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray | None:
        """``pin.constraintDynamics``'s accelerations (nv,); None when its iterations hit their cap."""
        model, data = self.model, self._pin_data
        applied = tau
        if isinstance(self.load, Load):
            applied = (
                tau + pin.computeFrameJacobian(model, data, q, self.load.frame_id, _LWA).T @ self.load.wrench
            )
        elif self.load is not None:
            applied = tau + self.load.generalized_force(model)
        a = pin.constraintDynamics(model, data, q, v, applied, self._cms, self._cds, self._settings)
        # not converged: ill-conditioned closures
        return None if self._settings.iter >= self._settings.max_iter else a

    def acceleration(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Joint accelerations [m/s^2, rad/s^2], shape (nv,), with the chosen solver."""
        if self.solver == "pinocchio":
            a = self._pinocchio_acceleration(q, v, tau)
            if a is not None:
                return a
        return self.kkt(q, v, tau)[0]

    def accelerator(self) -> Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
        """:meth:`acceleration` as a function ``(q, v, tau) -> a`` with the fewest Python calls.

        Without a wrench, Pinocchio's path calls ``pin.constraintDynamics`` directly (the
        inner loop of an integrator, where each call layer costs a noticeable share).
        """
        if self.solver != "pinocchio" or self.load is not None:
            return self.acceleration
        model, data, cms, cds, settings = self.model, self._pin_data, self._cms, self._cds, self._settings
        constraint_dynamics, kkt = pin.constraintDynamics, self.kkt

        def direct(q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
            a = constraint_dynamics(model, data, q, v, tau, cms, cds, settings)
            # not converged (ill-conditioned closures): as in _pinocchio_acceleration
            return a if settings.iter < settings.max_iter else kkt(q, v, tau)[0]

        return direct

    def solve(
        self,
        q: np.ndarray,
        v: np.ndarray,
        tau: np.ndarray,
        rows: ReducedRows | None = None,
        jacobian: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Joint accelerations (nv,) and closure forces (m,) [N, N m] with the chosen solver.

        ``rows``: the reduced closure rows at ``q`` when already known (from :meth:`project`);
        else ``jacobian``, the closure Jacobian at ``q`` when known (likewise).
        Where Pinocchio's iterations do not converge, both come from the KKT solve.
        """
        a = self._pinocchio_acceleration(q, v, tau) if self.solver == "pinocchio" else None
        if a is None:
            return self.kkt(q, v, tau, rows)
        if not self.closures:
            return a, np.zeros(0)
        model, pdata = self.model, self._pin_data
        pin.computeJointJacobians(model, pdata, q)
        force = pin.getConstraintsJacobian(model, pdata, self._cms, self._cds).T @ pdata.lambda_c  # (nv,)
        if rows is None:
            rows = self._reduced_rows(self._closure_terms(q)[1] if jacobian is None else jacobian, (q, v))
        Ur, sr, W = rows
        return a, Ur @ ((W @ force) / sr)

    def project(self, q: np.ndarray, v: np.ndarray, tol: float, velocity_tol: float = 0.0) -> Projection:
        r"""Project a state onto the closure manifold, in place of a Baumgarte correction.

        :math:`q` when its closure distance (:class:`ClosureDistance`) exceeds ``tol``: one minimum-norm
        Gauss-Newton step :math:`\delta = -J_\phi^+ \phi` (from an integrator's small drift it
        lands at round-off), then damped iterations (:func:`~plm_pin.core.assembly.assemble`)
        if that was not enough. Then :math:`v` onto :math:`J_\phi v = 0` by the
        least-kinetic-energy projection when :math:`q` moved or :math:`|J_\phi v|` exceeds
        ``velocity_tol``, with the SVD of :math:`J_\phi` at the projected :math:`q`, which the
        result keeps for the closure forces there (:meth:`solve`).

        Args:
            q: configuration, shape (nq,).
            v: joint velocities, shape (nv,).
            tol: largest closure distance left [m, rad].
            velocity_tol: largest closure rate left [m/s, rad/s].

        Returns:
            The projected state, the closure distances before and after, the reduced rows at ``q``.

        Raises:
            ClosureNotSatisfied: when the loops cannot be closed to ``tol`` from ``q``.
            SingularConfiguration: at a constraint singularity where the motion is not defined.
        """
        if not self.closures:
            return Projection(q, v, 0.0, 0.0, None)
        model, data, closures = self.model, self.data, self.closures
        phi, J = self._closure_terms(q)
        before = after = self.distance(phi)
        if before > tol:
            Ur, sr, W = self._split(J)[0]
            q = pin.integrate(model, q, -W.T @ ((Ur.T @ phi) / sr))
            phi, J = self._closure_terms(q)
            after = self.distance(phi)
            if after > tol:
                free, cap = self._all_columns, PROJECTION_ITERATIONS
                q = assemble(model, data, closures, q, free, tol=tol / 2, max_iterations=cap).q
                phi, J = self._closure_terms(q)
                after = self.distance(phi)
        elif np.max(np.abs(J @ v)) <= velocity_tol:
            return Projection(q, v, before, after, None, J)
        rows, lost = self._split(J)
        M = pin.crba(model, data, q)
        v = v + self._saddle(M, rows.W, np.zeros(model.nv), -(rows.W @ v))[: model.nv]
        if lost.shape[1]:
            self._check_through(q, v, lost, rows.W, J)
        return Projection(q, v, before, after, rows, J)

    def stage_rates(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r"""Rates of an integrator's stage, taken at its projection onto the closures.

        :data:`STAGE_ITERATIONS` minimum-norm Gauss-Newton steps on :math:`\phi(q) = 0`, then
        :math:`v` projected orthogonally onto :math:`J_\phi v = 0`; the accelerations there by
        the KKT solve. Near a constraint singularity the index-1 accelerations of an off-manifold
        state are off by its error over :math:`\sigma_r`; on the manifold they are exact
        (module docstring). Where the rank drops, the lost rows are dropped if the motion is
        defined there.

        Args:
            q: configuration of the stage, shape (nq,).
            v: joint velocities of the stage, shape (nv,).
            tau: applied generalized forces, shape (nv,).

        Returns:
            The projected velocities (the configuration's rate) and the accelerations, shape (nv,) each.

        Raises:
            SingularConfiguration: at a constraint singularity where the motion is not defined.
        """
        model = self.model
        if not self.closures:
            return v, self.kkt(q, v, tau)[0]
        for _ in range(STAGE_ITERATIONS):
            phi, J = self._closure_terms(q)
            Ur, sr, W = self._split(J)[0]
            q = pin.integrate(model, q, -W.T @ ((Ur.T @ phi) / sr))
        J = self._closure_terms(q)[1]
        rows, lost = self._split(J)
        v = v - rows.W.T @ (rows.W @ v)
        if lost.shape[1]:
            self._check_through(q, v, lost, rows.W, J)
        return v, self.kkt(q, v, tau, rows)[0]

    def time_to_crossing(self, q: np.ndarray, v: np.ndarray) -> float:
        r"""Predicted time [s] until an independent closure singular value reaches zero, moving at ``v``.

        Each of the closure Jacobian's r independent singular values :math:`\sigma_i` below
        :data:`CROSSING_WATCH_RTOL` of the largest changes at the rate
        :math:`\dot\sigma_i = u_i^T \dot J_\phi v_i`, with :math:`\dot J_\phi` by a central
        difference of :math:`J_\phi` along ``v``; the earliest :math:`\sigma_i / (-\dot\sigma_i)`
        of those decreasing. A singular value passes through zero linearly at a crossing of two
        sheets of the closure manifold. ``inf`` when none is near or decreasing.
        """
        r = self.rank
        if not r:
            return math.inf
        U, s, Vt = np.linalg.svd(self._closure_terms(q)[1], full_matrices=False)
        near = [i for i in range(r) if s[i] < CROSSING_WATCH_RTOL * s[0]]
        speed = float(np.linalg.norm(v))
        if not near or speed == 0.0:
            return math.inf
        tau = 1e-6 / speed  # [s]: a 1e-6 move along v
        Jp = self._closure_terms(pin.integrate(self.model, q, tau * v))[1]
        Jm = self._closure_terms(pin.integrate(self.model, q, -tau * v))[1]
        rates = [float(U[:, i] @ (Jp - Jm) @ Vt[i]) / (2 * tau) for i in near]
        times = [s[i] / -rate for i, rate in zip(near, rates, strict=True) if rate < 0.0]
        return min(times, default=math.inf)

    def energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic (armature included) plus gravitational potential energy [J]."""
        M = pin.crba(self.model, self.data, q)
        return 0.5 * float(v @ M @ v) + float(pin.computePotentialEnergy(self.model, self.data, q))
