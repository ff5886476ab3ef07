"""The Mechanism: a Pinocchio model of a spanning tree plus its closures, actuation and task."""

from __future__ import annotations

import functools
import math
import threading
import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import as_vector, count, positive
from .._text import short
from ..description.sidecar import Sidecar, TaskSpec
from ..exceptions import ClosureNotSatisfied, InvalidInput
from ..tolerances import ASSEMBLED_TOL, CLOSURE_TOL
from ..warnings import AmbiguousRankWarning
from . import closures as _closures
from .assembly import Assembly, assemble
from .idle import IdleGauge, find_gauges
from .legs import Leg, find_legs
from .rank import RankGap, gap_of, rank_by_gap
from .scratch import Workspace
from .task import FrameTask, Task, compile_task_spec


def body_name(model: pin.Model, j: int) -> str:
    """Name of the body joint ``j`` carries (its first BODY frame), else the joint name."""
    return body_names(model)[j - 1]


def body_names(model: pin.Model) -> tuple[str, ...]:
    """:func:`body_name` of every tree joint, in joint order, from one scan of the frames."""
    first: dict[int, str] = {}
    for f in model.frames:
        if f.type == pin.FrameType.BODY:
            first.setdefault(f.parentJoint, str(f.name))
    return tuple(first.get(j, str(model.names[j])) for j in range(1, model.njoints))


def _joint_names(value: object, name: str) -> list[str]:
    """``value`` as a list if it is an iterable of joint names (strings).

    Raises:
        InvalidInput: naming ``name`` and the valid forms.
    """
    names = list(value) if isinstance(value, Iterable) and not isinstance(value, bytes) else None
    if names is None or not all(isinstance(n, str) for n in names):
        raise InvalidInput(
            f"{name} must be joint names or a mapping from joint name to value [m, rad], got {short(value)}"
        )
    return names


@dataclass(frozen=True)
class Actuator:
    """A driven joint, resolved against the model.

    Attributes:
        joint: joint name.
        joint_id: Pinocchio joint index.
        idx_q: index in the configuration vector.
        idx_v: index in the velocity vector.
        kind: ``"prismatic"`` (force [N]) or ``"revolute"`` (torque [N m]).
        limits: effort bounds [N] or [N m], or None.
        lead: ball-screw lead [m/rev], or None.
        reflected_inertia: armature added to the joint [kg] or [kg m^2].
    """

    joint: str
    joint_id: int
    idx_q: int
    idx_v: int
    kind: str
    limits: tuple[float, float] | None
    lead: float | None
    reflected_inertia: float


JOINT_TYPES: tuple[tuple[str, str], ...] = (
    ("JointModelFreeFlyer", "free"),
    ("JointModelSpherical", "spherical"),
    ("JointModelPlanar", "planar"),
    ("JointModelTranslation", "translation"),
    ("JointModelUniversal", "universal"),
    ("JointModelRevoluteUnbounded", "continuous"),
    ("JointModelRUB", "continuous"),
    ("JointModelR", "revolute"),
    ("JointModelP", "prismatic"),
)
"""Pinocchio joint class prefixes and the joint type :meth:`Mechanism.summary` reports, first match."""


def joint_type(model: pin.Model, joint_id: int) -> str:
    """The type of joint ``joint_id`` in words (``revolute``, ``free``, ...; see :data:`JOINT_TYPES`)."""
    short = model.joints[joint_id].shortname()
    return next((kind for prefix, kind in JOINT_TYPES if short.startswith(prefix)), short)


def _joint_kind(model: pin.Model, joint_id: int) -> str:
    short = model.joints[joint_id].shortname()
    if short.startswith("JointModelP"):
        return "prismatic"
    return "revolute"


