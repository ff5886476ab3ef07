"""Typed errors of plm_pin: one base class and one subclass per condition.

Errors that stop an operation part-way derive from :class:`PartialResultError` and keep what
was computed before (or the best attempt) in ``partial``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ._text import short
from .results import Result


class PlmError(Exception):
    """Base class of every error plm_pin raises on purpose."""


class PartialResultError(PlmError):
    """An operation stopped part-way; what it computed before, or its best attempt, is kept.

    Attributes:
        partial: the partial result (see each subclass for its type).
    """

    partial: object

    def __init__(self, message: str, partial: object) -> None:
        self.partial = partial
        super().__init__(message)


class DescriptionError(PlmError):
    """A mechanism description (URDF, sidecar, preset name) is malformed or unsafe.

    Attributes:
        path: file or item the problem was found in, when known.
        problem: what is wrong, in words.
    """

    def __init__(self, problem: str, path: str | None = None) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"{path}: {problem}" if path else problem)


class FrameNotFound(DescriptionError):
    """A frame or joint named in a description does not exist in the model.

    Attributes:
        name: the missing name.
        kind: ``"frame"`` or ``"joint"``.
        choices: the names that do exist.
    """

    def __init__(
        self, name: str, choices: Sequence[str], kind: str = "frame", path: str | None = None
    ) -> None:
        self.name = name
        self.kind = kind
        self.choices = tuple(choices)
        shown = ", ".join(short(c) for c in self.choices[:40])
        more = f", ... ({len(self.choices)} in all)" if len(self.choices) > 40 else ""
        super().__init__(f"{kind} {short(name)} not found; {kind}s are [{shown}{more}]", path)


class ClosureNotSatisfied(PlmError):
    """The loops could not be closed from the given configuration.

    Attributes:
        residual_norm: closure residual norm reached [m, rad].
        tolerance: the tolerance that was asked for [m, rad].
        q: the best configuration found.
        worst_closure: name of the closure with the largest residual.
    """

    def __init__(
        self, message: str, residual_norm: float, tolerance: float, q: object, worst_closure: str
    ) -> None:
        self.residual_norm = residual_norm
        self.tolerance = tolerance
        self.q = q
        self.worst_closure = worst_closure
        super().__init__(message)


class InvalidInput(PlmError, ValueError):
    """An argument has the wrong shape, is not finite, or is not one of the valid choices."""


class PoseUnreachable(PlmError):
    """A task pose cannot be reached by the mechanism."""


class SingularConfiguration(PlmError):
    """A configuration is singular for the requested operation."""


class AllocationInfeasible(PartialResultError):
    """No actuator-force allocation meets the limits and conditions.

    Attributes:
        partial: the balancing actuator forces that violate the limits least (in the sum of
            squared violations) [N, N m], shape (n_act,).
        saturated: names of the actuators at or beyond a limit in that solution.
        violation: by how much each limit or condition is exceeded there, keyed by its name [N, N m].
    """

    partial: np.ndarray

    def __init__(
        self, message: str, partial: np.ndarray, saturated: Sequence[str], violation: dict[str, float]
    ) -> None:
        self.saturated = tuple(saturated)
        self.violation = dict(violation)
        super().__init__(message, partial)


class TrajectoryError(PartialResultError):
    """A trajectory stopped at a sample that cannot be solved (out of the workspace, or singular).

    Attributes:
        partial: the :class:`~plm_pin.dynamics.JointTrajectory` computed before that sample
            (``index`` samples).
        index: the sample that failed.
        time: its time [s].
        cause: the error met there (:class:`PoseUnreachable`, :class:`ClosureNotSatisfied`,
            :class:`SingularConfiguration` or :class:`InvalidInput`).
    """

    partial: Result

    def __init__(self, message: str, partial: Result, index: int, time: float, cause: PlmError) -> None:
        self.index = index
        self.time = time
        self.cause = cause
        super().__init__(message, partial)


class SimulationFailed(PartialResultError):
    """A simulation stopped early: the state or forces became non-finite, or the loops could not stay closed.

    Attributes:
        partial: the :class:`~plm_pin.dynamics.SimulationResult` of the samples computed before
            the failure.
        time: time of the step that failed [s].
        cause: the error met there (:class:`ClosureNotSatisfied`, :class:`SingularConfiguration`),
            or None when the state or the forces became non-finite.
    """

    partial: Result

    def __init__(self, message: str, partial: Result, time: float, cause: PlmError | None) -> None:
        self.time = time
        self.cause = cause
        super().__init__(message, partial)


class InverseDynamicsFailed(TrajectoryError):
    """Inverse dynamics stopped at a sample: infeasible allocation or an unresisted load.

    Attributes:
        partial: the :class:`~plm_pin.dynamics.InverseDynamics` of the samples computed before it.
        index: the sample that failed.
        time: its time [s].
        cause: the error met there (:class:`AllocationInfeasible` with the saturated actuators,
            or :class:`SingularConfiguration`).
    """


class ViewerError(PlmError):
    """The meshcat viewer cannot be used: meshcat is missing, or a server did not start or answer."""


class StoreMismatch(InvalidInput):
    """A sweep's checkpoint folder holds the results of another sweep (:mod:`plm_pin.sweep.store`).

    Attributes:
        path: the folder.
        differences: the top-level fields of the two sweeps' specs that differ.
    """

    def __init__(self, message: str, path: Path, differences: Sequence[str]) -> None:
        self.path = path
        self.differences = tuple(differences)
        super().__init__(message)


class StoreLocked(PlmError):
    """A sweep's checkpoint folder is in use by another running sweep (:mod:`plm_pin.sweep.store`).

    Attributes:
        path: the folder.
        holder: who holds it (process id, host and start time), as far as it is known.
    """

    def __init__(self, message: str, path: Path, holder: str) -> None:
        self.path = path
        self.holder = holder
        super().__init__(message)


class SchedulerUnreachable(PlmError):
    """A Dask scheduler could not be reached, or has no workers, within the time allowed.

    Attributes:
        address: the scheduler address given.
        timeout: how long it was waited for [s].
    """

    def __init__(self, message: str, address: str, timeout: float) -> None:
        self.address = address
        self.timeout = timeout
        super().__init__(message)


class JointLimitExceeded(PoseUnreachable):
    """The loops close at a pose, but only with joints outside their position limits.

    Attributes:
        violations: by how much each joint is outside its limits [m or rad], keyed by joint name.
        q: the configuration that closes the loops (limits ignored), shape (nq,).
    """

    def __init__(self, message: str, violations: dict[str, float], q: object) -> None:
        """Keep the violations and the configuration."""
        super().__init__(message)
        self.violations = violations
        self.q = q


class NoFeasibleDesign(PartialResultError):
    """No design of an optimisation met every constraint (:mod:`plm_pin.optimize`).

    Attributes:
        constraint: the level of the constraint hierarchy that no design met (the furthest
            any design got to).
        violation: the smallest relative violation of that level among the designs [-].
        partial: the :class:`~plm_pin.optimize.OptimizationResult`, every design evaluated.
    """

    def __init__(self, message: str, constraint: str, violation: float, partial: object) -> None:
        self.constraint = constraint
        self.violation = violation
        super().__init__(message, partial)
