r"""Forward dynamics of closed chains in time, with the loops kept closed.

The tree state :math:`(q, v)` is integrated under

.. math::
    M(q)\, a + h(q, v) = \tau + J_\phi^T \lambda, \qquad J_\phi a + \dot J_\phi v = 0

(:mod:`plm_pin.dynamics._constrained`; gravity and armature from the model). The index-1
form alone lets the closure residual :math:`\phi(q)` drift (only :math:`\ddot\phi = 0` is
imposed), so after every step the state is **projected** back onto the closure manifold:

- :math:`q` by Gauss-Newton on the closure residual whenever its largest entry exceeds
  ``closure_tol``: one minimum-norm step :math:`-J_\phi^+ \phi` (from an integrator's small
  drift it lands at round-off), damped iterations
  (:func:`plm_pin.kinematics.assembly.assemble`) if that is not enough;
- :math:`v` onto :math:`J_\phi v = 0` by the mass-weighted projection
  :math:`\min \|v^+ - v\|_M`, which removes only the closure-violating part of the motion
  and never adds kinetic energy, whenever :math:`q` moved or :math:`|J_\phi v|` would open
  the loops by ``closure_tol`` within one step.

Projection rather than integration in independent coordinates: it works unchanged for any
mechanism (redundant closure rows, spatial chains, free-flyer joints), needs no choice or
switching of independent coordinates near singularities of a partition, and with a
:math:`p`-th order integrator each projection corrects :math:`O(h^{p+1})`, so it does not
lower the order; the price is one residual and Jacobian evaluation per step, and an SVD
and a linear solve when a projection is due. The residual the integrator reaches *before*
each projection is returned as :attr:`SimulationResult.closure_drift`, so the correction is
never hidden.

Integrators:

- ``"fixed"``: classical Runge-Kutta 4 with step ``step`` (default 1 ms, or ``dt`` when
  smaller), fitted to divide every output interval; order 4, so halving the step divides
  the position and energy errors by about 16.
- ``"adaptive"``: SciPy's DOP853 (8th order, error control by ``rtol`` / ``atol``) over each
  output interval, the state projected between intervals.

Both integrate in the chart :math:`q = q_k \oplus \delta` (``pin.integrate``) of the step's
start, :math:`\dot\delta = (\partial (q_k \oplus \delta) / \partial \delta)^{-1} v`, which is
:math:`v` for joints whose configuration is a vector space and keeps the order for
free-flyer, spherical and unbounded revolute joints.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

from .._checks import as_vector, optional_name, real_numbers, sample_count
from ..exceptions import ClosureNotSatisfied, InvalidInput, PlmError, SimulationFailed
from ..kinematics import closures as _closures
from ..statics.balance import load_on_frame
from ._constrained import ClosedChainDynamics

if TYPE_CHECKING:
    from ..mechanism import Mechanism

METHODS = ("fixed", "adaptive")
"""Integration methods of :func:`simulate`."""

DEFAULT_STEP = 1e-3
"""Default step of the fixed-step integrator [s]."""

CLOSURE_TOL = 1e-12
"""Default largest closure residual kept during a simulation [m, rad]."""

V0_TOL = 1e-9
r"""Largest :math:`|J_\phi v_0|` accepted, relative to :math:`\max(1, |v_0|)` [m/s, rad/s]."""

ForceLaw = Callable[[float, np.ndarray, np.ndarray], Any]
"""Actuator forces as a function of time [s], configuration and velocity."""


@dataclass(frozen=True)
class SimulationResult:
    r"""Samples of a closed-chain simulation at the output times.

    Attributes:
        t: output times [s], shape (n,).
        q: configurations, shape (n, nq).
        v: joint velocities [m/s, rad/s], shape (n, nv).
        a: joint accelerations [m/s^2, rad/s^2], shape (n, nv).
        lam: closure forces [N, N m] in the rows of the closure residual (force on the second
            frame of each closure, world-aligned for point rows), shape (n, m).
        closure_residual: largest absolute closure residual of each sample [m, rad], shape (n,).
        closure_drift: largest residual the integrator reached before a projection since the
            previous sample [m, rad], shape (n,).
        energy: kinetic (armature included) plus gravitational potential energy [J], shape (n,).
        x: task coordinates of the end-effector frame [m, rad] (angles wrapped to
            :math:`(-\pi, \pi]`), shape (n, n_task); None without a task.
        method: ``"fixed"`` or ``"adaptive"``.
        solver: ``"kkt"`` or ``"pinocchio"``.
        steps: integration steps taken.
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    lam: np.ndarray
    closure_residual: np.ndarray
    closure_drift: np.ndarray
    energy: np.ndarray
    x: np.ndarray | None
    method: str
    solver: str
    steps: int = field(default=0)

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        arrays = {
            name: getattr(self, name)
            for name in ("t", "q", "v", "a", "lam", "closure_residual", "closure_drift", "energy", "x")
        }
        for name, arr in arrays.items():
            if arr is None:
                continue
            if arr.shape[:1] != (n,):
                raise InvalidInput(f"SimulationResult.{name} has {arr.shape[0]} samples, t has {n}")
            arr.setflags(write=False)

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def energy_drift(self) -> float:
        """Largest deviation of the energy from its initial value [J] (0 without samples)."""
        return float(np.max(np.abs(self.energy - self.energy[0]))) if len(self) else 0.0

    def max_closure_residual(self) -> float:
        """Largest closure residual over the samples [m, rad]."""
        return float(np.max(self.closure_residual)) if len(self) else 0.0

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "t": self.t.tolist(),
            "q": self.q.tolist(),
            "v": self.v.tolist(),
            "a": self.a.tolist(),
            "lam": self.lam.tolist(),
            "closure_residual": self.closure_residual.tolist(),
            "closure_drift": self.closure_drift.tolist(),
            "energy": self.energy.tolist(),
            "x": None if self.x is None else self.x.tolist(),
            "method": self.method,
            "solver": self.solver,
            "steps": self.steps,
        }


