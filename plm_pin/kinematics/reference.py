r"""The reference configuration: where it is, in which modes, how far from singularities, and choosing one.

Every analysis starts from :attr:`~plm_pin.Mechanism.q_ref`: maps and singularity searches
keep its working mode, trajectories its assembly mode. The loader closes the loops from the
sidecar's ``reference`` (or, without one, from the neutral configuration), so a reference
left out, or a length mistyped in the description, can put it next to a singularity or far
from where its author meant. This module reports it (:func:`reference_report`, shown by
``plm-pin info`` and ``plm-pin check``), says what is wrong with it
(:func:`reference_findings`), and chooses one well inside the workspace when the sidecar
gives none and the neutral configuration closes next to a singularity
(:func:`choose_reference`, called by :func:`plm_pin.load`).

The *assembly mode* is labelled by the sign of :math:`\det(\partial x / \partial c)`
(:math:`T C^{-1}` of :mod:`plm_pin.kinematics.jacobians`): it changes where the path crosses
a direct (type 2) singularity, the boundary between assembly modes at fixed actuators.
"""

from __future__ import annotations

import itertools
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..core.diagnostics import Finding
from ..core.mechanism import Mechanism, joint_type
from ..exceptions import PlmError
from ..results import Result, unit
from ..tolerances import REFERENCE_MARGIN, REFERENCE_SHIFT_ANGLE, REFERENCE_SHIFT_RTOL
from ..warnings import ReferenceWarning
from .forward import forward_kinematics, task_pose
from .inverse import inverse_kinematics
from .jacobians import closed_chain_jacobians
from .limits import limit_violations
from .singularity import KINDS, classify
from .working_mode import working_mode

REFERENCE_STEPS = 40
"""Pattern-search steps of :func:`choose_reference`."""


@dataclass(frozen=True)
class ReferenceReport(Result):
    """The reference configuration as a user checks it.

    Attributes:
        q: the reference configuration, shape (nq,).
        pose: its task coordinates [m, rad] (empty without a task), shape (n_task,).
        working_mode: one sign per leg (empty when not defined: no square task).
        assembly_mode: sign of det(dx/dc) (0 when not defined: actuators not as many as DOF).
        margins: singularity margin of each kind (constraint, inverse, direct) [-]; empty when
            the task or the actuation is not square.
        shifts: joints the assembly moved from the sidecar's reference by more than
            :data:`REFERENCE_SHIFT_ANGLE` [rad] or :data:`REFERENCE_SHIFT_RTOL` of the size [m].
    """

    q: np.ndarray = field(metadata=unit("m, rad"))
    pose: np.ndarray = field(metadata=unit("m, rad"))
    working_mode: tuple[int, ...]
    assembly_mode: int
    margins: dict[str, float] = field(metadata=unit("-"))
    shifts: dict[str, float] = field(metadata=unit("m, rad"))

    @property
    def nearest(self) -> tuple[str, float] | None:
        """The kind of singularity the reference is closest to and its margin, or None."""
        if not self.margins:
            return None
        kind = min(self.margins, key=lambda k: self.margins[k])
        return kind, self.margins[kind]

    def describe(self, dofs: tuple[str, ...]) -> str:
        """One line: pose, working and assembly modes, nearest singularity."""
        parts = []
        if self.pose.size:
            parts.append("pose " + ", ".join(f"{d} = {v:.6g}" for d, v in zip(dofs, self.pose, strict=True)))
        if self.working_mode:
            parts.append(f"working mode {self.working_mode}")
        if self.assembly_mode:
            parts.append(f"assembly mode {'+' if self.assembly_mode > 0 else '-'}")
        near = self.nearest
        if near is not None:
            parts.append(f"nearest singularity {near[0]} at margin {near[1]:.3g}")
        return "; ".join(parts) if parts else "no task: no pose or modes"


def _square(mech: Mechanism) -> bool:
    """Whether the task has as many coordinates as DOF (margins and working modes are defined)."""
    task = mech.task_compiled
    return task is not None and task.size == mech.mobility


def reference_report(mech: Mechanism) -> ReferenceReport:
    """Pose, modes, singularity margins and shifts of the mechanism's reference configuration."""
    q = np.array(mech.q_ref)
    task = mech.task_compiled
    pose = np.zeros(0)
    mode: tuple[int, ...] = ()
    sign = 0
    margins: dict[str, float] = {}
    if task is not None:
        pose = task_pose(mech, q)
    if _square(mech):
        report = classify(mech, q)
        margins = dict(
            zip(KINDS, (report.constraint_margin, report.inverse_margin, report.direct_margin), strict=True)
        )
        mode = working_mode(mech, q)
        if mech.n_actuators == mech.mobility:
            jac = closed_chain_jacobians(mech, q)
            sign = int(np.sign(np.linalg.det(jac.T) * np.linalg.det(jac.C)))
    return ReferenceReport(q, pose, mode, sign, margins, _shifts(mech, q))


