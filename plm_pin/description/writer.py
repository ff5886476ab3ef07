"""Writing a description: the URDF spanning tree (through yourdfpy) and its sidecar."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree

from .._io import atomic_write_text
from .._lazy import lazy_module
from ..exceptions import InvalidInput
from .sidecar import SIDECAR_SUFFIX_DEFAULT, Sidecar

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")


def urdf_text(robot: yourdfpy.Robot) -> str:
    """Serialise a yourdfpy robot to indented URDF text (one element per line, diff-friendly)."""
    urdf = yourdfpy.URDF(robot=robot, build_scene_graph=False, load_meshes=False)
    tree = urdf.write_xml()
    etree.indent(tree, space="  ")
    return etree.tostring(tree, xml_declaration=True, encoding="utf-8", pretty_print=True).decode()


def write_description(
    robot: yourdfpy.Robot, sidecar: Sidecar, folder: str | Path, name: str
) -> tuple[Path, Path]:
    """Write ``<name>.urdf`` and ``<name>.plm.yaml`` into ``folder`` (atomically).

    Args:
        robot: the spanning tree.
        sidecar: closures, actuation, task and reference.
        folder: destination folder (created if needed).
        name: file stem; letters, digits, ``_`` and ``-`` only.

    Returns:
        The URDF and sidecar paths.

    Raises:
        InvalidInput: ``name`` is empty or has another character than an ASCII letter, digit, ``_`` or ``-``.
    """
    if not name or not all(ch.isascii() and (ch.isalnum() or ch in "_-") for ch in name):
        raise InvalidInput(f"invalid description name {name!r}: use letters, digits, '_' and '-'")
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    urdf_path = out / f"{name}.urdf"
    sidecar_path = out / f"{name}{SIDECAR_SUFFIX_DEFAULT}"
    atomic_write_text(urdf_path, urdf_text(robot))
    atomic_write_text(sidecar_path, sidecar.to_yaml())
    return urdf_path, sidecar_path
