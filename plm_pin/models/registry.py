"""The registry of named presets: the papers' mechanisms and small classic chains."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import yourdfpy

from ..description.sidecar import Sidecar
from .classic import build_fivebar, build_fourbar
from .prrrp import build_2prrrp, rod_scaled

Builder = Callable[..., tuple[yourdfpy.Robot, Sidecar]]


@dataclass(frozen=True)
class Preset:
    """A named mechanism with the parameters of its source.

    Attributes:
        name: preset name, as given to :func:`plm_pin.load`.
        builder: parametric builder returning the URDF tree and the sidecar.
        parameters: keyword arguments of ``builder`` (SI units).
        source: the paper and the table or section the parameters come from.
        dof: mobility the mechanism must have.
        actuators: number of actuated joints.
        summary: one line describing the mechanism.
        notes: assumptions and values chosen where the source is silent.
    """

    name: str
    builder: Builder
    parameters: Mapping[str, Any]
    source: str
    dof: int
    actuators: int
    summary: str
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def redundancy(self) -> int:
        """Degree of actuation redundancy ``actuators - dof``."""
        return self.actuators - self.dof

    def build(self) -> tuple[yourdfpy.Robot, Sidecar]:
        """Run the builder with the preset's parameters."""
        return self.builder(name=self.name, source=self.source, **self.parameters)


def _frozen(**kwargs: Any) -> Mapping[str, Any]:
    return MappingProxyType(kwargs)


# Harada 2011, Table 1 and (M.36): l = 0.140 m, r_t = 0.05 m, rods 0.026 kg 9.84e-5 kg m^2,
# plate 0.132 kg 8.54e-4 kg m^2, moving parts 0.375 kg, g = 9.8 m/s^2 (M.37).
_HARADA2011 = dict(
    rod_lengths=(0.140, 0.140, 0.140, 0.140),
    half_plate=0.05,
    slider_mass=0.375,
    rod_masses=(0.026,) * 4,
    rod_inertias=(9.84e-5,) * 4,
    plate_mass=0.132,
    plate_inertia=8.54e-4,
    reference_pose=(0.0, 0.08, math.radians(-20.0)),
    working_modes=(-1, 1, -1, 1),
    gravity=9.8,
)
_HARADA2011_NOTES = (
    "Working modes (-, +, -, +) as in the code (M.5) and skeletons (M.42); the text after eq. (2) "
    "states the opposite signs.",
    "Reference pose x = 0, y = 0.08 m, theta = -20 deg: the initial state of simulations 1 and 2 "
    "as coded in (M.38) (Table 2 prints +20 deg).",
    "Rod and plate inertias are the table's values about the axis normal to the plane; the axial "
    "inertias (irrelevant in the plane) are those of a 5 mm radius bar and a 10 mm plate.",
    "No actuator force limits are given by the paper; none are set.",
)


def _harada2015() -> Mapping[str, Any]:
    lengths = (0.240, 0.170, 0.170, 0.240)
    scaled = [rod_scaled(l, 0.140, 0.026, 9.84e-5) for l in lengths]
    return _frozen(
        rod_lengths=lengths,
        half_plate=0.05,
        slider_mass=0.375,
        rod_masses=tuple(m for m, _ in scaled),
        rod_inertias=tuple(i for _, i in scaled),
        plate_mass=0.132,
        plate_inertia=8.54e-4,
        reference_pose=(0.0, 0.10, 0.0),
        working_modes=(-1, 1, -1, 1),
        gravity=9.81,
    )


PRESETS: dict[str, Preset] = {
    p.name: p
    for p in sorted(
        [
            Preset(
                "fivebar",
                build_fivebar,
                _frozen(),
                "classic RRRRR five-bar (plm_pin test mechanism)",
                2,
                2,
                "planar five-bar, 2 motors at the base, 2-DOF tip",
            ),
            Preset(
                "fourbar",
                build_fourbar,
                _frozen(),
                "classic crank-rocker four-bar (plm_pin test mechanism)",
                1,
                1,
                "planar crank-rocker four-bar, crank driven",
            ),
            Preset(
                "harada2011_3d3m",
                build_2prrrp,
                _frozen(**{**_HARADA2011, "legs": (1, 2, 4)}),
                "Harada 2011, Table 1, (M.36), eq. (5): 3D3M (slider 3 and rod 3 removed)",
                3,
                3,
                "planar xy-theta table, 3 linear motors on one stator (non-redundant)",
                _HARADA2011_NOTES,
            ),
            Preset(
                "harada2011_3d4m",
                build_2prrrp,
                _frozen(**_HARADA2011),
                "Harada 2011, Table 1, (M.36): 3D4M 2-PRRRP",
                3,
                4,
                "planar xy-theta table, 4 linear motors on one stator (1 redundant)",
                _HARADA2011_NOTES,
            ),
            Preset(
                "harada2015_asymmetric",
                build_2prrrp,
                _harada2015(),
                "Harada 2015, Fig. 2: asymmetric 2-PRRRP, l1 = l4 = 0.240 m, l2 = l3 = 0.170 m",
                3,
                4,
                "asymmetric 2-PRRRP for singularity-free mode changes (1 redundant)",
                (
                    "Only the rod lengths are given; r_t = 0.05 m, the moving-part and plate "
                    "masses and inertias are the 2011 prototype's (Table 1).",
                    "Rods: the 2011 rod's section and material, mass proportional to length and "
                    "centroidal inertia to mass x length^2 (9.84e-5 kg m^2 x (l / 0.14 m)^3).",
                    "Gravity 9.81 m/s^2 along -y; reference pose x = 0, y = 0.10 m, theta = 0, "
                    "assembly mode [+ +], working modes (- + - +).",
                ),
            ),
        ],
        key=lambda p: p.name,
    )
}


def preset_names() -> list[str]:
    """Names of every preset, sorted."""
    return sorted(PRESETS)


def urdf_folder() -> Path:
    """Folder holding the committed preset descriptions.

    Inside an installed wheel it is ``plm_pin/urdf``; in a source checkout it is the
    repository's top-level ``urdf/``.
    """
    here = Path(__file__).resolve().parent.parent
    for candidate in (here / "urdf", here.parent / "urdf"):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(f"preset descriptions not found next to {here}")
