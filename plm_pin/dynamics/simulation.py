r"""Forward dynamics of closed chains in time, with the loops kept closed.

The tree state :math:`(q, v)` is integrated under

.. math::
    M(q)\, a + h(q, v) = \tau + J_\phi^T \lambda, \qquad J_\phi a + \dot J_\phi v = 0

(:mod:`plm_pin.dynamics._constrained`; gravity and armature from the model). The index-1
form alone lets the closure residual :math:`\phi(q)` drift (only :math:`\ddot\phi = 0` is
imposed), so the state is **projected** back onto the closure manifold when its closure
distance (the Euclidean gap of each closure, :class:`~plm_pin.dynamics._constrained.ClosureDistance`)
passes ``closure_tol``:

- :math:`q` by one minimum-norm Gauss-Newton step :math:`-J_\phi^+ \phi` (from an
  integrator's small drift it lands at round-off), damped iterations
  (:func:`plm_pin.core.assembly.assemble`) if that is not enough;
- :math:`v` onto :math:`J_\phi v = 0` by the mass-weighted projection
  :math:`\min \|v^+ - v\|_M`, which removes only the closure-violating part of the motion
  and never adds kinetic energy.

Projection rather than integration in independent coordinates: it works unchanged for any
mechanism (redundant closure rows, spatial chains, free-flyer joints) and needs no choice or
switching of independent coordinates near singularities of a partition. The residual the
integrator reaches *before* a projection is returned as :attr:`SimulationResult.closure_drift`,
so the correction is never hidden.

Integrators:

- ``"adaptive"`` (the default): SciPy's DOP853 (8th order, error control by ``rtol`` /
  ``atol``) in **one integration over the whole run**; the samples are read from its dense
  output at the output times and projected there, and the integrator's own state is projected
  (and the integration restarted from it) only when its drift passes ``closure_tol``.
- ``"fixed"``: classical Runge-Kutta 4 with step ``step`` (default 1 ms, or ``dt`` when
  smaller), fitted to divide every output interval, the state projected after every step;
  order 4. A step that opens the loops by more than :data:`STEP_DRIFT_TOL` before its projection
  is too large for the dynamics there and is redone as two half steps (down to
  :data:`MAX_HALVINGS` halvings, then the run stops).

Both integrate in the chart :math:`q = q_c \oplus \delta` (``pin.integrate``) of a reference
configuration, :math:`\dot\delta = (\partial (q_c \oplus \delta) / \partial \delta)^{-1} v`,
which is :math:`v` for joints whose configuration is a vector space and keeps the order for
free-flyer, spherical and unbounded revolute joints.

**Energy guard.** A passive run (no actuator forces, no wrench) conserves the energy; when it
strays from its initial value by more than :data:`ENERGY_RTOL` of the largest kinetic energy
reached, the run stops with :class:`~plm_pin.exceptions.SimulationFailed` naming the time, the
energy change and the smallest closure singular value there, keeping the samples before.

**Constraint singularities.** Where two sheets of the closure manifold cross, the closure
Jacobian loses a rank (the passive 3D4M, ``harada2011_3d4m``, swings through such a place
whenever the two rods of a leg pair hang straight down, about twice a second). The motion
through it is defined when the lost row stays consistent and the velocity picks one sheet
(:mod:`plm_pin.dynamics._constrained`); then the run passes through, else it stops. The
index-1 accelerations of a state off the closures are off there by its error over the
vanishing singular value, so DOP853, whose stages are such states, shrinks its step; below
:data:`MIN_STEP` it hands over to a *bridge*: fixed RK4 steps from the sample before to
:data:`BRIDGE_STEPS` steps past the place, each stage put on the closures before its rates are
taken (:meth:`~plm_pin.dynamics._constrained.ClosedChainDynamics.stage_rates`), the step that
reaches the crossing shortened so that the crossing falls a quarter step from every stage.

Accelerations, closure forces, energy and task pose are computed once per sample, when it is
recorded, with the SVD of the closure Jacobian its projection computed there. In the adaptive
run, the samples of a DOP853 step are projected and recorded by one compiled call
(:meth:`plm_pin.kernels.Kernel.samples`: the same projection, KKT solve, energy and pose, to
round-off) for a mechanism with closures and a kernel under constant actuator forces without a
wrench; a sample at a constraint singularity, one whose configuration one Gauss-Newton step does
not close, or a non-finite one takes this module's Python path, so its checks and errors are
unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike
from scipy.integrate import DOP853

from .._arguments import as_vector, optional_name, physical_effort, positive, real_numbers, sample_count
from .._linalg import lu_solve
from ..core.mechanism import Mechanism
from ..exceptions import ClosureNotSatisfied, InvalidInput, PlmError, SimulationFailed, SingularConfiguration
from ..kernels import Kernel, kernel_of
from ..results import Result, unit
from ..statics.balance import JointLoad, load_on_frame
from ..tolerances import (
    CROSSING_MARGIN,
    ENERGY_ROUND_OFF_RTOL,
    ENERGY_RTOL,
    FEASIBLE_VELOCITY_RTOL,
    SAMPLE_COUNT_RTOL,
    SIMULATION_ATOL,
    SIMULATION_RTOL,
    STEP_DRIFT_TOL,
)
from ._constrained import ClosedChainDynamics, Projection, ReducedRows

METHODS = ("fixed", "adaptive")
"""Integration methods of :func:`simulate`."""

DEFAULT_STEP = 1e-3
"""Default step of the fixed-step integrator [s]."""

MAX_HALVINGS = 10
"""Halvings of a fixed step allowed before the run stops."""

MIN_STEP = 1e-6
"""Adaptive step [s] below which DOP853 is taken to be stuck (at a constraint singularity): bridged."""

BRIDGE_STEPS = 10
"""Fixed RK4 steps (of DEFAULT_STEP at most) past a place DOP853 cannot step, from the sample before it.