def _size(mech: Mechanism, q: np.ndarray) -> float:
    data = mech.model.createData()
    pin.forwardKinematics(mech.model, data, q)
    p = np.array([data.oMi[j].translation for j in range(mech.model.njoints)])
    return float(np.max(np.linalg.norm(p[:, None] - p[None], axis=-1), initial=0.0))


def _shifts(mech: Mechanism, q: np.ndarray) -> dict[str, float]:
    """Joints of the sidecar's reference that the assembly moved beyond the thresholds."""
    reference = mech.sidecar.reference
    if not reference:
        return {}
    guess = mech.reference_guess()
    dv = pin.difference(mech.model, guess, q)
    size = _size(mech, q)
    out = {}
    for name in reference:
        j = mech.model.joints[mech.model.getJointId(name)]
        move = float(np.linalg.norm(dv[j.idx_v : j.idx_v + j.nv]))
        prismatic = joint_type(mech.model, mech.model.getJointId(name)) == "prismatic"
        limit = REFERENCE_SHIFT_RTOL * size if prismatic else REFERENCE_SHIFT_ANGLE
        if move > limit:
            out[name] = move
    return out


def reference_findings(mech: Mechanism) -> tuple[Finding, ...]:
    """What ``plm-pin check`` says of the reference: where it is, and whether it is suspect.

    A note with the pose and modes; an error when the assembly moved joints far from the
    sidecar's reference (a mistyped length or reference); a note when the reference lies
    within :data:`REFERENCE_MARGIN` of a singularity.
    """
    try:
        rep = reference_report(mech)
    except PlmError as exc:  # a singular or ill-posed reference: say it, the other findings stand
        return (Finding("note", f"the reference configuration cannot be characterised: {exc}"),)
    dofs = mech.task.dofs if mech.task is not None else ()
    out = [Finding("note", f"reference: {rep.describe(dofs)}")]
    if rep.shifts:
        moved = ", ".join(f"{k} by {v:.3g}" for k, v in rep.shifts.items())
        out.append(
            Finding(
                "error",
                f"the loops closed far from the sidecar's reference: {moved} (m or rad); a length in the "
                "description or a reference value is likely mistyped, or the reference is in another "
                "assembly; write the intended values under `reference`",
            )
        )
    near = rep.nearest
    if near is not None and near[1] < REFERENCE_MARGIN:
        out.append(
            Finding(
                "note",
                f"the reference is near a singularity ({near[0]}, margin {near[1]:.3g} < "
                f"{REFERENCE_MARGIN}): maps and singularity searches start there and keep its modes; "
                "move `reference` inside the workspace",
            )
        )
    return tuple(out)


def singularity_margin(mech: Mechanism, q: np.ndarray) -> float | None:
    """The smallest singularity margin (constraint, inverse, direct) at an assembled ``q``, or None.

    None when the task has not as many coordinates as DOF (the margins are undefined).
    """
    if not _square(mech):
        return None
    report = classify(mech, q)
    return min(report.constraint_margin, report.inverse_margin, report.direct_margin)


def choose_reference(mech: Mechanism, iterations: int = REFERENCE_STEPS) -> tuple[np.ndarray, float] | None:
    """The reference moved inside the workspace, away from singularities, in its own modes; and its margin.

    A pattern search from :attr:`~plm_pin.Mechanism.q_ref`: each step tries the pose moved by
    plus or minus a step along each task coordinate and each actuator (see :func:`_neighbours`;
    solved from the current configuration, so the working mode and the assembly are kept: a
    parallelogram stays one; a leg singular at the start, sign 0, may take either sign) and
    moves to the one whose smallest singularity margin is largest; without progress the step
    halves. The steps start at 10 % of the mechanism's size [m] and 0.2 rad. Needs a task with
    as many coordinates as DOF.

    Returns:
        ``(q, margin)``, or None when the task is not square or the reference is singular.
    """
    if not _square(mech):
        return None
    task = mech.task_compiled
    assert task is not None  # _square(mech) holds
    q = np.array(mech.q_ref)
    try:
        margin = singularity_margin(mech, q)
    except PlmError:
        return None
    assert margin is not None
    mode = working_mode(mech, q)
    size = _size(mech, q)
    task_unit = np.where(np.isin(np.arange(task.size), task.angles), 0.2, 0.1 * size)
    actuator_unit = np.array([0.1 * size if a.kind == "prismatic" else 0.2 for a in mech.actuators])
    scale = 1.0
    for _ in range(iterations):
        best: tuple[np.ndarray, float] | None = None
        for candidate in _neighbours(mech, q, scale * task_unit, scale * actuator_unit):
            if candidate is None or not _same_mode(mode, working_mode(mech, candidate)):
                continue
            try:
                m = singularity_margin(mech, candidate)
            except PlmError:
                continue
            if m is not None and m > (margin if best is None else best[1]):
                best = (candidate, m)
        if best is None:
            scale /= 2.0
            if scale < 1e-3:
                break
            continue
        q, margin = best
        mode = working_mode(mech, q)
    return q, margin


