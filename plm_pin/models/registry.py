"""The registry of named presets: the papers' mechanisms, classic chains, textbook ones from leg types.

Each preset names its builder as a ``"module:function"`` string, imported when the preset is
built (:attr:`Preset.builder`), so the registry (read by :func:`plm_pin.load`) imports no
mechanism family nor :mod:`plm_pin.legs`: loading a shipped preset reads its committed URDF and
never runs a builder.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from .._lazy import import_object, lazy_module
from ..description.sidecar import Sidecar

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

Builder = Callable[..., "tuple[yourdfpy.Robot, Sidecar]"]


@dataclass(frozen=True)
class Preset:
    """A named mechanism with the parameters of its source.

    Attributes:
        name: preset name, as given to :func:`plm_pin.load`.
        builder_path: ``"module:function"`` of the parametric builder returning the URDF tree
            and the sidecar (imported by :attr:`builder`).
        parameters: keyword arguments of ``builder`` (SI units).
        source: the paper and the table or section the parameters come from.
        dof: mobility the mechanism must have.
        actuators: number of actuated joints.
        summary: one line describing the mechanism.
        notes: assumptions and values chosen where the source is silent.
    """

    name: str
    builder_path: str
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

    @property
    def builder(self) -> Builder:
        """The parametric builder, imported on first use."""
        builder: Builder = import_object(self.builder_path)
        return builder

    def build(self) -> tuple[yourdfpy.Robot, Sidecar]:
        """Run the builder with the preset's parameters."""
        return self.builder(name=self.name, source=self.source, **self.parameters)


def _frozen(**kwargs: Any) -> Mapping[str, Any]:
    return MappingProxyType(kwargs)


HARADA2011_DRIVE_STIFFNESS = 1.0e6
"""Assumed stiffness of each linear motor of the Harada 2011 tables [N/m] (the paper gives none)."""

ZHAO2011_DRIVE_STIFFNESS = 1.0e8
"""Assumed axial stiffness of each ball-screw drive of the Zhao 2011 platforms [N/m] (none in the paper)."""

HARADA2011_ROD = (0.140, 0.026, 9.84e-5)
"""The Harada 2011 rod (Table 1): length [m], mass [kg], inertia about the plane normal [kg m^2]."""


def rod_scaled(length: float, ref_length: float, ref_mass: float, ref_inertia: float) -> tuple[float, float]:
    """Mass [kg] and centroidal inertia [kg m^2] of a rod of the same section and material.

    Mass scales with length and the centroidal inertia with mass times length squared.
    """
    k = length / ref_length
    return ref_mass * k, ref_inertia * k**3


_PRRRP_LAYERS = (
    "Self-collision (ours; the papers show no layout): the carriages ride in one layer on the stator "
    "and collide when closer than their length (3 cm); each rod moves in a layer of its own above "
    "them and the plate above the rods, so rod-rod, rod-carriage and plate-carriage contacts of the "
    "planar drawing are not collisions (sidecar self_collision.ignore)."
)
"""The layers assumed by the 2-PRRRP builder's self-collision check, as a preset note."""

# Harada 2011, Table 1 and (M.36): l = 0.140 m, r_t = 0.05 m, rods 0.026 kg 9.84e-5 kg m^2,
# plate 0.132 kg 8.54e-4 kg m^2, moving parts 0.375 kg, g = 9.8 m/s^2 (M.37).
_HARADA2011 = dict(
    rod_lengths=(HARADA2011_ROD[0],) * 4,
    half_plate=0.05,
    slider_mass=0.375,
    rod_masses=(HARADA2011_ROD[1],) * 4,
    rod_inertias=(HARADA2011_ROD[2],) * 4,
    plate_mass=0.132,
    plate_inertia=8.54e-4,
    reference_pose=(0.0, 0.08, math.radians(-20.0)),
    working_modes=(-1, 1, -1, 1),
    gravity=9.8,
    actuator_stiffness=HARADA2011_DRIVE_STIFFNESS,
)
_HARADA2011_NOTES = (
    "Working modes (-, +, -, +) as in the code (M.5) and skeletons (M.42); the text after eq. (2) "
    "states the opposite signs.",
    "Reference pose x = 0, y = 0.08 m, theta = -20 deg: the initial state of simulations 1 and 2 "
    "as coded in (M.38) (Table 2 prints +20 deg).",
    "Rod and plate inertias are the table's values about the axis normal to the plane; the axial "
    "inertias (irrelevant in the plane) are those of a 5 mm radius bar and a 10 mm plate.",
    "No actuator force limits are given by the paper; none are set.",
    "No stiffness is given by the paper: each linear motor is assumed to hold its slider with "
    "1e6 N/m (a servo position loop of a small linear motor); rods and plate rigid.",
    _PRRRP_LAYERS,
)