class _NonFinite(Exception):
    """The state or the forces became non-finite (internal signal)."""


def _positive(value: float, name: str) -> float:
    x = float(value)
    if not math.isfinite(x) or x <= 0.0:
        raise InvalidInput(f"{name} must be a positive finite number, got {value!r}")
    return x


class _Run:
    """State of one simulation: dynamics, force law, projection and the sample buffers."""

    def __init__(
        self,
        mech: Mechanism,
        dyn: ClosedChainDynamics,
        forces: np.ndarray | ForceLaw,
        closure_tol: float,
        times: np.ndarray,
        method: str,
    ) -> None:
        self.mech = mech
        self.dyn = dyn
        self.model = mech.model
        self.data = dyn.data
        self.forces = forces
        self.closure_tol = closure_tol
        self.method = method
        self.times = times
        self.euclidean = self.model.nq == self.model.nv
        self.actuated = mech.actuated_v_indices
        self.steps = 0
        self.tau_constant = None if callable(forces) else self._joint_forces(forces)
        n, task = times.size, mech.task_compiled
        self.q = np.empty((n, mech.nq))
        self.v = np.empty((n, mech.nv))
        self.a = np.empty((n, mech.nv))
        self.lam = np.empty((n, mech.n_closure_rows))
        self.residual = np.empty(n)
        self.drift = np.empty(n)
        self.energy = np.empty(n)
        self.x = None if task is None else np.empty((n, task.size))

    # ------------------------------------------------------------- forces
    def _joint_forces(self, f: np.ndarray) -> np.ndarray:
        tau = np.zeros(self.mech.nv)
        tau[self.actuated] = f
        return tau

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Actuator forces as generalized forces, shape (nv,)."""
        if self.tau_constant is not None:
            return self.tau_constant
        assert callable(self.forces)
        n_act = self.mech.n_actuators
        try:
            f = np.asarray(self.forces(t, q.copy(), v.copy()), dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidInput(f"actuator_forces(t, q, v) must return {n_act} numbers: {exc}") from None
        if f.shape != (n_act,):
            raise InvalidInput(
                f"actuator_forces(t, q, v) must return shape ({n_act},) (one per actuator "
                f"{[a.joint for a in self.mech.actuators]}), got {f.shape} at t = {t:.6g} s"
            )
        if not np.all(np.isfinite(f)):
            raise _NonFinite(f"actuator_forces(t, q, v) returned non-finite values {f.tolist()}")
        return self._joint_forces(f)

    # -------------------------------------------------------- integration
    def _delta_rate(self, q0: np.ndarray, delta: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Chart rate of ``q = q0 + delta``: the velocity ``v`` pulled back to ``delta``."""
        if self.euclidean:
            return v
        return np.linalg.solve(pin.dIntegrate(self.model, q0, delta, pin.ArgumentPosition.ARG1), v)

    def _accel(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self.dyn.acceleration(q, v, self.tau(t, q, v))

    def rk4(self, t: float, q: np.ndarray, v: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
        """One classical Runge-Kutta 4 step of size ``h`` [s] in the chart at ``q``."""
        model = self.model
        k1d, k1v = v, self._accel(t, q, v)
        d, w = 0.5 * h * k1d, v + 0.5 * h * k1v
        k2d, k2v = self._delta_rate(q, d, w), self._accel(t + 0.5 * h, pin.integrate(model, q, d), w)
        d, w = 0.5 * h * k2d, v + 0.5 * h * k2v
        k3d, k3v = self._delta_rate(q, d, w), self._accel(t + 0.5 * h, pin.integrate(model, q, d), w)
        d, w = h * k3d, v + h * k3v
        k4d, k4v = self._delta_rate(q, d, w), self._accel(t + h, pin.integrate(model, q, d), w)
        delta = (h / 6.0) * (k1d + 2.0 * k2d + 2.0 * k3d + k4d)
        self.steps += 1
        return pin.integrate(model, q, delta), v + (h / 6.0) * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)

    def adaptive(
        self, t0: float, t1: float, q: np.ndarray, v: np.ndarray, rtol: float, atol: float, max_step: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """DOP853 from ``t0`` to ``t1`` [s] in the chart at ``q``."""
        nv, model = self.mech.nv, self.model

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            delta, w = y[:nv], y[nv:]
            return np.concatenate(
                [self._delta_rate(q, delta, w), self._accel(t, pin.integrate(model, q, delta), w)]
            )

        sol = solve_ivp(
            rhs,
            (t0, t1),
            np.concatenate([np.zeros(nv), v]),
            "DOP853",
            rtol=rtol,
            atol=atol,
            max_step=max_step,
        )
        self.steps += len(sol.t) - 1
        if sol.status < 0:
            raise _NonFinite(f"the adaptive integrator failed: {sol.message}")
        return pin.integrate(model, q, sol.y[:nv, -1]), sol.y[nv:, -1]

    # --------------------------------------------------------- projection
    def residual_norm(self, q: np.ndarray) -> float:
        """Largest absolute closure residual at ``q`` [m, rad]; leaves the placements in the data."""
        phi = _closures.residual(self.model, self.data, self.mech.closures, q)
        return float(np.max(np.abs(phi))) if phi.size else 0.0

    def project(self, q: np.ndarray, v: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, float]:
        """Project the state after a step of ``h`` [s]; also return the residual before [m, rad].

        The velocity is projected when the closure rate would open the loops by more than
        ``closure_tol`` within such a step (or when the configuration was projected).
        """
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            raise _NonFinite("the state became non-finite")
        return self.dyn.project(q, v, self.closure_tol, self.closure_tol / h)

    # ------------------------------------------------------------ samples
    def record(self, k: int, q: np.ndarray, v: np.ndarray, drift: float) -> None:
        """Store sample ``k`` of the projected state."""
        t = float(self.times[k])
        a, lam = self.dyn.solve(q, v, self.tau(t, q, v))
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(lam))):
            raise _NonFinite("the accelerations or closure forces became non-finite")
        self.q[k], self.v[k], self.a[k], self.lam[k] = q, v, a, lam
        self.residual[k] = self.residual_norm(q)
        if self.x is not None:
            assert self.mech.task_compiled is not None
            self.x[k] = self.mech.task_compiled.pose_from_data(self.data)
        self.drift[k] = drift
        self.energy[k] = self.dyn.energy(q, v)

    def result(self, n: int) -> SimulationResult:
        """The first ``n`` samples as a result."""
        return SimulationResult(
            t=self.times[:n].copy(),
            q=self.q[:n].copy(),
            v=self.v[:n].copy(),
            a=self.a[:n].copy(),
            lam=self.lam[:n].copy(),
            closure_residual=self.residual[:n].copy(),
            closure_drift=self.drift[:n].copy(),
            energy=self.energy[:n].copy(),
            x=None if self.x is None else self.x[:n].copy(),
            method=self.method,
            solver=self.dyn.solver,
            steps=self.steps,
        )