def _neighbours(
    mech: Mechanism, q: np.ndarray, task_steps: np.ndarray, actuator_steps: np.ndarray
) -> list[np.ndarray | None]:
    """Configurations one step from ``q``, each task coordinate and each actuator moved.

    Task steps by inverse kinematics, actuator steps by forward kinematics (the same
    assembly), both from ``q``; None where a step cannot be solved or leaves the joint limits.

    Both kinds are needed: at an inverse singularity (a slider-crank at its dead centre) the
    task cannot move but the actuators can, at a direct singularity the other way round.
    """
    x = task_pose(mech, q)
    a = mech.actuator_positions(q)
    out: list[np.ndarray | None] = []
    for k, sign in itertools.product(range(x.size), (1.0, -1.0)):
        target = x.copy()
        target[k] += sign * task_steps[k]
        try:
            sol = inverse_kinematics(mech, target, q, explain=False)
            out.append(None if sol.limit_violations else np.array(sol.q))
        except PlmError:
            out.append(None)
    for k, sign in itertools.product(range(a.size), (1.0, -1.0)):
        moved = a.copy()
        moved[k] += sign * actuator_steps[k]
        try:
            (fk,) = forward_kinematics(mech, moved, q, all_modes=False)
            out.append(None if limit_violations(mech, fk.q) else np.array(fk.q))
        except PlmError:
            out.append(None)
    return out


def _same_mode(mode: tuple[int, ...], other: tuple[int, ...]) -> bool:
    """Whether ``other`` keeps ``mode``: equal signs where ``mode`` has one (a singular leg, 0, takes any)."""
    return all(a == 0 or a == b for a, b in zip(mode, other, strict=True))


def away_from_singularities(
    mech: Mechanism, rebuild: Callable[[dict[str, tuple[float, ...]]], Mechanism], name: str
) -> Mechanism:
    """``mech``, or its reference chosen again when the neutral one is near a singularity.

    When the reference closed from the neutral configuration lies within
    :data:`REFERENCE_MARGIN` of a singularity, the mechanism is
    built again (``rebuild``, given the sidecar ``reference`` entry) with the reference
    :func:`choose_reference` moves it to. The loader calls this for a description without a
    ``reference`` (see :data:`plm_pin.loading.REFERENCE_CHOOSER`).

    Warns with the reference chosen (pose, modes, margin) and the ``reference:`` entry that
    keeps it, or, when no move finds a larger margin, with where the reference is and how
    close to which singularity; keeps ``mech`` as it is when no square task allows the choice.
    """
    try:
        current = singularity_margin(mech, mech.q_ref)
    except PlmError:  # singular right there: choose
        current = 0.0
    if current is None or current >= REFERENCE_MARGIN:
        return mech
    chosen = choose_reference(mech)
    if chosen is None or chosen[1] <= current:
        warnings.warn(
            f"{name}: the sidecar gives no reference and the loops close from the neutral configuration "
            f"within {current:.3g} of a singularity, and no move of the task found a better one: "
            f"{reference_report(mech).describe(mech.task.dofs if mech.task is not None else ())}. "
            "Give a `reference:` in the sidecar inside the workspace",
            ReferenceWarning,
            stacklevel=3,
        )
        return mech
    q, margin = chosen
    reference: dict[str, tuple[float, ...]] = {}
    for jid in range(1, mech.model.njoints):
        j = mech.model.joints[jid]
        values = tuple(float(v) for v in q[j.idx_q : j.idx_q + j.nq])
        if j.nq == 2 and j.nv == 1:  # unbounded revolute: its angle
            values = (float(np.arctan2(values[1], values[0])),)
        reference[str(mech.model.names[jid])] = values
    out = rebuild(reference)
    report = reference_report(out)
    dofs = out.task.dofs if out.task is not None else ()
    entry = ", ".join(f"{k}: {v[0]:.6g}" if len(v) == 1 else f"{k}: {list(v)}" for k, v in reference.items())
    closeness = (
        f" (even so within {REFERENCE_MARGIN} of a singularity: the workspace may be small)"
        if margin < REFERENCE_MARGIN
        else ""
    )
    warnings.warn(
        f"{name}: the sidecar gives no reference and the loops close from the neutral configuration "
        f"within {current:.3g} of a singularity; moved it away, in the same working mode and assembly: "
        f"{report.describe(dofs)}{closeness}. "
        f"Keep it with `reference: {{{entry}}}`",
        ReferenceWarning,
        stacklevel=3,
    )
    return out
