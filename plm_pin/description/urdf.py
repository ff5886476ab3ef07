"""Safe reading of untrusted URDF files: no entity expansion, no escaping mesh paths."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from lxml import etree

from ..exceptions import DescriptionError
from ..warnings import MissingMeshWarning

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


def read_urdf_text(text: str | bytes, folder: Path | None, label: str = "<urdf>") -> UrdfSource:
    """Check URDF text and resolve its mesh references against ``folder``.

    Args:
        text: the URDF document.
        folder: folder that holds the URDF and its meshes, or None (meshes then count as
            missing).
        label: name used in messages.

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