def _harada2015() -> Mapping[str, Any]:
    lengths = (0.240, 0.170, 0.170, 0.240)
    scaled = [rod_scaled(l, *HARADA2011_ROD) for l in lengths]
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


# Zhao 2011, Tables 1-4 and section "Simulation" (m_p, inertias, I_L, I_C + I_M), eq. (19) (lead).
_ZHAO2011 = dict(
    legs=(1, 2, 3, 4, 5, 6, 7, 8),
    # Table 1: guide points B_1 .. B_8 (slider ball centre at q = 0), world frame [m]
    guide_points=(
        (0.4, -0.4, 0.0),
        (0.4, 0.4, 0.0),
        (-0.4, 0.4, 0.0),
        (-0.4, -0.4, 0.0),
        (0.4, -2.0, 1.5),
        (-0.4, -2.0, 1.5),
        (-2.0, -0.4, 1.5),
        (-2.0, 0.4, 1.5),
    ),
    # guide directions e_1 .. e_8: section "Description" and Tables 1-2 (plm_pin.families.pss.builder)
    guide_directions=(
        (0.0, 0.0, 1.0),
        (0.0, 0.0, 1.0),
        (0.0, 0.0, 1.0),
        (0.0, 0.0, 1.0),
        (0.0, 1.0, 0.0),
        (0.0, 1.0, 0.0),
        (1.0, 0.0, 0.0),
        (1.0, 0.0, 0.0),
    ),
    # Table 2: platform ball joints a_1 .. a_8 in the platform frame O'-uvw (centre of mass) [m]
    platform_points=(
        (0.4, -0.4, -0.166),
        (0.4, 0.4, -0.166),
        (-0.4, 0.4, -0.166),
        (-0.4, -0.4, -0.166),
        (0.4, -0.681, -0.0375),
        (-0.4, -0.681, -0.0375),
        (-0.681, -0.4, -0.0375),
        (-0.681, 0.4, -0.0375),
    ),
    strut_lengths=(1.0,) * 8,  # Table 3: l_i = |C_i A_i| [m]
    strut_mass=20.0,  # Table 4: m_i [kg]
    strut_inertia=(1.279, 1.279, 0.005),  # "Simulation": about its centre, z along the strut [kg m^2]
    platform_mass=200.0,  # "Simulation": m_p [kg]
    platform_inertia=(17.333, 17.333, 33.333),  # "Simulation": about its mass centre, O'-uvw [kg m^2]
    slider_mass=50.0,  # Table 4: m_qi [kg]
    lead=0.05,  # eq. (19): ball-screw lead p_i [m/rev] (printed "0.05 m^-1")
    screw_inertia=10.5e-4,  # "Simulation": lead-screw inertia I_Li [kg m^2]
    rotor_inertia=248e-4,  # "Simulation": coupler plus motor rotor I_Ci + I_Mi [kg m^2]
    # ours: the midpoint of the eq. (35) trajectory; the paper names no home pose
    home_pose=(0.0, 0.0, 1.744, 0.0, 0.0, 0.0),
    # along -z (sliders 1-4 "vertical to the ground", the platform above them); magnitude not
    # printed, 9.8 m/s^2 as the paper's a_max [m/s^2]
    gravity=(0.0, 0.0, -9.8),
    stroke=(0.0, 1.5),
    actuator_stiffness=ZHAO2011_DRIVE_STIFFNESS,
)

_ZHAO2011_6PSS_LEGS: tuple[int, ...] = (2, 3, 4, 5, 6, 7)
"""Legs kept by the 6-PSS counterpart (ours; the paper does not say): three vertical,
both y-sliders and one x-slider. Of the 28 six-leg subsets it has the smallest worst
condition number of J (eq. (6a)) along the eq. (35) trajectory, 4.85 (4.24 at home). Any
set keeping all four vertical legs is singular (their rows of J span only z, rx, ry)."""

