r"""Writing a mechanism as a MuJoCo model (MJCF) that simulates with its loops closed.

- **Tree**: one MuJoCo body per Pinocchio joint, at the joint's placement, holding the
  joint's inertia (``<inertial>`` with ``fullinertia``); a chain of massless joints (the
  gimbal of a universal joint) becomes one body with several joints, as MuJoCo requires
  moving bodies to have mass. Revolute (bounded or not) -> ``hinge``, prismatic ->
  ``slide``, spherical -> ``ball``, free flyer (on the world only) -> ``free``; the
  position limits of a revolute or prismatic joint, when it has finite ones, -> ``range``.
  The body is placed at the frame of the body the joint carries (a URDF link, an MJCF
  body), the joint at its anchor there, so that a re-import gives the same frames.
  MuJoCo refuses principal moments below 1e-15 kg m^2; a body with a smaller one (a
  slender strut's axial moment of 0) gets :data:`MIN_PRINCIPAL_MOMENT` about that axis.
- **Frames**: body and operational frames become ``site``\ s of their name; the frames of
  closures and task that are a body's own frame get an extra site ``<frame>_site``.
- **Closures**: ``point`` -> ``connect`` between two sites, ``weld`` -> ``weld`` between two
  sites, ``revolute`` -> two ``connect``\ s, at the closure point and
  :data:`REVOLUTE_PAIR_SPACING` along the axis (5 independent rows, as the closure; a
  re-import reads them as two point closures: 6 rows of rank 5). Every equality gets
  ``solref = (2 timestep, 1)``, the stiffest MuJoCo allows at that step, and
  ``solimp = (0.99, 0.999, 0.001)``.
- **Idle gauges** (:mod:`plm_pin.core.idle`) are a plm_pin analysis device, not part
  of the mechanism: neither their welds nor their frames are written. MuJoCo simulates the
  idle spins as the motions they are, and a re-import detects and holds them again.
- **Actuation**: a ``motor`` per driven joint (gear 1), ``ctrlrange`` and ``forcerange`` the
  effort limits; the joint ``armature`` is the model's, reflected rotor and screw inertia
  included; lead, rotor and screw inertia kept as ``<custom><numeric>`` data
  ``plm_pin:<actuator>:<field>`` for the motor torques of a re-import.
- **Geometry**: the visual shapes as geoms without contacts (``contype = conaffinity = 0``,
  group 1; meshes with ``inertia="shell"``, never used for inertia, so that MuJoCo does
  not refuse a thin mesh's volume); a mechanism's own collision shapes (a URDF's
  ``<collision>``) as geoms with contacts (group 3), so that a re-import checks
  self-collision with them.
- **Solver**: RK4 (or ``implicitfast``), the given timestep, Newton with tolerance 1e-10,
  contacts disabled, gravity from the mechanism, the reference configuration as keyframe
  ``reference``.
- **Measured**: the model is compiled and simulated by MuJoCo for :data:`MEASURE_DURATION`
  passive under gravity from the reference at rest; the largest closure error (position
  [m], rotation [rad]) is written in an XML comment and returned; when MuJoCo's run
  diverges (very light or very heavy bodies for the step), the comment and a warning say so.

The task, name and source go to a sidecar ``<stem>.plm.yaml`` beside the file (see
:mod:`plm_pin.description.mjcf`), so that :func:`plm_pin.load` reads the export back.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from lxml import etree

from ._arguments import flag, positive
from ._io import atomic_write_text
from .core.mechanism import Mechanism, body_name
from .description.mjcf import DRIVE_FIELDS, StateMap, require_mujoco, rotation_to_quat_wxyz
from .description.sidecar import Sidecar
from .exceptions import DescriptionError, InvalidInput
from .results import Result, unit
from .tolerances import MIN_PRINCIPAL_MOMENT
from .warnings import IgnoredElementWarning, SimulationUnstableWarning

__all__ = ["ClosureDrift", "mjcf_text"]

REVOLUTE_PAIR_SPACING = 0.05
"""Distance along the axis between the two ``connect``\\ s of an exported revolute closure [m]."""

MEASURE_DURATION = 1.0
"""Passive simulation whose closure error the export measures and writes down [s]."""

INTEGRATORS = ("RK4", "implicitfast")
"""MuJoCo integrators :func:`export_mjcf` offers."""

SOLIMP = (0.99, 0.999, 0.001)
"""Impedance of the exported equalities (MuJoCo ``solimp``): stiff from the first micrometre."""

_MESH_SUFFIXES = (".stl", ".obj")
_NO_LIMIT = np.finfo(float).max  # Pinocchio's position limit of a joint without one (or inf)


@dataclass(frozen=True)
class ClosureDrift(Result):
    """Largest closure drift MuJoCo reached in the measuring simulation (its equalities hold loops softly).

    Attributes:
        position: largest distance between connected or welded points [m].
        rotation: largest rotation between welded frames [rad] (0 without welds).
        duration: simulated time [s].
        timestep: MuJoCo step [s].
        diverged_at: time at which MuJoCo found the state non-finite or huge and reset it [s],
            or None; the errors above are those before it.
    """

    position: float = field(metadata=unit("m"))
    rotation: float = field(metadata=unit("rad"))
    duration: float = field(metadata=unit("s"))
    timestep: float = field(metadata=unit("s"))
    diverged_at: float | None = field(default=None, metadata=unit("s"))

    def describe(self) -> str:
        """One line for the XML comment."""
        if self.diverged_at is not None:
            return (
                f"MuJoCo's passive run from the reference DIVERGES at t = {self.diverged_at:.3g} s with "
                f"{self.timestep * 1e3:g} ms steps (closure error before: {self.position:.2g} m, "
                f"{self.rotation:.2g} rad); export with a smaller timestep or integrator implicitfast"
            )
        return (
            f"closure error measured by MuJoCo over {self.duration:g} s passive under gravity from the "
            f"reference at rest, {self.timestep * 1e3:g} ms steps: {self.position:.2g} m, "
            f"{self.rotation:.2g} rad"
        )


def _fmt(values: Iterable[float]) -> str:
    return " ".join(repr(float(v)) if v != 0.0 else "0" for v in values)


def _axis(joint: pin.JointModel, name: str) -> tuple[str, np.ndarray]:
    short = joint.shortname()
    for prefix, kind in (("JointModelRUB", "hinge"), ("JointModelR", "hinge"), ("JointModelP", "slide")):
        letter = short[len(prefix) :]
        if short.startswith(prefix) and letter in ("X", "Y", "Z"):
            return kind, np.eye(3)["XYZ".index(letter)]
    if short in ("JointModelRevoluteUnaligned", "JointModelRevoluteUnboundedUnaligned"):
        return "hinge", np.asarray(joint.extract().axis, dtype=float)
    if short == "JointModelPrismaticUnaligned":
        return "slide", np.asarray(joint.extract().axis, dtype=float)
    if short == "JointModelSpherical":
        return "ball", np.array([0.0, 0.0, 1.0])
    if short == "JointModelFreeFlyer":
        return "free", np.array([0.0, 0.0, 1.0])
    raise DescriptionError(
        f"joint {name!r} ({short}) has no MuJoCo counterpart; exportable joints are revolute, prismatic, "
        "spherical and free flyer"
    )


def _with_min_moment(I: np.ndarray) -> np.ndarray:
    """The rotational inertia with principal moments under :data:`MIN_PRINCIPAL_MOMENT` raised to it."""
    moments, axes = np.linalg.eigh(I)
    if moments.min() >= MIN_PRINCIPAL_MOMENT:
        return I
    return (axes * np.maximum(moments, MIN_PRINCIPAL_MOMENT)) @ axes.T


def _massless(inertia: pin.Inertia) -> bool:
    return bool(inertia.mass == 0.0 and not np.any(inertia.inertia))


def _groups(model: pin.Model) -> list[list[int]]:
    """Joints grouped into MuJoCo bodies: massless one-DOF joints merged into their only child."""
    children: dict[int, list[int]] = {j: [] for j in range(model.njoints)}
    for j in range(1, model.njoints):
        children[model.parents[j]].append(j)
    absorbed: set[int] = set()
    groups = []
    for j in range(1, model.njoints):
        if j in absorbed:
            continue
        group = [j]
        while (
            _massless(model.inertias[group[-1]])
            and len(children[group[-1]]) == 1
            and _axis(model.joints[group[-1]], model.names[group[-1]])[0] in ("hinge", "slide")
        ):
            group.append(children[group[-1]][0])
            absorbed.add(group[-1])
        groups.append(group)
    return groups


class _Writer:
    def __init__(self, mech: Mechanism, timestep: float, integrator: str) -> None:
        self.mech = mech
        self.model = mech.model
        self.timestep = timestep
        self.integrator = integrator
        self.body_of_joint: dict[int, etree._Element] = {}
        self.last_of_group: dict[int, int] = {}  # joint -> last joint of its body
        self.body_offset: dict[int, pin.SE3] = {0: pin.SE3.Identity()}  # joint -> its body's frame there
        self.body_frames: set[int] = set()  # frame ids that are MuJoCo bodies' own frames
        self.site_names: dict[int, str] = {}  # frame id -> site name
        self.names: set[str] = set()  # body and site names written (one namespace on re-import)
        self.geom_names: set[str] = set()
        gauges = {g.closure.name for g in mech.idle_gauges}
        self.closures_out = tuple(c for c in mech.closures if c.name not in gauges)
        self.gauge_frames = {fid for c in mech.closures if c.name in gauges for fid in c.frame_ids}

    def _unique(self, name: str) -> str:
        """``name``, or ``name_site``, ``name_site2``, ... when a body or site already has it."""
        out, k = name, 1
        while out in self.names:
            out = f"{name}_site" + (str(k) if k > 1 else "")
            k += 1
        self.names.add(out)
        return out

    def _body_frame(self, group: list[int]) -> tuple[str, pin.SE3]:
        """The name of the MuJoCo body of a joint group and its frame in the last joint's frame.

        The body is the first body frame of the last joint (a URDF link, an MJCF body), placed
        where that frame is, so that a re-import gives the frame back as the body's (a joint
        whose anchor is away from its body's origin gets ``pos``). A free joint's body must be
        its joint frame (MuJoCo's free joint moves the body frame): when its body frame sits
        elsewhere, the body takes the joint's name and the frame becomes a site.
        """
        j = group[-1]
        name = body_name(self.model, j)
        fid = next(
            (
                i
                for i, f in enumerate(self.model.frames)
                if f.type == pin.FrameType.BODY and f.parentJoint == j and f.name == name
            ),
            None,
        )
        free = _axis(self.model.joints[j], self.model.names[j])[0] == "free"
        if fid is None or name in self.names or (free and not self.model.frames[fid].placement.isIdentity()):
            return self._unique(str(self.model.names[j])), pin.SE3.Identity()
        self.names.add(name)
        self.body_frames.add(fid)
        return name, self.model.frames[fid].placement

    def in_body(self, joint: int, placement: pin.SE3) -> pin.SE3:
        """A placement in the frame of joint ``joint`` expressed in the frame of its MuJoCo body."""
        return self.body_offset[self.last_of_group.get(joint, joint)].actInv(placement)

    def tree(self, world: etree._Element) -> None:
        model = self.model
        for group in _groups(model):
            parent_joint = model.parents[group[0]]
            parent = world if parent_joint == 0 else self.body_of_joint[parent_joint]
            placements = [model.jointPlacements[j] for j in group]
            frame = pin.SE3.Identity()
            for placement in placements:
                frame = frame * placement
            name, offset_b = self._body_frame(group)
            pose = self.in_body(parent_joint, frame * offset_b)
            body = etree.SubElement(parent, "body", name=name)
            body.set("pos", _fmt(pose.translation))
            body.set("quat", _fmt(rotation_to_quat_wxyz(pose.rotation)))
            tail = pin.SE3.Identity()  # C_i = (P_{i+1} ... P_n)^-1, then in the body frame B^-1 C_i
            offsets = []
            for placement in reversed(placements):
                offsets.append(offset_b.actInv(tail.inverse()))
                tail = placement * tail
            offsets.reverse()
            for j, offset in zip(group, offsets, strict=True):
                kind, axis = _axis(model.joints[j], model.names[j])
                if kind == "free" and parent_joint != 0:
                    raise DescriptionError(f"free joint {model.names[j]!r} must hang on the world for MuJoCo")
                element = etree.SubElement(body, "joint", name=str(model.names[j]), type=kind)
                joint = model.joints[j]
                if kind in ("hinge", "slide"):
                    element.set("axis", _fmt(offset.rotation @ axis))
                    if np.any(offset.translation):
                        element.set("pos", _fmt(offset.translation))
                    if joint.nq == 1:
                        k = joint.idx_q
                        limits = (model.lowerPositionLimit[k], model.upperPositionLimit[k])
                        if np.all(np.abs(limits) < _NO_LIMIT) and limits[0] < limits[1]:
                            element.set("range", _fmt(limits))
                armature = model.armature[joint.idx_v : joint.idx_v + joint.nv]
                if np.any(armature != armature[0]):
                    raise DescriptionError(f"joint {model.names[j]!r}: MuJoCo takes one armature per joint")
                if armature[0]:
                    element.set("armature", repr(float(armature[0])))
                self.body_of_joint[j] = body
                self.last_of_group[j] = group[-1]
                self.body_offset[j] = offset_b
            inertia = offset_b.actInv(model.inertias[group[-1]])
            if inertia.mass <= 0.0:
                raise DescriptionError(
                    f"the body of joint {model.names[group[-1]]!r} has no mass: MuJoCo refuses massless "
                    "moving bodies"
                )
            I = _with_min_moment(inertia.inertia)
            etree.SubElement(
                body,
                "inertial",
                pos=_fmt(inertia.lever),
                mass=repr(float(inertia.mass)),
                fullinertia=_fmt([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]),
            )

    def _merged(self, frame_id: int) -> bool:
        """Whether a frame sits on a massless joint merged into the MuJoCo body of the next joint."""
        j = self.model.frames[frame_id].parentJoint
        return bool(j and self.last_of_group[j] != j)

    def _body(self, world: etree._Element, frame_id: int, what: str) -> etree._Element:
        if self._merged(frame_id):
            j = self.model.frames[frame_id].parentJoint
            raise DescriptionError(
                f"{what} {self.model.frames[frame_id].name!r} sits on the massless joint "
                f"{self.model.names[j]!r}, merged into one MuJoCo body with the next joint"
            )
        j = self.model.frames[frame_id].parentJoint
        return world if j == 0 else self.body_of_joint[j]

    def site(self, world: etree._Element, frame_id: int, what: str, suffix: str = "") -> str:
        """The site of a frame, written on first use."""
        if frame_id in self.site_names:
            return self.site_names[frame_id]
        frame = self.model.frames[frame_id]
        name = self._unique(f"{frame.name}{suffix}")
        placement = self.in_body(frame.parentJoint, frame.placement)
        etree.SubElement(
            self._body(world, frame_id, what),
            "site",
            name=name,
            pos=_fmt(placement.translation),
            quat=_fmt(rotation_to_quat_wxyz(placement.rotation)),
        )
        self.site_names[frame_id] = name
        return name

    def frames(self, world: etree._Element) -> None:
        """Sites: body and operational frames but the gauges', closure frames (own body frames too)."""
        model = self.model
        plain = (pin.FrameType.BODY, pin.FrameType.OP_FRAME)
        own = self.body_frames
        closing = {fid for c in self.closures_out for fid in c.frame_ids}
        task = self.mech.task_frame_id
        for i, f in enumerate(model.frames):
            if i in closing or i == task:
                if i not in own or i in closing:
                    self.site(world, i, "frame", "" if f.type in plain and i not in own and i else "_site")
            elif (
                f.type in plain and i and i not in own and i not in self.gauge_frames and not self._merged(i)
            ):
                self.site(world, i, "frame")

    def geoms(self, world: etree._Element, asset: etree._Element, collision: bool) -> None:
        """The visual geoms (no contacts, group 1), or the collision shapes (contacts, group 3).

        Collision shapes are written when the mechanism has its own (a URDF's ``<collision>``);
        the file's contacts stay disabled, the shapes are there for a re-import's self-collision.
        """
        import coal

        mech = self.mech
        if collision and mech.collision_model is mech.visual_model:
            return
        what = "collision shape" if collision else "visual"
        for obj in (mech.collision_model if collision else mech.visual_model).geometryObjects:
            j = obj.parentJoint
            body = world if j == 0 else self.body_of_joint[j]
            if j and self.last_of_group[j] != j:
                warnings.warn(
                    f"{what} {obj.name!r} sits on the massless joint {self.model.names[j]!r}, merged into "
                    "one MuJoCo body with the next joint: left out",
                    IgnoredElementWarning,
                    stacklevel=4,
                )
                continue
            shape = obj.geometry
            attrs: dict[str, str]
            if isinstance(shape, coal.Box):
                attrs = {"type": "box", "size": _fmt(shape.halfSide)}
            elif isinstance(shape, coal.Sphere):
                attrs = {"type": "sphere", "size": _fmt([shape.radius])}
            elif isinstance(shape, coal.Cylinder):
                attrs = {"type": "cylinder", "size": _fmt([shape.radius, shape.halfLength])}
            elif isinstance(shape, coal.Capsule):
                attrs = {"type": "capsule", "size": _fmt([shape.radius, shape.halfLength])}
            elif obj.meshPath and Path(obj.meshPath).suffix.lower() in _MESH_SUFFIXES:
                mesh = f"mesh{len(asset)}"
                etree.SubElement(
                    asset,
                    "mesh",
                    name=mesh,
                    file=str(obj.meshPath),
                    scale=_fmt(obj.meshScale),
                    inertia="shell",
                )
                attrs = {"type": "mesh", "mesh": mesh}
            elif isinstance(shape, coal.BVHModelBase) and shape.num_tris:  # a mesh read from an MJCF
                mesh = f"mesh{len(asset)}"
                faces = [shape.tri_indices(k) for k in range(shape.num_tris)]
                etree.SubElement(
                    asset,
                    "mesh",
                    name=mesh,
                    vertex=_fmt(np.asarray(shape.vertices()).ravel()),
                    face=" ".join(str(t[i]) for t in faces for i in range(3)),
                    inertia="shell",
                )
                attrs = {"type": "mesh", "mesh": mesh}
            else:
                warnings.warn(
                    f"{what} {obj.name!r} ({type(shape).__name__}) has no MuJoCo geom: left out",
                    IgnoredElementWarning,
                    stacklevel=4,
                )
                continue
            placement = self.in_body(j, obj.placement)
            name, k = str(obj.name), 1
            while name in self.geom_names:  # Pinocchio names visuals and collisions alike
                name, k = f"{obj.name}_{'collision' if collision else 'visual'}{k}", k + 1
            self.geom_names.add(name)
            etree.SubElement(
                body,
                "geom",
                name=name,
                pos=_fmt(placement.translation),
                quat=_fmt(rotation_to_quat_wxyz(placement.rotation)),
                rgba=_fmt(obj.meshColor),
                contype="1" if collision else "0",
                conaffinity="1" if collision else "0",
                group="3" if collision else "1",
                **attrs,
            )

    def closures(self, world: etree._Element, equality: etree._Element) -> None:
        solref = _fmt([2.0 * self.timestep, 1.0])
        common = {"solref": solref, "solimp": _fmt(SOLIMP)}
        for c in self.closures_out:
            a, b = (self.site(world, fid, "closure frame") for fid in c.frame_ids)
            kind = c.spec.type
            if kind == "weld":
                etree.SubElement(equality, "weld", name=c.name, site1=a, site2=b, **common)
                continue
            etree.SubElement(equality, "connect", name=c.name, site1=a, site2=b, **common)
            if kind == "revolute":
                assert c.axis is not None
                ends = []
                for fid, side in zip(c.frame_ids, "ab", strict=True):
                    frame = self.model.frames[fid]
                    name = self._unique(f"{c.name}_axis_{side}")
                    placement = self.in_body(frame.parentJoint, frame.placement)
                    pos = placement.translation + placement.rotation @ (REVOLUTE_PAIR_SPACING * c.axis)
                    etree.SubElement(
                        self._body(world, fid, "closure frame"), "site", name=name, pos=_fmt(pos)
                    )
                    ends.append(name)
                etree.SubElement(
                    equality, "connect", name=f"{c.name}_axis", site1=ends[0], site2=ends[1], **common
                )

    def actuators(self, actuator: etree._Element, custom: etree._Element) -> None:
        for spec in self.mech.sidecar.actuation:
            attrs = {"name": spec.joint, "joint": spec.joint, "gear": "1"}
            if spec.limits is not None:
                attrs["ctrlrange"] = attrs["forcerange"] = _fmt(spec.limits)
            etree.SubElement(actuator, "motor", **attrs)
            for drive_field in DRIVE_FIELDS:
                value = getattr(spec, drive_field)
                if value:
                    etree.SubElement(
                        custom, "numeric", name=f"plm_pin:{spec.joint}:{drive_field}", data=repr(float(value))
                    )

    def document(self) -> etree._Element:
        mech = self.mech
        root = etree.Element("mujoco", model=mech.name)
        etree.SubElement(root, "compiler", angle="radian", inertiafromgeom="false", autolimits="true")
        option = etree.SubElement(
            root,
            "option",
            timestep=repr(self.timestep),
            integrator=self.integrator,
            gravity=_fmt(self.model.gravity.linear),
            solver="Newton",
            tolerance="1e-10",
            iterations="100",
        )
        etree.SubElement(option, "flag", contact="disable", energy="enable")
        asset = etree.SubElement(root, "asset")
        world = etree.SubElement(root, "worldbody")
        self.tree(world)
        self.frames(world)
        self.geoms(world, asset, collision=False)
        self.geoms(world, asset, collision=True)
        equality = etree.SubElement(root, "equality")
        self.closures(world, equality)
        actuator = etree.SubElement(root, "actuator")
        custom = etree.SubElement(root, "custom")
        self.actuators(actuator, custom)
        for element in (asset, equality, actuator, custom):
            if not len(element):
                root.remove(element)
        return root


def _measure(mj_model: Any, sites: list[tuple[str, str, str]], duration: float) -> ClosureDrift:
    """Largest closure error of a passive run from the keyframe, MuJoCo's own warnings kept quiet.

    MuJoCo reports a diverging state through its warning handler (and a ``MUJOCO_LOG.TXT`` in
    the working folder): the handler is replaced for the run, and the divergence returned.
    """
    mujoco = require_mujoco()
    data = mujoco.MjData(mj_model)
    mujoco.mj_resetDataKeyframe(mj_model, data, 0)
    ids = [(kind, mj_model.site(a).id, mj_model.site(b).id) for kind, a, b in sites]
    position = rotation = 0.0
    h = float(mj_model.opt.timestep)
    unstable = [int(getattr(mujoco.mjtWarning, f"mjWARN_BAD{x}")) for x in ("QPOS", "QVEL", "QACC")]
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda message: None)
    try:
        for k in range(max(1, round(duration / h))):
            mujoco.mj_step(mj_model, data)
            if any(data.warning[w].number for w in unstable):  # MuJoCo reset the state at k h
                return ClosureDrift(position, rotation, duration, h, k * h)
            mujoco.mj_kinematics(mj_model, data)  # mj_step leaves the poses of the step's start
            for kind, a, b in ids:
                position = max(position, float(np.linalg.norm(data.site_xpos[a] - data.site_xpos[b])))
                if kind == "weld":
                    relative = data.site_xmat[a].reshape(3, 3).T @ data.site_xmat[b].reshape(3, 3)
                    rotation = max(rotation, float(np.linalg.norm(pin.log3(relative))))
    finally:
        mujoco.set_mju_user_warning(previous)
    return ClosureDrift(position, rotation, duration, h)


