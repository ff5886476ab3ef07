"""Mechanism families: one package per family, with its parametric builder and its own analyses.

- :mod:`plm_pin.families.prrrp`: 2-PRRRP planar tables on one stator (Harada 2011, 2015):
  builder, layout, assembly and working modes, mode-change planners, complex singularity.
- :mod:`plm_pin.families.pss`: n-PSS spatial platforms (Zhao 2011).
- :mod:`plm_pin.families.star_triangle`: 3-PRP star-triangle (Enferadi 2017).
- :mod:`plm_pin.families.classic`: four-bar and five-bar test mechanisms.

The named presets built from them are in :mod:`plm_pin.models`; the generic closed-chain
machinery they use is in :mod:`plm_pin.kinematics`.
"""

from .classic import (
    build_fivebar,
    build_fourbar,
)
from .prrrp import (
    ASSEMBLY_MODES,
    PAPER_ASSEMBLY_ROUTE,
    PAPER_WORKING_ROUTE,
    AssemblyModeChange,
    CoincidentCircleSample,
    ComplexSingularityCase,
    ModeCrossing,
    PairSolutions,
    PrrrpLayout,
    PrrrpLeg,
    PrrrpState,
    PrrrpSubMechanism,
    WorkingModeChange,
    assembly_mode,
    assembly_mode_graph,
    build_2prrrp,
    complex_singularity_check,
    leg_inverse_kinematics,
    mode_label,
    pair_solutions,
    paper_working_modes,
    plan_assembly_mode_change,
    plan_working_mode_change,
    prrrp_configuration,
    prrrp_layout,
    prrrp_state,
    working_mode_label,
)
from .pss import (
    build_pss,
    pss_inverse_kinematics,
)
from .star_triangle import (
    build_star_triangle,
    star_triangle_inverse_kinematics,
)

__all__ = [
    "ASSEMBLY_MODES",
    "PAPER_ASSEMBLY_ROUTE",
    "PAPER_WORKING_ROUTE",
    "AssemblyModeChange",
    "CoincidentCircleSample",
    "ComplexSingularityCase",
    "ModeCrossing",
    "PairSolutions",
    "PrrrpLayout",
    "PrrrpLeg",
    "PrrrpState",
    "PrrrpSubMechanism",
    "WorkingModeChange",
    "assembly_mode",
    "assembly_mode_graph",
    "build_2prrrp",
    "build_fivebar",
    "build_fourbar",
    "build_pss",
    "build_star_triangle",
    "complex_singularity_check",
    "leg_inverse_kinematics",
    "mode_label",
    "pair_solutions",
    "paper_working_modes",
    "plan_assembly_mode_change",
    "plan_working_mode_change",
    "prrrp_configuration",
    "prrrp_layout",
    "prrrp_state",
    "pss_inverse_kinematics",
    "star_triangle_inverse_kinematics",
    "working_mode_label",
]
