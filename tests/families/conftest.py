"""Shared helpers of the tests of the mechanism families."""

from __future__ import annotations

import pinocchio as pin

from plm_pin.core.mechanism import Mechanism


def body_inertia(mech: Mechanism, joint: str) -> pin.Inertia:
    """The inertia of the body that ``joint`` carries."""
    return mech.model.inertias[mech.model.getJointId(joint)]