def mjcf_text(
    mech: Mechanism,
    *,
    timestep: float = 1e-3,
    integrator: str = "RK4",
    measure_duration: float = MEASURE_DURATION,
) -> tuple[str, ClosureDrift]:
    """The MJCF of a mechanism, with its closure error measured by MuJoCo (see the module docstring).

    Args:
        mech: the mechanism.
        timestep: MuJoCo step [s]; the equalities' time constant is twice it.
        integrator: one of :data:`INTEGRATORS`.
        measure_duration: passive simulation measured for the comment [s].

    Returns:
        The XML text and the measured closure error.

    Raises:
        InvalidInput: a bad timestep or integrator.
        DescriptionError: a joint, frame or body MuJoCo cannot hold, or MuJoCo missing.
    """
    if not isinstance(integrator, str) or integrator not in INTEGRATORS:
        raise InvalidInput(f"unknown integrator {integrator!r}; valid are {list(INTEGRATORS)}")
    timestep = positive(timestep, "timestep", "s")
    measure_duration = positive(measure_duration, "measure_duration", "s")
    mujoco = require_mujoco()
    writer = _Writer(mech, timestep, integrator)
    root = writer.document()
    text = etree.tostring(root, encoding="unicode")
    try:
        compiled = mujoco.MjModel.from_xml_string(text)
    except ValueError as exc:
        raise DescriptionError(
            f"MuJoCo rejects the exported model: {str(exc).strip().splitlines()[0]}"
        ) from None
    qpos = StateMap(mech.model, compiled).qpos(np.asarray(mech.q_ref))
    etree.SubElement(etree.SubElement(root, "keyframe"), "key", name="reference", qpos=_fmt(qpos))
    text = etree.tostring(root, encoding="unicode")
    compiled = mujoco.MjModel.from_xml_string(text)
    sites = [(e.tag, e.get("site1"), e.get("site2")) for e in root.iterfind("equality/*")]
    error = _measure(compiled, sites, measure_duration)
    root.insert(0, etree.Comment(f" written by plm_pin from {mech.name}; {error.describe()} "))
    etree.indent(root, space="  ")
    return etree.tostring(root, encoding="unicode") + "\n", error


