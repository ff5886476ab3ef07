r"""Reading a MuJoCo model (MJCF) as a closed chain: tree, closures, actuation, inertias, visuals.

The MJCF is compiled by MuJoCo itself (``mujoco.MjModel.from_xml_path``, the ``mjcf`` extra),
so defaults, ``<include>``, angle units, ``euler``/``axisangle`` orientations, inertias
computed from geoms and the anchors of ``connect`` / ``weld`` equalities are exactly what
MuJoCo simulates; the Pinocchio model is then built from the compiled model. (Pinocchio
4.1's MJCF parser keeps only the first body of ``<worldbody>``: the benchmark four-bar comes
out with 2 of its 3 hinges, with or without its constraints.)

Mapping:

- body -> Pinocchio body frame (``BODY``) of the joint that moves it; its inertia is appended
  to that joint; a body without joints is welded to its parent (as URDF ``fixed`` links are).
- hinge -> revolute, slide -> prismatic, ball -> spherical, free -> free flyer. A body's
  joints act in order about their anchors, as in MuJoCo (a chain of Pinocchio joints with
  massless intermediate bodies). Pinocchio's hinge / slide coordinate is MuJoCo's
  ``qpos - qpos0`` (the joint ``ref``); quaternions are stored (x, y, z, w) by Pinocchio and
  (w, x, y, z) by MuJoCo; a free joint's linear velocity is local in Pinocchio and world in
  MuJoCo. :class:`StateMap` converts both ways.
- site -> Pinocchio frame (``OP_FRAME``), named after the site.
- ``connect`` -> ``point`` closure, ``weld`` -> ``weld`` closure (a weld with
  ``torquescale = 0`` constrains no rotation: ``point``); between sites (site semantics) or
  between frames added at the body anchors (body semantics, ``<name>/1`` and ``<name>/2``).
  An unnamed equality is named ``equality<i>``, or ``closing_<name>`` when it joins the sites
  ``closing_<name>_1`` and ``closing_<name>_2`` of onshape-to-robot (see
  :mod:`plm_pin.description.onshape`).
- an unnamed joint is named after its body: ``<body>_free``, or ``<body>_<kind><i>`` for
  the ``i``-th joint (from 0) of its body, of type ``kind`` (``hinge``, ``slide``, ``ball``);
  see :func:`joint_names`.
- geoms: those that take part in contacts (``contype`` or ``conaffinity`` not zero) are the
  collision geometry, the others the visual geometry (every geom when none is visual-only).
- actuator on a hinge or slide -> actuation of that joint, limits ``gear * forcerange`` when
  force-limited, else ``gear * gain * ctrlrange`` for a motor; joint ``armature`` -> armature;
  the ball-screw lead and inertias of :data:`DRIVE_FIELDS` from ``<custom><numeric
  name="plm_pin:<actuator>:<field>">`` (as the export writes them).
- gravity from ``<option gravity>`` (zero when gravity is disabled); the reference
  configuration from the first ``<keyframe>``, else ``qpos0``.

The sidecar ``<name>.plm.yaml`` beside ``<name>.xml`` may add ``end_effector`` (a body or
site), ``reference``, ``name`` and ``source``; closures and actuation come from the MJCF.

Refused with one :class:`~plm_pin.exceptions.DescriptionError` listing every such element
with counts: tendons, flexes, ``joint`` / ``tendon`` / ``flex`` equalities (polynomial
couplings), inactive equalities, explicit contact pairs, mocap bodies, actuators not on one
hinge or slide; and two actuators on one joint. The kinds of :data:`IGNORABLE` (contact
pairs, tendons, joint couplings, inactive equalities, other actuators) can be dropped instead
with ``read_mjcf(path, ignore=...)`` (``plm_pin.load(..., ignore=...)``, ``--ignore``), with
an :class:`~plm_pin.warnings.IgnoredElementWarning` listing what was dropped: contacts and
coupling tendons do not change a linkage's kinematics. Joint damping, stiffness and
friction loss are ignored with an :class:`~plm_pin.warnings.IgnoredElementWarning`.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..exceptions import DescriptionError, FrameNotFound, InvalidInput
from ..warnings import IgnoredElementWarning
from .onshape import closing_name
from .sidecar import ActuatorSpec, ClosureSpec, Sidecar, parse_sidecar, read_yaml

MJCF_SUFFIX = ".xml"
MJCF_SIDECAR_KEYS: tuple[str, ...] = ("format", "name", "source", "end_effector", "reference")
"""Keys a sidecar beside an MJCF may hold (closures and actuation come from the MJCF)."""

_HINGE, _SLIDE, _BALL, _FREE = 3, 2, 1, 0  # mjtJoint
_OBJ_SITE = 6  # mjtObj.mjOBJ_SITE
_EQ_CONNECT, _EQ_WELD, _EQ_JOINT, _EQ_TENDON = 0, 1, 2, 3  # mjtEq
_EQ_NAMES = {2: "joint", 3: "tendon", 4: "flex", 5: "flexvert", 6: "flexstrain", 7: "distance"}
_TRN_JOINT, _TRN_TENDON = 0, 3  # mjtTrn
_GEOM_PLANE, _GEOM_HFIELD, _GEOM_SPHERE, _GEOM_CAPSULE = 0, 1, 2, 3
_GEOM_ELLIPSOID, _GEOM_CYLINDER, _GEOM_BOX, _GEOM_MESH = 4, 5, 6, 7


def require_mujoco() -> Any:
    """Import MuJoCo, or fail with the install hint.

    Raises:
        DescriptionError: when MuJoCo is not installed.
    """
    try:
        import mujoco
    except ImportError:
        raise DescriptionError("reading or writing MJCF needs MuJoCo: pip install 'plm-pin[mjcf]'") from None
    return mujoco


def quat_wxyz_to_rotation(quat: np.ndarray) -> np.ndarray:
    """Rotation matrix of a MuJoCo quaternion (w, x, y, z)."""
    w, x, y, z = (float(c) for c in quat)
    return np.asarray(pin.Quaternion(w, x, y, z).normalized().toRotationMatrix())


def rotation_to_quat_wxyz(rotation: np.ndarray) -> np.ndarray:
    """MuJoCo quaternion (w, x, y, z) of a rotation matrix, with w >= 0."""
    xyzw = np.asarray(pin.Quaternion(np.asarray(rotation)).coeffs(), dtype=float)
    wxyz = np.array([xyzw[3], xyzw[0], xyzw[1], xyzw[2]])
    return wxyz if wxyz[0] >= 0.0 else -wxyz


def _se3(pos: np.ndarray, quat: np.ndarray) -> pin.SE3:
    return pin.SE3(quat_wxyz_to_rotation(quat), np.asarray(pos, dtype=float).copy())


def _name(mujoco: Any, m: Any, kind: str, i: int) -> str:
    return str(mujoco.mj_id2name(m, getattr(mujoco.mjtObj, f"mjOBJ_{kind.upper()}"), i) or "")


JOINT_KINDS: dict[int, str] = {_FREE: "free", _BALL: "ball", _SLIDE: "slide", _HINGE: "hinge"}
"""MuJoCo joint types by their ``mjtJoint`` code, as written in MJCF."""


def body_label(mujoco: Any, m: Any, b: int) -> str:
    """The name of MuJoCo body ``b``, or ``body<b>`` for an unnamed one."""
    return _name(mujoco, m, "body", b) or f"body{b}"


def joint_names(mujoco: Any, m: Any, label: str | None = None) -> list[str]:
    """The name of every MuJoCo joint, in MuJoCo order, unnamed ones named after their body.

    A joint without a name (a floating base's ``<freejoint/>``, say) is named
    ``<body>_free`` for a free joint, else ``<body>_<kind><i>`` with ``kind`` its type
    (``hinge``, ``slide``, ``ball``) and ``i`` its position among the joints of its body
    (from 0): the second, unnamed hinge of body ``knee`` is ``knee_hinge1``. The names depend
    on the MJCF alone, so they are the same at every load.

    Raises:
        DescriptionError: when such a name is already the name of another joint.
    """
    names = [_name(mujoco, m, "joint", k) for k in range(m.njnt)]
    given = set(names)
    for k, name in enumerate(names):
        if name:
            continue
        b = int(m.jnt_bodyid[k])
        kind = int(m.jnt_type[k])
        suffix = "free" if kind == _FREE else f"{JOINT_KINDS[kind]}{k - int(m.body_jntadr[b])}"
        names[k] = f"{body_label(mujoco, m, b)}_{suffix}"
        if names[k] in given:
            raise DescriptionError(
                f"an unnamed joint of body {body_label(mujoco, m, b)!r} would be named {names[k]!r}, "
                "the name of another joint; name it",
                label,
            )
        given.add(names[k])
    return names


@dataclass(frozen=True)
class _JointPair:
    """One joint present in both models: Pinocchio index and MuJoCo addresses."""

    pin_id: int
    kind: int  # mjtJoint
    qposadr: int
    dofadr: int
    qpos0: float


class StateMap:
    r"""Conversion of states between a Pinocchio model and a MuJoCo model with the same joints.

    Joints are matched by name; every MuJoCo joint must be a Pinocchio joint and the other
    way round. Positions: hinge and slide ``qpos = q + qpos0`` (an unbounded revolute's
    :math:`(\cos, \sin)` becomes its angle), ball and free quaternions reordered, a free
    joint's pose being the world pose of the Pinocchio joint frame. Velocities: equal, but
    for a free joint's linear part (local in Pinocchio, world in MuJoCo).
    """

    def __init__(self, model: pin.Model, mj_model: Any) -> None:
        """Match the joints of ``model`` and ``mj_model`` by name.

        Raises:
            DescriptionError: when a joint is missing on one side or of a different kind.
        """
        mujoco = require_mujoco()
        self.model = model
        self.mj_model = mj_model
        names = list(model.names)
        pairs = []
        for k, name in enumerate(joint_names(mujoco, mj_model)):
            if name not in names:
                raise DescriptionError(
                    f"MuJoCo joint {name!r} has no Pinocchio joint; joints are {names[1:]}"
                )
            jid = names.index(name)
            kind = int(mj_model.jnt_type[k])
            joint = model.joints[jid]
            expected = {_FREE: (7, 6), _BALL: (4, 3)}.get(kind)
            if (expected and (joint.nq, joint.nv) != expected) or (not expected and joint.nv != 1):
                raise DescriptionError(
                    f"joint {name!r}: MuJoCo type {kind} does not match {joint.shortname()}"
                )
            adr = int(mj_model.jnt_qposadr[k])
            pairs.append(_JointPair(jid, kind, adr, int(mj_model.jnt_dofadr[k]), float(mj_model.qpos0[adr])))
        if len(pairs) != model.njoints - 1:
            raise DescriptionError(
                f"the MuJoCo model has {len(pairs)} joints, the Pinocchio model {model.njoints - 1}"
            )
        self._pairs = tuple(pairs)

    def _free_placement(self, pair: _JointPair) -> pin.SE3:
        return self.model.jointPlacements[pair.pin_id]

    def qpos(self, q: np.ndarray) -> np.ndarray:
        """MuJoCo ``qpos`` of the Pinocchio configuration ``q``, shape (mj nq,)."""
        out = np.array(self.mj_model.qpos0, dtype=float)
        for p in self._pairs:
            j = self.model.joints[p.pin_id]
            qj = q[j.idx_q : j.idx_q + j.nq]
            a = p.qposadr
            if p.kind in (_HINGE, _SLIDE):
                value = np.arctan2(qj[1], qj[0]) if j.nq == 2 else qj[0]
                out[a] = value + p.qpos0
            elif p.kind == _BALL:
                out[a : a + 4] = [qj[3], qj[0], qj[1], qj[2]]
            else:  # world pose of the joint frame; quaternion product, so the sign is kept
                P = self._free_placement(p)
                out[a : a + 3] = P.act(qj[:3])
                x, y, z, w = (pin.Quaternion(P.rotation) * pin.Quaternion(qj[6], *qj[3:6])).coeffs()
                out[a + 3 : a + 7] = [w, x, y, z]
        return out

    def q(self, qpos: np.ndarray) -> np.ndarray:
        """Pinocchio configuration of the MuJoCo ``qpos``, shape (nq,)."""
        out = np.asarray(pin.neutral(self.model), dtype=float).copy()
        for p in self._pairs:
            j = self.model.joints[p.pin_id]
            a = p.qposadr
            if p.kind in (_HINGE, _SLIDE):
                value = qpos[a] - p.qpos0
                out[j.idx_q : j.idx_q + j.nq] = [np.cos(value), np.sin(value)] if j.nq == 2 else [value]
            elif p.kind == _BALL:
                w, x, y, z = qpos[a : a + 4]
                out[j.idx_q : j.idx_q + 4] = np.array([x, y, z, w]) / np.linalg.norm(qpos[a : a + 4])
            else:
                P = self._free_placement(p).inverse()
                w, x, y, z = qpos[a + 3 : a + 7] / np.linalg.norm(qpos[a + 3 : a + 7])
                out[j.idx_q : j.idx_q + 3] = P.act(np.array(qpos[a : a + 3], dtype=float))
                out[j.idx_q + 3 : j.idx_q + 7] = (
                    pin.Quaternion(P.rotation) * pin.Quaternion(w, x, y, z)
                ).coeffs()
        return out

    def velocity_matrix(self, q: np.ndarray) -> np.ndarray:
        """Matrix :math:`G` with ``qvel = G v`` at configuration ``q``, shape (mj nv, nv)."""
        G = np.zeros((self.mj_model.nv, self.model.nv))
        for p in self._pairs:
            j = self.model.joints[p.pin_id]
            block = np.eye(j.nv)
            if p.kind == _FREE:
                qj = q[j.idx_q : j.idx_q + 7]
                block[:3, :3] = (self._free_placement(p) * pin.XYZQUATToSE3(qj)).rotation
            G[p.dofadr : p.dofadr + j.nv, j.idx_v : j.idx_v + j.nv] = block
        return G

    def qvel(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """MuJoCo ``qvel`` of the Pinocchio state ``(q, v)``, shape (mj nv,)."""
        return self.velocity_matrix(q) @ np.asarray(v, dtype=float)

    def v(self, q: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """Pinocchio velocity of the MuJoCo ``qvel`` at Pinocchio configuration ``q``, shape (nv,)."""
        return np.linalg.solve(self.velocity_matrix(q), np.asarray(qvel, dtype=float))


@dataclass(frozen=True)
class MjcfDescription:
    """A compiled MJCF turned into a Pinocchio model and a sidecar.

    Attributes:
        model: the Pinocchio model (gravity and armature set).
        sidecar: closures, actuation, task and reference.
        mj_model: the compiled MuJoCo model.
        path: the MJCF file.
        sidecar_path: the sidecar beside it, or None.
        reference_origin: where the reference guess comes from, for messages.
    """

    model: pin.Model
    sidecar: Sidecar
    mj_model: Any
    path: Path
    sidecar_path: Path | None
    reference_origin: str = "qpos0"

    def state_map(self) -> StateMap:
        """Conversion of states between :attr:`model` and :attr:`mj_model`."""
        return StateMap(self.model, self.mj_model)

    def visual_model(self) -> pin.GeometryModel:
        """The visual geoms (planes and height fields left out) as Pinocchio geometry.

        The geoms that take no part in contacts (``contype = conaffinity = 0``, MuJoCo's
        convention for visual-only geoms); every geom when the model has none of them.
        """
        colliding = _colliding(self.mj_model)
        shown = [g for g in range(self.mj_model.ngeom) if not colliding[g]]
        return _geometry(self.model, self.mj_model, shown or range(self.mj_model.ngeom))

    def collision_model(self) -> pin.GeometryModel:
        """The geoms that take part in contacts (``contype`` or ``conaffinity`` not zero), as geometry."""
        colliding = _colliding(self.mj_model)
        return _geometry(self.model, self.mj_model, [g for g in range(self.mj_model.ngeom) if colliding[g]])


def _joint_model(kind: int, axis: np.ndarray) -> pin.JointModel:
    units = {(1.0, 0.0, 0.0): "X", (0.0, 1.0, 0.0): "Y", (0.0, 0.0, 1.0): "Z"}
    unit = units.get((float(axis[0]), float(axis[1]), float(axis[2])))
    if kind == _HINGE:
        return getattr(pin, f"JointModelR{unit}")() if unit else pin.JointModelRevoluteUnaligned(axis)
    if kind == _SLIDE:
        return getattr(pin, f"JointModelP{unit}")() if unit else pin.JointModelPrismaticUnaligned(axis)
    if kind == _BALL:
        return pin.JointModelSpherical()
    return pin.JointModelFreeFlyer()


IGNORABLE: dict[str, str] = {
    "contacts": "explicit contact pairs (<contact><pair>)",
    "tendons": "tendons, with the tendon equalities and actuators that use them",
    "joint_equalities": "joint couplings (<equality><joint>)",
    "inactive_equalities": 'equalities with active="false"',
    "actuators": "actuators on a site, a body or a ball joint (not on one hinge or slide)",
}
"""Kinds of MJCF elements ``read_mjcf(..., ignore=...)`` may drop, and what each kind holds."""

_SAFE_TO_DROP = ("contacts", "tendons", "inactive_equalities")
"""Kinds whose dropping leaves the kinematics of a linkage unchanged (said in the warning)."""


@dataclass(frozen=True)
class _Unsupported:
    """Elements of one tag plm_pin cannot represent.

    Attributes:
        kind: their key in :data:`IGNORABLE`, or a kind that cannot be ignored.
        what: the MJCF tag, in words.
        obj: the MuJoCo object type (``equality``, ``actuator``, ...).
        indices: their MuJoCo indices.
        names: their names (``#i`` when unnamed).
    """

    kind: str
    what: str
    obj: str
    indices: tuple[int, ...]
    names: tuple[str, ...]

    def describe(self) -> str:
        """``<count> <what> ('name', ...)``, at most five names shown."""
        shown = ", ".join(repr(n) for n in self.names[:5]) + (", ..." if len(self.names) > 5 else "")
        return f"{len(self.indices)} {self.what} ({shown})"


def check_ignore(ignore: str | Iterable[str]) -> frozenset[str]:
    """The kinds of ``ignore`` (names, or one comma-separated string), checked against :data:`IGNORABLE`.

    Raises:
        InvalidInput: naming a kind that is not one of :data:`IGNORABLE`.
    """
    items = ignore.split(",") if isinstance(ignore, str) else list(ignore)
    kinds = [str(k).strip() for k in items if str(k).strip()]
    bad = [k for k in kinds if k not in IGNORABLE]
    if bad:
        raise InvalidInput(f"ignore: unknown element kind(s) {bad}; valid are {list(IGNORABLE)}")
    return frozenset(kinds)


def _unsupported(mujoco: Any, m: Any) -> list[_Unsupported]:
    """Every element plm_pin cannot represent, grouped by tag, in a fixed order."""
    found: dict[tuple[str, str, str], tuple[list[int], list[str]]] = {}

    def add(kind: str, what: str, obj: str, i: int) -> None:
        indices, names = found.setdefault((kind, what, obj), ([], []))
        indices.append(i)
        names.append(_name(mujoco, m, obj, i) or f"#{i}")

    for i in range(m.npair):
        add("contacts", "<contact><pair>", "pair", i)
    for i in range(m.ntendon):
        add("tendons", "<tendon>", "tendon", i)
    for i in range(m.nflex):
        add("flexes", "<flex> (deformable bodies)", "flex", i)
    for i in range(m.neq):
        kind = int(m.eq_type[i])
        tag = f"<equality><{_EQ_NAMES.get(kind, str(kind))}>"
        if kind == _EQ_JOINT:
            add("joint_equalities", tag, "equality", i)
        elif kind == _EQ_TENDON:
            add("tendons", tag, "equality", i)
        elif kind not in (_EQ_CONNECT, _EQ_WELD):
            add("equalities", tag + " (only connect and weld can be represented)", "equality", i)
        elif not m.eq_active0[i]:
            what = '<equality active="false"> (plm_pin closures always hold)'
            add("inactive_equalities", what, "equality", i)
    for a in range(m.nu):
        trn = int(m.actuator_trntype[a])
        if trn == _TRN_TENDON:
            add("tendons", "<actuator> on a tendon", "actuator", a)
        elif trn != _TRN_JOINT or int(m.jnt_type[int(m.actuator_trnid[a][0])]) not in (_HINGE, _SLIDE):
            add("actuators", "<actuator> not on one hinge or slide", "actuator", a)
    for b in range(1, m.nbody):
        if m.body_mocapid[b] >= 0:
            add("mocap", "mocap <body>", "body", b)
    return [
        _Unsupported(kind, what, obj, tuple(indices), tuple(names))
        for (kind, what, obj), (indices, names) in found.items()
    ]


def _drop_unsupported(mujoco: Any, m: Any, label: str, ignore: frozenset[str]) -> dict[str, set[int]]:
    """Refuse at once every element plm_pin cannot represent, but the kinds ``ignore`` drops (warned).

    Returns:
        The dropped MuJoCo indices by MuJoCo object type (``equality``, ``actuator``, ...).

    Raises:
        DescriptionError: listing every element neither represented nor ignored, with counts,
            and the ``ignore`` value that would drop the ignorable ones.
    """
    groups = _unsupported(mujoco, m)
    refused = [g for g in groups if g.kind not in ignore]
    if refused:
        ignorable = list(dict.fromkeys(g.kind for g in groups if g.kind in IGNORABLE))
        hint = (
            f". To read the loops without them, load with ignore={tuple(ignorable)} "
            f"(CLI: --ignore {','.join(ignorable)})"
            if any(g.kind in IGNORABLE for g in refused)
            else ""
        )
        raise DescriptionError(
            "the model holds elements plm_pin cannot represent: "
            + "; ".join(g.describe() for g in refused)
            + hint,
            label,
        )
    dropped = [g for g in groups if g.kind in ignore]
    if dropped:
        text = f"{label}: dropped as asked by ignore: " + "; ".join(g.describe() for g in dropped)
        if any(g.kind in _SAFE_TO_DROP for g in dropped):
            text += ". Contacts, tendons and inactive equalities do not change a linkage's kinematics"
        changing = list(dict.fromkeys(g.kind for g in dropped if g.kind not in _SAFE_TO_DROP))
        if changing:
            text += (
                f". Without the {' and '.join(changing)}, the joints they coupled or drove move "
                "freely: mobility and actuation change"
            )
        warnings.warn(text, IgnoredElementWarning, stacklevel=4)
    out: dict[str, set[int]] = {}
    for g in dropped:
        out.setdefault(g.obj, set()).update(g.indices)
    return out


def _warn_ignored_joint_properties(m: Any, label: str) -> None:
    for what, values in (
        ("damping", m.dof_damping),
        ("frictionloss", m.dof_frictionloss),
        ("stiffness", m.jnt_stiffness),
    ):
        if np.any(values != 0.0):
            warnings.warn(
                f"{label}: joint {what} is not modelled by plm_pin and is ignored",
                IgnoredElementWarning,
                stacklevel=4,
            )


def _build_tree(mujoco: Any, m: Any, label: str) -> tuple[pin.Model, dict[int, tuple[int, pin.SE3]]]:
    """The Pinocchio tree; returns it and, per MuJoCo body, its joint and placement there."""
    model = pin.Model()
    model.name = Path(label).stem
    where: dict[int, tuple[int, pin.SE3]] = {0: (0, pin.SE3.Identity())}
    body_frame: dict[int, int] = {0: 0}
    used: dict[str, str] = {}
    for element, count in (("body", m.nbody), ("site", m.nsite)):
        for i in range(1 if element == "body" else 0, count):
            name = _name(mujoco, m, element, i) or f"{element}{i}"
            if name in used:
                raise DescriptionError(
                    f"the {element} and the {used[name]} named {name!r} would give two Pinocchio frames "
                    "of one name; rename one",
                    label,
                )
            used[name] = element

    jnames = joint_names(mujoco, m, label)
    for b in range(1, m.nbody):
        bname = body_label(mujoco, m, b)
        parent = int(m.body_parentid[b])
        pj, pM = where[parent]
        current, offset = pj, pM * _se3(m.body_pos[b], m.body_quat[b])
        for k in range(int(m.body_jntadr[b]), int(m.body_jntadr[b] + m.body_jntnum[b])):
            kind = int(m.jnt_type[k])
            jname = jnames[k]
            anchor = pin.SE3(np.eye(3), np.array(m.jnt_pos[k], dtype=float))
            if kind == _FREE:
                if parent != 0:
                    raise DescriptionError(
                        f"joint {jname!r}: a free joint must be in a child of <worldbody>", label
                    )
                placement = pin.SE3.Identity()
                anchor = pin.SE3.Identity()
            else:
                placement = offset * anchor
            joint = _joint_model(kind, np.array(m.jnt_axis[k], dtype=float))
            current = model.addJoint(current, joint, placement, jname)
            if kind in (_HINGE, _SLIDE):  # MuJoCo's range, else unlimited (as an unlimited URDF joint)
                q0 = float(m.qpos0[m.jnt_qposadr[k]])
                lower, upper = (m.jnt_range[k] - q0) if m.jnt_limited[k] else (-np.inf, np.inf)
                model.lowerPositionLimit[model.joints[current].idx_q] = lower
                model.upperPositionLimit[model.joints[current].idx_q] = upper
            if jname not in used:  # a body or site of that name keeps the frame name
                model.addJointFrame(current, body_frame[parent])
            offset = anchor.inverse()
        R = quat_wxyz_to_rotation(m.body_iquat[b])
        inertia = pin.Inertia(
            float(m.body_mass[b]), np.array(m.body_ipos[b], dtype=float), R @ np.diag(m.body_inertia[b]) @ R.T
        )
        model.appendBodyToJoint(current, inertia, offset)
        body_frame[b] = model.addBodyFrame(bname, current, offset, body_frame[parent])
        where[b] = (current, offset)
    for s in range(m.nsite):
        sname = _name(mujoco, m, "site", s) or f"site{s}"
        b = int(m.site_bodyid[s])
        j, M = where[b]
        model.addFrame(
            pin.Frame(
                sname, j, body_frame[b], M * _se3(m.site_pos[s], m.site_quat[s]), pin.FrameType.OP_FRAME
            )
        )
    return model, where


def _closures(
    mujoco: Any, m: Any, model: pin.Model, where: dict[int, tuple[int, pin.SE3]], dropped: set[int]
) -> tuple[ClosureSpec, ...]:
    out = []
    for i in range(m.neq):
        if i in dropped:
            continue
        name = _name(mujoco, m, "equality", i) or f"equality{i}"
        kind = int(m.eq_type[i])
        data = np.array(m.eq_data[i], dtype=float)
        ctype = "weld" if kind == _EQ_WELD and data[10] != 0.0 else "point"
        o1, o2 = int(m.eq_obj1id[i]), int(m.eq_obj2id[i])
        if int(m.eq_objtype[i]) == _OBJ_SITE:
            frames = (
                _name(mujoco, m, "site", o1) or f"site{o1}",
                _name(mujoco, m, "site", o2) or f"site{o2}",
            )
            if not _name(mujoco, m, "equality", i):  # onshape-to-robot's: named after its frames
                name = closing_name(*frames) or name
        else:
            if kind == _EQ_CONNECT:
                local = ((data[0:3], np.array([1.0, 0, 0, 0])), (data[3:6], np.array([1.0, 0, 0, 0])))
            else:  # weld: body1 frame at (data[3:6], relpose quat), body2 frame at (data[0:3], identity)
                local = ((data[3:6], data[6:10]), (data[0:3], np.array([1.0, 0, 0, 0])))
            names = []
            for side, (body, (pos, quat)) in enumerate(zip((o1, o2), local, strict=True)):
                j, M = where[body]
                fname = f"{name}/{side + 1}"
                parent = model.getFrameId(_name(mujoco, m, "body", body)) if body else 0
                model.addFrame(pin.Frame(fname, j, parent, M * _se3(pos, quat), pin.FrameType.OP_FRAME))
                names.append(fname)
            frames = (names[0], names[1])
        out.append(ClosureSpec(name=name, frames=frames, type=ctype))  # type: ignore[arg-type]
    return tuple(out)


def _actuation(mujoco: Any, m: Any, label: str, dropped: set[int]) -> tuple[ActuatorSpec, ...]:
    out: list[ActuatorSpec] = []
    jnames = joint_names(mujoco, m, label)
    seen: dict[int, str] = {}
    for a in range(m.nu):
        if a in dropped:
            continue
        aname = _name(mujoco, m, "actuator", a) or f"#{a}"
        joint = int(m.actuator_trnid[a][0])  # on one hinge or slide: the others are refused or dropped
        jname = jnames[joint]
        if joint in seen:
            raise DescriptionError(
                f"<actuator> {aname!r}: joint {jname!r} is already driven by {seen[joint]!r}", label
            )
        seen[joint] = aname
        gear = float(m.actuator_gear[a][0])
        limits = None
        if m.actuator_forcelimited[a]:
            limits = gear * np.array(m.actuator_forcerange[a], dtype=float)
        elif m.actuator_ctrllimited[a] and m.actuator_biastype[a] == 0 and m.actuator_gaintype[a] == 0:
            limits = gear * float(m.actuator_gainprm[a][0]) * np.array(m.actuator_ctrlrange[a], dtype=float)
        bounds = None
        if limits is not None:
            lo, hi = sorted(float(x) for x in limits)
            bounds = (lo, hi) if lo < hi else None
        drive = _drive(mujoco, m, aname)
        out.append(
            ActuatorSpec(
                jname,
                bounds,
                drive.get("lead"),
                drive.get("rotor_inertia", 0.0),
                drive.get("screw_inertia", 0.0),
            )
        )
    return tuple(out)


DRIVE_FIELDS = ("lead", "rotor_inertia", "screw_inertia")
"""Drive data an actuator keeps in ``<custom><numeric name="plm_pin:<actuator>:<field>">``."""


def _drive(mujoco: Any, m: Any, actuator: str) -> dict[str, float]:
    """The lead [m/rev] and rotor and screw inertias [kg m^2] recorded for an actuator, if any.

    The joint armature already holds their reflected inertia; these values are kept for the
    motor torques and speeds of :func:`plm_pin.dynamics.inverse_dynamics`.
    """
    out = {}
    for k in range(m.nnumeric):
        prefix, _, rest = _name(mujoco, m, "numeric", k).partition(":")
        name, _, field = rest.rpartition(":")
        if prefix == "plm_pin" and name == actuator and field in DRIVE_FIELDS:
            out[field] = float(m.numeric_data[m.numeric_adr[k]])
    return out


def _colliding(m: Any) -> np.ndarray:
    """Whether each geom can take part in a contact (MuJoCo: ``contype`` or ``conaffinity`` not zero)."""
    return (np.asarray(m.geom_contype) != 0) | (np.asarray(m.geom_conaffinity) != 0)


def _geometry(model: pin.Model, m: Any, geoms: Iterable[int]) -> pin.GeometryModel:
    """The geoms ``geoms`` (planes and height fields left out) as a Pinocchio geometry model."""
    import coal

    mujoco = require_mujoco()
    geometry = pin.GeometryModel()
    frame_of_body = {0: 0}
    joint_of_body = {0: (0, pin.SE3.Identity())}
    for b in range(1, m.nbody):
        fid = model.getFrameId(_name(mujoco, m, "body", b) or f"body{b}")
        frame_of_body[b] = fid
        joint_of_body[b] = (model.frames[fid].parentJoint, model.frames[fid].placement)
    for g in geoms:
        kind, size = int(m.geom_type[g]), np.array(m.geom_size[g], dtype=float)
        shape: Any
        if kind == _GEOM_SPHERE:
            shape = coal.Sphere(size[0])
        elif kind == _GEOM_CAPSULE:
            shape = coal.Capsule(size[0], 2 * size[1])
        elif kind == _GEOM_CYLINDER:
            shape = coal.Cylinder(size[0], 2 * size[1])
        elif kind == _GEOM_BOX:
            shape = coal.Box(*(2 * size))
        elif kind == _GEOM_ELLIPSOID:
            shape = coal.Ellipsoid(*size)
        elif kind == _GEOM_MESH:
            mesh = int(m.geom_dataid[g])
            v0, nv_ = int(m.mesh_vertadr[mesh]), int(m.mesh_vertnum[mesh])
            f0, nf = int(m.mesh_faceadr[mesh]), int(m.mesh_facenum[mesh])
            shape = coal.BVHModelOBBRSS()
            shape.beginModel(nf, nv_)
            shape.addVertices(np.array(m.mesh_vert[v0 : v0 + nv_], dtype=float))
            shape.addTriangles(np.array(m.mesh_face[f0 : f0 + nf], dtype=np.int64))
            shape.endModel()
        else:  # planes and height fields: no finite visual
            continue
        b = int(m.geom_bodyid[g])
        j, M = joint_of_body[b]
        name = _name(mujoco, m, "geom", g) or f"geom{g}"
        obj = pin.GeometryObject(name, j, frame_of_body[b], M * _se3(m.geom_pos[g], m.geom_quat[g]), shape)
        obj.meshColor = np.array(m.geom_rgba[g], dtype=float)
        geometry.addGeometryObject(obj)
    return geometry


def _reference(m: Any, model: pin.Model) -> dict[str, tuple[float, ...]]:
    qpos = np.array(m.key_qpos[0] if m.nkey else m.qpos0, dtype=float)
    q = StateMap(model, m).q(qpos)
    return {
        str(model.names[j]): tuple(
            float(x) for x in q[model.joints[j].idx_q : model.joints[j].idx_q + model.joints[j].nq]
        )
        for j in range(1, model.njoints)
    }


def _read_mjcf_sidecar(path: Path) -> tuple[Sidecar | None, Path | None]:
    sidecar_path = path.with_name(path.stem + ".plm.yaml")
    if not sidecar_path.is_file():
        return None, None
    try:
        text = sidecar_path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise DescriptionError(f"cannot read file: {exc}", str(sidecar_path)) from None
    raw = read_yaml(text, str(sidecar_path))
    if isinstance(raw, dict):
        extra = sorted(set(raw) - set(MJCF_SIDECAR_KEYS), key=str)
        if extra:
            raise DescriptionError(
                f"key(s) {extra} not allowed beside an MJCF: its closures, actuation and gravity "
                f"come from the MJCF; the sidecar may hold {list(MJCF_SIDECAR_KEYS)}",
                str(sidecar_path),
            )
    return parse_sidecar(raw, str(sidecar_path)), sidecar_path


def read_mjcf(path: str | Path, ignore: str | Iterable[str] = ()) -> MjcfDescription:
    """Compile an MJCF with MuJoCo and build the Pinocchio model and sidecar of the closed chain.

    Args:
        path: the ``.xml`` file; a sidecar ``<stem>.plm.yaml`` beside it is read when present.
        ignore: kinds of elements to drop rather than refuse (keys of :data:`IGNORABLE`, or
            one comma-separated string), with an :class:`~plm_pin.warnings.IgnoredElementWarning`
            that lists what was dropped.

    Returns:
        The description (see the module docstring for the mapping).

    Raises:
        DescriptionError: when MuJoCo is missing or rejects the file, or the model holds
            elements plm_pin cannot represent and ``ignore`` does not drop (all of them listed).
        FrameNotFound: when the sidecar's task frame or a reference joint does not exist.
        InvalidInput: when ``ignore`` names an unknown kind.
    """
    kinds = check_ignore(ignore)
    mujoco = require_mujoco()
    p = Path(path)
    label = str(p)
    try:
        m = mujoco.MjModel.from_xml_path(str(p))
    except (ValueError, RuntimeError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise DescriptionError(f"MuJoCo cannot compile this MJCF: {first}", label) from None
    dropped = _drop_unsupported(mujoco, m, label, kinds)
    _warn_ignored_joint_properties(m, label)
    model, where = _build_tree(mujoco, m, label)
    closures = _closures(mujoco, m, model, where, dropped.get("equality", set()))
    actuation = _actuation(mujoco, m, label, dropped.get("actuator", set()))
    model.armature = np.array(m.dof_armature, dtype=float)
    gravity = (
        np.zeros(3)
        if m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_GRAVITY)
        else np.array(m.opt.gravity, dtype=float)
    )
    model.gravity.linear = gravity
    extra, sidecar_path = _read_mjcf_sidecar(p)
    side = str(sidecar_path)
    reference = _reference(m, model)
    origin = "first <keyframe>" if m.nkey else "qpos0"
    task = name = source = None
    if extra is not None:
        frames = [f.name for f in model.frames]
        if extra.task is not None and extra.task.frame is not None and not model.existFrame(extra.task.frame):
            raise FrameNotFound(extra.task.frame, frames, "frame", f"{side}: end_effector")
        for joint, values in extra.reference.items():
            if not model.existJointName(joint):
                raise FrameNotFound(joint, list(model.names)[1:], "joint", f"{side}: reference")
            if len(values) != model.joints[model.getJointId(joint)].nq:
                raise DescriptionError(
                    f"reference.{joint} has {len(values)} value(s); the joint takes "
                    f"{model.joints[model.getJointId(joint)].nq}",
                    side,
                )
        reference.update(extra.reference)
        origin = "sidecar reference over " + origin if extra.reference else origin
        task, name, source = extra.task, extra.name, extra.source
    sidecar = Sidecar(
        closures=closures,
        actuation=actuation,
        task=task,
        gravity=(float(gravity[0]), float(gravity[1]), float(gravity[2])),
        reference=reference,
        name=name,
        source=source or f"MJCF {p.name}",
        closure_tolerance=None if extra is None else extra.closure_tolerance,
        mobility=None if extra is None else extra.mobility,
    )
    return MjcfDescription(model, sidecar, m, p, sidecar_path, origin)
