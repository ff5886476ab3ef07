"""The closure sidecar ``<name>.plm.yaml``: its data model, parser and serialiser.

A URDF holds a spanning tree only; the sidecar says which joints were cut to open the
loops (the closures), which joints are driven (the actuation) and which frame and
directions form the task. Format ``plm-pin/1``::

    format: plm-pin/1
    gravity: [0.0, -9.8, 0.0]          # optional [m/s^2], default [0, 0, -9.81]
    closures:
      - name: rod2_plate
        frames: [rod2_tip, plate_left]
        type: point                    # point (3 rows) | weld (6) | revolute (5, axis given)
        axis: [0, 0, 1]                # revolute only: axis in the second frame's coordinates
    actuation:
      - joint: slider1
        limits: [-50.0, 50.0]          # force [N] or torque [N m]
        lead: 0.05                     # optional ball-screw lead [m/rev]
        rotor_inertia: 0.0248          # optional [kg m^2], reflected through the lead
        screw_inertia: 0.001           # optional [kg m^2], reflected through the lead
    end_effector:
      frame: plate_center
      task: [x, y, rz]                 # or, for a linkage without an end effector (a gripper
                                       # finger): joints: [finger] (the output joints' positions)
    reference:                         # optional guess of an assembled configuration
      slider1: -0.1                    # [m] or [rad]; multi-DOF joints take a list (Pinocchio order)
    closure_tolerance: 1.0e-6          # optional [m, rad]: how far the loops close (rounded CAD data)
    mobility: 2                        # optional: fixes the closure rank (see plm_pin.core.rank)
    compliance:                        # optional springs, see plm_pin.description.compliance
      actuators: {slider1: 2.0e7}      # [N/m] or [N m/rad] along the actuated joint
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from .._arguments import repeated
from .._lazy import lazy_module
from .._text import short
from .._yaml import YamlRefused, load_yaml
from ..exceptions import DescriptionError
from ..tolerances import AXIS_MIN
from ._numbers import number
from .compliance import ComplianceSpec, parse_compliance

yaml = lazy_module("yaml")  # safe_dump: imported when a sidecar is written

FORMAT = "plm-pin/1"
SIDECAR_SUFFIX_DEFAULT = ".plm.yaml"
CLOSURE_TYPES: tuple[str, ...] = ("point", "revolute", "weld")
TASK_DOFS: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")
CLOSURE_ROWS: dict[str, int] = {"point": 3, "revolute": 5, "weld": 6, "twist": 1}
"""Rows of each closure type; ``twist`` holds the idle spin of a multi-DOF joint (a gauge, never read
from a sidecar: see :mod:`plm_pin.core.idle`)."""

DEFAULT_GRAVITY: tuple[float, float, float] = (0.0, 0.0, -9.81)

ClosureType = Literal["point", "revolute", "weld", "twist"]


@dataclass(frozen=True)
class ClosureSpec:
    """One cut joint: two frames made to coincide.

    Attributes:
        name: closure name, unique in the description.
        frames: the two frame names (links, joints or URDF frames).
        type: ``point`` (positions coincide), ``revolute`` (positions coincide and
            the frames may only turn about ``axis``), ``weld`` (frames coincide) or ``twist``
            (an idle gauge: the frames may not turn about ``axis`` relative to each other).
        axis: unit axis of a revolute or twist closure, in the second frame's coordinates.
    """

    name: str
    frames: tuple[str, str]
    type: ClosureType
    axis: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        """Refuse a closure of the wrong types (descriptions built in Python, not through the parser).

        Raises:
            DescriptionError: a name or frames that are not strings, a type other than those of
                :data:`CLOSURE_TYPES` (e.g. a list), or an axis that is not 3 finite numbers.
        """
        where = f"closure {short(self.name)}"
        if not isinstance(self.name, str):
            raise DescriptionError(f"{where}: the name must be a string")
        frames = self.frames
        if not (
            isinstance(frames, (tuple, list)) and len(frames) == 2 and all(isinstance(f, str) for f in frames)
        ):
            raise DescriptionError(f"{where}: frames must be a pair of frame names, got {short(frames)}")
        if not isinstance(self.type, str) or self.type not in CLOSURE_ROWS:  # twist: the idle gauges'
            raise DescriptionError(
                f"{where}: invalid closure type {short(self.type)}; valid types are {list(CLOSURE_TYPES)}"
            )
        if self.axis is not None:
            try:
                if isinstance(self.axis, (str, bytes)):
                    raise TypeError
                axis = [float(a) for a in self.axis]
            except (TypeError, ValueError):
                axis = []
            if len(axis) != 3 or not all(math.isfinite(a) for a in axis):
                raise DescriptionError(f"{where}: axis must be 3 finite numbers, got {short(self.axis)}")

    @property
    def rows(self) -> int:
        """Number of scalar constraint equations of this closure."""
        return CLOSURE_ROWS[self.type]


@dataclass(frozen=True)
class ActuatorSpec:
    """One driven joint.

    Attributes:
        joint: name of a one-DOF (prismatic or revolute) joint.
        limits: lower and upper actuator effort [N] or [N m], or None when unbounded.
        lead: ball-screw lead [m/rev], or None for a direct drive.
        rotor_inertia: motor rotor (and coupler) inertia [kg m^2] reflected through the lead.
        screw_inertia: lead-screw inertia [kg m^2] reflected through the lead.
    """

    joint: str
    limits: tuple[float, float] | None = None
    lead: float | None = None
    rotor_inertia: float = 0.0
    screw_inertia: float = 0.0

    def __post_init__(self) -> None:
        """Refuse a drive no motor has (builders make these directly, not through the parser).

        Raises:
            DescriptionError: a lead that is not positive, a negative or non-finite inertia, or a
                reflected inertia too large for a float; the message names the joint.
        """
        where = f"actuator {short(self.joint)}"
        if self.lead is not None and not (math.isfinite(self.lead) and self.lead > 0.0):
            raise DescriptionError(f"{where}: lead must be positive and finite [m/rev], got {self.lead!r}")
        for key in ("rotor_inertia", "screw_inertia"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value >= 0.0):
                raise DescriptionError(f"{where}: {key} must be finite and >= 0 [kg m^2], got {value!r}")
        try:
            reflected = self.reflected_inertia()
        except OverflowError:
            reflected = math.inf
        if not math.isfinite(reflected):
            raise DescriptionError(
                f"{where}: the reflected inertia (rotor_inertia + screw_inertia) (2 pi / lead)^2 overflows a "
                f"float (rotor_inertia {self.rotor_inertia:g}, screw_inertia {self.screw_inertia:g} kg m^2, "
                f"lead {self.lead:g} m/rev)"
            )

    def reflected_inertia(self) -> float:
        r"""Armature this drive adds on its joint [kg] or [kg m^2].

        .. math:: m_r = (J_{rotor} + J_{screw}) (2\pi / \text{lead})^2
        """
        inertia = self.rotor_inertia + self.screw_inertia
        if self.lead is None:
            return inertia
        return inertia * (2.0 * math.pi / self.lead) ** 2


@dataclass(frozen=True)
class TaskSpec:
    """The task: an end-effector frame and its directions (world-aligned), or output joints.

    Attributes:
        frame: end-effector frame name, or None for a joint task.
        dofs: task directions among ``x y z rx ry rz``; for a joint task, the output joints
            (one-DOF revolute or prismatic) whose positions are the task coordinates.
    """

    frame: str | None
    dofs: tuple[str, ...]

    @property
    def joints(self) -> tuple[str, ...]:
        """The output joints of a joint task; () for a frame task."""
        return self.dofs if self.frame is None else ()

    def rows(self) -> tuple[int, ...]:
        """Rows of a 6-D spatial velocity (linear, angular) that a frame task keeps (() for a joint task)."""
        return tuple(TASK_DOFS.index(d) for d in self.dofs) if self.frame is not None else ()

    def to_dict(self) -> dict[str, Any]:
        """The sidecar's ``end_effector`` entry."""
        if self.frame is None:
            return {"joints": list(self.dofs)}
        return {"frame": self.frame, "task": list(self.dofs)}