def export_mjcf(
    mech: Mechanism,
    path: str | Path,
    *,
    timestep: float = 1e-3,
    integrator: str = "RK4",
    sidecar: bool = True,
) -> ClosureDrift:
    """Write a mechanism as a MuJoCo model, and its task in a sidecar beside it.

    Args:
        mech: the mechanism.
        path: the ``.xml`` file to write (atomically).
        timestep: MuJoCo step [s].
        integrator: ``"RK4"`` or ``"implicitfast"``.
        sidecar: also write ``<stem>.plm.yaml`` (name, source, task) so that
            :func:`plm_pin.load` reads the export back as the same mechanism.

    Returns:
        The closure error MuJoCo reached in the measuring simulation (also in an XML comment);
        a :class:`~plm_pin.warnings.SimulationUnstableWarning` says when that run diverged.

    Raises:
        InvalidInput: a path not ending in ``.xml``, a bad timestep or integrator.
        DescriptionError: what MuJoCo cannot hold (named), or MuJoCo missing.
    """
    flag(sidecar, "sidecar")
    out = Path(path)
    if out.suffix != ".xml":
        raise InvalidInput(f"MJCF file name must end in .xml, got {out.name!r}")
    text, error = mjcf_text(mech, timestep=timestep, integrator=integrator)
    if error.diverged_at is not None:
        warnings.warn(f"{out}: {error.describe()}", SimulationUnstableWarning, stacklevel=2)
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out, text)
    if sidecar:
        side = Sidecar(task=mech.task, name=mech.name, source=mech.source or None).to_dict()
        for key in ("gravity", "closures", "actuation"):
            side.pop(key, None)
        import yaml

        atomic_write_text(out.with_name(out.stem + ".plm.yaml"), yaml.safe_dump(side, sort_keys=False))
    return error