_ZHAO2011_NOTES = (
    "Guides: sliders 1-4 along +z, 5-6 along +y, 7-8 along +x, q_i measured from B_i (Table 1); "
    "the text says 1-4 vertical, 5-8 horizontal and mutually orthogonal, Tables 1-2 fix which "
    "horizontal axis (the other cannot reach); root with the slider below / outside its platform joint.",
    "Reference pose x = y = 0, z = 1.744 m, angles 0: the midpoint of the eq. (35) trajectory "
    "(the paper names no home pose); R = Rz(phi_z) Ry(phi_y) Rx(phi_x), fixed axes.",
    "Slider ball joint replaced by a universal joint (massless cross, frame z along the guide). It "
    "slaves the strut's spin to its swing (up to 0.1 rad/s on eq. (35)), which the paper's S-S strut, "
    "transmitting no axial torque, never does (its omega is normal to the strut, eqs. (6b), (9)); so "
    "the tree's strut has axial moment 0 instead of 0.005 kg m^2, which makes the dynamics exactly "
    "the paper's (with 0.005 the motors would drive the spin: up to 5 mN, 2.4e-4 J of work per motor).",
    "Lead printed '0.05 m^-1' (eq. (19)), read 0.05 m/rev; armature per slider "
    "(2 pi / 0.05)^2 (10.5e-4 + 248e-4) = 408.21 kg.",
    "Gravity 9.8 m/s^2 along -z: direction from the vertical screws 1-4 below the platform, "
    "magnitude not printed (the paper's a_max = 9.8 m/s^2).",
    "Strut transverse inertia 1.279 kg m^2 about its centre kept as printed (a uniform "
    "1 m, 20 kg rod gives 1.667); slider inertia that of a 0.12 x 0.12 x 0.08 m box (it never "
    "rotates); stroke 0-1.5 m ours; no force limits given; d_i = 0.244 m enters no equation, unused.",
    "Table 5 (work per motor, sum 15242.219 J) is not reproduced by the paper's printed model "
    "(a literal re-implementation gives about 8479 J); quoted in the Zhao 2011 study only.",
    "No stiffness is given by the paper: each ball-screw drive (screw, nut, bearings, servo) is "
    "assumed to hold its slider with 1e8 N/m along the guide; struts and platform rigid.",
)


def _ring(
    radius: float, degrees: tuple[float, ...], z: float = 0.0
) -> tuple[tuple[float, float, float], ...]:
    """Points at ``degrees`` on a horizontal circle of ``radius`` [m] at height ``z`` [m]."""
    return tuple(
        (radius * math.cos(math.radians(a)) + 0.0, radius * math.sin(math.radians(a)) + 0.0, z)
        for a in degrees
    )