@dataclass(frozen=True)
class Sidecar:
    """Everything a URDF spanning tree lacks to describe a closed chain.

    Attributes:
        closures: the cut joints.
        actuation: the driven joints.
        task: the end-effector task, or None.
        gravity: gravity vector in the world frame [m/s^2].
        reference: a guess of an assembled configuration, per joint name.
        name: optional mechanism name.
        source: optional provenance (paper, table).
        compliance: springs of the drives, joints and links, or None (a rigid description).
        collision_ignore: body pairs whose contact is not a self-collision (key
            ``self_collision: {ignore: [[a, b], ...]}``; see :mod:`plm_pin.kinematics.collisions`).
        closure_tolerance: how far the description's loops close [m, rad] (a CAD export
            rounded to a few significant digits closes only to 1e-8...1e-5), or None for an
            exact description (:data:`plm_pin.tolerances.CLOSURE_TOL`).
        mobility: the mobility, idle mobilities not counted, when the rank of the closure
            Jacobian should not be decided from its singular values; or None.
    """

    closures: tuple[ClosureSpec, ...] = ()
    actuation: tuple[ActuatorSpec, ...] = ()
    task: TaskSpec | None = None
    gravity: tuple[float, float, float] = DEFAULT_GRAVITY
    reference: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    name: str | None = None
    source: str | None = None
    compliance: ComplianceSpec | None = None
    collision_ignore: tuple[tuple[str, str], ...] = ()
    closure_tolerance: float | None = None
    mobility: int | None = None

    def to_dict(self) -> dict[str, Any]:
        """The sidecar as plain data, ready for YAML."""
        out: dict[str, Any] = {"format": FORMAT}
        if self.name:
            out["name"] = self.name
        if self.source:
            out["source"] = self.source
        out["gravity"] = [float(g) for g in self.gravity]
        closures = []
        for c in self.closures:
            item: dict[str, Any] = {"name": c.name, "frames": list(c.frames), "type": c.type}
            if c.axis is not None:
                item["axis"] = [float(a) for a in c.axis]
            closures.append(item)
        out["closures"] = closures
        actuation = []
        for a in self.actuation:
            act: dict[str, Any] = {"joint": a.joint}
            if a.limits is not None:
                act["limits"] = [float(v) for v in a.limits]
            if a.lead is not None:
                act["lead"] = float(a.lead)
            if a.rotor_inertia:
                act["rotor_inertia"] = float(a.rotor_inertia)
            if a.screw_inertia:
                act["screw_inertia"] = float(a.screw_inertia)
            actuation.append(act)
        out["actuation"] = actuation
        if self.task is not None:
            out["end_effector"] = self.task.to_dict()
        if self.reference:
            out["reference"] = {
                k: (float(v[0]) if len(v) == 1 else [float(x) for x in v]) for k, v in self.reference.items()
            }
        if self.compliance is not None:
            out["compliance"] = self.compliance.to_dict()
        if self.collision_ignore:
            out["self_collision"] = {"ignore": [list(p) for p in self.collision_ignore]}
        if self.closure_tolerance is not None:
            out["closure_tolerance"] = float(self.closure_tolerance)
        if self.mobility is not None:
            out["mobility"] = int(self.mobility)
        return out

    def to_yaml(self) -> str:
        """The sidecar as YAML text (format ``plm-pin/1``)."""
        return yaml.safe_dump(self.to_dict(), sort_keys=False, default_flow_style=None)