def _output_times(duration: float, dt: float) -> np.ndarray:
    """0, dt, 2 dt, ... up to ``duration`` (the last interval shorter when dt does not divide it)."""
    n = max(1, math.ceil(duration / dt - 1e-9))
    return np.minimum(np.arange(n + 1) * dt, duration)


def _check_forces(mech: Mechanism, actuator_forces: Any) -> np.ndarray | ForceLaw:
    if actuator_forces is None:
        return np.zeros(mech.n_actuators)
    if callable(actuator_forces):
        return actuator_forces
    return as_vector(actuator_forces, mech.n_actuators, "actuator_forces")


def _check_start(
    mech: Mechanism, dyn: ClosedChainDynamics, q0: Any, v0: Any, closure_tol: float
) -> tuple[np.ndarray, np.ndarray]:
    q = mech.check_q(q0, "q0").copy()
    v = np.zeros(mech.nv) if v0 is None else as_vector(v0, mech.nv, "v0").copy()
    if mech.closures:
        errors = mech.closure_errors(q)
        worst = max(errors, key=lambda k: errors[k])
        if errors[worst] > closure_tol:
            raise ClosureNotSatisfied(
                f"{mech.name}: q0 is not assembled: closure {worst!r} residual {errors[worst]:.3g} above "
                f"closure_tol {closure_tol:.3g}; close the loops first with mech.assemble(q0)",
                errors[worst],
                closure_tol,
                q,
                worst,
            )
        Jv = mech.closure_jacobian(q) @ v
        bound = V0_TOL * max(1.0, float(np.max(np.abs(v))))
        if np.max(np.abs(Jv)) > bound:
            raise InvalidInput(
                f"{mech.name}: v0 violates the closures: |J_phi v0| = {np.max(np.abs(Jv)):.3g} > "
                f"{bound:.3g}; "
                "choose v0 = S @ xdot with S from plm_pin.kinematics.closed_chain_jacobians(mech, q0)"
            )
        v = dyn.project(q, v, closure_tol)[1]
    return q, v


