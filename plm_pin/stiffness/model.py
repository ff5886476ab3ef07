r"""The compliant model of a mechanism: its springs and, for flexible links, its virtual joints.

The virtual joint method (Pashkevich, Klimchik and Chablat) models a flexible link as a
rigid body followed by a six-DOF spring at its tip: here six one-DOF joints (translations
along, then rotations about, the beam frame's x, y, z) inserted between the link and what
its tip carries (child joints and frames whose origin is the tip's), with the 6x6
stiffness :math:`K_v = C^{-1}` of the beam's tip compliance
(:meth:`~plm_pin.description.compliance.BeamSpec.tip_compliance`). At zero deflection the
compliant model coincides with the rigid one. The virtual bodies are massless.

The compliant model holds the mechanism's idle gauges (:mod:`plm_pin.core.idle`):
its closures, and so the cut-joint forces of a static solution, are the mechanism's.

A drive with a stiffness :math:`k` is a spring along its joint; a drive without one is
rigid and its joint is locked. Passive joints may carry springs too.
"""

from __future__ import annotations

import dataclasses
import weakref
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .._text import short
from ..core.mechanism import Mechanism
from ..description.compliance import BeamSpec, ComplianceSpec
from ..exceptions import FrameNotFound, InvalidInput
from ..tolerances import BEAM_AXIS_MIN, BEAM_MIN_LENGTH, MASSLESS_INERTIA_RTOL, TIP_TOL

SOURCES: tuple[str, ...] = ("actuators", "joints", "links")
"""The kinds of springs, in the order results list them."""

_VIRTUAL_AXES = ("PX", "PY", "PZ", "RX", "RY", "RZ")


@dataclass(frozen=True)
class VirtualLink:
    """A flexible link of the compliant model.

    Attributes:
        beam: its description.
        length: beam length, from the link's joint to its tip frame [m].
        v_index: velocity indices of its six virtual joints in the compliant model, shape (6,).
        stiffness: tip stiffness in the beam frame [N/m, N/rad, N m/m, N m/rad], shape (6, 6).
    """

    beam: BeamSpec
    length: float
    v_index: np.ndarray
    stiffness: np.ndarray


@dataclass(frozen=True, eq=False)
class CompliantModel:
    """A mechanism with its springs.

    Attributes:
        rigid: the mechanism as described.
        mech: the compliant mechanism (``rigid`` itself when no link is flexible).
        spec: the compliance.
        q_index: where each rigid configuration entry sits in the compliant one, shape (nq,).
        v_index: where each rigid velocity entry sits in the compliant one, shape (nv,).
        springs: the spring stiffness of each source on the compliant velocities, shape (nv_c, nv_c).
        locked: compliant velocity indices of the rigid drives.
        links: the flexible links.
    """

    rigid: Mechanism
    mech: Mechanism
    spec: ComplianceSpec
    q_index: np.ndarray
    v_index: np.ndarray
    springs: Mapping[str, np.ndarray]
    locked: np.ndarray
    links: tuple[VirtualLink, ...]

    @property
    def stiffness_matrix(self) -> np.ndarray:
        """Sum of the springs' stiffness, shape (nv_c, nv_c)."""
        return sum((self.springs[s] for s in SOURCES), np.zeros((self.mech.nv, self.mech.nv)))

    def lift(self, q: np.ndarray) -> np.ndarray:
        """The compliant configuration of a rigid one (virtual joints undeflected), shape (nq_c,)."""
        qc = self.mech.neutral()
        qc[self.q_index] = q
        return qc

    def drop(self, qc: np.ndarray) -> np.ndarray:
        """The rigid joints' entries of a compliant configuration, shape (nq,)."""
        return np.asarray(qc, dtype=float)[self.q_index]


_CACHE: weakref.WeakKeyDictionary[Mechanism, dict[ComplianceSpec, CompliantModel]] = (
    weakref.WeakKeyDictionary()
)


def compliant_model(mech: Mechanism, compliance: ComplianceSpec | None = None) -> CompliantModel:
    """The compliant model of ``mech`` (built once per mechanism and compliance, then cached).

    Args:
        mech: the mechanism.
        compliance: the springs; default the sidecar's ``compliance`` section.

    Raises:
        InvalidInput: no compliance given or described, a stiffness on a joint that is not
            an actuated (``actuators``) or passive one-DOF (``joints``) joint, a beam whose
            tip is not on its link or has zero length.
        FrameNotFound: an unknown link or tip frame.
    """
    if compliance is not None and not isinstance(compliance, ComplianceSpec):
        raise InvalidInput(
            "compliance must be a ComplianceSpec (plm_pin.description.compliance) or None, got "
            f"{short(compliance)}"
        )
    spec = compliance if compliance is not None else mech.sidecar.compliance
    if spec is None:
        raise InvalidInput(
            f"{mech.name} has no compliance: add a 'compliance' section to its sidecar (drive stiffness "
            "under 'actuators' [N/m or N m/rad]) or pass compliance=ComplianceSpec(...)"
        )
    per_mech = _CACHE.setdefault(mech, {})
    if spec not in per_mech:
        per_mech[spec] = _build(mech, spec)
    return per_mech[spec]


