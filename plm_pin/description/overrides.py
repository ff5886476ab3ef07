"""A user's description as a parametric builder: joint origins, lengths and masses by name.

``DescriptionBuilder("path/robot.urdf")`` behaves like the builders of :mod:`plm_pin.models`
(``builder(name=..., source=..., **parameters) -> (robot, sidecar)``), so that
:func:`plm_pin.sweep` and :func:`plm_pin.build_mechanism` take a description path. Its
parameters, named after the URDF's joints and links:

- ``<joint>.x``, ``<joint>.y``, ``<joint>.z``: the joint origin's coordinates in its parent
  link [m];
- ``<joint>.length``: the distance of the joint origin from its parent link's frame [m] (the
  direction is kept), e.g. a rod length when the rod's end joint sits on its axis;
- ``<link>.mass``: the link's mass [kg], its inertia tensor scaled with it.

Unknown names are refused with the list of valid ones before any work starts; a value that
makes no sense (a mass or length not positive) is refused when the variant is built.
"""

from __future__ import annotations

import dataclasses
import functools
import io
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._lazy import lazy_module
from ..exceptions import DescriptionError, InvalidInput
from .loader import read_description
from .sidecar import Sidecar

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

ORIGIN_KEYS: tuple[str, ...] = ("x", "y", "z", "length")
"""Joint-origin parameters: coordinates [m] and distance from the parent frame [m]."""


class DescriptionBuilder:
    """Builder of variants of the description at ``path`` (see the module docstring).

    Attributes:
        path: the description (a ``.urdf``, ``.plm.yaml`` or folder), as given.
    """

    def __init__(self, path: str | Path) -> None:
        """Read nothing yet: the description is read on first use (the builder pickles as its path)."""
        self.path = str(path)
        self.__name__ = Path(self.path).name.split(".")[0]
        if self.__name__ == "robot":
            self.__name__ = Path(self.path).resolve().parent.name

    @functools.cached_property
    def _source(self) -> tuple[str, Sidecar]:
        description = read_description(self.path)
        if description.urdf_path is None:  # pragma: no cover - read_description always has a file
            raise DescriptionError("description has no URDF file", self.path)
        return description.urdf_path.read_text(encoding="utf-8"), description.sidecar

    def _robot(self) -> yourdfpy.Robot:
        """A fresh copy of the URDF tree (parsed again: variants never share links or joints)."""
        stream = io.BytesIO(self._source[0].encode())
        return yourdfpy.URDF.load(
            stream, build_scene_graph=False, load_meshes=False, build_collision_scene_graph=False
        ).robot

    @functools.cached_property
    def parameters(self) -> tuple[str, ...]:
        """Names of every parameter, joints' then links', in URDF order."""
        robot = self._robot()
        names = [f"{j.name}.{k}" for j in robot.joints if j.origin is not None for k in ORIGIN_KEYS]
        names += [f"{link.name}.mass" for link in robot.links if link.inertial is not None]
        return tuple(names)

    def __call__(self, *, name: str, source: str, **parameters: Any) -> tuple[yourdfpy.Robot, Sidecar]:
        """The description with ``parameters`` applied, named ``name``.

        Raises:
            InvalidInput: an unknown parameter (the message lists them) or a value that is not
                a finite number, or not positive for a mass or a length.
        """
        unknown = [p for p in parameters if p not in self.parameters]
        if unknown:
            raise InvalidInput(
                f"unknown parameter(s) {unknown} of {self.path}; its parameters are {list(self.parameters)}"
            )
        robot = self._robot()
        joints = {j.name: j for j in robot.joints}
        links = {link.name: link for link in robot.links}
        for key, raw in parameters.items():
            target, what = key.rsplit(".", 1)
            try:
                value = float(raw)
            except (TypeError, ValueError):
                raise InvalidInput(f"parameter {key!r} must be a number, got {raw!r}") from None
            positive = what in ("mass", "length")
            if not np.isfinite(value) or (positive and value <= 0.0):
                kind = "finite positive" if positive else "finite"
                raise InvalidInput(f"parameter {key!r} must be a {kind} number, got {raw!r}")
            if what == "mass":
                inertial = links[target].inertial
                inertial.inertia = np.asarray(inertial.inertia, dtype=float) * (value / inertial.mass)
                inertial.mass = value
                continue
            origin = np.array(joints[target].origin, dtype=float)
            if what == "length":
                norm = float(np.linalg.norm(origin[:3, 3]))
                if norm == 0.0:
                    raise InvalidInput(
                        f"parameter {key!r}: joint {target!r} sits at its parent's origin, "
                        "so there is no direction to scale"
                    )
                origin[:3, 3] *= value / norm
            else:
                origin[ORIGIN_KEYS.index(what), 3] = value
            joints[target].origin = origin
        robot.name = name
        return robot, dataclasses.replace(self._source[1], name=name, source=source)
