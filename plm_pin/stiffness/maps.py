"""Stiffness over a workspace slice: smallest translational eigen-stiffness, compliance, lowest frequency."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import real_numbers
from ..core.mechanism import Mechanism
from ..description.compliance import ComplianceSpec
from ..exceptions import AllocationInfeasible, InvalidInput, SingularConfiguration
from ..results import Result, unit, units
from ..workspace import WorkspaceSlice
from .cartesian import stiffness
from .vibration import natural_frequencies

_MEANINGS = {
    "min_translational_stiffness": "smallest eigen-stiffness under a pure force",
    "compliance_along": "displacement per unit force along the map's direction",
    "lowest_frequency": "lowest natural frequency from M_x and K_x",
}


@dataclass(frozen=True)
class StiffnessMap(Result):
    """Stiffness metrics at every reached point of a workspace slice (NaN elsewhere and where singular).

    Attributes:
        axes: the slice's varied task coordinates.
        values: their grid values [m, rad].
        reachable: points reached by the slice, shape ``shape``.
        direction: unit direction of ``compliance_along`` in the task's translation coordinates.
        min_translational_stiffness: [N/m], shape ``shape``.
        compliance_along: [m/N], shape ``shape``.
        lowest_frequency: [Hz], shape ``shape``.
    """

    axes: tuple[str, ...]
    values: tuple[np.ndarray, ...] = field(metadata=unit("m, rad"))
    reachable: np.ndarray
    direction: np.ndarray = field(metadata=unit("-"))
    min_translational_stiffness: np.ndarray = field(metadata=unit("N/m"))
    compliance_along: np.ndarray = field(metadata=unit("m/N"))
    lowest_frequency: np.ndarray = field(metadata=unit("Hz"))
    _NONFINITE_AS_TEXT = tuple(_MEANINGS)

    def variable(self, name: str) -> np.ndarray:
        """One of :data:`VARIABLES` by name.

        Raises:
            InvalidInput: an unknown name.
        """
        if not isinstance(name, str) or name not in VARIABLES:
            raise InvalidInput(f"unknown stiffness-map variable {name!r}; variables are {list(VARIABLES)}")
        return np.asarray(getattr(self, name))

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON (``'nan'`` where unreached), with the units of the variables."""
        return {**super().to_dict(), "units": {name: unit for name, (unit, _) in VARIABLES.items()}}


_UNITS = units(StiffnessMap)
VARIABLES: dict[str, tuple[str, str]] = {name: (_UNITS[name], doc) for name, doc in _MEANINGS.items()}
"""The variables of a stiffness map: unit (from the fields of :class:`StiffnessMap`) and meaning."""


def stiffness_map(
    mech: Mechanism,
    grid: WorkspaceSlice,
    *,
    direction: ArrayLike | None = None,
    gravity: bool = True,
    internal: ArrayLike | Mapping[str, float] | None = None,
    compliance: ComplianceSpec | None = None,
) -> StiffnessMap:
    """Stiffness metrics at the configurations of a workspace slice.

    Args:
        mech: the mechanism the slice was computed for.
        grid: a slice from :func:`plm_pin.workspace.workspace_map` (or ``workspace_grid``).
        direction: direction of ``compliance_along`` in the task's translation coordinates
            (default the first one, e.g. x).
        gravity: hold the bodies' weight (and include its geometric stiffness).
        internal: internal preload, as in :func:`plm_pin.statics.static_forces`.
        compliance: the springs; default the sidecar's.

    Raises:
        InvalidInput: a malformed direction, no compliance.
    """
    shape = grid.reachable.shape
    out = {name: np.full(shape, np.nan) for name in VARIABLES}
    n_lin = sum(1 for d in grid.dofs if not d.startswith("r"))
    u = (
        np.eye(n_lin)[0]
        if direction is None
        else np.asarray(real_numbers(direction, "direction"), dtype=float)
    )
    if u.shape != (n_lin,) or not np.all(np.isfinite(u)) or not np.any(u):
        raise InvalidInput(f"direction must be {n_lin} finite numbers, not all zero, got {direction!r}")
    u = u / np.linalg.norm(u)
    for index in zip(*np.nonzero(grid.reachable), strict=True):
        q = grid.q[index]
        try:
            res = stiffness(mech, q, gravity=gravity, internal=internal, compliance=compliance)
            vibration = natural_frequencies(mech, q, result=res)
        except (SingularConfiguration, AllocationInfeasible):
            continue
        out["min_translational_stiffness"][index] = res.min_translational
        out["compliance_along"][index] = res.compliance_along(u)
        out["lowest_frequency"][index] = vibration.lowest
    for arr in (*out.values(), u):
        arr.setflags(write=False)
    return StiffnessMap(
        tuple(grid.axes),
        tuple(grid.values),
        grid.reachable,
        u,
        out["min_translational_stiffness"],
        out["compliance_along"],
        out["lowest_frequency"],
    )