def _one_dof(mech: Mechanism, name: str) -> int:
    jid = mech.model.getJointId(name)
    if mech.model.joints[jid].nv != 1:
        raise InvalidInput(
            f"{mech.name}: joint {name!r} has {mech.model.joints[jid].nv} DOF; springs go on one-DOF joints"
        )
    return int(mech.model.joints[jid].idx_v)


def _build(mech: Mechanism, spec: ComplianceSpec) -> CompliantModel:
    actuated = [a.joint for a in mech.actuators]
    for name in spec.actuators:
        if name not in actuated:
            raise InvalidInput(
                f"{mech.name}: compliance.actuators names {name!r}, not a drive; drives are {actuated}"
            )
    passive = [n for n in mech.joint_names if n not in actuated]
    for name in spec.joints:
        if name not in passive:
            raise InvalidInput(
                f"{mech.name}: compliance.joints names {name!r}, not a passive joint; passive: {passive}"
            )
        _one_dof(mech, name)
    gauges = mech.idle_gauges  # their frames are in the model before it is copied
    beams = [_place_beam(mech, b) for b in spec.links]
    if beams:
        model, q_index, v_index, first_v = _insert_virtual_joints(mech.model, beams)
        cmech = Mechanism(
            model,
            dataclasses.replace(mech.sidecar, mobility=None),  # the virtual joints add DOF: rank from the gap
            name=f"{mech.name}_compliant",
            source=mech.source,
            idle_gauges=gauges,
            closure_tol=mech.closure_tol,
        )
    else:
        cmech, q_index, v_index, first_v = mech, np.arange(mech.nq), np.arange(mech.nv), []
    nv = cmech.nv
    springs = {s: np.zeros((nv, nv)) for s in SOURCES}
    locked = []
    for a in mech.actuators:
        iv = int(v_index[a.idx_v])
        if a.joint in spec.actuators:
            springs["actuators"][iv, iv] = spec.actuators[a.joint]
        else:
            locked.append(iv)
    for name, k in spec.joints.items():
        iv = int(v_index[_one_dof(mech, name)])
        springs["joints"][iv, iv] = k
    links = []
    for (beam, length, _, _), v0 in zip(beams, first_v, strict=True):
        idx = np.arange(v0, v0 + 6)
        K = np.linalg.inv(beam.tip_compliance(length))
        K = 0.5 * (K + K.T)
        springs["links"][np.ix_(idx, idx)] = K
        links.append(VirtualLink(beam, length, idx, K))
    for arr in (q_index, v_index, *springs.values()):
        arr.setflags(write=False)
    return CompliantModel(
        mech, cmech, spec, q_index, v_index, springs, np.array(locked, dtype=int), tuple(links)
    )


def _place_beam(mech: Mechanism, beam: BeamSpec) -> tuple[BeamSpec, float, int, pin.SE3]:
    """The beam's length, its joint, and its tip frame (x along the beam) in that joint's frame."""
    model = mech.model
    for name in (beam.link, beam.tip):
        if not model.existFrame(name):
            raise FrameNotFound(name, mech.frame_names, "frame", "compliance.links")
    link = model.frames[model.getFrameId(beam.link)]
    tip = model.frames[model.getFrameId(beam.tip)]
    if tip.parentJoint == link.parentJoint:
        tip_position = tip.placement.translation
    elif tip.type == pin.FrameType.JOINT and model.parents[tip.parentJoint] == link.parentJoint:
        tip_position = model.jointPlacements[tip.parentJoint].translation  # a child joint's origin
    else:
        tip_position = None
    if tip_position is None or link.parentJoint == 0:
        raise InvalidInput(
            f"{mech.name}: beam {beam.link!r}: its tip {beam.tip!r} must be a frame on the same moving body "
            "or a joint it carries"
        )
    axis = tip_position - link.placement.translation
    length = float(np.linalg.norm(axis))
    if length < BEAM_MIN_LENGTH:
        raise InvalidInput(
            f"{mech.name}: beam {beam.link!r} has zero length (tip {beam.tip!r} at its origin)"
        )
    x = axis / length
    if beam.y_axis is not None:
        y = link.placement.rotation @ np.array(beam.y_axis)
        y = y - x * (x @ y)
        if np.linalg.norm(y) < BEAM_AXIS_MIN:
            raise InvalidInput(f"{mech.name}: beam {beam.link!r}: y_axis is along the beam")
    else:
        y = np.cross(np.eye(3)[int(np.argmin(np.abs(x)))], x)
    y /= np.linalg.norm(y)
    R = np.column_stack([x, y, np.cross(x, y)])
    return beam, length, int(link.parentJoint), pin.SE3(R, np.array(tip_position))


