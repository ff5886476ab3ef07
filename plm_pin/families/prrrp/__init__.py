"""The 2-PRRRP family (Harada 2011, 2015): builder, layout, modes and mode-change planners.

- :mod:`~plm_pin.families.prrrp.builder`: :func:`build_2prrrp` and the closed-form leg IK.
- :mod:`~plm_pin.families.prrrp.layout`: :func:`prrrp_layout`, legs and plate pairs read from a model.
- :mod:`~plm_pin.families.prrrp.modes`: assembly and working modes, eq. (4) and eq. (6).
- :mod:`~plm_pin.families.prrrp.planners`: the mode-transition graph and the mode-change planners.
- :mod:`~plm_pin.families.prrrp.complex_singularity`: the complex singularity of equal rods.

A preset rebuilt with four equal rods: ``plm_pin.build_mechanism("harada2015_asymmetric",
symmetric_rods(0.240))``.

Each name is imported from its module on first use, so that building a preset (which needs the
builder alone) loads neither the planners nor the kinematics they use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._lazy import lazy_exports

if TYPE_CHECKING:
    from .builder import build_2prrrp, leg_inverse_kinematics, symmetric_rods
    from .complex_singularity import CoincidentCircleSample, ComplexSingularityCase, complex_singularity_check
    from .layout import PrrrpLayout, PrrrpLeg, PrrrpSubMechanism, prrrp_layout
    from .modes import (
        ASSEMBLY_MODES,
        PairSolutions,
        PrrrpState,
        assembly_mode,
        mode_label,
        pair_solutions,
        paper_working_modes,
        prrrp_configuration,
        prrrp_state,
        working_mode_label,
    )
    from .planners import (
        PAPER_ASSEMBLY_ROUTE,
        PAPER_WORKING_ROUTE,
        AssemblyModeChange,
        ModeCrossing,
        WorkingModeChange,
        assembly_mode_graph,
        plan_assembly_mode_change,
        plan_working_mode_change,
    )

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ASSEMBLY_MODES": ".modes",
        "AssemblyModeChange": ".planners",
        "CoincidentCircleSample": ".complex_singularity",
        "ComplexSingularityCase": ".complex_singularity",
        "ModeCrossing": ".planners",
        "PAPER_ASSEMBLY_ROUTE": ".planners",
        "PAPER_WORKING_ROUTE": ".planners",
        "PairSolutions": ".modes",
        "PrrrpLayout": ".layout",
        "PrrrpLeg": ".layout",
        "PrrrpState": ".modes",
        "PrrrpSubMechanism": ".layout",
        "WorkingModeChange": ".planners",
        "assembly_mode": ".modes",
        "assembly_mode_graph": ".planners",
        "build_2prrrp": ".builder",
        "complex_singularity_check": ".complex_singularity",
        "leg_inverse_kinematics": ".builder",
        "mode_label": ".modes",
        "pair_solutions": ".modes",
        "paper_working_modes": ".modes",
        "plan_assembly_mode_change": ".planners",
        "plan_working_mode_change": ".planners",
        "prrrp_configuration": ".modes",
        "prrrp_layout": ".layout",
        "prrrp_state": ".modes",
        "symmetric_rods": ".builder",
        "working_mode_label": ".modes",
    },
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
    "symmetric_rods",
    "working_mode_label",
]
