r"""Trajectories on the closure manifold: consistent :math:`q, v, a` along a task or actuator motion.

Generic: any mechanism with a task as large as its mobility (:class:`plm_pin.Mechanism`).

A *profile* is a callable ``t -> (x, xd, xdd)``: positions and their first two time
derivatives at time ``t`` [s]. Write it analytically when you can
(the studies' ``zhao2011_trajectory`` and ``enferadi2017_line`` in ``analyses/_zhao2011_paper.py``
and ``analyses/_enferadi2017_paper.py`` are profiles); otherwise build one with

- :func:`differentiated_profile` from positions alone, ``t -> x``: five-point central
  differences (error stated there);
- :func:`sampled_profile` from samples ``(t, x)`` (quintic spline, continuous up to the
  fourth derivative) or ``(t, x, xd, xdd)`` (quintic Hermite, continuous accelerations).

:func:`task_trajectory` follows a task profile :math:`x(t)`: at each sample, :math:`q` by
inverse kinematics (:func:`plm_pin.kinematics.inverse_kinematics`) from the second-order
prediction :math:`q_{k-1} \oplus (v\,\Delta t + a\,\Delta t^2/2)`, keeping the working mode
of the first sample; then the velocity and acceleration that keep the loops closed and
the task frame on the profile,

.. math::
    J_\phi v = 0, \quad J_r v = \dot x, \qquad
    J_\phi a = -\dot J_\phi v, \quad J_r a = \ddot x - \dot J_r v,

solved as :math:`v = N T_r^{-1} \dot x` (:math:`S \dot x`) and :math:`a = a_p + N T_r^{-1}
(\ddot x - \dot J_r v - J_r a_p)`, with :math:`N` the feasible motions
(:mod:`plm_pin.kinematics.jacobians`), :math:`T_r = J_r N` and :math:`a_p` the minimum-norm
solution of the closure rows (by the pseudo-inverse of :math:`J_\phi` from the SVD that gives
:math:`N`); :math:`\dot J_\phi v` and :math:`\dot J_x v` are
:func:`plm_pin.core.closures.drift_from_data` and :meth:`plm_pin.core.task.Task.drift_from_data`.

Rotation rates. A profile gives time derivatives of the task coordinates, so for angles
the roll-pitch-yaw rates :math:`\dot r`, while plm_pin's task velocities are the frame's
world-aligned twist rows :math:`(v, \omega)` (:mod:`plm_pin.core.task`). With
:math:`\omega = E(r) \dot r` (``pin.rpy.computeRpyJacobian``, world frame),

.. math::
    \dot r = E^{-1} \omega, \qquad \ddot r = E^{-1} (\dot\omega - \dot E \dot r),

so the rows of the angles are :math:`J_r = (E^{-1} J_\omega)_{sel}` and
:math:`\dot J_r v = (E^{-1}(\alpha - \dot E \dot r))_{sel}` (:math:`\alpha` the angular
acceleration at :math:`a = 0`); translations keep :math:`J_r = J_x`. This is exact for any
selection of angles (the others and their rates come from :math:`q, v`) and undefined at
:math:`\cos r_y = 0`. For a planar task (``rz`` with the motion in the plane)
:math:`E^{-1}` leaves :math:`\omega_z = \dot r_z`. The result's ``xd`` and ``xdd`` are the twist rows
:math:`J_x v` and :math:`J_x a + \dot J_x v` (what :math:`S` and :math:`J_{ce}` act on); they
equal the profile's rates for translations and planar rotations.

:func:`actuator_trajectory` follows an actuator profile :math:`c(t)`: :math:`q` by
forward-kinematics continuation (:meth:`plm_pin.Mechanism.assemble` with every actuator
fixed, from the same prediction, so the assembly mode of the first sample is kept), then
:math:`v = N s`, :math:`C s = \dot c` and :math:`a = a_p + N s_2`,
:math:`C s_2 = \ddot c - S_a a_p` (:math:`C = S_a N`). With redundant actuators every
actuator is used: the positions must assemble with all of them fixed, and the rates are
solved in the least-squares sense, the trajectory stopping where they disagree beyond a tolerance.

Both stop at the first sample that cannot be solved (out of the workspace, or at or across
a singularity that breaks their map: constraint or inverse for a task trajectory,
constraint or direct for an actuator trajectory) with a
:class:`plm_pin.exceptions.TrajectoryError` holding the samples computed before it.

Units: time [s]; lengths [m], angles [rad] and their rates [/s], [/s^2].
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, positive, real_numbers, signs
from .._lazy import lazy_module
from .._linalg import LU, det_sign
from .._text import short
from ..core import closures as _closures
from ..core.legs import Leg, working_mode_from_data
from ..core.mechanism import Mechanism, require_task
from ..core.task import FrameTask, Task
from ..exceptions import (
    ClosureNotSatisfied,
    InvalidInput,
    PlmError,
    PoseUnreachable,
    SingularConfiguration,
    TrajectoryError,
)
from ..kinematics.inverse import inverse_kinematics
from ..kinematics.jacobians import (
    ClosedChainJacobians,
    check_square_task,
    closed_chain_jacobians,
    inverse_if_regular,
)
from ..kinematics.singularity import constraint_margins, direct_margins, inverse_margins
from ..results import Result, unit
from ..tolerances import LEG_SINGULAR_RTOL, RANK_RTOL, RATE_CONSISTENCY_TOL, SINGULARITY_TOL

interpolate = lazy_module("scipy.interpolate")  # BPoly, make_interp_spline

Profile = Callable[[float], ArrayLike]
"""A profile: ``t`` [s] -> ``(x, xd, xdd)``, each shape (n,) (or three numbers when n = 1)."""

FD_STEP = 1e-3
"""Default time step of :func:`differentiated_profile` [s]."""

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_WORLD = pin.ReferenceFrame.WORLD


# ---------------------------------------------------------------- profiles
def differentiated_profile(positions: Callable[[float], ArrayLike], step: float = FD_STEP) -> Profile:
    r"""A profile from positions alone, its derivatives by five-point central differences.

    .. math::
        \dot x \approx \frac{x_{-2} - 8 x_{-1} + 8 x_1 - x_2}{12 h}, \qquad
        \ddot x \approx \frac{-x_{-2} + 16 x_{-1} - 30 x_0 + 16 x_1 - x_2}{12 h^2},

    :math:`x_j = x(t + j h)`. Truncation errors :math:`h^4 |x^{(5)}| / 30` and
    :math:`h^4 |x^{(6)}| / 90`; round-off about :math:`1.5\,\epsilon |x| / h` and
    :math:`5.3\,\epsilon |x| / h^2` (:math:`\epsilon = 2.2 \cdot 10^{-16}`). With the default
    1 ms on Zhao 2011's eq. (35) (0.36 s, 9.8 m/s^2 peak): about 2e-9 m/s and 1e-8 m/s^2.
    Prefer analytic derivatives when you have them.

    Args:
        positions: ``t`` [s] -> ``x``, shape (n,); it must be defined on
            :math:`[t - 2h, t + 2h]` around every sample time (beyond the ends too).
        step: :math:`h` [s], positive; about a fiftieth of the profile's time scale (its period / 300).

    Returns:
        The profile ``t -> (x, xd, xdd)``.

    Raises:
        InvalidInput: on a step that is not a positive finite number.
    """
    h = positive(step, "step", "s")

    def profile(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        xm2, xm1, x0, xp1, xp2 = (np.asarray(positions(t + j * h), dtype=float) for j in (-2, -1, 0, 1, 2))
        xd = (xm2 - 8.0 * xm1 + 8.0 * xp1 - xp2) / (12.0 * h)
        xdd = (-xm2 + 16.0 * (xm1 + xp1) - 30.0 * x0 - xp2) / (12.0 * h * h)
        return x0, xd, xdd

    return profile


def sampled_profile(
    t: ArrayLike, x: ArrayLike, xd: ArrayLike | None = None, xdd: ArrayLike | None = None
) -> Profile:
    """A profile interpolating samples with scipy: positions only, or positions, rates and accelerations.

    - ``x`` only: the quintic interpolating spline (``scipy.interpolate.make_interp_spline``,
      ``k = 5``, not-a-knot ends), continuous up to its fourth derivative; needs 6 samples.
      Its rates and accelerations at the ends are the spline's, not data: give ``xd`` and
      ``xdd`` for a rest-to-rest motion.
    - ``x``, ``xd`` and ``xdd``: the quintic Hermite interpolant
      (``scipy.interpolate.BPoly.from_derivatives``), matching all three at every sample,
      continuous accelerations.

    Outside ``[t[0], t[-1]]`` the polynomials of the end intervals are extended.

    Args:
        t: sample times [s], shape (N,), strictly increasing.
        x: positions, shape (N, n) (or (N,) for n = 1).
        xd: their rates, same shape (optional, with ``xdd``).
        xdd: their accelerations, same shape (optional, with ``xd``).

    Returns:
        The profile ``t -> (x, xd, xdd)``.

    Raises:
        InvalidInput: on non-finite or non-increasing times, mismatched shapes, non-finite
            samples, only one of ``xd`` and ``xdd``, or too few samples.
    """
    ts = _check_times(t)
    pairs = ((x, "x"), (xd, "xd"), (xdd, "xdd"))
    given = [_samples(values, ts.shape[0], name) for values, name in pairs if values is not None]
    if (xd is None) != (xdd is None):
        raise InvalidInput("give both xd and xdd (quintic Hermite) or neither (quintic spline through x)")
    if any(g.shape != given[0].shape for g in given):
        raise InvalidInput(f"x, xd and xdd must have the same shape, got {[g.shape for g in given]}")
    if len(given) == 3:
        if ts.shape[0] < 2:
            raise InvalidInput("a Hermite profile needs at least 2 samples")
        poly = interpolate.BPoly.from_derivatives(ts, np.stack(given, axis=1))
        d1, d2 = poly.derivative(1), poly.derivative(2)
    else:
        if ts.shape[0] < 6:
            raise InvalidInput(f"a quintic spline through x needs at least 6 samples, got {ts.shape[0]}")
        poly = interpolate.make_interp_spline(ts, given[0], k=5, axis=0)
        d1, d2 = poly.derivative(1), poly.derivative(2)

    def profile(time: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return poly(time), d1(time), d2(time)

    return profile


def _samples(values: ArrayLike, n: int, name: str) -> np.ndarray:
    arr = np.asarray(real_numbers(values, name), dtype=float)
    arr = arr[:, None] if arr.ndim == 1 else arr
    if arr.ndim != 2 or arr.shape[0] != n:
        raise InvalidInput(f"{name} must have shape ({n}, n) or ({n},), one row per time, got {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
    if bad.size:
        raise InvalidInput(f"{name} is not finite at samples {bad.tolist()}")
    return arr


def _check_times(times: ArrayLike) -> np.ndarray:
    """Return ``times`` [s] as a float array of shape (N,), N >= 1, finite and strictly increasing.

    Raises:
        InvalidInput: naming the first offending sample.
    """
    try:
        ts = np.asarray(times, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidInput(f"times must be numbers [s]: {exc}") from None
    if ts.ndim != 1 or ts.shape[0] == 0:
        raise InvalidInput(f"times must be a non-empty 1-D array [s], got shape {ts.shape}")
    if not np.all(np.isfinite(ts)):
        raise InvalidInput(f"times are not finite at samples {np.flatnonzero(~np.isfinite(ts)).tolist()}")
    steps = np.diff(ts)
    if np.any(steps <= 0.0):
        k = int(np.flatnonzero(steps <= 0.0)[0]) + 1
        raise InvalidInput(
            f"times must be strictly increasing: sample {k} (t = {ts[k]:.9g} s) follows t = {ts[k - 1]:.9g} s"
        )
    return ts


def _evaluate(
    profile: Profile | ArrayLike, times: np.ndarray, size: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Profile values at every time: positions, rates and accelerations, each shape (N, size).

    ``profile`` may also be positions sampled at ``times``, shape (N, size), interpolated by
    :func:`sampled_profile`.

    Raises:
        InvalidInput: on a value of the wrong shape or not finite, naming the sample.
    """
    if profile is None or isinstance(profile, (str, bytes, Mapping)):
        raise InvalidInput(
            f"profile must be a function t -> (x, xd, xdd) or positions sampled at the times, shape "
            f"({times.shape[0]}, {size}); got {short(profile)}"
        )
    fn: Profile = profile if callable(profile) else sampled_profile(times, profile)
    out = np.empty((3, times.shape[0], size))
    for k, t in enumerate(times.tolist()):
        try:
            arr = np.asarray(fn(t), dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidInput(f"profile({t:.9g}) must return (x, xd, xdd) as numbers: {exc}") from None
        if arr.shape == (3,) and size == 1:
            arr = arr[:, None]
        if arr.shape != (3, size):
            raise InvalidInput(
                f"profile({t:.9g}) must return (x, xd, xdd), each of shape ({size},); got shape {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            raise InvalidInput(f"profile is not finite at sample {k} (t = {t:.9g} s): {arr.tolist()}")
        out[:, k] = arr
    return out[0], out[1], out[2]


# ---------------------------------------------------------------- result
_ARRAYS = ("t", "q", "v", "a", "x", "xd", "xdd", "c", "cd", "cdd", "residual")


@dataclass(frozen=True)
class JointTrajectory(Result):
    r"""Configurations, velocities and accelerations of a closed chain along a sampled motion.

    Arrays are read-only; every one has one row per sample.

    Attributes:
        t: sample times [s], shape (N,).
        q: configurations, shape (N, nq).
        v: tree velocities [m/s, rad/s], shape (N, nv); :math:`J_\phi v = 0`.
        a: tree accelerations [m/s^2, rad/s^2], shape (N, nv); :math:`J_\phi a + \dot J_\phi v = 0`.
        x: task coordinates of the end-effector frame [m, rad], shape (N, n_task).
        xd: task velocities: world-aligned twist rows :math:`J_x v` [m/s, rad/s], shape (N, n_task).
        xdd: task accelerations :math:`J_x a + \dot J_x v`: classical acceleration of the frame
            origin and angular acceleration [m/s^2, rad/s^2], shape (N, n_task).
        c: actuator positions [m, rad], shape (N, n_act).
        cd: actuator rates [m/s, rad/s], shape (N, n_act).
        cdd: actuator accelerations [m/s^2, rad/s^2], shape (N, n_act).
        residual: largest absolute closure residual per sample [m, rad], shape (N,).
    """

    t: np.ndarray = field(metadata=unit("s"))
    q: np.ndarray = field(metadata=unit("m, rad"))
    v: np.ndarray = field(metadata=unit("m/s, rad/s"))
    a: np.ndarray = field(metadata=unit("m/s^2, rad/s^2"))
    x: np.ndarray = field(metadata=unit("m, rad"))
    xd: np.ndarray = field(metadata=unit("m/s, rad/s"))
    xdd: np.ndarray = field(metadata=unit("m/s^2, rad/s^2"))
    c: np.ndarray = field(metadata=unit("m, rad"))
    cd: np.ndarray = field(metadata=unit("m/s, rad/s"))
    cdd: np.ndarray = field(metadata=unit("m/s^2, rad/s^2"))
    residual: np.ndarray = field(metadata=unit("m, rad"))
    _DERIVED = ("n_samples", "max_residual")

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        for name in _ARRAYS:
            arr = getattr(self, name)
            if arr.ndim != (1 if name in ("t", "residual") else 2) or arr.shape[0] != n:
                raise InvalidInput(f"{name} has shape {arr.shape}; t has {n} samples")
            arr.setflags(write=False)
        if self.v.shape != self.a.shape or not self.x.shape == self.xd.shape == self.xdd.shape:
            raise InvalidInput("v and a, and x, xd and xdd, must have the same shapes")
        if not self.c.shape == self.cd.shape == self.cdd.shape:
            raise InvalidInput("c, cd and cdd must have the same shapes")

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.t.shape[0])

    @property
    def max_residual(self) -> float:
        """Largest closure residual over the samples [m, rad] (0 without samples)."""
        return float(np.max(self.residual)) if self.residual.size else 0.0


class _Recorder:
    """Preallocated sample arrays, filled one sample at a time."""

    def __init__(self, mech: Mechanism, task: Task, times: np.ndarray) -> None:
        n = times.shape[0]
        self.mech = mech
        self.task = task
        self.t = times
        self.q = np.empty((n, mech.nq))
        self.v = np.empty((n, mech.nv))
        self.a = np.empty((n, mech.nv))
        self.x = np.empty((n, task.size))
        self.xd = np.empty((n, task.size))
        self.xdd = np.empty((n, task.size))
        self.c = np.empty((n, mech.n_actuators))
        self.cd = np.empty((n, mech.n_actuators))
        self.cdd = np.empty((n, mech.n_actuators))
        self.residual = np.empty(n)

    def predict(self, k: int) -> np.ndarray:
        r"""Second-order prediction of sample ``k``: :math:`q_{k-1} \oplus (v \Delta t + a \Delta t^2/2)`."""
        dt = float(self.t[k] - self.t[k - 1])
        step = dt * self.v[k - 1] + (0.5 * dt * dt) * self.a[k - 1]
        return np.asarray(pin.integrate(self.mech.model, self.q[k - 1], step))

    def record(
        self, k: int, q: np.ndarray, v: np.ndarray, a: np.ndarray, J_x: np.ndarray, c: np.ndarray
    ) -> None:
        """Store sample ``k`` and what follows; ``mech.data`` holds the kinematics of ``(q, v, 0)``."""
        mech = self.mech
        act = mech.actuated_v_indices
        self.q[k] = q
        self.v[k] = v
        self.a[k] = a
        self.xd[k] = J_x @ v
        self.xdd[k] = J_x @ a + self.task.drift_from_data(mech.model, mech.data)
        self.c[k] = c
        self.cd[k] = v[act]
        self.cdd[k] = a[act]
        phi = _closures.residual_from_placements(mech.data, mech.closures)
        self.residual[k] = float(np.max(np.abs(phi))) if phi.size else 0.0

    def result(self, k: int | None = None) -> JointTrajectory:
        """The first ``k`` samples (copied), or all of them."""
        arrays = [getattr(self, name) for name in _ARRAYS]
        if k is not None:
            arrays = [arr[:k].copy() for arr in arrays]
        return JointTrajectory(*arrays)

    def stop(self, what: str, k: int, cause: PlmError) -> TrajectoryError:
        """The error stopping the trajectory at sample ``k``, with the samples before it."""
        t = float(self.t[k])
        return TrajectoryError(
            f"{self.mech.name}: {what} trajectory stops at sample {k} of {self.t.shape[0]} (t = {t:.9g} s): "
            f"{cause}; the {k} samples before it are in .partial",
            self.result(k),
            k,
            t,
            cause,
        )


# ---------------------------------------------------------------- per-sample kinematics
def _check_regular(mech: Mechanism, jac: ClosedChainJacobians, tol: float, kind: str) -> None:
    """Refuse a configuration whose constraint or ``kind`` margin is at most ``tol``.

    ``kind`` is ``inverse`` (margin of :math:`T`) or ``direct`` (margin of :math:`C`), as
    :func:`plm_pin.kinematics.classify` defines them.

    An inverse margin above ``tol`` by a bound (:func:`plm_pin.kinematics.jacobians.inverse_if_regular`)
    needs no SVD; near the tolerance the margin decides.

    Raises:
        SingularConfiguration: naming the kinds and margins.
    """
    constraint = float(constraint_margins(jac.closure_singular_values, mech.nv - mech.mobility))
    if constraint > tol and kind == "inverse" and inverse_if_regular(jac.T, jac.J_x, tol) is not None:
        return
    margins = {
        "constraint": constraint,
        kind: float(inverse_margins(jac.T, jac.J_x) if kind == "inverse" else direct_margins(jac.C)),
    }
    bad = [f"{name} (margin {m:.3g})" for name, m in margins.items() if m <= tol]
    if bad:
        raise SingularConfiguration(f"{' and '.join(bad)} singular, at or below the tolerance {tol:.3g}")


def _sample_mode(
    mech: Mechanism, task: Task, legs: tuple[Leg, ...], jac: ClosedChainJacobians
) -> tuple[int, ...]:
    """Working mode at the configuration of :func:`closed_chain_jacobians` (its pass still in ``mech.data``).

    :func:`plm_pin.kinematics.working_mode` without its own kinematics pass and Jacobians.
    """
    ik_rows = np.concatenate((jac.J_phi, jac.J_x))
    return working_mode_from_data(
        mech.model, mech.data, mech.closures, task, legs, LEG_SINGULAR_RTOL, ik_rows
    )


def particular_acceleration(
    mech: Mechanism, q: np.ndarray, v: np.ndarray, jac: ClosedChainJacobians
) -> np.ndarray:
    r"""Kinematics of ``(q, v, 0)`` into ``mech.data``, and the least-norm :math:`a_p` of the closure rows.

    :math:`J_\phi a_p = -\dot J_\phi v`; the rows are consistent on the closure manifold, so
    :math:`a_p` solves them exactly. ``jac``: the Jacobians at ``q``, whose pseudo-inverse of
    :math:`J_\phi` gives :math:`a_p`.
    """
    model, data = mech.model, mech.data
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.updateFramePlacements(model, data)
    if not mech.closures:
        return np.zeros(model.nv)
    gamma = _closures.drift_from_data(model, data, mech.closures)
    return jac.closure_pinv @ -gamma


class _RateRows:
    r"""Rows :math:`J_r` and drift :math:`\dot J_r v` of the time derivatives of the task coordinates.

    :meth:`jacobian` then :meth:`drift` at each sample (module docstring); without angles they
    are :math:`J_x` and :math:`\dot J_x v`.
    """

    def __init__(self, task: Task, model: pin.Model) -> None:
        self.task = task
        self.model = model
        frame = task if isinstance(task, FrameTask) else None  # a joint task's rates are its velocities
        self.n_lin = len(frame.linear) if frame is not None else task.size
        self.angular = list(frame.angular) if frame is not None else []
        self.frame_id = frame.frame_id if frame is not None else -1
        self.E_inv = np.eye(3)
        self.rpy = np.zeros(3)

    def jacobian(self, data: pin.Data, J_x: np.ndarray, x: np.ndarray) -> np.ndarray:
        r""":math:`J_r` from joint Jacobians and placements in ``data``; ``x``: the prescribed coordinates.

        Raises:
            SingularConfiguration: at :math:`\cos r_y = 0`, where roll-pitch-yaw rates are undefined.
        """
        if not self.angular:
            return J_x
        self.rpy = pin.rpy.matrixToRpy(data.oMf[self.frame_id].rotation)
        self.rpy[self.angular] = x[self.n_lin :]
        if abs(np.cos(self.rpy[1])) <= RANK_RTOL:
            raise SingularConfiguration(
                f"roll-pitch-yaw rates are undefined at pitch ry = {self.rpy[1]:.9g} rad (cos ry = 0)"
            )
        self.E_inv = pin.rpy.computeRpyJacobianInverse(self.rpy, _WORLD)
        J_omega = pin.getFrameJacobian(self.model, data, self.frame_id, _LWA)[3:]
        J_r = J_x.copy()
        J_r[self.n_lin :] = (self.E_inv @ J_omega)[self.angular]
        return J_r

    def drift(self, data: pin.Data) -> np.ndarray:
        r""":math:`\dot J_r v` from the kinematics of ``(q, v, 0)`` in ``data``, after :meth:`jacobian`."""
        drift = self.task.drift_from_data(self.model, data)
        if not self.angular:
            return drift
        fid = self.frame_id
        omega = pin.getFrameVelocity(self.model, data, fid, _LWA).angular
        alpha = pin.getFrameClassicalAcceleration(self.model, data, fid, _LWA).angular
        rates = self.E_inv @ omega
        E_dot = pin.rpy.computeRpyJacobianTimeDerivative(self.rpy, rates, _WORLD)
        drift[self.n_lin :] = (self.E_inv @ (alpha - E_dot @ rates))[self.angular]
        return drift


# ---------------------------------------------------------------- task trajectories
def task_trajectory(
    mech: Mechanism,
    profile: Profile | ArrayLike,
    times: ArrayLike,
    *,
    guess: ArrayLike | None = None,
    mode: tuple[int, ...] | None = None,
    tol: float | None = None,
    singularity_tol: float = SINGULARITY_TOL,
) -> JointTrajectory:
    r"""Configurations, velocities and accelerations along a task profile :math:`x(t)`.

    At each time, inverse kinematics continued from the previous sample, then :math:`v` and
    :math:`a` from the closure and task rows (module docstring). The working mode of the
    first sample is kept: the trajectory stops at a sample out of reach, at a constraint or
    inverse (type 1) singularity, or whose working mode differs from the first (the path
    crossed an inverse singularity between two samples). Direct (type 2) singularities do
    not break this map and are not checked (see :func:`plm_pin.kinematics.classify`).

    Args:
        mech: the mechanism; its task must have as many coordinates as DOF.
        profile: ``t -> (x, xd, xdd)``: task coordinates [m, rad] and their time derivatives
            (roll-pitch-yaw rates for angles), each shape (n_task,); or task coordinates sampled
            at ``times``, shape (N, n_task), interpolated by :func:`sampled_profile`.
        times: sample times [s], shape (N,), strictly increasing.
        guess: configuration to solve the first sample from (default: the reference).
        mode: working mode of the first sample, one sign per square leg (see
            :func:`plm_pin.kinematics.inverse_kinematics`); default: that of ``guess``'s basin.
        tol: largest closure and task residual accepted at each sample [m, rad] (default: the
            mechanism's ``closure_tol``).
        singularity_tol: margin at or below which a sample counts as singular [-].

    Returns:
        The trajectory; its ``x`` is the profile's.

    Raises:
        TrajectoryError: at the first sample that cannot be solved, with the samples before it
            (``partial``), the sample ``index`` and ``time``, and the ``cause``
            (:class:`PoseUnreachable` or :class:`SingularConfiguration`).
        InvalidInput: malformed times, mode or guess; a profile value of the wrong shape or not
            finite (naming the sample); a task with more or fewer coordinates than DOF.
    """
    task = require_task(mech)
    check_square_task(task.size, mech.mobility, "a task trajectory needs", mech.name)
    tol = mech.closure_tol if tol is None else positive(tol, "tol", "m, rad")
    singularity_tol = check_tolerance(singularity_tol, "singularity_tol")
    mode = signs(mode, "mode")
    ts = _check_times(times)
    x_all, xd_all, xdd_all = _evaluate(profile, ts, task.size)
    rec = _Recorder(mech, task, ts)
    rec.x[:] = x_all
    rows = _RateRows(task, mech.model)
    first_mode: tuple[int, ...] = ()
    legs: tuple[Leg, ...] = ()
    for k in range(ts.shape[0]):
        x = x_all[k]
        try:
            if k == 0:
                sol = inverse_kinematics(mech, x, guess, mode=mode, tol=tol)
                first_mode = sol.mode
                legs = mech.legs  # built by the line above: no pass of its own between the two below
            else:
                sol = inverse_kinematics(mech, x, rec.predict(k), tol=tol)
            jac = closed_chain_jacobians(mech, sol.q)
            _check_regular(mech, jac, singularity_tol, "inverse")
            # the working mode from the Jacobians just computed at sol.q (what sol.mode recomputes)
            sample_mode = first_mode if k == 0 else _sample_mode(mech, task, legs, jac)
            if sample_mode != first_mode:
                raise SingularConfiguration(
                    f"working mode {sample_mode} differs from the first sample's {first_mode}: the path "
                    f"crossed an inverse (type 1) singularity after t = {ts[k - 1]:.9g} s, or the samples "
                    "are too sparse"
                )
            J_r = rows.jacobian(mech.data, jac.J_x, x)
        except (PoseUnreachable, SingularConfiguration) as exc:
            raise rec.stop("task", k, exc) from exc
        T_r = J_r @ jac.N  # (n_task, mobility)
        lu = LU(T_r)
        v = jac.N @ lu.solve(xd_all[k])
        a_p = particular_acceleration(mech, sol.q, v, jac)
        a = a_p + jac.N @ lu.solve(xdd_all[k] - rows.drift(mech.data) - J_r @ a_p)
        rec.record(k, sol.q, v, a, jac.J_x, sol.actuators)
    return rec.result()


# ---------------------------------------------------------------- actuator trajectories
def actuator_trajectory(
    mech: Mechanism,
    profile: Profile | ArrayLike,
    times: ArrayLike,
    *,
    guess: ArrayLike | None = None,
    tol: float | None = None,
    singularity_tol: float = SINGULARITY_TOL,
    consistency_tol: float = RATE_CONSISTENCY_TOL,
) -> JointTrajectory:
    r"""Configurations, velocities and accelerations along an actuator profile :math:`c(t)`.

    At each time, the loops are closed with every actuator fixed, continued from the previous
    sample (module docstring), so the assembly mode of ``guess`` is kept; then
    :math:`v = N s` and :math:`a = a_p + N s_2` with :math:`C s = \dot c` and
    :math:`C s_2 = \ddot c - S_a a_p` solved by least squares over all actuators. For a
    redundantly actuated chain the profile must be consistent (e.g. the actuator motion of a
    :func:`task_trajectory`): the positions must assemble with every actuator fixed, and the
    rates (accelerations) may miss the fitted closed-chain motion by at most
    ``consistency_tol * max(1, max|c_dot|)`` (``max|c_ddot|``). The trajectory also stops at a
    constraint or direct (type 2) singularity and, for a non-redundant chain, where
    :math:`\det C` (with :math:`N` oriented continuously along the path) changes sign: the
    path crossed a direct singularity between two samples and the assembly mode changed.

    Args:
        mech: the mechanism, with a task (for ``x``) and at least as many actuators as DOF.
        profile: ``t -> (c, cd, cdd)``: actuator positions [m, rad] and their time derivatives,
            each shape (n_act,), in the order of ``mech.actuators``; or positions sampled at
            ``times``, shape (N, n_act), interpolated by :func:`sampled_profile`.
        times: sample times [s], shape (N,), strictly increasing.
        guess: configuration near the first sample; it picks the assembly mode (default: the reference).
        tol: closure tolerance of each assembly [m, rad] (default: the mechanism's ``closure_tol``).
        singularity_tol: margin at or below which a sample counts as singular [-].
        consistency_tol: tolerance on the misfit of redundant actuator rates and accelerations
            [m/s, rad/s, /s]: absolute below 1, relative above.

    Returns:
        The trajectory; its ``x`` is measured at each ``q`` (angles unwrapped along the samples).

    Raises:
        TrajectoryError: at the first sample that cannot be solved, with the samples before it
            (``partial``), the sample ``index`` and ``time``, and the ``cause``
            (:class:`ClosureNotSatisfied`, :class:`SingularConfiguration`, or :class:`InvalidInput`
            for inconsistent redundant rates).
        InvalidInput: malformed times or guess; a profile value of the wrong shape or not finite
            (naming the sample); fewer actuators than DOF.
    """
    task = require_task(mech)
    if mech.n_actuators < mech.mobility:
        raise InvalidInput(
            f"{mech.name}: {mech.n_actuators} actuators cannot drive {mech.mobility} DOF; an actuator "
            "trajectory needs at least as many actuators as DOF"
        )
    tol = mech.closure_tol if tol is None else positive(tol, "tol", "m, rad")
    singularity_tol = check_tolerance(singularity_tol, "singularity_tol")
    consistency_tol = check_tolerance(consistency_tol, "consistency_tol")
    ts = _check_times(times)
    c_all, cd_all, cdd_all = _evaluate(profile, ts, mech.n_actuators)
    q0 = mech.q_ref if guess is None else mech.check_q(guess, "guess")
    rec = _Recorder(mech, task, ts)
    names = [act.joint for act in mech.actuators]
    act = mech.actuated_v_indices
    square = mech.n_actuators == mech.mobility
    N_prev: np.ndarray | None = None
    path_sign = 0.0
    for k in range(ts.shape[0]):
        try:
            fixed = dict(zip(names, c_all[k].tolist(), strict=True))
            q = mech.assemble(q0 if k == 0 else rec.predict(k), fixed, tol=tol, max_iterations=60).q
            jac = closed_chain_jacobians(mech, q)
            _check_regular(mech, jac, singularity_tol, "direct")
            N = jac.N  # (nv, mobility)
            if square:  # orient N along the path; det C must then keep its sign
                if N_prev is not None and det_sign(N_prev.T @ N) < 0.0:
                    N = N.copy()
                    N[:, 0] *= -1.0
                sign = det_sign(N[act])
                if path_sign and sign != path_sign:
                    raise SingularConfiguration(
                        f"det C changed sign after t = {ts[k - 1]:.9g} s: the path crossed a direct "
                        "(type 2) singularity and the assembly mode changed"
                    )
                path_sign, N_prev = sign, N
            C = N[act]  # (n_act, mobility)
            v = N @ _fit(C, cd_all[k], consistency_tol, "rates", names)
            a_p = particular_acceleration(mech, q, v, jac)
            a = a_p + N @ _fit(C, cdd_all[k] - a_p[act], consistency_tol, "accelerations", names)
        except (ClosureNotSatisfied, SingularConfiguration, InvalidInput) as exc:
            raise rec.stop("actuator", k, exc) from exc
        rec.x[k] = task.pose_from_data(mech.data)
        rec.record(k, q, v, a, jac.J_x, mech.actuator_positions(q))
    rec.x[:, task.angles] = np.unwrap(rec.x[:, task.angles], axis=0)
    return rec.result()


def _fit(C: np.ndarray, rhs: np.ndarray, tol: float, what: str, names: list[str]) -> np.ndarray:
    """Least-squares ``s`` of ``C s = rhs``; refuse a misfit above ``tol * max(1, max|rhs|)``.

    Raises:
        InvalidInput: naming the actuator that misses most.
    """
    s = np.linalg.lstsq(C, rhs, rcond=None)[0]
    misfit = C @ s - rhs
    worst = int(np.argmax(np.abs(misfit)))
    if abs(misfit[worst]) > tol * max(1.0, float(np.max(np.abs(rhs)))):
        raise InvalidInput(
            f"the actuator {what} are inconsistent: {names[worst]} misses the closed-chain motion fitted to "
            f"all actuators by {abs(misfit[worst]):.3g} (tolerance {tol:.3g} x max(1, max |{what}|))"
        )
    return s


def checked_trajectory(trajectory: object, name: str) -> JointTrajectory:
    """``trajectory`` if it is a :class:`~plm_pin.dynamics.trajectory.JointTrajectory` with finite samples.

    Raises:
        InvalidInput: naming ``name``: another type (e.g. None), or the first sample holding NaN or inf.
    """
    if not isinstance(trajectory, JointTrajectory):
        raise InvalidInput(
            f"{name} must be a JointTrajectory (see plm_pin.dynamics.trajectory), got {short(trajectory)}"
        )
    for attr in ("t", "q", "v", "a"):
        values = np.asarray(getattr(trajectory, attr))
        bad = ~np.isfinite(values)
        if bad.any():
            index = int(np.argwhere(bad)[0][0])
            raise InvalidInput(f"{name}.{attr} holds NaN or inf at sample {index}")
    return trajectory