def _inertia(pi: np.ndarray) -> pin.Inertia:
    """An inertia from its dynamic parameters (zero when massless)."""
    if pi[0] <= MASSLESS_INERTIA_RTOL * max(1.0, float(np.max(np.abs(pi)))):
        return pin.Inertia.Zero()
    return pin.Inertia.FromDynamicParameters(pi)


def _insert_virtual_joints(
    model: pin.Model, beams: list[tuple[BeamSpec, float, int, pin.SE3]]
) -> tuple[pin.Model, np.ndarray, np.ndarray, list[int]]:
    """A copy of ``model`` with six virtual joints at each beam's tip; index maps of q and v."""
    at = {joint: (beam, tipM) for beam, _, joint, tipM in beams}
    new = pin.Model()
    new.name = model.name
    new.gravity = model.gravity
    jmap = {0: 0}
    tip_joint: dict[int, int] = {}

    def parent_of(old_parent: int, placement: pin.SE3) -> tuple[int, pin.SE3]:
        if old_parent in at:
            tipM = at[old_parent][1]
            if np.linalg.norm(placement.translation - tipM.translation) <= TIP_TOL:
                return tip_joint[old_parent], tipM.inverse() * placement
        return jmap[old_parent], placement

    # bodies welded at a tip (their inertia sits on a frame there) move with the virtual joints
    rigid = {j: model.inertias[j].toDynamicParameters() for j in range(1, model.njoints)}
    moved = {j: np.zeros(10) for j in at}
    for f in model.frames:
        j = f.parentJoint
        if (
            j in at
            and f.inertia.mass > 0.0
            and np.linalg.norm(f.placement.translation - at[j][1].translation) <= TIP_TOL
        ):
            rigid[j] = rigid[j] - f.placement.act(f.inertia).toDynamicParameters()
            moved[j] = moved[j] + (at[j][1].inverse() * f.placement).act(f.inertia).toDynamicParameters()
    for j in range(1, model.njoints):
        parent, placement = parent_of(model.parents[j], model.jointPlacements[j])
        jid = new.addJoint(parent, model.joints[j], placement, model.names[j])
        new.appendBodyToJoint(jid, _inertia(rigid[j]), pin.SE3.Identity())
        jmap[j] = jid
        if j in at:
            beam, tipM = at[j]
            last, place = jid, tipM
            for axis in _VIRTUAL_AXES:
                joint_model = getattr(pin, f"JointModel{axis}")()
                last = new.addJoint(last, joint_model, place, f"{beam.link}_virtual_{axis.lower()}")
                place = pin.SE3.Identity()
            new.appendBodyToJoint(last, _inertia(moved[j]), pin.SE3.Identity())
            tip_joint[j] = last
    fmap = {0: 0}
    for fi in range(1, len(model.frames)):
        f = model.frames[fi]
        parent, placement = parent_of(f.parentJoint, f.placement)
        frame = pin.Frame(f.name, parent, fmap.get(f.parentFrame, 0), placement, f.type, f.inertia)
        fmap[fi] = new.addFrame(frame, False)
    q_index = np.concatenate(
        [
            np.arange(new.joints[jmap[j]].idx_q, new.joints[jmap[j]].idx_q + model.joints[j].nq)
            for j in range(1, model.njoints)
        ]
    ).astype(int)
    v_index = np.concatenate(
        [
            np.arange(new.joints[jmap[j]].idx_v, new.joints[jmap[j]].idx_v + model.joints[j].nv)
            for j in range(1, model.njoints)
        ]
    ).astype(int)
    new.armature[v_index] = model.armature
    new.lowerPositionLimit[q_index] = model.lowerPositionLimit
    new.upperPositionLimit[q_index] = model.upperPositionLimit
    first_v = [int(new.joints[new.getJointId(f"{b.link}_virtual_px")].idx_v) for b, _, _, _ in beams]
    return new, q_index, v_index, first_v
