"""Reading a closed-chain description from disk: plm-pin sidecars and example-parallel-robots."""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
from lxml import etree

from .._text import short
from .._yaml import read_head
from ..exceptions import DescriptionError, FrameNotFound
from ..warnings import MissingLimitsWarning
from .interop import corpus_task, parse_epr_sidecar
from .onshape import closing_closures
from .sidecar import SIDECAR_SUFFIX_DEFAULT, Sidecar, parse_sidecar, read_yaml
from .urdf import UrdfSource, read_urdf, read_urdf_text

SIDECAR_SUFFIX = SIDECAR_SUFFIX_DEFAULT
EPR_SIDECAR = "robot.yaml"


@dataclass(frozen=True)
class Description:
    """A URDF spanning tree with its closure sidecar.

    Attributes:
        urdf: the checked URDF source.
        sidecar: closures, actuation, task and reference.
        urdf_path: the URDF file, or None when built from text.
        sidecar_path: the sidecar file, or None.
        convention: ``"plm-pin/1"``, ``"example-parallel-robots"`` or ``"onshape-to-robot"``
            (closures from closing frames, see :mod:`plm_pin.description.onshape`).
    """

    urdf: UrdfSource
    sidecar: Sidecar
    urdf_path: Path | None = None
    sidecar_path: Path | None = None
    convention: str = "plm-pin/1"


def _read_head(path: Path) -> bytes:
    try:
        return read_head(path)
    except OSError as exc:
        raise DescriptionError(f"cannot read file: {exc.strerror}", str(path)) from None


def read_description(path: str | Path) -> Description:
    """Read a description from a URDF, a sidecar, or an example-parallel-robots folder.

    Args:
        path: ``<name>.urdf`` (sidecar ``<name>.plm.yaml`` beside it), ``<name>.plm.yaml``
            (URDF beside it), or a folder holding ``robot.urdf`` and ``robot.yaml``. A URDF
            holding onshape-to-robot closing frames (``closing_<name>_1`` / ``_2`` links)
            needs no sidecar: its closures are read from them, as they are when a sidecar
            gives no ``closures``.

    Returns:
        The description.

    Raises:
        DescriptionError: when files are missing, unreadable, malformed or unsafe.
    """
    p = Path(path)
    if p.is_dir():
        if (p / EPR_SIDECAR).is_file() and (p / "robot.urdf").is_file():
            return read_epr_folder(p)
        urdfs = sorted(p.glob("*.urdf"))
        if len(urdfs) == 1:
            return read_description(urdfs[0])
        raise DescriptionError(
            "folder holds neither robot.urdf + robot.yaml (example-parallel-robots) nor "
            f"exactly one .urdf file (found {[u.name for u in urdfs]})",
            str(p),
        )
    if not p.exists():
        raise DescriptionError("no such file or folder", str(p))
    if p.name.endswith(SIDECAR_SUFFIX):
        urdf_path = p.with_name(p.name[: -len(SIDECAR_SUFFIX)] + ".urdf")
        if not urdf_path.is_file():
            raise DescriptionError(f"sidecar has no URDF beside it: expected {urdf_path.name}", str(p))
        return _read_pair(urdf_path, p)
    if p.suffix == ".urdf":
        sidecar_path = p.with_name(p.stem + SIDECAR_SUFFIX)
        if sidecar_path.is_file():
            return _read_pair(p, sidecar_path)
        if p.name == "robot.urdf" and (p.parent / EPR_SIDECAR).is_file():
            return read_epr_folder(p.parent)
        urdf = read_urdf(p)
        closures = closing_closures(_link_names(urdf), str(p))
        if closures:
            source = f"onshape-to-robot closing frames in {p.name}"
            return Description(urdf, Sidecar(closures=closures, source=source), p, None, "onshape-to-robot")
        raise DescriptionError(
            f"no closure sidecar found beside the URDF: expected {sidecar_path.name} "
            f"(format plm-pin/1) or {EPR_SIDECAR} (example-parallel-robots), or closing frames "
            "closing_<name>_1 / closing_<name>_2 (onshape-to-robot)",
            str(p),
        )
    raise DescriptionError(
        f"unsupported file {short(p.name)}; give a .urdf, a {SIDECAR_SUFFIX} or a description folder",
        str(p),
    )


