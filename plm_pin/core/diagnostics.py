"""What ``plm-pin check`` says about a loaded mechanism beyond its files: DOF, task, limits."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from .mechanism import Mechanism


@dataclass(frozen=True)
class Finding:
    """One finding about a mechanism.

    Attributes:
        severity: ``"error"`` (analyses would refuse or be wrong: the check fails) or
            ``"note"`` (how the mechanism is read; the check passes).
        message: what was found and what it means, in one sentence or two.
    """

    severity: Literal["error", "note"]
    message: str


def mobility_text(mech: Mechanism) -> str:
    """The mobility, with its idle part apart: ``"2"`` or ``"2, 1 idle"``."""
    return f"{mech.mobility}" + (f", {mech.idle_mobility} idle" if mech.idle_mobility else "")


def findings(mech: Mechanism) -> tuple[Finding, ...]:
    """Idle mobilities, a task that does not match the DOF, under-actuation.

    Args:
        mech: the mechanism (its mobility is computed here).

    Returns:
        The findings, errors first.
    """
    out: list[Finding] = []
    task = mech.task
    if task is not None and len(task.dofs) != mech.mobility:
        few = len(task.dofs) < mech.mobility
        out.append(
            Finding(
                "error",
                f"the task {list(task.dofs)} has {len(task.dofs)} coordinates but the mechanism has "
                f"{mech.mobility} DOF: "
                + (
                    "a pose does not determine the configuration, so IK, FK, the Jacobians and "
                    "manipulability are undefined; add the missing coordinates to end_effector.task"
                    if few
                    else "the task coordinates are not independent, so the Jacobians and "
                    "manipulability are undefined; keep only independent coordinates in end_effector.task"
                ),
            )
        )
    if mech.idle_mobility:
        joints = [g.joint for g in mech.idle_gauges]
        out.append(
            Finding(
                "note",
                f"mobility {mobility_text(mech)}: {mech.idle_mobility} motion(s) move nothing else (a strut "
                "spinning about its own axis, a half-revolute pair turning together); joint(s) "
                f"{joints} are held at their reference values and every analysis runs on the "
                f"{mech.mobility} effective DOF",
            )
        )
    if mech.n_actuators < mech.mobility:
        out.append(
            Finding(
                "note",
                f"{mech.n_actuators} actuators for {mech.mobility} DOF: under-actuated, the actuators do "
                "not determine the configuration (forward kinematics refuses)",
            )
        )
    return tuple(sorted(out, key=lambda f: f.severity != "error"))
