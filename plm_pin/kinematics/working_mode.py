"""A mechanism's working mode at a configuration: the sign of each actuated leg's block.

The legs and the signs are defined in :mod:`plm_pin.core.legs`; this evaluates them on a
:class:`~plm_pin.Mechanism` at ``q``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import check_tolerance
from ..core.legs import structure_jacobian_from_data, working_mode_from_data
from ..core.mechanism import Mechanism, require_task
from ..tolerances import LEG_SINGULAR_RTOL


def structure_jacobian(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """:func:`~plm_pin.core.legs.structure_jacobian_from_data` at ``q``, shape (m + 6, nv)."""
    task = require_task(mech)
    pin.computeJointJacobians(mech.model, mech.data, q)
    pin.updateFramePlacements(mech.model, mech.data)
    return structure_jacobian_from_data(mech.model, mech.data, mech.closures, task)


def working_mode(mech: Mechanism, q: ArrayLike, rtol: float = LEG_SINGULAR_RTOL) -> tuple[int, ...]:
    """Sign (+1, -1, or 0 when singular) of each actuated leg block's determinant at ``q``.

    See :func:`~plm_pin.core.legs.working_mode_from_data`.

    Raises:
        InvalidInput: a malformed ``q`` or an ``rtol`` outside [0, 1).
    """
    rtol = check_tolerance(rtol, "rtol", relative=True)
    legs = mech.legs  # built first: building it must not come between the pass and its reading
    structure_jacobian(mech, mech.check_q(q))
    return working_mode_from_data(mech.model, mech.data, mech.closures, require_task(mech), legs, rtol)


def start_configuration(mech: Mechanism, guess: ArrayLike | None) -> np.ndarray:
    """The configuration an analysis starts from: ``guess`` (checked), or the reference one."""
    return mech.q_ref if guess is None else mech.check_q(guess, "guess")


def guess_mode(mech: Mechanism, guess: ArrayLike | None = None) -> tuple[int, ...] | None:
    """Working mode of ``guess`` (default: the reference configuration); None if a leg is singular there.

    Passed as ``mode`` to an analysis (a workspace map, a sweep) it keeps the analysis in the
    guess's working mode wherever its seed is.

    Raises:
        InvalidInput: a guess of the wrong size or not finite.
        ClosureNotSatisfied: without a guess, when the reference cannot be assembled.
    """
    mode = working_mode(mech, start_configuration(mech, guess))
    return None if 0 in mode else mode