def _read_pair(urdf_path: Path, sidecar_path: Path) -> Description:
    raw = read_yaml(_read_head(sidecar_path), str(sidecar_path))
    sidecar = parse_sidecar(raw, str(sidecar_path))
    urdf = read_urdf(urdf_path)
    if "closures" not in raw:  # a sidecar for actuation and task only: the closing frames' loops
        closures = closing_closures(_link_names(urdf), str(urdf_path))
        if closures:
            sidecar = dataclasses.replace(sidecar, closures=closures)
            return Description(urdf, sidecar, urdf_path, sidecar_path, "onshape-to-robot")
    return Description(urdf, sidecar, urdf_path, sidecar_path)


def _link_names(urdf: UrdfSource) -> list[str]:
    """The link names of a checked URDF, in file order."""
    return [str(e.get("name")) for e in etree.fromstring(urdf.xml.encode()).iter("link")]


def read_epr_folder(folder: Path) -> Description:
    """Read an example-parallel-robots folder (``robot.urdf`` + ``robot.yaml``).

    The task is ``robot.yaml``'s ``end_effector``, else the corpus's for a known folder
    (see :mod:`plm_pin.description.interop`).
    """
    sidecar_path = folder / EPR_SIDECAR
    raw = read_yaml(_read_head(sidecar_path), str(sidecar_path))
    sidecar = parse_epr_sidecar(raw, str(sidecar_path), name=folder.name)
    urdf_path = folder / "robot.urdf"
    urdf = read_urdf(urdf_path)
    if sidecar.task is None:
        root = etree.fromstring(urdf.xml.encode())
        frames = [str(e.get("name")) for e in root.iter("link", "joint")]
        task = corpus_task(folder.name, frames)
        if task is not None:
            sidecar = dataclasses.replace(sidecar, task=task)
    return Description(urdf, sidecar, urdf_path, sidecar_path, "example-parallel-robots")


def description_from_text(urdf_text: str, sidecar_text: str, folder: Path | None = None) -> Description:
    """Build a description from in-memory URDF and sidecar texts."""
    sidecar = parse_sidecar(read_yaml(sidecar_text, "<sidecar>"), "<sidecar>")
    return Description(read_urdf_text(urdf_text, folder, "<urdf>"), sidecar)