def simulate(
    mech: Mechanism,
    q0: Any,
    v0: Any = None,
    *,
    duration: float,
    dt: float,
    actuator_forces: Any = None,
    wrench: Any = None,
    wrench_frame: str | None = None,
    method: str = "fixed",
    step: float | None = None,
    rtol: float = 1e-9,
    atol: float = 1e-12,
    solver: str = "auto",
    closure_tol: float = CLOSURE_TOL,
) -> SimulationResult:
    r"""Simulate the closed chain from ``(q0, v0)`` for ``duration``, keeping the loops closed.

    Example:
        >>> import plm_pin
        >>> from plm_pin.dynamics.simulation import simulate
        >>> mech = plm_pin.load("fourbar")
        >>> run = simulate(mech, mech.q_ref, duration=1.0, dt=0.01)
        >>> bool(run.max_closure_residual() < 1e-10)
        True

    Args:
        mech: the mechanism (gravity and armature from its model).
        q0: assembled initial configuration, shape (nq,).
        v0: initial joint velocities [m/s, rad/s] with :math:`J_\phi v_0 = 0`, shape (nv,);
            default at rest.
        duration: simulated time [s].
        dt: output step [s]: samples at 0, dt, 2 dt, ... and ``duration``.
        actuator_forces: forces [N] or torques [N m] of the actuators, shape (n_act,), constant,
            or a function ``(t, q, v) -> forces``; default none (a passive mechanism).
        wrench: constant external wrench on ``wrench_frame``: ``(fx, fy, fz, mx, my, mz)``
            [N, N m] world-aligned about the frame origin, or on the task frame one value
            per task coordinate (``fx fy mz`` for ``x y rz``).
        wrench_frame: frame the wrench acts on; default the end-effector (task) frame.
        method: ``"fixed"`` (Runge-Kutta 4) or ``"adaptive"`` (DOP853).
        step: ``fixed``: integration step [s], default ``min(dt, 1 ms)``, shortened to divide each
            output interval; ``adaptive``: the largest step allowed (default unbounded).
        rtol: relative tolerance of the adaptive integrator.
        atol: absolute tolerance of the adaptive integrator [m, rad, m/s, rad/s].
        solver: ``"auto"``, ``"kkt"`` (ours, any closure) or ``"pinocchio"``
            (``pin.constraintDynamics``, point and weld closures); ``auto`` picks ``pinocchio``
            when it applies.
        closure_tol: largest closure residual kept [m, rad]; ``q0`` must satisfy it.

    Returns:
        The samples at the output times.

    Raises:
        InvalidInput: a malformed or non-finite argument, an unknown method or solver
            (the message lists the choices), or ``v0`` violating the closures.
        FrameNotFound: unknown ``wrench_frame``.
        ClosureNotSatisfied: ``q0`` is not assembled to ``closure_tol``.
        SimulationFailed: the state or the forces became non-finite, or the loops could not
            be kept closed (for instance at a constraint singularity); the error carries
            the samples computed before.
    """
    sample_count(duration, dt)
    real_numbers(wrench, "wrench"), optional_name(wrench_frame, "wrench_frame")
    if method not in METHODS:
        raise InvalidInput(f"method {method!r} is not one of {list(METHODS)}")
    duration = _positive(duration, "duration")
    dt = _positive(dt, "dt")
    closure_tol = _positive(closure_tol, "closure_tol")
    rtol, atol = _positive(rtol, "rtol"), _positive(atol, "atol")
    default_step = min(dt, DEFAULT_STEP) if method == "fixed" else math.inf
    h_max = default_step if step is None else _positive(step, "step")
    if wrench is None and wrench_frame is not None:
        raise InvalidInput(f"wrench_frame {wrench_frame!r} given without a wrench")
    load = None if wrench is None else load_on_frame(mech, wrench, wrench_frame)
    forces = _check_forces(mech, actuator_forces)
    dyn = ClosedChainDynamics(mech, solver, load)
    q, v = _check_start(mech, dyn, q0, v0, closure_tol)
    times = _output_times(duration, dt)
    run = _Run(mech, dyn, forces, closure_tol, times, method)
    k, t_now = 0, 0.0
    try:
        run.record(0, q, v, run.residual_norm(q))
        for k in range(1, times.size):
            t0, t1 = float(times[k - 1]), float(times[k])
            if method == "fixed":
                n_sub = max(1, math.ceil((t1 - t0) / h_max - 1e-9))
                h = (t1 - t0) / n_sub
                drift = 0.0
                for i in range(n_sub):
                    t_now = t0 + i * h
                    q, v = run.rk4(t_now, q, v, h)
                    q, v, before = run.project(q, v, h)
                    drift = max(drift, before)
            else:
                t_now = t0
                q, v = run.adaptive(t0, t1, q, v, rtol, atol, h_max)
                q, v, drift = run.project(q, v, t1 - t0)
            t_now = t1
            run.record(k, q, v, drift)
    except (_NonFinite, PlmError) as exc:
        if isinstance(exc, InvalidInput):
            raise
        raise SimulationFailed(
            f"{mech.name}: simulation stopped in the step from t = {t_now:.6g} s ({method}, {dyn.solver}): "
            f"{exc}; the {k} sample(s) before are in .partial",
            run.result(k),
            t_now,
            exc if isinstance(exc, PlmError) else None,
        ) from exc
    return run.result(times.size)