class Mechanism:
    r"""A closed (or open) kinematic chain ready for analysis.

    Build one with :func:`plm_pin.load`. The configuration ``q`` (size :attr:`nq`) and
    velocity ``v`` (size :attr:`nv`) are those of the Pinocchio spanning tree; the closures
    constrain them to :math:`\phi(q) = 0`.

    A Mechanism is not changed by any analysis: its cached properties (``q_ref``,
    ``mobility``, ``legs``) depend on the mechanism alone, and what a computation writes
    lives in a :class:`~plm_pin.core.scratch.Workspace` (:meth:`workspace`) or in a
    per-thread scratch data, so one Mechanism may be shared by threads. It pickles (with
    ``pickle`` or ``cloudpickle``), to be sent to worker processes as it is.

    Attributes:
        name: mechanism name.
        model: the Pinocchio model of the spanning tree (gravity and armature set).
        sidecar: the description's closures, actuation and task.
        closures: the compiled closures, in sidecar order, then the gauges of idle mobilities.
        actuators: the driven joints, in sidecar order.
        source: provenance (paper, file).
        closure_tol: how far the description's loops close [m, rad]: the tolerance of the
            assembly, the kinematics and the simulation's projection, and the floor of the
            closure rank (see :mod:`plm_pin.tolerances`).
    """

    def __init__(
        self,
        model: pin.Model,
        sidecar: Sidecar,
        *,
        name: str,
        source: str = "",
        visual_factory: Callable[[], pin.GeometryModel] | None = None,
        idle_gauges: tuple[IdleGauge, ...] | None = None,
        collision_factory: Callable[[], pin.GeometryModel] | None = None,
        closure_tol: float | None = None,
        mobility: int | None = None,
    ) -> None:
        """Wrap a Pinocchio model and a validated sidecar (use :func:`plm_pin.load`).

        ``idle_gauges`` holds these gauges (their frames already in ``model``) instead of
        detecting the idle mobilities, for a model derived from a mechanism's own.
        ``collision_factory`` builds the description's collision shapes (see
        :attr:`collision_model`). ``closure_tol`` [m, rad] and ``mobility`` override the
        sidecar's ``closure_tolerance`` and ``mobility`` (default
        :data:`~plm_pin.tolerances.CLOSURE_TOL`, and the rank decided from the singular values).

        Raises:
            InvalidInput: a ``closure_tol`` not positive and finite, a ``mobility`` not an
                integer in [0, nv].
        """
        tol = closure_tol if closure_tol is not None else sidecar.closure_tolerance
        tol = CLOSURE_TOL if tol is None else tol
        if isinstance(tol, bool) or not isinstance(tol, int | float) or not (0.0 < tol < math.inf):
            raise InvalidInput(f"closure_tol must be a positive finite number [m, rad], got {tol!r}")
        self.closure_tol = float(tol)
        fixed = mobility if mobility is not None else sidecar.mobility
        if fixed is not None and (
            isinstance(fixed, bool) or not isinstance(fixed, int) or not 0 <= fixed <= model.nv
        ):
            raise InvalidInput(f"mobility must be an integer in [0, {model.nv}] (nv), got {fixed!r}")
        self.fixed_mobility: int | None = fixed
        self.name = name
        self.model = model
        self.sidecar = sidecar
        self.source = source
        self._local = threading.local()  # per-thread scratch data (not pickled)
        self._visual_factory = visual_factory
        self._collision_factory = collision_factory
        self._assembled_guess: np.ndarray | None = None
        if idle_gauges is not None:
            self.__dict__["idle_gauges"] = idle_gauges  # fills the cached property
        actuators = []
        for spec in sidecar.actuation:
            jid = model.getJointId(spec.joint)
            joint = model.joints[jid]
            actuators.append(
                Actuator(
                    joint=spec.joint,
                    joint_id=jid,
                    idx_q=joint.idx_q,
                    idx_v=joint.idx_v,
                    kind=_joint_kind(model, jid),
                    limits=spec.limits,
                    lead=spec.lead,
                    reflected_inertia=spec.reflected_inertia(),
                )
            )
        self.actuators = tuple(actuators)
        self.task_compiled: Task | None = compile_task_spec(model, sidecar.task) if sidecar.task else None
        self._task_frame = self.task_compiled.frame_id if isinstance(self.task_compiled, FrameTask) else None

    # ----------------------------------------------------------------- sizes
    @property
    def nq(self) -> int:
        """Size of the configuration vector."""
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        """Size of the velocity vector (tree DOF)."""
        return int(self.model.nv)

    @property
    def n_closure_rows(self) -> int:
        r"""Number of scalar closure equations (rows of :math:`J_\phi`, redundant ones included)."""
        return _closures.closure_rows(self.closures)

    @property
    def n_actuators(self) -> int:
        """Number of driven joints."""
        return len(self.actuators)

    @property
    def task(self) -> TaskSpec | None:
        """The end-effector task, or None."""
        return self.sidecar.task

    @property
    def data(self) -> pin.Data:
        """Scratch Pinocchio data of the calling thread, for callers that fill it before reading it.

        Each thread gets its own. It holds nothing between calls: the Mechanism's own methods
        use another scratch data, and a function must compute (``pin.forwardKinematics``,
        ``pin.computeJointJacobians``, ...) what it reads. Loops should rather own a
        :meth:`workspace` (or ``mech.model.createData()``).
        """
        return self._thread_data("user")

    def _thread_data(self, key: str) -> pin.Data:
        data = getattr(self._local, key, None)
        if data is None:
            self.idle_gauges  # noqa: B018 - the model is final (gauge frames added) before data is made
            data = self.model.createData()
            setattr(self._local, key, data)
        return data

    @property
    def _data(self) -> pin.Data:
        """The scratch data of the Mechanism's own methods in the calling thread."""
        return self._thread_data("own")

    def workspace(self) -> Workspace:
        """A new :class:`~plm_pin.core.scratch.Workspace`: Pinocchio data and Newton buffers.

        Create one per thread (or per loop) and pass it to the calls of a hot loop.
        """
        n_task = self.task_compiled.size if self.task_compiled is not None else 0
        return Workspace.create(self.model, self.n_closure_rows, n_task)

    def _thread_workspace(self) -> Workspace:
        """The workspace the public kinematics functions use in the calling thread (filled by each call)."""
        ws = getattr(self._local, "workspace", None)
        if ws is None:
            ws = self._local.workspace = self.workspace()
        return ws

    def __getstate__(self) -> dict[str, Any]:
        """Pickled state: everything but the per-thread scratch and the built visual geometry."""
        state = dict(self.__dict__)
        state.pop("_local", None)
        state.pop("visual_model", None)  # rebuilt on first use from the factory
        state.pop("collision_model", None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        """Restore a pickled Mechanism (with fresh per-thread scratch)."""
        self.__dict__.update(state)
        self._local = threading.local()

    @functools.cached_property
    def idle_gauges(self) -> tuple[IdleGauge, ...]:
        """Gauges of the idle mobilities: one joint held per idle motion (see :mod:`plm_pin.core.idle`).

        Found at first use near the reference guess; the model gains two frames per gauge.
        """
        cut = _closures.compile_closures(self.model, self.sidecar.closures)
        gauges, self._assembled_guess = find_gauges(
            self.model,
            cut,
            self.reference_guess(),
            self.actuated_v_indices,
            self._task_frame,
            tol=self.closure_tol,
        )
        if gauges:  # the model gained frames: scratch data made before them is dropped
            self._local = threading.local()
        return gauges

    @functools.cached_property
    def closures(self) -> tuple[_closures.Closure, ...]:
        """The compiled closures, in sidecar order, then one weld ``idle:<joint>`` per idle gauge."""
        specs = (*self.sidecar.closures, *(g.closure for g in self.idle_gauges))
        return _closures.compile_closures(self.model, specs)

    @property
    def idle_mobility(self) -> int:
        """Number of idle mobilities (motions that move nothing else), fixed by :attr:`idle_gauges`."""
        return len(self.idle_gauges)

    @property
    def task_frame_id(self) -> int | None:
        """Pinocchio index of the end-effector frame, or None (no task, or a joint task)."""
        return self._task_frame

    @property
    def actuated_v_indices(self) -> np.ndarray:
        """Velocity indices of the actuated joints, shape (n_act,)."""
        return np.array([a.idx_v for a in self.actuators], dtype=int)

    @functools.cached_property
    def passive_v_indices(self) -> np.ndarray:
        """Velocity indices of the joints not actuated, ascending, shape (nv - n_act,) (read-only)."""
        out = np.setdiff1d(np.arange(self.nv), self.actuated_v_indices)
        out.setflags(write=False)
        return out

    @property
    def actuated_q_indices(self) -> np.ndarray:
        """Configuration indices of the actuated joints, shape (n_act,)."""
        return np.array([a.idx_q for a in self.actuators], dtype=int)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the tree joints (universe excluded)."""
        return tuple(self.model.names)[1:]

    @property
    def frame_names(self) -> tuple[str, ...]:
        """Names of every frame of the model."""
        return tuple(f.name for f in self.model.frames)

    @property
    def body_names(self) -> tuple[str, ...]:
        """Name of the body each tree joint carries, in joint order (the names body groups take).

        A body is named by its joint's first body frame (the URDF link), else by the joint.
        """
        return body_names(self.model)

    # ------------------------------------------------------------ checking
    def check_q(self, q: ArrayLike, name: str = "q") -> np.ndarray:
        """Return ``q`` as a float array after checking its shape and finiteness.

        Raises:
            InvalidInput: on a wrong shape or a non-finite entry.
        """
        return as_vector(q, self.model.nq, name)  # the model's nq is an int: no int() to pay on a hot path

    # ---------------------------------------------------------- closures
    def closure_residual(self, q: ArrayLike) -> np.ndarray:
        r"""Closure residual :math:`\phi(q)` [m, rad] (see :mod:`plm_pin.core.closures`), shape (m,)."""
        return _closures.residual(self.model, self._data, self.closures, self.check_q(q))

    def closure_jacobian(self, q: ArrayLike) -> np.ndarray:
        r"""Closure Jacobian :math:`J_\phi(q)` on the tangent space, shape (m, nv)."""
        return _closures.jacobian(self.model, self._data, self.closures, self.check_q(q))

    def closure_rank(self, q: ArrayLike) -> int:
        r"""Rank of :math:`J_\phi(q)`, cut at the largest gap of its singular values (closure_rank_gap)."""
        return self.closure_rank_gap(q).rank

    def closure_rank_gap(self, q: ArrayLike) -> RankGap:
        r"""Rank of :math:`J_\phi(q)` and the gap it is cut at (see :func:`~plm_pin.core.rank.rank_by_gap`).

        The floor is the closure tolerance :attr:`closure_tol`. With a fixed mobility (the
        sidecar's ``mobility``), the rank is ``nv - mobility`` and the gap is only reported.
        """
        J = self.closure_jacobian(q)
        if self.fixed_mobility is not None:
            s = np.linalg.svd(J, compute_uv=False) if J.size else np.zeros(0)
            return gap_of(s, min(self.nv - self.fixed_mobility, s.size), fixed=True)
        return rank_by_gap(J, self.closure_tol)

    @property
    def assembled_tol(self) -> float:
        """Largest closure residual [m, rad] of a configuration the analyses accept as assembled.

        :data:`~plm_pin.tolerances.ASSEMBLED_TOL`, or the closure tolerance when that is larger.
        """
        return max(ASSEMBLED_TOL, self.closure_tol)

    def closure_errors(self, q: ArrayLike) -> dict[str, float]:
        """Largest absolute residual of each closure [m, rad]."""
        phi = self.closure_residual(q)
        return {c.name: float(np.max(np.abs(phi[c.rows]))) for c in self.closures}

    # ---------------------------------------------------------- assembly
    def neutral(self) -> np.ndarray:
        """Pinocchio's neutral configuration of the tree (loops generally open), shape (nq,)."""
        return np.asarray(pin.neutral(self.model), dtype=float)

    def free_columns(self, fixed: Iterable[str]) -> np.ndarray:
        """Velocity indices not held by the joints ``fixed`` (every DOF of each), ascending.

        Raises:
            InvalidInput: when a joint does not exist; the message lists the joints.
        """
        frozen: set[int] = set()
        for joint in fixed:
            if not self.model.existJointName(joint):
                raise InvalidInput(
                    f"cannot fix joint {joint!r}: no such joint; joints are {list(self.joint_names)}"
                )
            j = self.model.joints[self.model.getJointId(joint)]
            frozen.update(range(j.idx_v, j.idx_v + j.nv))
        return np.array([i for i in range(self.nv) if i not in frozen], dtype=int)

    def assemble(
        self,
        guess: ArrayLike | None = None,
        fixed: Mapping[str, float] | Iterable[str] | None = None,
        *,
        tol: float | None = None,
        max_iterations: int = 100,
    ) -> Assembly:
        r"""Project a configuration onto the closure manifold :math:`\phi(q) = 0`.

        Damped Gauss-Newton (Levenberg-Marquardt) on the closure residual with the exact
        closure Jacobian; the minimum-norm step keeps the result close to ``guess``.

        Args:
            guess: starting configuration (default: the reference configuration, or the sidecar's
                reference guess when ``tol`` is looser than :attr:`closure_tol` and :attr:`q_ref`
                is not assembled yet). # (nq,)
            fixed: joints that must not move: names (kept at their ``guess`` values) or a
                mapping from one-DOF joint name to the value to impose [m] or [rad].
            tol: largest absolute residual accepted [m, rad] (default: :attr:`closure_tol`).
            max_iterations: iteration cap.

        Returns:
            The assembled configuration with its residual and the tolerance used.

        Raises:
            ClosureNotSatisfied: when the loops cannot be closed to ``tol``; the error
                carries the best configuration and the worst closure.
            InvalidInput: on a malformed ``guess``, an unknown joint in ``fixed``, a ``tol`` that
                is not a positive number or a ``max_iterations`` that is not a whole number >= 1.
        """
        tol = self.closure_tol if tol is None else positive(tol, "tol", "m, rad")
        max_iterations = count(max_iterations, "max_iterations", minimum=1)
        if guess is not None:
            q0 = self.check_q(guess, "guess").copy()
        elif "q_ref" in self.__dict__ or tol <= self.closure_tol:
            q0 = self.q_ref.copy()
        else:  # a looser tolerance than the mechanism's: do not assemble q_ref to the tighter one first
            q0 = self.reference_guess()
        names: list[str] = []
        if fixed is not None:
            if isinstance(fixed, Mapping):
                for joint, value in fixed.items():
                    if not isinstance(joint, str):
                        raise InvalidInput(f"fixed must map joint names to values, got a key {short(joint)}")
                    names.append(joint)
                    self.set_joint(q0, joint, value)
            else:
                names = [fixed] if isinstance(fixed, str) else _joint_names(fixed, "fixed")
        free = self.free_columns(names)

        def failure(q: np.ndarray, phi: np.ndarray) -> ClosureNotSatisfied:
            errors = {c.name: float(np.max(np.abs(phi[c.rows]))) for c in self.closures}
            worst = max(errors, key=lambda k: errors[k])
            norm = float(np.max(np.abs(phi)))
            return ClosureNotSatisfied(
                f"{self.name}: cannot close the loops: residual {norm:.3g} (worst closure "
                f"{worst!r}: {errors[worst]:.3g}) above tolerance {tol:.3g}; the closure frames "
                "cannot be brought together from this guess (fixed joints: "
                f"{names or 'none'})",
                norm,
                tol,
                q,
                worst,
            )

        return assemble(
            self.model,
            self._data,
            self.closures,
            q0,
            free,
            tol=tol,
            max_iterations=max_iterations,
            on_failure=failure,
        )

    def set_joint(self, q: np.ndarray, joint: str, value: ArrayLike) -> None:
        """Write the value of one joint into ``q`` in place.

        Args:
            q: configuration to modify, shape (nq,).
            joint: joint name.
            value: its ``nq`` configuration entries, or for a one-DOF joint its position
                [m] or [rad] (an unbounded revolute's angle is stored as (cos, sin)).

        Raises:
            InvalidInput: unknown joint, or a value of the wrong size or not finite.
        """
        if not self.model.existJointName(joint):
            raise InvalidInput(f"no joint {joint!r}; joints are {list(self.joint_names)}")
        j = self.model.joints[self.model.getJointId(joint)]
        vals = np.atleast_1d(np.asarray(value, dtype=float))
        if j.nq == 2 and j.nv == 1 and vals.shape == (1,):  # unbounded revolute: angle -> (cos, sin)
            vals = np.array([np.cos(vals[0]), np.sin(vals[0])])
        if vals.shape != (j.nq,) or not np.all(np.isfinite(vals)):
            raise InvalidInput(f"value for joint {joint!r} must be {j.nq} finite number(s), got {value!r}")
        q[j.idx_q : j.idx_q + j.nq] = vals

    def reference_guess(self) -> np.ndarray:
        """The sidecar's reference values over the neutral configuration (loops may be open), shape (nq,)."""
        q = self.neutral()
        for joint, values in self.sidecar.reference.items():
            self.set_joint(q, joint, values)
        return q

    @functools.cached_property
    def q_ref(self) -> np.ndarray:
        """Reference assembled configuration, closed to :attr:`closure_tol`, shape (nq,).

        Assembled from the sidecar's reference values (or the neutral configuration), with
        the loops closed first and the idle gauges then held where that left them.
        """
        self.idle_gauges  # noqa: B018 - closes the loops from the reference guess
        guess = self._assembled_guess if self._assembled_guess is not None else self.reference_guess()
        q = self.assemble(guess).q.copy()
        q.setflags(write=False)
        return q

    # --------------------------------------------------- mobility, redundancy
    @functools.cached_property
    def mobility(self) -> int:
        """Degrees of freedom of the closed chain: ``nv - rank J_phi`` at a generic assembly.

        Idle mobilities are not counted: their gauge rows are part of ``J_phi``
        (see :attr:`idle_mobility`).

        The rank is the largest found at the reference configuration and at two
        assembled random perturbations of it (a special configuration can only lose rank,
        so the maximum is the generic rank), each cut at the largest gap of the singular
        values (:attr:`rank_gap`); or ``nv - mobility`` with the sidecar's ``mobility``.
        """
        return self.nv - self.rank_gap.rank

    @functools.cached_property
    def rank_gap(self) -> RankGap:
        """The gap the generic closure rank (:attr:`mobility`) was cut at.

        Of the configurations giving the largest rank, the one with the narrowest gap.
        Warns :class:`~plm_pin.warnings.AmbiguousRankWarning` when the gap is not clear-cut
        (a ratio below :data:`~plm_pin.tolerances.RANK_GAP_MIN`).
        """
        gaps = [self.closure_rank_gap(q) for q in self._generic_configurations()]
        top = max(g.rank for g in gaps)
        gap = min((g for g in gaps if g.rank == top), key=lambda g: g.ratio)
        if not gap.clear:
            warnings.warn(
                f"{self.name}: no clear-cut gap in the singular values of the closure Jacobian: rank "
                f"{gap.rank} cut between {gap.above:.3g} and {gap.below:.3g} (ratio {gap.ratio:.3g}), so "
                f"mobility {self.nv - gap.rank} is in doubt; state the closure tolerance "
                f"(closure_tolerance, now {self.closure_tol:.3g}) or the mobility (mobility:) in the sidecar",
                AmbiguousRankWarning,
                stacklevel=2,
            )
        return gap

    @property
    def redundancy(self) -> int:
        """Degree of actuation redundancy: ``n_actuators - mobility``."""
        return self.n_actuators - self.mobility

    def _generic_configurations(self) -> list[np.ndarray]:
        """The reference and two assembled perturbations of it (seeded), kept for the same tolerance."""
        key = (self.closure_tol, self.q_ref)
        kept = self.__dict__.get("_generic")
        if kept is not None and kept[0][0] == key[0] and kept[0][1] is key[1]:
            return list(kept[1])
        configs = self._assemble_generic()
        self.__dict__["_generic"] = (key, tuple(configs))
        return configs

    def _assemble_generic(self) -> list[np.ndarray]:
        configs = [self.q_ref]
        rng = np.random.default_rng(20111009)
        for _ in range(2):
            step = rng.normal(scale=0.02, size=self.nv)
            try:
                configs.append(self.assemble(pin.integrate(self.model, self.q_ref, step)).q)
            except ClosureNotSatisfied:
                continue
        return configs

    @functools.cached_property
    def legs(self) -> tuple[Leg, ...]:
        """Legs: diagonal blocks of the inverse-kinematics Jacobian (see :mod:`plm_pin.core.legs`)."""
        actuated = {a.idx_v: a.joint for a in self.actuators}
        q = self._generic_configurations()[-1]
        return find_legs(
            self.model, self._data, self.closures, require_task(self), actuated, q, self.closure_tol
        )

    # ---------------------------------------------------------- reading
    def actuator_positions(self, q: ArrayLike) -> np.ndarray:
        """Actuated joint positions [m] or [rad] (angles of unbounded revolutes too), shape (n_act,).

        ``q`` may also stack configurations, shape (..., nq), for positions of shape
        (..., n_act); NaN configurations (points of a map left unsolved) give NaN.
        """
        if np.ndim(q) > 1:
            arr = np.asarray(q, dtype=float)
            if arr.shape[-1] != self.nq:
                raise InvalidInput(f"q must stack configurations of size {self.nq}, got shape {arr.shape}")
        else:
            arr = self.check_q(q)
        out = arr[..., self._actuator_q[0]]
        for k, iq in self._actuator_q[1]:
            out[..., k] = np.arctan2(arr[..., iq + 1], arr[..., iq])
        return out

    @functools.cached_property
    def _actuator_q(self) -> tuple[list[int], list[tuple[int, int]]]:
        """Each actuator's index in ``q``; ``(k, index)`` of those stored as ``(cos, sin)`` (unbounded)."""
        unbounded = [
            (k, a.idx_q) for k, a in enumerate(self.actuators) if self.model.joints[a.joint_id].nq == 2
        ]
        return [a.idx_q for a in self.actuators], unbounded

    @functools.cached_property
    def visual_model(self) -> pin.GeometryModel:
        """Visual geometry (built on first use; missing meshes were dropped with a warning)."""
        if self._visual_factory is None:
            return pin.GeometryModel()
        return self._visual_factory()

    @functools.cached_property
    def collision_model(self) -> pin.GeometryModel:
        """Collision geometry: the description's collision shapes where it has any, else :attr:`visual_model`.

        A URDF's ``<collision>`` elements, an MJCF's geoms that take part in contacts
        (``contype`` or ``conaffinity`` not zero); a description without any gets its visual
        shapes, so that self-collision can still be checked.
        """
        shapes = self._collision_factory() if self._collision_factory is not None else None
        return shapes if shapes is not None and shapes.ngeoms else self.visual_model

    def summary(self) -> dict[str, Any]:
        """Sizes, closures, actuators, task, mobility, redundancy and reference residual."""
        return {
            "name": self.name,
            "source": self.source,
            "nq": self.nq,
            "nv": self.nv,
            "joints": [
                {"name": str(self.model.names[j]), "type": joint_type(self.model, j)}
                for j in range(1, self.model.njoints)
            ],
            "closures": [
                {"name": c.name, "type": c.spec.type, "frames": list(c.spec.frames), "rows": c.spec.rows}
                for c in self.closures
            ],
            "closure_rows": self.n_closure_rows,
            "actuators": [
                {"joint": a.joint, "kind": a.kind, "limits": list(a.limits) if a.limits else None}
                for a in self.actuators
            ],
            "task": {"frame": self.task.frame, "dofs": list(self.task.dofs)} if self.task else None,
            "mobility": self.mobility,
            "closure_tolerance": self.closure_tol,
            "rank_gap": self.rank_gap.to_dict(),
            "idle_mobility": self.idle_mobility,
            "idle_joints": [g.joint for g in self.idle_gauges],
            "redundancy": self.redundancy,
            "reference_residual": float(np.max(np.abs(self.closure_residual(self.q_ref))))
            if self.closures
            else 0.0,
            "gravity": list(self.sidecar.gravity),
        }

    def __repr__(self) -> str:
        return (
            f"Mechanism({self.name!r}, nv={self.nv}, closures={len(self.closures)}, "
            f"actuators={self.n_actuators})"
        )


def require_task(mech: Mechanism) -> Task:
    """The mechanism's compiled task, or a clear error when it has none."""
    if mech.task_compiled is None:
        raise InvalidInput(f"{mech.name} has no end-effector task; add 'end_effector' to its sidecar")
    return mech.task_compiled


def require_frame_task(mech: Mechanism, needed_by: str) -> FrameTask:
    """The mechanism's compiled frame task, or a clear error (no task, or a joint task).

    Args:
        mech: the mechanism.
        needed_by: what needs it, completing the message (``"the deflection needs"``).
    """
    task = require_task(mech)
    if not isinstance(task, FrameTask):
        raise InvalidInput(
            f"{mech.name} has a joint task (joints {list(task.dofs)}); {needed_by} an end-effector frame "
            "task (end_effector: {frame: ..., task: [...]})"
        )
    return task