def build_model(description: Description) -> pin.Model:
    """Build the Pinocchio model and check every name the sidecar uses.

    Gravity comes from the sidecar; the reflected inertia of each drive is added to its
    joint's armature. Joints without position limits in the URDF are made unlimited, with
    one :class:`~plm_pin.warnings.MissingLimitsWarning` (see :func:`open_missing_limits`).

    Raises:
        DescriptionError: when Pinocchio rejects the URDF, or a frame the sidecar names is the
            name of several frames (a joint and a link named alike).
        FrameNotFound: when the sidecar names a frame or joint the model lacks.
    """
    label = str(description.urdf_path) if description.urdf_path else "<urdf>"
    side = str(description.sidecar_path) if description.sidecar_path else "<sidecar>"
    try:
        model = pin.buildModelFromXML(description.urdf.xml)
    except (RuntimeError, ValueError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise DescriptionError(f"Pinocchio cannot build a model from this URDF: {first}", label) from None
    sidecar = description.sidecar
    frames = [f.name for f in model.frames]
    for closure in sidecar.closures:
        for name in closure.frames:
            if not model.existFrame(name):
                raise FrameNotFound(name, frames, "frame", f"{side}: closure {short(closure.name)}")
            _unique_frame(model, name, f"{side}: closure {short(closure.name)}")
        bodies = {model.frames[model.getFrameId(name)].parentJoint for name in closure.frames}
        if len(bodies) == 1:
            raise DescriptionError(
                f"closure {short(closure.name)} joins {short(closure.frames[0])} and "
                f"{short(closure.frames[1])}, two frames of one rigid body (both move with joint "
                f"{short(model.names[bodies.pop()])}): it constrains nothing",
                side,
            )
    task = sidecar.task
    if task is not None and task.frame is not None:
        if not model.existFrame(task.frame):
            raise FrameNotFound(task.frame, frames, "frame", f"{side}: end_effector")
        _unique_frame(model, task.frame, f"{side}: end_effector")
    joints = list(model.names)[1:]
    for joint in task.joints if task is not None else ():
        if not model.existJointName(joint):
            raise FrameNotFound(joint, joints, "joint", f"{side}: end_effector.joints")
    for actuator in sidecar.actuation:
        if not model.existJointName(actuator.joint):
            raise FrameNotFound(actuator.joint, joints, "joint", f"{side}: actuation")
        jid = model.getJointId(actuator.joint)
        if model.joints[jid].nv != 1:
            raise DescriptionError(
                f"actuated joint {short(actuator.joint)} has {model.joints[jid].nv} DOF; only "
                "one-DOF (prismatic or revolute) joints can be actuated",
                side,
            )
        model.armature[model.joints[jid].idx_v] += actuator.reflected_inertia()
    for joint in sidecar.reference:
        if not model.existJointName(joint):
            raise FrameNotFound(joint, joints, "joint", f"{side}: reference")
        jid = model.getJointId(joint)
        j = model.joints[jid]
        n_values = len(sidecar.reference[joint])
        if n_values != j.nq and not (j.nq == 2 and j.nv == 1 and n_values == 1):
            raise DescriptionError(
                f"reference.{joint} has {len(sidecar.reference[joint])} value(s); the joint "
                f"takes {j.nq}" + (" (or one angle [rad])" if j.nq == 2 and j.nv == 1 else ""),
                side,
            )
    model.gravity.linear = np.array(sidecar.gravity, dtype=float)
    open_missing_limits(model, label)
    return model


def _unique_frame(model: pin.Model, name: str, where: str) -> None:
    """Refuse a sidecar frame name that several frames of the model carry (a joint and a link of one name).

    Raises:
        DescriptionError: naming the frame, the kinds of frames carrying it and ``where`` it is used.
    """
    kinds = [str(f.type).split(".")[-1].lower() for f in model.frames if f.name == name]
    if len(kinds) > 1:
        raise DescriptionError(
            f"frame {short(name)} is ambiguous: {len(kinds)} frames of the model carry that name "
            f"({', '.join(kinds)}: a joint and a link named alike); rename the link or the joint",
            where,
        )


def build_visual_model(model: pin.Model, description: Description) -> pin.GeometryModel:
    """Build the visual geometry (meshes already resolved and checked)."""
    return _geometry(model, description, pin.GeometryType.VISUAL)


def build_collision_model(model: pin.Model, description: Description) -> pin.GeometryModel:
    """Build the collision geometry: the URDF's ``<collision>`` shapes (none when it has none)."""
    return _geometry(model, description, pin.GeometryType.COLLISION)


def _geometry(model: pin.Model, description: Description, kind: pin.GeometryType) -> pin.GeometryModel:
    try:
        return pin.buildGeomFromUrdfString(model, description.urdf.xml, kind)
    except (RuntimeError, ValueError) as exc:
        what = str(kind).split(".")[-1].lower()
        raise DescriptionError(f"cannot build the {what} geometry: {exc}") from None


def open_missing_limits(model: pin.Model, label: str = "") -> list[str]:
    """Make every one-DOF joint with a zero-width position range unlimited, warning once.

    Args:
        model: the model, changed in place.
        label: where the joints come from (a file), to start the warning with.

    Returns:
        The names of the joints changed, in model order.
    """
    changed = []
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint.nq != 1:
            continue
        k = joint.idx_q
        if model.lowerPositionLimit[k] == model.upperPositionLimit[k]:
            model.lowerPositionLimit[k] = -np.inf
            model.upperPositionLimit[k] = np.inf
            changed.append(str(model.names[j]))
    if changed:
        prefix = f"{label}: " if label else ""
        warnings.warn(
            f"{prefix}{len(changed)} joint(s) have no position limits (lower = upper = 0 in the URDF) "
            f"and are treated as unlimited (continuous): {changed}",
            MissingLimitsWarning,
            stacklevel=2,
        )
    return changed