def _numbers(value: Any, n: int | None, where: str, path: str | None) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)):
        raise DescriptionError(f"{where} must be a list of numbers, got {short(value)}", path)
    if n is not None and len(value) != n:
        raise DescriptionError(f"{where} must have {n} numbers, got {len(value)}", path)
    return tuple(number(v, f"{where}[{i}]", path) for i, v in enumerate(value))


def _keys(item: Mapping[str, Any], allowed: Sequence[str], where: str, path: str | None) -> None:
    unknown = sorted(set(item) - set(allowed), key=str)
    if unknown:
        raise DescriptionError(
            f"{where}: unknown key(s) {short(unknown)}; valid keys are {sorted(allowed)}", path
        )


def _string(value: Any, where: str, path: str | None) -> str:
    if not isinstance(value, str) or not value:
        raise DescriptionError(f"{where} must be a non-empty string, got {short(value)}", path)
    return value


def _joint_task(ee: Mapping[str, Any], path: str | None) -> TaskSpec:
    """The joint task of ``end_effector: {joints: [...]}`` (no frame, no task directions)."""
    if "frame" in ee or "task" in ee:
        raise DescriptionError(
            "end_effector takes either joints (a joint task) or frame and task (a frame task), not both",
            path,
        )
    joints = ee.get("joints")
    if not isinstance(joints, list) or not joints or not all(isinstance(j, str) and j for j in joints):
        raise DescriptionError("end_effector.joints must be a non-empty list of joint names", path)
    if len(set(joints)) != len(joints):
        raise DescriptionError(f"end_effector.joints repeats a joint: {short(joints)}", path)
    return TaskSpec(None, tuple(joints))


