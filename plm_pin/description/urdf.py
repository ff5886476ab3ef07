"""Safe reading of untrusted URDF files: no entity expansion, no escaping mesh paths."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

import numpy as np
from lxml import etree

from .._arguments import repeated
from .._text import short
from ..exceptions import DescriptionError, FrameNotFound
from ..tolerances import AXIS_MIN, INERTIA_RTOL
from ..warnings import DescriptionWarning, MissingMeshWarning

_MAX_BYTES = 64 * 1024 * 1024


@dataclass(frozen=True)
class UrdfSource:
    """A URDF checked for safety, with mesh paths resolved.

    Attributes:
        xml: the URDF text with mesh file names made absolute and the visuals and
            collisions of missing meshes removed; ready for Pinocchio.
        name: the robot name.
        folder: folder of the URDF file (meshes must stay inside it), or None for text.
        missing_meshes: mesh references whose file does not exist.
    """

    xml: str
    name: str
    folder: Path | None
    missing_meshes: tuple[str, ...]


def _parser() -> etree.XMLParser:
    return etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        dtd_validation=False,
        huge_tree=False,
        remove_comments=True,
    )


def _resolve_mesh(filename: str, folder: Path, where: str) -> Path:
    """Map a URDF mesh reference to a file inside ``folder``; refuse any escape."""
    if filename.startswith("package://"):
        rest = filename[len("package://") :]
        package, _, relative = rest.partition("/")
        parts = [relative, f"{package}/{relative}"] if package else [relative]
    elif filename.startswith("file://"):
        parts = [filename[len("file://") :]]
    else:
        parts = [filename]
    root = folder.resolve()
    candidates = []
    for part in parts:
        pure = PurePosixPath(part)
        if ".." in pure.parts:
            raise DescriptionError(
                f"{where}: mesh path {filename!r} climbs out of the description folder {root}"
            )
        path = (root / part).resolve() if not pure.is_absolute() else Path(part).resolve()
        if not path.is_relative_to(root):
            raise DescriptionError(
                f"{where}: mesh path {filename!r} points outside the description folder {root}"
            )
        candidates.append(path)
    for path in candidates:
        if path.is_file():
            return path
    return candidates[0]


JOINT_TYPES: tuple[str, ...] = ("continuous", "fixed", "floating", "planar", "prismatic", "revolute")

_MOVING = ("continuous", "prismatic", "revolute")

# numeric attributes of URDF elements and how many numbers each holds
_NUMERIC: dict[str, dict[str, int]] = {
    "origin": {"xyz": 3, "rpy": 3},
    "axis": {"xyz": 3},
    "mass": {"value": 1},
    "inertia": {k: 1 for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")},
    "limit": {"lower": 1, "upper": 1, "effort": 1, "velocity": 1},
    "box": {"size": 3},
    "cylinder": {"radius": 1, "length": 1},
    "sphere": {"radius": 1},
    "mesh": {"scale": 3},
    "mimic": {"multiplier": 1, "offset": 1},
}


def _owner(element: etree._Element) -> str:
    node: etree._Element | None = element
    while node is not None and node.tag not in ("link", "joint"):
        node = node.getparent()
    return f"{node.tag} {short(node.get('name'))}" if node is not None else "robot"


def check_numbers(root: etree._Element, label: str, strict: bool = True) -> None:
    """Check every numeric attribute: Pinocchio's parser would skip a bad one silently.

    Args:
        root: the ``<robot>`` element.
        label: the file, for messages.
        strict: refuse (True) or only warn about the flaws third-party CAD exports often
            hold and Pinocchio tolerates: inertias breaking a triangle inequality (see
            :func:`check_inertia`) and a ``<mimic>`` naming no other moving joint.

    Raises:
        DescriptionError: naming the element, the attribute and the bad text.
    """
    for tag, attributes in _NUMERIC.items():
        for element in root.iter(tag):
            for attribute, count in attributes.items():
                text = element.get(attribute)
                if text is None:
                    continue
                parts = text.split()
                try:
                    values = [float(v) for v in parts]
                except ValueError:
                    values = []
                if len(values) != count or not all(math.isfinite(v) for v in values):
                    raise DescriptionError(
                        f"{_owner(element)}: <{tag} {attribute}={text!r}> must hold {count} finite number(s)",
                        label,
                    )
                if tag == "mass" and values[0] < 0.0:
                    raise DescriptionError(f"{_owner(element)}: negative mass {values[0]}", label)
                moving = element.getparent() is not None and element.getparent().get("type") in _MOVING
                if tag == "axis" and moving and math.hypot(*values) < AXIS_MIN:
                    raise DescriptionError(
                        f"{_owner(element)}: <axis xyz={short(text)}> must be non-zero (norm at least "
                        f"{AXIS_MIN:g}); it is normalised",
                        label,
                    )
    for inertial in root.iter("inertial"):
        mass = inertial.find("mass")
        inertia = inertial.find("inertia")
        if mass is None or mass.get("value") is None:
            raise DescriptionError(f"{_owner(inertial)}: <inertial> needs <mass value=...>", label)
        absent = [k for k in _NUMERIC["inertia"] if inertia is None or inertia.get(k) is None]
        if absent:
            raise DescriptionError(f"{_owner(inertial)}: <inertia> lacks {absent}", label)
        assert inertia is not None
        moments = {k: float(inertia.get(k)) for k in _NUMERIC["inertia"]}
        check_inertia(moments, _owner(inertial), label, strict)
    for joint in root.iter("joint"):
        if joint.get("type") in ("revolute", "prismatic"):
            limit = joint.find("limit")
            if limit is None or limit.get("effort") is None or limit.get("velocity") is None:
                raise DescriptionError(
                    f"{_owner(joint)}: a {joint.get('type')} joint needs <limit effort=... velocity=...>",
                    label,
                )
        _check_limit(joint, label)
    _check_mimics(root, label, strict)


def check_inertia(moments: dict[str, float], owner: str, label: str, strict: bool = True) -> None:
    """Refuse an inertia no rigid body has: not positive semi-definite, or breaking a triangle inequality.

    The principal moments of a rigid body are >= 0 and each is at most the sum of the other two.

    Args:
        moments: ``ixx ixy ixz iyy iyz izz`` [kg m^2].
        owner: the link, for the message.
        label: the file, for the message.
        strict: refuse a broken triangle inequality; if False, only warn
            (:class:`~plm_pin.warnings.DescriptionWarning`): CAD exports of open-chain robots
            often hold such moments, and the mass matrix stays positive semi-definite.

    Raises:
        DescriptionError: naming the link, the principal moments and the broken condition.
    """
    m = moments
    tensor = np.array(
        [[m["ixx"], m["ixy"], m["ixz"]], [m["ixy"], m["iyy"], m["iyz"]], [m["ixz"], m["iyz"], m["izz"]]]
    )
    principal = np.linalg.eigvalsh(tensor)  # ascending
    tol = INERTIA_RTOL * max(float(np.abs(principal).max()), 1e-300)
    shown = ", ".join(f"{v:.6g}" for v in principal)
    if principal[0] < -tol:
        raise DescriptionError(
            f"{owner}: the inertia is not positive semi-definite (principal moments {shown} kg m^2): no body "
            "has a negative moment of inertia",
            label,
        )
    if principal[0] + principal[1] < principal[2] - tol:
        problem = (
            f"{owner}: the principal moments of inertia {shown} kg m^2 break the triangle inequality "
            f"({principal[0]:.6g} + {principal[1]:.6g} < {principal[2]:.6g}): no rigid body has them"
        )
        if strict:
            raise DescriptionError(problem, label)
        warnings.warn(f"{label}: {problem}", DescriptionWarning, stacklevel=4)


def _check_limit(joint: etree._Element, label: str) -> None:
    """Refuse a joint limit with a negative effort or velocity, or a lower bound above the upper."""
    limit = joint.find("limit")
    if limit is None:
        return
    for attribute, unit in (("effort", "N or N m"), ("velocity", "m/s or rad/s")):
        text = limit.get(attribute)
        if text is not None and float(text) < 0.0:
            raise DescriptionError(
                f"joint {short(joint.get('name'))}: <limit {attribute}={text!r}> must be >= 0 [{unit}]", label
            )
    lower, upper = limit.get("lower"), limit.get("upper")
    if lower is not None and upper is not None and float(lower) > float(upper):
        raise DescriptionError(
            f"joint {short(joint.get('name'))}: <limit lower={lower!r} upper={upper!r}> has lower > upper",
            label,
        )


def _check_mimics(root: etree._Element, label: str, strict: bool) -> None:
    """Refuse (or if not ``strict`` warn about) a ``<mimic>`` naming no other moving joint."""
    moving = {j.get("name") for j in root.findall("joint") if j.get("type") in _MOVING}
    for joint in root.findall("joint"):
        for mimic in joint.findall("mimic"):
            target = mimic.get("joint")
            name = joint.get("name")
            if joint.get("type") not in _MOVING:
                raise DescriptionError(
                    f"joint {short(name)}: a {short(joint.get('type'))} joint cannot mimic another", label
                )
            if target is None or target == name or target not in moving:
                problem = (
                    f"joint {short(name)}: <mimic joint={short(target)}> must name another moving joint "
                    "(continuous, prismatic, revolute) of this URDF"
                )
                if strict:
                    raise DescriptionError(problem, label)
                warnings.warn(f"{label}: {problem}; the mimic is ignored", DescriptionWarning, stacklevel=4)


def check_tree(root: etree._Element, label: str) -> None:
    """Check that links and joints form one tree, with messages that say what is wrong.

    Raises:
        DescriptionError: duplicate names, unknown joint types, a joint whose parent or
            child link does not exist (:class:`FrameNotFound`), a link with two parents,
            or not exactly one root link.
    """
    links = [link.get("name", "") for link in root.findall("link")]
    if not links:
        raise DescriptionError("URDF has no <link>", label)
    for kind, names in (("link", links), ("joint", [j.get("name", "") for j in root.findall("joint")])):
        if "" in names:
            raise DescriptionError(f"a <{kind}> has no name", label)
        dup = repeated(names)
        if dup:
            raise DescriptionError(f"duplicate {kind} name(s) {short(dup)}", label)
    known = set(links)
    parent_of: dict[str, str] = {}
    for joint in root.findall("joint"):
        name = joint.get("name", "")
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            raise DescriptionError(
                f"joint {name!r}: unknown type {kind!r}; valid types are {list(JOINT_TYPES)}", label
            )
        ends = {}
        for end in ("parent", "child"):
            element = joint.find(end)
            link = element.get("link") if element is not None else None
            if not link:
                raise DescriptionError(f"joint {name!r} has no <{end} link=...>", label)
            if link not in known:
                raise FrameNotFound(link, links, "link", f"{label}: joint {name!r} {end}")
            ends[end] = link
        if ends["child"] in parent_of:
            raise DescriptionError(
                f"link {ends['child']!r} is the child of two joints ({parent_of[ends['child']]!r} and "
                f"{name!r}); a URDF is a tree: cut one of them and declare it as a closure in the sidecar",
                label,
            )
        parent_of[ends["child"]] = name
    roots = [link for link in links if link not in parent_of]
    if len(roots) != 1:
        raise DescriptionError(f"the links must form one tree with one root; roots are {roots}", label)
    children: dict[str, list[str]] = {}
    for joint in root.findall("joint"):
        children.setdefault(joint.find("parent").get("link"), []).append(joint.find("child").get("link"))
    reached, todo = {roots[0]}, [roots[0]]
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in reached:
                reached.add(child)
                todo.append(child)
    detached = [link for link in links if link not in reached]
    if detached:
        raise DescriptionError(
            f"link(s) {short(detached)} do not hang from the root link {roots[0]!r}: their joints form a "
            "cycle; a URDF is a tree: cut one joint of the cycle and declare it as a closure in the sidecar",
            label,
        )


def read_urdf_text(
    text: str | bytes, folder: Path | None, label: str = "<urdf>", *, strict: bool = True
) -> UrdfSource:
    """Check URDF text and resolve its mesh references against ``folder``.

    Args:
        text: the URDF document.
        folder: folder that holds the URDF and its meshes, or None (meshes then count as
            missing).
        label: name used in messages.
        strict: refuse (True) or only warn (:class:`~plm_pin.warnings.DescriptionWarning`)
            about flaws third-party exports often hold (see :func:`check_numbers`); inertias
            that are not positive semi-definite are always refused.

    Returns:
        The checked source.

    Raises:
        DescriptionError: on malformed XML, a DOCTYPE or entity declaration (refused, not
            expanded), a root other than ``<robot>``, or a mesh path leaving ``folder``.
    """
    data = text.encode() if isinstance(text, str) else text
    if len(data) > _MAX_BYTES:
        raise DescriptionError(f"URDF is larger than {_MAX_BYTES // 2**20} MiB", label)
    doctype_refused = DescriptionError(
        "DOCTYPE and ENTITY declarations are not allowed in a URDF (entity expansion "
        "and external entities are refused)",
        label,
    )
    if b"<!DOCTYPE" in data or b"<!ENTITY" in data:
        raise doctype_refused
    try:
        root = etree.fromstring(data, _parser())
    except etree.XMLSyntaxError as exc:
        raise DescriptionError(f"malformed URDF XML: {exc}", label) from None
    # The byte check above misses encodings that are not ASCII-compatible (UTF-16, UTF-7):
    # refuse a document type declaration however it was encoded.
    docinfo = root.getroottree().docinfo
    if docinfo.doctype or docinfo.internalDTD is not None:
        raise doctype_refused
    if root.tag != "robot":
        raise DescriptionError(f"URDF root element must be <robot>, got <{root.tag}>", label)
    check_tree(root, label)
    check_numbers(root, label, strict)
    missing: list[str] = []
    for kind in ("visual", "collision"):
        for element in list(root.iter(kind)):
            mesh = element.find("geometry/mesh")
            if mesh is None:
                continue
            filename = mesh.get("filename", "")
            link = element.getparent()
            where = f"link {link.get('name') if link is not None else '?'} {kind}"
            if folder is None:
                if kind == "visual":
                    missing.append(filename)
                element.getparent().remove(element)
                continue
            path = _resolve_mesh(filename, folder, f"{label}: {where}")
            if path.is_file():
                mesh.set("filename", str(path))
            else:
                if kind == "visual":
                    missing.append(filename)
                element.getparent().remove(element)
    if missing:
        unique = sorted(set(missing))
        shown = ", ".join(unique[:8]) + (f", ... ({len(unique)} files)" if len(unique) > 8 else "")
        warnings.warn(
            f"{label}: {len(unique)} mesh file(s) missing, loading without those visuals: {shown}",
            MissingMeshWarning,
            stacklevel=3,
        )
    xml = etree.tostring(root, encoding="unicode")
    return UrdfSource(xml, root.get("name", ""), folder, tuple(sorted(set(missing))))


def read_urdf(path: Path) -> UrdfSource:
    """Read and check a URDF file (see :func:`read_urdf_text`)."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise DescriptionError(f"cannot read URDF: {exc.strerror}", str(path)) from None
    return read_urdf_text(data, path.parent, str(path))