Each bridge advances the run by at least this many steps, so repeated bridges always progress.
"""

_CHART_SPAN = 0.5
"""Largest chart coordinate [m, rad] of the adaptive run before it re-centres on a non-vector-space joint."""

ForceLaw = Callable[[float, np.ndarray, np.ndarray], ArrayLike]
"""Actuator forces as a function of time [s], configuration and velocity."""

_NO_POSE = np.empty((0, 0))
"""The task pose buffer of a sample kernel without a task."""


@dataclass(frozen=True)
class SimulationResult(Result):
    r"""Samples of a closed-chain simulation at the output times.

    Attributes:
        t: output times [s], shape (n,).
        q: configurations, shape (n, nq).
        v: joint velocities [m/s, rad/s], shape (n, nv).
        a: joint accelerations [m/s^2, rad/s^2], shape (n, nv).
        lam: closure forces [N, N m] in the rows of the closure residual (force on the second
            frame of each closure, world-aligned for point rows), shape (n, m).
        residual: closure distance of each sample (largest Euclidean gap of a closure's
            point rows, or norm of its rotation rows) [m, rad], shape (n,).
        closure_drift: largest closure distance the integrator reached before a projection since
            the previous sample [m, rad], shape (n,).
        energy: kinetic (armature included) plus gravitational potential energy [J], shape (n,).
        x: task coordinates of the end-effector frame [m, rad] (angles wrapped to
            :math:`(-\pi, \pi]`), shape (n, n_task); None without a task.
        method: ``"fixed"`` or ``"adaptive"``.
        solver: ``"kkt"`` or ``"pinocchio"``.
        steps: integration steps taken.
    """

    t: np.ndarray = field(metadata=unit("s"))
    q: np.ndarray = field(metadata=unit("m, rad"))
    v: np.ndarray = field(metadata=unit("m/s, rad/s"))
    a: np.ndarray = field(metadata=unit("m/s^2, rad/s^2"))
    lam: np.ndarray = field(metadata=unit("N, N m"))
    residual: np.ndarray = field(metadata=unit("m, rad"))
    closure_drift: np.ndarray = field(metadata=unit("m, rad"))
    energy: np.ndarray = field(metadata=unit("J"))
    x: np.ndarray | None = field(metadata=unit("m, rad"))
    method: str
    solver: str
    steps: int = field(default=0)

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        arrays = {
            name: getattr(self, name)
            for name in ("t", "q", "v", "a", "lam", "residual", "closure_drift", "energy", "x")
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

    @property
    def max_residual(self) -> float:
        """Largest closure distance over the samples [m, rad]."""
        return float(np.max(self.residual)) if len(self) else 0.0


class _NonFinite(Exception):
    """The state or the forces became non-finite (internal signal)."""


class _Stop(Exception):
    """The run cannot go on accurately: a step too large, or a passive run's energy strayed (internal)."""