def _closure(item: Any, i: int, path: str | None) -> ClosureSpec:
    where = f"closures[{i}]"
    if not isinstance(item, Mapping):
        raise DescriptionError(f"{where} must be a mapping, got {short(item)}", path)
    _keys(item, ("name", "frames", "type", "axis"), where, path)
    frames = item.get("frames")
    if not isinstance(frames, (list, tuple)) or len(frames) != 2:
        raise DescriptionError(f"{where}.frames must be a list of two frame names", path)
    f0 = _string(frames[0], f"{where}.frames[0]", path)
    f1 = _string(frames[1], f"{where}.frames[1]", path)
    name = _string(item.get("name", f"{f0}__{f1}"), f"{where}.name", path)
    label = f"{where} ({short(name, quote=False)})"
    if f0 == f1:
        raise DescriptionError(
            f"{label}: joins frame {short(f0)} to itself; a closure needs two frames",
            path,
        )
    ctype = item.get("type")
    if ctype not in CLOSURE_TYPES:
        raise DescriptionError(
            f"{label}: invalid closure type {short(ctype)}; valid types are {list(CLOSURE_TYPES)}",
            path,
        )
    axis = None
    if ctype == "revolute":
        if "axis" not in item:
            raise DescriptionError(f"{label}: a revolute closure needs an 'axis'", path)
        raw = _numbers(item["axis"], 3, f"{where}.axis", path)
        norm = math.sqrt(sum(a * a for a in raw))
        if norm < AXIS_MIN:
            raise DescriptionError(f"{where}.axis must be non-zero, got {list(raw)}", path)
        axis = (raw[0] / norm, raw[1] / norm, raw[2] / norm)
    elif "axis" in item:
        raise DescriptionError(f"{label}: 'axis' is only valid for revolute", path)
    return ClosureSpec(name=name, frames=(f0, f1), type=ctype, axis=axis)


def _actuator(item: Any, i: int, path: str | None) -> ActuatorSpec:
    where = f"actuation[{i}]"
    if not isinstance(item, Mapping):
        raise DescriptionError(f"{where} must be a mapping, got {short(item)}", path)
    _keys(item, ("joint", "limits", "lead", "rotor_inertia", "screw_inertia"), where, path)
    joint = _string(item.get("joint"), f"{where}.joint", path)
    limits = None
    if item.get("limits") is not None:
        lo, hi = _numbers(item["limits"], 2, f"{where}.limits", path)
        if not lo < hi:
            raise DescriptionError(f"{where}.limits must have lower < upper, got {[lo, hi]}", path)
        limits = (lo, hi)
    lead = None
    if item.get("lead") is not None:
        lead = number(item["lead"], f"{where}.lead", path)
        if lead <= 0.0:
            raise DescriptionError(f"{where}.lead must be positive [m/rev], got {lead}", path)
    inertias = []
    for key in ("rotor_inertia", "screw_inertia"):
        value = number(item.get(key, 0.0), f"{where}.{key}", path)
        if value < 0.0:
            raise DescriptionError(f"{where}.{key} must be >= 0 [kg m^2], got {value}", path)
        inertias.append(value)
    try:
        return ActuatorSpec(joint, limits, lead, inertias[0], inertias[1])
    except DescriptionError as exc:
        raise DescriptionError(f"{where} ({exc.problem})", path) from None