PRESETS: dict[str, Preset] = {
    p.name: p
    for p in sorted(
        [
            Preset(
                "enferadi2017_star_triangle",
                "plm_pin.families.star_triangle.builder:build_star_triangle",
                _frozen(
                    side=0.5,
                    slider_mass=2.0,
                    link_mass=3.0,
                    link_inertia=37.5,
                    star_mass=2.0,
                    star_inertia=25.0,
                    reference_pose=(0.25, 0.35, math.pi / 2),
                    gravity=9.81,
                ),
                "Enferadi & Tavakolian 2017, section 6: 3-PRP star-triangle, a = 0.5 m, m_a = 2 kg, "
                "m_il = 3 kg, m_p = 2 kg, I_il = 37.5 kg m^2, I_p = 25 kg m^2",
                3,
                3,
                "planar xy-theta machine tool, 3 sliders on an equilateral triangle, star end effector",
                (
                    "Figures missing: geometry rebuilt from Lambda_1-6 and eqs. (3)-(5); world origin at "
                    "vertex V1, x along side V1-V3 (rail 3), rails V1->V2, V2->V3, V3->V1.",
                    "Gamma_2 prints q1 cos/sin theta_1 for a1 cos/sin theta_1 (Lambda_3-4 and b_32 have "
                    "a1); Lambda_4 prints +q2 sin theta_2 where rail 2 descends (-q2 sin theta_2, "
                    "theta_2 = 60 deg is a magnitude).",
                    "alpha_2 in (24) is alpha_3 and theta_3 in (30) is theta_2 (same values); (24) I-III "
                    "masses are m_a + m_il; (31) swaps M and N; (7) orders the twist [phi, x, y], (24)-(34) "
                    "[x, y, phi].",
                    "I_il = 37.5 and I_p = 25 kg m^2 are kept as printed although implausible for 3 kg and "
                    "2 kg bodies on a 0.5 m base (perhaps kg cm^2); in-plane inertias are half of them.",
                    "Intermediate link mass centre on its revolute at A_i (zero leg length, eq. (20)); "
                    "slider inertia that of a 40 x 30 x 10 mm box (it never rotates).",
                    "Horizontal plane: gravity 9.81 m/s^2 along -z, no work. No actuator force limits given.",
                    "Reference pose: start of the vertical-line path, C = (0.25, 0.35) m, phi = pi/2.",
                ),
            ),
            Preset(
                "fivebar",
                "plm_pin.families.classic.builder:build_fivebar",
                _frozen(),
                "classic RRRRR five-bar (plm_pin test mechanism)",
                2,
                2,
                "planar five-bar, 2 motors at the base, 2-DOF tip",
            ),
            Preset(
                "fourbar",
                "plm_pin.families.classic.builder:build_fourbar",
                _frozen(),
                "classic crank-rocker four-bar (plm_pin test mechanism)",
                1,
                1,
                "planar crank-rocker four-bar, crank driven",
            ),
            Preset(
                "harada2011_3d3m",
                "plm_pin.families.prrrp.builder:build_2prrrp",
                _frozen(**{**_HARADA2011, "legs": (1, 2, 4)}),
                "Harada 2011, Table 1, (M.36), eq. (5): 3D3M (slider 3 and rod 3 removed)",
                3,
                3,
                "planar xy-theta table, 3 linear motors on one stator (non-redundant)",
                _HARADA2011_NOTES,
            ),
            Preset(
                "harada2011_3d4m",
                "plm_pin.families.prrrp.builder:build_2prrrp",
                _frozen(**_HARADA2011),
                "Harada 2011, Table 1, (M.36): 3D4M 2-PRRRP",
                3,
                4,
                "planar xy-theta table, 4 linear motors on one stator (1 redundant)",
                _HARADA2011_NOTES,
            ),
            Preset(
                "harada2015_asymmetric",
                "plm_pin.families.prrrp.builder:build_2prrrp",
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
                    _PRRRP_LAYERS,
                ),
            ),
            Preset(
                "delta",
                "plm_pin.legs.delta:build_delta",
                _frozen(
                    base=_ring(0.20, (0.0, 120.0, 240.0)),
                    platform=_ring(0.05, (0.0, 120.0, 240.0)),
                    arm=0.30,
                    forearm=0.60,
                    width=0.08,
                    pose=(0.0, 0.0, -0.50),
                    density=0.5,
                    platform_mass=0.3,
                ),
                "plm_pin: a Clavel Delta built from leg types (plm_pin.legs.delta)",
                3,
                3,
                "spatial Delta, 3 driven arms and 3 parallelograms (6 ball-ended rods), x-y-z platform",
                (
                    "Dimensions ours (a textbook Delta): pivots on a 0.20 m circle, platform points on "
                    "0.05 m, arms 0.30 m, rods 0.60 m, parallelograms 0.08 m wide; reference 0.50 m below "
                    "the base.",
                    "Rods and arms 0.5 kg/m, platform 0.3 kg; no torque limits.",
                ),
            ),
            Preset(
                "planar_3rpr",
                "plm_pin.legs.planar:build_planar",
                _frozen(
                    leg="RPR",
                    base=tuple((x, y) for x, y, _ in _ring(0.30, (90.0, 210.0, 330.0))),
                    platform=tuple((x, y) for x, y, _ in _ring(0.15, (30.0, 150.0, 270.0))),
                    pose=(0.0, 0.0, 0.0),
                    stroke=(0.10, 0.40),
                    density=1.0,
                    platform_mass=1.0,
                    gravity=(0.0, 0.0, -9.81),
                ),
                "plm_pin: a planar 3-RPR built from leg types (plm_pin.legs.planar)",
                3,
                3,
                "planar 3-RPR, 3 driven cylinders between a base and a platform triangle, x-y-rz platform",
                (
                    "Dimensions ours: base hinges on a 0.30 m circle at 90, 210 and 330 deg, platform "
                    "hinges on 0.15 m at 30, 150 and 270 deg (turned by 60 deg: with both triangles alike "
                    "the legs of the centred pose meet in the centre, a direct singularity); cylinders "
                    "0.10-0.40 m.",
                    "Horizontal plane (gravity along -z); cylinders 1 kg/m, platform 1 kg; no force limits.",
                ),
            ),
            Preset(
                "stewart_6ups",
                "plm_pin.legs.hexapod:build_hexapod",
                _frozen(
                    leg="UPS",
                    base=_ring(0.50, (-10.0, 10.0, 110.0, 130.0, 230.0, 250.0)),
                    platform=_ring(0.30, (-50.0, 50.0, 70.0, 170.0, 190.0, 290.0)),
                    pose=(0.0, 0.0, 0.80, 0.0, 0.0, 0.0),
                    stroke=(0.50, 1.20),
                    density=2.0,
                    platform_mass=5.0,
                ),
                "plm_pin: a Gough-Stewart 6-UPS built from leg types (plm_pin.legs.hexapod)",
                6,
                6,
                "spatial Gough-Stewart platform, 6 driven legs (universal joint, cylinder, ball)",
                (
                    "Dimensions ours (a textbook 6-6 platform): base joints on a 0.50 m circle in pairs "
                    "20 deg apart, platform joints on 0.30 m, offset by 60 deg; reference 0.80 m above the "
                    "base, level; legs 0.50-1.20 m.",
                    "Cylinders and pistons 2 kg/m, platform 5 kg; no force limits.",
                ),
            ),
            Preset(
                "zhao2011_6pss",
                "plm_pin.families.pss.builder:build_pss",
                _frozen(**{**_ZHAO2011, "legs": _ZHAO2011_6PSS_LEGS}),
                "Zhao 2011, Tables 1-4, section 'Simulation', eq. (19): 8-PSS without legs 1 and 8",
                6,
                6,
                "spatial 6-PSS counterpart: legs 2-7 of the 8-PSS, 6 ball-screw sliders (non-redundant)",
                (
                    "Legs {2, 3, 4, 5, 6, 7} kept (ours: the paper only names a 6-PSS counterpart): three "
                    "vertical legs, both y-sliders and one x-slider; of the 28 six-leg subsets, the smallest "
                    "worst condition number of J (eq. (6a)) along the eq. (35) trajectory (4.85; 4.24 at "
                    "home); every subset keeping all four vertical legs (legs 1-6 among them) is singular.",
                    *_ZHAO2011_NOTES,
                ),
            ),
            Preset(
                "zhao2011_8pss",
                "plm_pin.families.pss.builder:build_pss",
                _frozen(**_ZHAO2011),
                "Zhao 2011, Tables 1-4, section 'Simulation', eq. (19): redundant 8-PSS",
                6,
                8,
                "spatial 8-PSS motion platform, 8 ball-screw sliders on three orthogonal axes (2 redundant)",
                _ZHAO2011_NOTES,
            ),
        ],
        key=lambda p: p.name,
    )
}


BUILDER_RESERVED = ("name", "source")
"""Builder arguments that label a description rather than shape it (never swept or overridden)."""


def builder_parameters(builder: Builder) -> tuple[str, ...]:
    """Names of the keyword parameters a builder takes, :data:`BUILDER_RESERVED` excluded, in order.

    A builder that lists its parameters itself (a ``parameters`` attribute, as
    :class:`plm_pin.description.overrides.DescriptionBuilder`) gives that list.
    """
    listed = getattr(builder, "parameters", None)
    if isinstance(listed, tuple):
        return listed
    kinds = (inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    return tuple(
        name
        for name, p in inspect.signature(builder).parameters.items()
        if p.kind in kinds and name not in BUILDER_RESERVED
    )


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
