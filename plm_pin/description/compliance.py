r"""The compliance model of a description: the sidecar's ``compliance`` section.

Springs the rigid description lacks, for the elastostatics of :mod:`plm_pin.stiffness`::

    compliance:
      source: assumed values, not from the paper   # optional provenance
      actuators:                 # drive stiffness along the actuated joint (ball screw + servo)
        slider1: 2.0e7           # [N/m] on a prismatic joint, [N m/rad] on a revolute one
      joints:                    # optional stiffness of passive one-DOF joints [N/m] or [N m/rad]
        rod1_pivot: 50.0
      links:                     # optional flexible links, as virtual joints (Pashkevich, Klimchik, Chablat)
        - link: rod2             # the URDF link (the body of one joint)
          tip: rod2_tip          # frame at the beam's far end; the beam runs from the link's joint to it
          E: 2.1e11              # Young's modulus [Pa]
          G: 8.1e10              # shear modulus [Pa]
          A: 1.0e-4              # cross-section area [m^2]
          Iy: 8.3e-10            # second moments of area about the section's y and z axes [m^4]
          Iz: 8.3e-10
          J: 1.4e-9              # torsion constant [m^4]
          y_axis: [0, 0, 1]      # optional: the section's y axis in the link frame
        - link: rod3
          tip: rod3_tip
          compliance: [[...6 rows of 6...]]   # or a 6x6 tip compliance, x along the beam

An actuator left out of ``actuators`` is rigid (its joint does not move under load). A
link's beam is an Euler-Bernoulli cantilever clamped at the link's joint: its tip
compliance, in the beam frame (x from the joint to the tip, y and z the section's axes),
relates the tip displacement and rotation ``(dx, dy, dz, rx, ry, rz)`` [m, rad] to a tip
force and moment ``(Fx, Fy, Fz, Mx, My, Mz)`` [N, N m]:

.. math::

    \delta_x = \frac{L}{EA} F_x, \quad
    \delta_y = \frac{L^3}{3 E I_z} F_y + \frac{L^2}{2 E I_z} M_z, \quad
    \theta_z = \frac{L^2}{2 E I_z} F_y + \frac{L}{E I_z} M_z, \quad
    \theta_x = \frac{L}{G J} M_x,

and likewise in z with :math:`I_y` (with the opposite sign of the coupling).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._arguments import repeated
from .._text import short
from ..exceptions import DescriptionError
from ..tolerances import AXIS_MIN, COMPLIANCE_SYMMETRY_RTOL
from ._numbers import positive_number

BEAM_KEYS: tuple[str, ...] = ("E", "G", "A", "Iy", "Iz", "J")
"""Section and material constants of a beam link: [Pa], [Pa], [m^2], [m^4], [m^4], [m^4]."""


@dataclass(frozen=True)
class BeamSpec:
    """A flexible link: an Euler-Bernoulli beam from the link's joint to its tip frame.

    Attributes:
        link: URDF link name (the body of one joint).
        tip: frame at the beam's far end (on the same body).
        section: ``(E [Pa], G [Pa], A [m^2], Iy [m^4], Iz [m^4], J [m^4])``, or None when
            ``compliance`` is given.
        compliance: 6x6 tip compliance in the beam frame, rows of ``(dx, dy, dz, rx, ry, rz)``
            [m, rad] per ``(Fx, Fy, Fz, Mx, My, Mz)`` [N, N m], or None.
        y_axis: the section's y axis in the link frame, or None (any normal to the beam).
    """

    link: str
    tip: str
    section: tuple[float, float, float, float, float, float] | None = None
    compliance: tuple[tuple[float, ...], ...] | None = None
    y_axis: tuple[float, float, float] | None = None

    def tip_compliance(self, length: float) -> np.ndarray:
        """The 6x6 tip compliance in the beam frame for a beam of ``length`` [m], shape (6, 6)."""
        if self.compliance is not None:
            return np.array(self.compliance, dtype=float)
        assert self.section is not None
        E, G, A, Iy, Iz, J = self.section
        L = length
        c = np.zeros((6, 6))
        c[0, 0] = L / (E * A)
        c[1, 1], c[1, 5], c[5, 5] = L**3 / (3 * E * Iz), L**2 / (2 * E * Iz), L / (E * Iz)
        c[2, 2], c[2, 4], c[4, 4] = L**3 / (3 * E * Iy), -(L**2) / (2 * E * Iy), L / (E * Iy)
        c[3, 3] = L / (G * J)
        c[5, 1], c[4, 2] = c[1, 5], c[2, 4]
        return c

    def to_dict(self) -> dict[str, Any]:
        """Plain data for YAML."""
        out: dict[str, Any] = {"link": self.link, "tip": self.tip}
        if self.section is not None:
            out.update({k: float(v) for k, v in zip(BEAM_KEYS, self.section, strict=True)})
        if self.compliance is not None:
            out["compliance"] = [[float(x) for x in row] for row in self.compliance]
        if self.y_axis is not None:
            out["y_axis"] = [float(a) for a in self.y_axis]
        return out


@dataclass(frozen=True)
class ComplianceSpec:
    """Springs of a mechanism: drives, passive joints and flexible links.

    Attributes:
        actuators: stiffness of each listed drive along its joint [N/m] or [N m/rad];
            unlisted drives are rigid.
        joints: stiffness of listed passive one-DOF joints [N/m] or [N m/rad].
        links: flexible links.
        source: provenance of the values (for instance "assumed").
    """

    actuators: Mapping[str, float] = field(default_factory=dict)
    joints: Mapping[str, float] = field(default_factory=dict)
    links: tuple[BeamSpec, ...] = ()
    source: str | None = None

    def __hash__(self) -> int:
        return hash((tuple(self.actuators.items()), tuple(self.joints.items()), self.links, self.source))

    def to_dict(self) -> dict[str, Any]:
        """Plain data for YAML."""
        out: dict[str, Any] = {}
        if self.source:
            out["source"] = self.source
        if self.actuators:
            out["actuators"] = {k: float(v) for k, v in self.actuators.items()}
        if self.joints:
            out["joints"] = {k: float(v) for k, v in self.joints.items()}
        if self.links:
            out["links"] = [b.to_dict() for b in self.links]
        return out


ASSUMED = "assumed values (the source gives no stiffness): drive stiffness only, links rigid"
"""Provenance written with the drive stiffness a preset assumes."""


def assumed_drive_stiffness(joints: Sequence[str], k: float | None) -> ComplianceSpec | None:
    """The compliance of a preset whose drives all have an assumed stiffness ``k`` [N/m or N m/rad].

    Returns None when ``k`` is None (a rigid description).
    """
    if k is None:
        return None
    return ComplianceSpec(actuators={j: float(k) for j in joints}, source=ASSUMED)


def _springs(raw: Any, where: str, path: str | None) -> dict[str, float]:
    if raw is None:
        return {}
    if not isinstance(raw, Mapping):
        raise DescriptionError(f"{where} must be a mapping of joint name to stiffness", path)
    return {str(k): positive_number(v, f"{where}.{k}", path) for k, v in raw.items()}


def _beam(item: Any, i: int, path: str | None) -> BeamSpec:
    where = f"compliance.links[{i}]"
    if not isinstance(item, Mapping):
        raise DescriptionError(f"{where} must be a mapping, got {short(item)}", path)
    allowed = ("link", "tip", "compliance", "y_axis", *BEAM_KEYS)
    unknown = sorted(set(item) - set(allowed), key=str)
    if unknown:
        raise DescriptionError(f"{where}: unknown key(s) {unknown}; valid keys are {sorted(allowed)}", path)
    names = []
    for key in ("link", "tip"):
        value = item.get(key)
        if not isinstance(value, str) or not value:
            raise DescriptionError(f"{where}.{key} must be a non-empty string, got {short(value)}", path)
        names.append(value)
    given = [k for k in BEAM_KEYS if k in item]
    section = compliance = None
    if "compliance" in item:
        if given:
            raise DescriptionError(
                f"{where}: give either 'compliance' or the section {list(BEAM_KEYS)}", path
            )
        try:
            c = np.array(item["compliance"], dtype=float)
        except (TypeError, ValueError):
            raise DescriptionError(f"{where}.compliance must be a 6x6 list of numbers", path) from None
        if c.shape != (6, 6) or not np.all(np.isfinite(c)):
            raise DescriptionError(
                f"{where}.compliance must be a 6x6 list of numbers, got shape {c.shape}", path
            )
        if (
            np.max(np.abs(c - c.T)) > COMPLIANCE_SYMMETRY_RTOL * np.max(np.abs(c))
            or np.linalg.eigvalsh(c).min() <= 0.0
        ):
            raise DescriptionError(f"{where}.compliance must be symmetric positive definite", path)
        compliance = tuple(tuple(float(x) for x in row) for row in c)
    else:
        missing = [k for k in BEAM_KEYS if k not in item]
        if missing:
            raise DescriptionError(
                f"{where}: missing {missing}; a beam needs {list(BEAM_KEYS)} or 'compliance'", path
            )
        s = [positive_number(item[k], f"{where}.{k}", path) for k in BEAM_KEYS]
        section = (s[0], s[1], s[2], s[3], s[4], s[5])
    y_axis = None
    if item.get("y_axis") is not None:
        raw = item["y_axis"]
        if not isinstance(raw, (list, tuple)) or len(raw) != 3:
            raise DescriptionError(f"{where}.y_axis must be a list of 3 numbers, got {short(raw)}", path)
        try:
            ax = np.array(raw, dtype=float)
        except (TypeError, ValueError):
            raise DescriptionError(
                f"{where}.y_axis must be a list of 3 numbers, got {short(raw)}", path
            ) from None
        norm = float(np.linalg.norm(ax))
        if not np.isfinite(norm) or norm < AXIS_MIN:
            raise DescriptionError(f"{where}.y_axis must be a non-zero vector, got {short(raw)}", path)
        y_axis = (float(ax[0] / norm), float(ax[1] / norm), float(ax[2] / norm))
    return BeamSpec(names[0], names[1], section, compliance, y_axis)


def parse_compliance(data: Any, path: str | None = None) -> ComplianceSpec | None:
    """Validate the sidecar's ``compliance`` section (None when absent).

    Raises:
        DescriptionError: naming the bad key or value and the valid choices.
    """
    if data is None:
        return None
    if not isinstance(data, Mapping):
        raise DescriptionError("'compliance' must be a mapping", path)
    allowed = ("source", "actuators", "joints", "links")
    unknown = sorted(set(data) - set(allowed), key=str)
    if unknown:
        raise DescriptionError(
            f"compliance: unknown key(s) {unknown}; valid keys are {sorted(allowed)}", path
        )
    links_raw = data.get("links") or []
    if not isinstance(links_raw, list):
        raise DescriptionError("compliance.links must be a list", path)
    links = tuple(_beam(b, i, path) for i, b in enumerate(links_raw))
    dup = repeated(b.link for b in links)
    if dup:
        raise DescriptionError(f"compliance.links: link(s) {dup} given twice", path)
    source = data.get("source")
    return ComplianceSpec(
        actuators=_springs(data.get("actuators"), "compliance.actuators", path),
        joints=_springs(data.get("joints"), "compliance.joints", path),
        links=links,
        source=str(source) if source is not None else None,
    )