def parse_sidecar(data: Any, path: str | None = None) -> Sidecar:
    """Validate plain data (as loaded from YAML) and build a :class:`Sidecar`.

    Args:
        data: the loaded YAML document.
        path: file name used in error messages.

    Returns:
        The validated sidecar.

    Raises:
        DescriptionError: naming the bad key or value and the valid choices.
    """
    if not isinstance(data, Mapping):
        raise DescriptionError("the sidecar must be a YAML mapping", path)
    allowed = (
        "format",
        "name",
        "source",
        "gravity",
        "closures",
        "actuation",
        "end_effector",
        "reference",
        "compliance",
        "self_collision",
        "closure_tolerance",
        "mobility",
    )
    _keys(data, allowed, "sidecar", path)
    if data.get("format") != FORMAT:
        found = short(data.get("format"))
        raise DescriptionError(f"unknown sidecar format {found}; expected {FORMAT!r}", path)
    closures_raw = data.get("closures") or []
    actuation_raw = data.get("actuation") or []
    if not isinstance(closures_raw, list):
        raise DescriptionError("'closures' must be a list", path)
    if not isinstance(actuation_raw, list):
        raise DescriptionError("'actuation' must be a list", path)
    closures = tuple(_closure(c, i, path) for i, c in enumerate(closures_raw))
    dup = repeated(c.name for c in closures)
    if dup:
        raise DescriptionError(f"duplicate closure name(s) {short(dup)}", path)
    actuation = tuple(_actuator(a, i, path) for i, a in enumerate(actuation_raw))
    dup = repeated(a.joint for a in actuation)
    if dup:
        raise DescriptionError(f"joint(s) {short(dup)} actuated twice", path)
    task = None
    if data.get("end_effector") is not None:
        ee = data["end_effector"]
        if not isinstance(ee, Mapping):
            raise DescriptionError("'end_effector' must be a mapping", path)
        _keys(ee, ("frame", "task", "joints"), "end_effector", path)
        if "joints" in ee:
            task = _joint_task(ee, path)
    if data.get("end_effector") is not None and task is None:
        ee = data["end_effector"]
        frame = _string(ee.get("frame"), "end_effector.frame", path)
        dofs = ee.get("task")
        if not isinstance(dofs, list) or not dofs:
            raise DescriptionError(f"end_effector.task must be a non-empty list of {list(TASK_DOFS)}", path)
        for d in dofs:
            if d not in TASK_DOFS:
                raise DescriptionError(
                    f"end_effector.task: unknown direction {short(d)}; valid are {list(TASK_DOFS)}", path
                )
        if len(set(dofs)) != len(dofs):
            raise DescriptionError(f"end_effector.task repeats a direction: {short(dofs)}", path)
        task = TaskSpec(frame, tuple(sorted(dofs, key=TASK_DOFS.index)))
    gravity = DEFAULT_GRAVITY
    if data.get("gravity") is not None:
        g = _numbers(data["gravity"], 3, "gravity", path)
        gravity = (g[0], g[1], g[2])
    reference: dict[str, tuple[float, ...]] = {}
    raw_ref = data.get("reference") or {}
    if not isinstance(raw_ref, Mapping):
        raise DescriptionError("'reference' must be a mapping of joint name to value(s)", path)
    for joint, value in raw_ref.items():
        where = f"reference.{short(joint, quote=False)}"
        if isinstance(value, (list, tuple)):
            reference[str(joint)] = _numbers(value, None, where, path)
        else:
            reference[str(joint)] = (number(value, where, path),)
    name = None if data.get("name") is None else _string(data["name"], "name", path)
    source = None if data.get("source") is None else _string(data["source"], "source", path)
    collision_ignore = _collision_ignore(data.get("self_collision"), path)
    closure_tolerance = None
    if data.get("closure_tolerance") is not None:
        closure_tolerance = number(data["closure_tolerance"], "closure_tolerance", path)
        if closure_tolerance <= 0.0:
            raise DescriptionError(f"closure_tolerance must be > 0 [m, rad], got {closure_tolerance}", path)
    mobility = data.get("mobility")
    if mobility is not None and (isinstance(mobility, bool) or not isinstance(mobility, int) or mobility < 0):
        raise DescriptionError(f"mobility must be an integer >= 0, got {short(mobility)}", path)
    return Sidecar(
        closures=closures,
        actuation=actuation,
        task=task,
        gravity=gravity,
        reference=reference,
        name=name,
        source=source,
        compliance=parse_compliance(data.get("compliance"), path),
        collision_ignore=collision_ignore,
        closure_tolerance=closure_tolerance,
        mobility=mobility,
    )


def _collision_ignore(raw: Any, path: str | None) -> tuple[tuple[str, str], ...]:
    """The ``self_collision: {ignore: [[a, b], ...]}`` body pairs, checked."""
    if raw is None:
        return ()
    if not isinstance(raw, Mapping):
        raise DescriptionError("'self_collision' must be a mapping with key 'ignore'", path)
    _keys(raw, ("ignore",), "self_collision", path)
    pairs = raw.get("ignore") or []
    if not isinstance(pairs, list) or not all(
        isinstance(p, list) and len(p) == 2 and all(isinstance(n, str) for n in p) for p in pairs
    ):
        raise DescriptionError("self_collision.ignore must be a list of [body, body] name pairs", path)
    return tuple((p[0], p[1]) for p in pairs)


def read_yaml(text: str | bytes, path: str | None = None) -> Any:
    """Parse untrusted YAML text safely (see :func:`plm_pin._yaml.load_yaml`), wrapping YAML errors.

    Raises:
        DescriptionError: when the text is not valid YAML, is too large, or its aliases
            expand it beyond the node cap.
    """
    try:
        return load_yaml(text)
    except YamlRefused as exc:
        raise DescriptionError(str(exc), path) from None