class _StepFailed(_Stop):
    """DOP853 could not take a step (internal signal)."""


class _DOP853(DOP853):
    """SciPy's DOP853 calling the right-hand side directly.

    SciPy wraps ``fun`` in two Python calls that count its calls and convert its value with
    ``np.asarray``; the right-hand side here returns a new float array already, so the stages
    call it unwrapped (``nfev`` is not counted).
    """

    def __init__(self, fun: Callable[[float, np.ndarray], np.ndarray], *args: Any, **kwargs: Any) -> None:
        super().__init__(fun, *args, **kwargs)
        self.fun = fun


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
        self.done = 0  # samples recorded
        self.t_now = 0.0  # start of the step under way [s]
        self.tau_constant = None if callable(forces) else self._joint_forces(forces)
        # passive: nothing does work, so the energy is conserved and guarded
        self.passive = self.tau_constant is not None and not self.tau_constant.any() and dyn.load is None
        self.peak_kinetic = 0.0
        n = times.size
        self.q = np.empty((n, mech.nq))
        self.v = np.empty((n, mech.nv))
        self.a = np.empty((n, mech.nv))
        self.lam = np.empty((n, mech.n_closure_rows))
        self.residual = np.empty(n)
        self.drift = np.empty(n)
        self.energy = np.empty(n)
        task = mech.task_compiled
        self.x = None if task is None else np.empty((n, task.size))
        self.kernel = self._sample_kernel()
        self.potential = np.empty(n)  # potential energy of each sample [J], for the energy guard

    def _sample_kernel(self) -> Kernel | None:
        """The kernel that records the dense samples of the adaptive run in one compiled call, or None.

        It serves mechanisms with closures under constant actuator forces and no wrench, whose
        kernel holds the task (:meth:`_samples`).
        """
        if not self.mech.closures or self.tau_constant is None or self.dyn.load is not None:
            return None
        kernel = kernel_of(self.mech)
        if kernel is None or kernel.n_task != (0 if self.x is None else self.x.shape[1]):
            return None
        return kernel

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
        return lu_solve(pin.dIntegrate(self.model, q0, delta, pin.ArgumentPosition.ARG1), v)

    def _accel(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self.dyn.acceleration(q, v, self.tau(t, q, v))

    def _stage_rates(self, t: float, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Velocity and acceleration of a stage, taken at its projection onto the closures."""
        return self.dyn.stage_rates(q, v, self.tau(t, q, v))

    def _rates(self, t: float, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Velocity and acceleration of a stage, by the index-1 solve at the stage itself."""
        return v, self._accel(t, q, v)

    def rk4(
        self, t: float, q: np.ndarray, v: np.ndarray, h: float, projected: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        """One classical Runge-Kutta 4 step of size ``h`` [s] in the chart at ``q``.

        ``projected``: take each stage's rates at its projection onto the closures (near a
        constraint singularity, :meth:`~plm_pin.dynamics._constrained.ClosedChainDynamics.stage_rates`).
        """
        model, rates = self.model, self._stage_rates if projected else self._rates
        k1d, k1v = rates(t, q, v)
        d, w = 0.5 * h * k1d, v + 0.5 * h * k1v
        qs = pin.integrate(model, q, d)
        w, k2v = rates(t + 0.5 * h, qs, w)
        k2d = self._delta_rate(q, d, w)
        d, w = 0.5 * h * k2d, v + 0.5 * h * k2v
        w, k3v = rates(t + 0.5 * h, pin.integrate(model, q, d), w)
        k3d = self._delta_rate(q, d, w)
        d, w = h * k3d, v + h * k3v
        w, k4v = rates(t + h, pin.integrate(model, q, d), w)
        k4d = self._delta_rate(q, d, w)
        delta = (h / 6.0) * (k1d + 2.0 * k2d + 2.0 * k3d + k4d)
        self.steps += 1
        return pin.integrate(model, q, delta), v + (h / 6.0) * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)

    def fixed_step(
        self, t: float, q: np.ndarray, v: np.ndarray, h: float, halvings: int = 0, projected: bool = False
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """RK4 over ``h`` [s] then projection; halved while the step opens the loops past STEP_DRIFT_TOL.

        ``projected``: stages' rates at their projection onto the closures (:meth:`rk4`).
        Returns the projected state and the largest closure distance before a projection.
        """
        self.t_now = t
        q1, v1 = self.rk4(t, q, v, h, projected)
        if np.all(np.isfinite(q1)) and np.all(np.isfinite(v1)):
            opened = self.distance(q1)
            if opened <= STEP_DRIFT_TOL:
                p = self.project(q1, v1, h)
                return p.q, p.v, p.before
        else:
            opened = math.inf
        if halvings >= MAX_HALVINGS:
            raise _Stop(
                f"a step of {h:.3g} s ({MAX_HALVINGS} halvings of the one asked) still opens the loops by "
                f"{opened:.3g} before its projection (more than {STEP_DRIFT_TOL:g}): the dynamics change "
                f"faster than RK4 resolves there{self._conditioning(q)}"
            )
        qm, vm, d1 = self.fixed_step(t, q, v, 0.5 * h, halvings + 1, projected)
        q2, v2, d2 = self.fixed_step(t + 0.5 * h, qm, vm, 0.5 * h, halvings + 1, projected)
        return q2, v2, max(d1, d2)

    def adaptive(self, q: np.ndarray, v: np.ndarray, rtol: float, atol: float, max_step: float) -> None:
        """DOP853 over the whole run; samples from its dense output, projected; the state when it drifts.

        Where DOP853 cannot step on (its step shrinks to nothing, or a closure row vanishes at a
        stage: a constraint singularity crossed), fixed RK4 steps with the stages' rates taken on
        the closures carry the state from the sample before to :data:`BRIDGE_STEPS` steps past
        the place, then DOP853 resumes. A bridge stops the run only where the motion is not
        defined (:mod:`plm_pin.dynamics._constrained`) or its steps cannot keep the loops closed.
        """
        nv, model, times, euclidean = self.mech.nv, self.model, self.times, self.euclidean
        accel, tau, rate, tau_c = self.dyn.accelerator(), self.tau, self._delta_rate, self.tau_constant
        t, k, first_step, drift = 0.0, 1, None, 0.0
        while k < times.size:
            origin = q

            def rhs(time: float, y: np.ndarray, origin: np.ndarray = origin) -> np.ndarray:
                out = np.empty(2 * nv)
                delta, w = y[:nv], y[nv:]
                if euclidean:
                    out[:nv] = w
                    out[nv:] = accel(delta, w, tau_c if tau_c is not None else tau(time, delta, w))
                else:
                    out[:nv] = rate(origin, delta, w)
                    qs = pin.integrate(model, origin, delta)
                    out[nv:] = accel(qs, w, tau_c if tau_c is not None else tau(time, qs, w))
                return out

            y0 = np.concatenate([q if self.euclidean else np.zeros(nv), v])
            solver = _DOP853(
                rhs, t, y0, float(times[-1]), rtol=rtol, atol=atol, max_step=max_step, first_step=first_step
            )
            first_step = None
            try:
                while k < times.size:
                    self.t_now = solver.t
                    message = solver.step()
                    if solver.status == "failed":
                        raise _StepFailed(f"the adaptive integrator failed: {message}")
                    if solver.h_abs < MIN_STEP and solver.t < times[-1] - MIN_STEP:
                        raise _StepFailed(
                            f"the adaptive step fell to {solver.h_abs:.3g} s at t = {solver.t:.6g} s"
                        )
                    self.steps += 1
                    y = solver.y
                    if not np.isfinite(y).all():
                        raise _NonFinite("the state became non-finite")
                    if times[k] <= solver.t:
                        stop = int(np.searchsorted(times, solver.t, side="right"))  # samples k..stop-1
                        dense = np.ascontiguousarray(solver.dense_output()(times[k:stop]).T)  # one pass
                        k, drift = self._samples(k, dense, origin, solver.h_abs or max_step, drift)
                    t = solver.t
                    q = y[:nv] if euclidean else pin.integrate(model, origin, y[:nv])
                    v = y[nv:]
                    opened = self.distance(q)
                    drift = max(drift, opened)
                    rechart = not euclidean and float(np.max(np.abs(y[:nv]))) > _CHART_SPAN
                    if solver.status == "finished" and k < times.size:
                        raise _NonFinite(f"the integrator stopped at t = {solver.t:.6g} s, before the end")
                    if k < times.size and (opened > self.closure_tol or rechart):
                        p = self.project(q.copy(), v.copy(), solver.h_abs)
                        q, v = p.q, p.v
                        first_step = min(solver.h_abs, float(times[-1]) - t)
                        break
            except (_StepFailed, SingularConfiguration):
                # from the last sample: DOP853 may have crept up to the singular place itself
                h = min(DEFAULT_STEP, max_step)
                last = float(times[k - 1])
                t, k, q, v, drift = self._bridge(
                    last, k, self.q[k - 1], self.v[k - 1], max(t, last) + BRIDGE_STEPS * h, h
                )

    def _samples(
        self, k: int, dense: np.ndarray, origin: np.ndarray, h: float, drift: float
    ) -> tuple[int, float]:
        """Record samples ``k``... from the dense-output states ``dense`` (n, 2 nv) of a step of ``h`` [s].

        Each state is projected (:meth:`project`) and recorded (:meth:`record`); with a sample
        kernel, all in compiled calls (:meth:`plm_pin.kernels.Kernel.samples`, the same
        projection, KKT solve, energy and pose) but those it hands back: a constraint
        singularity, a projection needing more than one Gauss-Newton step, a non-finite value,
        which take the Python path, so that its checks and errors are unchanged. ``drift``:
        the closure distance reached before the first sample [m, rad].

        Returns:
            The next sample index and the drift to carry to it.
        """
        nv, model, kernel, i, n = self.mech.nv, self.model, self.kernel, 0, dense.shape[0]
        while i < n:
            if kernel is not None:
                assert self.tau_constant is not None
                x = self.x[k:] if self.x is not None else _NO_POSE
                out = (self.q[k:], self.v[k:], self.a[k:], self.lam[k:], self.residual[k:], self.drift[k:])
                done = kernel.samples(
                    dense[i:], origin, self.tau_constant, self.dyn.rank, self.closure_tol,
                    self.closure_tol / h,
                    (*out, self.energy[k:], self.potential[k:], x),
                )  # fmt: skip
                for _ in range(done):
                    self.drift[k] = max(drift, float(self.drift[k]))
                    if self.passive:
                        self._guard_energy(k, float(self.potential[k]))
                    self.done = k + 1
                    k, drift = k + 1, 0.0
                i += done
                if i == n:
                    break
            yk = dense[i]
            qk = yk[:nv] if self.euclidean else pin.integrate(model, origin, yk[:nv])
            p = self.project(qk, yk[nv:], h)
            self.record(k, p.q, p.v, max(drift, p.before), p.after, p.rows, p.jacobian)
            k, drift, i = k + 1, 0.0, i + 1
        return k, drift

    def _bridge(
        self, t: float, k: int, q: np.ndarray, v: np.ndarray, end: float, h: float
    ) -> tuple[float, int, np.ndarray, np.ndarray, float]:
        """Fixed steps of at most ``h`` [s] from ``t`` to ``end``, landing on the samples they pass.

        The stages' rates are taken on the closures (:meth:`rk4`), and a step that would reach
        a constraint singularity is shortened so that the crossing falls at three quarters of
        it, a quarter step from every stage but the first (:meth:`_across`).
        """
        times, drift = self.times, 0.0
        end = min(end, float(times[-1]))
        while t < end and k < times.size:
            t_next = t + self._across(q, v, min(h, float(times[k]) - t))
            q, v, before = self.fixed_step(t, q, v, t_next - t, projected=True)
            drift = max(drift, before)
            t = t_next
            if t >= times[k]:
                self.record(k, q, v, drift)
                k, drift = k + 1, 0.0
        return t, k, q, v, drift

    def _across(self, q: np.ndarray, v: np.ndarray, h: float) -> float:
        r"""A step [s] from the state ``(q, v)`` on the closures whose stages keep clear of a crossing.

        Near a constraint singularity a stage's projection onto the closures is reliable only
        while its error (of order :math:`h^2`) is small beside its distance to the crossing,
        where the sheets of the closure manifold meet (there it may land on the other sheet).
        The RK4 stages sit at 0, h/2 and h; with the crossing predicted at :math:`\Delta` from
        now (:meth:`~plm_pin.dynamics._constrained.ClosedChainDynamics.time_to_crossing`), the step
        is :math:`4\Delta/3` (the crossing at three quarters) when that fits in ``h``, else
        :math:`\Delta/2` when the crossing is near its end; else ``h``. The first stage, at the
        projected state itself, may be at the crossing.
        """
        delta = self.dyn.time_to_crossing(q, v)
        if not CROSSING_MARGIN * h < delta < 1.25 * h:
            return h
        return 4.0 * delta / 3.0 if 4.0 * delta / 3.0 <= h else 0.5 * delta

    # --------------------------------------------------------- projection
    def distance(self, q: np.ndarray) -> float:
        """Closure distance at ``q`` [m, rad]; leaves the placements in the data."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return self.dyn.distance(self.dyn.residual_from_data())

    def project(self, q: np.ndarray, v: np.ndarray, h: float) -> Projection:
        """Project the state after a step of ``h`` [s] (with the closure distances before and after).

        The velocity is projected when the closure rate would open the loops by more than
        ``closure_tol`` within such a step (or when the configuration was projected).
        """
        if not (np.isfinite(q).all() and np.isfinite(v).all()):
            raise _NonFinite("the state became non-finite")
        return self.dyn.project(q, v, self.closure_tol, self.closure_tol / h)

    def _conditioning(self, q: np.ndarray) -> str:
        """A note on the closure Jacobian's smallest kept singular value at ``q`` (constraint singularity)."""
        if not self.mech.closures:
            return ""
        s = np.linalg.svd(self.mech.closure_jacobian(q), compute_uv=False)
        r = self.dyn.rank
        return (
            f"; the closure Jacobian's {r}-th singular value is {s[r - 1]:.3g} (largest {s[0]:.3g}): "
            "near a constraint singularity, where branches of the closed loops meet, the accelerations "
            "of slightly open states are amplified by its inverse"
        )

    # ------------------------------------------------------------ samples
    def record(
        self,
        k: int,
        q: np.ndarray,
        v: np.ndarray,
        drift: float,
        distance: float | None = None,
        rows: ReducedRows | None = None,
        jacobian: np.ndarray | None = None,
    ) -> None:
        """Store sample ``k`` of the projected state with its accelerations, forces, energy and pose.

        ``distance``, ``rows`` and ``jacobian``: the closure distance, reduced closure rows and
        closure Jacobian at ``q`` when the projection computed them (it leaves the frame
        placements of ``q`` in the data). A passive run's energy is guarded.
        """
        self.q[k], self.v[k] = q, v
        if distance is None or not self.mech.closures:
            distance = self.distance(q)  # the frame placements of q in the data
        self.residual[k] = distance
        self.drift[k] = drift
        self.a[k], self.lam[k] = self.dyn.solve(q, v, self.tau(float(self.times[k]), q, v), rows, jacobian)
        if not (np.isfinite(self.a[k]).all() and np.isfinite(self.lam[k]).all()):
            raise _NonFinite("the accelerations or closure forces became non-finite")
        if self.x is not None:
            task = self.mech.task_compiled
            assert task is not None
            self.x[k] = task.pose_from_data(self.data)
        self.energy[k] = self.dyn.energy(q, v)
        if self.passive:
            self._guard_energy(k, float(self.data.potential_energy))
        self.done = k + 1

    def _guard_energy(self, k: int, potential: float) -> None:
        """Stop when the energy of sample ``k`` (potential ``potential`` [J]) strays past ENERGY_RTOL."""
        e = float(self.energy[k])
        self.peak_kinetic = max(self.peak_kinetic, e - potential)
        allowed = ENERGY_RTOL * self.peak_kinetic + ENERGY_ROUND_OFF_RTOL * max(
            1.0, abs(float(self.energy[0]))
        )
        if abs(e - self.energy[0]) > allowed:  # the sample that strayed is not kept
            raise _Stop(
                f"the passive energy changed from {self.energy[0]:.6g} J to {e:.6g} J by t = "
                f"{self.times[k]:.6g} s (allowed {allowed:.3g} J, {ENERGY_RTOL:g} of the peak kinetic energy "
                f"{self.peak_kinetic:.3g} J){self._conditioning(self.q[k - 1])}"
            )

    def result(self, n: int) -> SimulationResult:
        """The first ``n`` samples as a result."""
        return SimulationResult(
            t=self.times[:n].copy(),
            q=self.q[:n].copy(),
            v=self.v[:n].copy(),
            a=self.a[:n].copy(),
            lam=self.lam[:n].copy(),
            residual=self.residual[:n].copy(),
            closure_drift=self.drift[:n].copy(),
            energy=self.energy[:n].copy(),
            x=None if self.x is None else self.x[:n].copy(),
            method=self.method,
            solver=self.dyn.solver,
            steps=self.steps,
        )


def _output_times(duration: float, dt: float) -> np.ndarray:
    """0, dt, 2 dt, ... up to ``duration`` (the last interval shorter when dt does not divide it)."""
    n = max(1, math.ceil(duration / dt - SAMPLE_COUNT_RTOL))
    return np.minimum(np.arange(n + 1) * dt, duration)


def _check_forces(mech: Mechanism, actuator_forces: ArrayLike | ForceLaw | None) -> np.ndarray | ForceLaw:
    if actuator_forces is None:
        return np.zeros(mech.n_actuators)
    if callable(actuator_forces):
        return actuator_forces
    return as_vector(actuator_forces, mech.n_actuators, "actuator_forces")


def _check_start(
    mech: Mechanism, q0: ArrayLike, v0: ArrayLike | None, closure_tol: float
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
        bound = FEASIBLE_VELOCITY_RTOL * max(1.0, float(np.max(np.abs(v))))
        if np.max(np.abs(Jv)) > bound:
            raise InvalidInput(
                f"{mech.name}: v0 violates the closures: |J_phi v0| = {np.max(np.abs(Jv)):.3g} > "
                f"{bound:.3g}; "
                "choose v0 = S @ xdot with S from plm_pin.kinematics.closed_chain_jacobians(mech, q0)"
            )
    return q, v


def simulate(
    mech: Mechanism,
    q0: ArrayLike,
    v0: ArrayLike | None = None,
    *,
    duration: float,
    dt: float,
    actuator_forces: ArrayLike | ForceLaw | None = None,
    wrench: ArrayLike | None = None,
    frame: str | None = None,
    method: str = "adaptive",
    step: float | None = None,
    rtol: float = SIMULATION_RTOL,
    atol: float = SIMULATION_ATOL,
    solver: str = "auto",
    closure_tol: float | None = None,
) -> SimulationResult:
    r"""Simulate the closed chain from ``(q0, v0)`` for ``duration``, keeping the loops closed.

    Example:
        >>> import plm_pin
        >>> from plm_pin.dynamics.simulation import simulate
        >>> mech = plm_pin.load("fourbar")
        >>> run = simulate(mech, mech.q_ref, duration=1.0, dt=0.01)
        >>> bool(run.max_residual < 1e-10)
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
        wrench: constant external wrench on ``frame``: ``(fx, fy, fz, mx, my, mz)``
            [N, N m] world-aligned about the frame origin, or on the task frame one value
            per task coordinate (``fx fy mz`` for ``x y rz``).
        frame: frame the wrench acts on; default the end-effector (task) frame.
        method: ``"adaptive"`` (DOP853 over the whole run, samples from its dense output; the
            default) or ``"fixed"`` (Runge-Kutta 4, projected after every step).
        step: ``fixed``: integration step [s], default ``min(dt, 1 ms)``, shortened to divide each
            output interval and halved where it opens the loops by more than
            :data:`STEP_DRIFT_TOL`; ``adaptive``: the largest step allowed (default unbounded).
        rtol: relative tolerance of the adaptive integrator.
        atol: absolute tolerance of the adaptive integrator [m, rad, m/s, rad/s].
        solver: ``"auto"``, ``"kkt"`` (ours, any closure) or ``"pinocchio"``
            (``pin.constraintDynamics``, point and weld closures); ``auto`` picks ``pinocchio``
            when it applies.
        closure_tol: largest closure distance kept (Euclidean gap of each closure's point rows,
            norm of its rotation rows) [m, rad]; ``q0`` must satisfy it (default: the mechanism's
            ``closure_tol``).

    Returns:
        The samples at the output times.

    Raises:
        InvalidInput: a malformed or non-finite argument, an unknown method or solver
            (the message lists the choices), or ``v0`` violating the closures.
        FrameNotFound: unknown ``frame``.
        ClosureNotSatisfied: ``q0`` is not assembled to ``closure_tol``.
        SimulationFailed: the state or the forces became non-finite, the loops could not
            be kept closed, the motion is not defined at a constraint singularity reached
            (at rest there, or a velocity on no sheet: the cause is a
            :class:`~plm_pin.exceptions.SingularConfiguration` saying which), a fixed step stayed too
            large after :data:`MAX_HALVINGS` halvings, or a passive run's energy strayed past
            :data:`ENERGY_RTOL`; the message names the time and the reason, and the error
            carries the samples computed before.
    """
    sample_count(duration, dt)
    real_numbers(wrench, "wrench"), optional_name(frame, "frame")
    if method not in METHODS:
        raise InvalidInput(f"method {method!r} is not one of {list(METHODS)}")
    duration = positive(duration, "duration")
    dt = positive(dt, "dt")
    closure_tol = mech.closure_tol if closure_tol is None else positive(closure_tol, "closure_tol")
    rtol, atol = positive(rtol, "rtol"), positive(atol, "atol")
    default_step = min(dt, DEFAULT_STEP) if method == "fixed" else math.inf
    h_max = default_step if step is None else positive(step, "step")
    if wrench is None and frame is not None:
        raise InvalidInput(f"frame {frame!r} given without a wrench")
    load = None if wrench is None else load_on_frame(mech, wrench, frame)
    if load is not None:
        physical_effort(load.forces if isinstance(load, JointLoad) else load.wrench, "wrench")
    forces = _check_forces(mech, actuator_forces)
    if not callable(forces):
        physical_effort(forces, "actuator_forces")
    dyn = ClosedChainDynamics(mech, solver, load)
    q, v = _check_start(mech, q0, v0, closure_tol)
    times = _output_times(duration, dt)
    run = _Run(mech, dyn, forces, closure_tol, times, method)
    try:
        p = dyn.project(q, v, closure_tol)  # a constraint singularity may stop the run here
        q, v = p.q, p.v
        run.record(0, q, v, run.distance(q))
        if method == "adaptive":
            run.adaptive(q, v, rtol, atol, h_max)
        else:
            for k in range(1, times.size):
                t0, t1 = float(times[k - 1]), float(times[k])
                n_sub = max(1, math.ceil((t1 - t0) / h_max - 1e-9))
                h = (t1 - t0) / n_sub
                drift = 0.0
                for i in range(n_sub):
                    q, v, before = run.fixed_step(t0 + i * h, q, v, h)
                    drift = max(drift, before)
                run.record(k, q, v, drift)
        return run.result(times.size)
    except (_NonFinite, _Stop, PlmError) as exc:
        if isinstance(exc, InvalidInput):
            raise
        raise SimulationFailed(
            f"{mech.name}: simulation stopped in the step from t = {run.t_now:.6g} s "
            f"({method}, {dyn.solver}): "
            f"{exc}; the {run.done} sample(s) before are in .partial",
            run.result(run.done),
            run.t_now,
            exc if isinstance(exc, PlmError) else None,
        ) from exc
