"""The overview study: mobility, workspace slice, statics, decoupling, motion and 3D view of any mechanism.

The library's own study (the paper studies are in the checkout's ``analyses/``), so that an
installed wheel writes the report of any description: ``plm-pin report overview --mechanism
path/to/robot.urdf`` (or ``plm-pin report path/to/robot.urdf``); ``plm-pin report all`` runs it
on :data:`MECHANISM`.

It reads the context's :class:`~plm_pin.report.study.StudyCase` (``plm-pin report NAME --load
fx,fy,mz --pose x=..,y=.. --mode +,- --x a:b:n --y a:b:n``): the statics, stiffness and
simulation take the load, every section the pose and working mode, the slice the ranges.
"""

from __future__ import annotations

import itertools
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from ..core.mechanism import Mechanism
from ..description.sidecar import TASK_DOFS
from ..dynamics import SimulationResult, decoupling_check, simulate
from ..exceptions import InvalidInput, PlmError, SimulationFailed, SingularConfiguration
from ..kinematics import classify, forward_kinematics, inverse_kinematics, task_pose
from ..kinematics.collisions import self_collisions
from ..kinematics.inverse import check_mode
from ..loading import load
from ..results import units
from ..statics import StaticForces, actuator_limits, internal_force_range, static_forces, transmission
from ..stiffness import StiffnessResult, natural_frequencies, stiffness, stiffness_map
from ..viz import (
    MeshcatViewer,
    force_arrows,
    plot_map,
    plot_panels,
    plot_static_forces,
    plot_stiffness_map,
    plot_sweep,
)
from ..workspace import (
    SingularPoint,
    WorkspaceSlice,
    manipulability,
    manipulability_unit,
    singular_loci,
    workspace_map,
    workspace_sweep,
)
from .animation import Animation
from .content import Column, Section
from .study import StudyCase, StudyContext

TITLE = "Overview"
SUMMARY = (
    "Mobility, redundancy, a workspace slice, statics with the internal-force range, decoupling, "
    "a short simulation and a 3D view."
)
MECHANISM = "harada2011_3d4m"
TAKES_CASE = True

_K = units(StiffnessResult)
"""Units of the stiffness results' fields (eigen-stiffnesses: ``translational``, ``rotational``)."""

ANGLE_SPAN = np.radians(30.0)
"""Half-width of the slice along an angle [rad]."""

LENGTH_SPAN = 0.25
"""Half-width of the slice along a translation, as a fraction of the mechanism's extent [-]."""

GRID = 41
"""Samples per slice axis."""

LOCI_LINES = 11
"""Lines of the slice searched for singular points."""

DECOUPLING_POSES = 6
"""Poses per slice axis in the decoupling sample (taken from the slice's reachable points)."""

SIMULATION_TIME = 1.0
"""Length of the passive simulation [s]."""

SIMULATION_DT = 0.005
"""Output step of the passive simulation [s] (samples of simulate's default DOP853 run)."""


def _is_angle(mech: Mechanism, dof: str) -> bool:
    """Whether task coordinate ``dof`` is an angle: a rotation direction, or a revolute output joint."""
    task = mech.task_compiled
    if task is not None and mech.task is not None and mech.task.frame is None:
        return task.dofs.index(dof) in task.angles
    return dof.startswith("r")


def _display(mech: Mechanism, dof: str, value: float) -> tuple[float, str]:
    """A task coordinate in report units: degrees for angles (said so), metres otherwise."""
    return (float(np.degrees(value)), "deg") if _is_angle(mech, dof) else (float(value), "m")


NEEDS_SQUARE_TASK = (
    "{what}: it needs a task (`end_effector` in the sidecar) with as many coordinates as the "
    "mechanism has degrees of freedom."
)


def _frame_origins(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """World positions of every frame [m], shape (n_frames, 3)."""
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    return np.array([M.translation for M in data.oMf])


def passive_motion(
    mech: Mechanism, q: np.ndarray | None = None, wrench: np.ndarray | None = None
) -> tuple[SimulationResult, SimulationFailed | None]:
    """The mechanism released at rest, actuators free, under gravity and a constant load.

    Args:
        mech: the mechanism.
        q: where it starts (default: the reference configuration).
        wrench: the load, one value per task coordinate [N, N m] (default: none).

    Returns:
        The samples (up to the failure, if any) and the failure (None when the run completed).
    """
    start = mech.q_ref if q is None else q
    try:
        return simulate(mech, start, duration=SIMULATION_TIME, dt=SIMULATION_DT, wrench=wrench), None
    except SimulationFailed as exc:
        if not isinstance(exc.partial, SimulationResult):
            raise PlmError(f"{mech.name}: the failed simulation carries no samples ({exc})") from exc
        return exc.partial, exc


def _passive_animation(target: str) -> Animation:
    mech = load(target)
    run, _ = passive_motion(mech)
    return Animation(mech, run.q, run.t, f"{mech.name} released at rest under gravity, actuators free")


ANIMATIONS = {"simulation": _passive_animation}
"""The passive simulation, for ``plm-pin view NAME|PATH --animate overview:simulation``."""


@dataclass(frozen=True)
class OverviewCase:
    """A :class:`~plm_pin.report.study.StudyCase` checked against the mechanism.

    Attributes:
        q: the configuration studied, shape (nq,).
        where: how the report names it ("the reference configuration", or the pose and mode).
        wrench: the load, one value per task coordinate [N, N m], or None.
        mode: the working mode the slice keeps (None: that of ``q``).
        ranges: the slice's values per varied task coordinate [m, rad] (empty: the default slice).
    """

    q: np.ndarray
    where: str
    wrench: np.ndarray | None
    mode: tuple[int, ...] | None
    ranges: dict[str, np.ndarray]

    @property
    def at_reference(self) -> bool:
        """Whether the configuration studied is the reference one."""
        return self.where == REFERENCE


REFERENCE = "the reference configuration"
"""How the report names the configuration studied when no pose or mode is asked for."""


def load_names(mech: Mechanism) -> list[str]:
    """Names of the load's entries: ``fx fy fz mx my mz`` for a frame task's coordinates, else the joints."""
    if mech.task is None:
        return []
    if mech.task.frame is None:
        return list(mech.task.dofs)
    return [("m" if d.startswith("r") else "f") + d[-1] for d in mech.task.dofs]


_solved: weakref.WeakKeyDictionary[Mechanism, tuple[tuple[Any, ...], OverviewCase]] = (
    weakref.WeakKeyDictionary()
)
"""The last case solved for each mechanism, with its key: the shell checks a case, then the study reads it."""


def overview_case(mech: Mechanism, case: StudyCase) -> OverviewCase:
    """Check ``case`` against ``mech`` and solve its pose (inverse kinematics in its working mode).

    The answer is kept for ``mech`` (while it lives): asked again for the same case, the
    pose is not solved again.

    Raises:
        InvalidInput: a load of the wrong size, unknown pose or slice coordinates, more than two
            varied coordinates, a malformed working mode, or a case given to a mechanism without task.
        PoseUnreachable: a pose the inverse kinematics cannot reach (in the working mode).
    """
    key = (
        case.load,
        tuple(sorted(case.pose.items())),
        case.mode,
        tuple(sorted((name, tuple(v)) for name, v in case.ranges.items())),
    )
    kept = _solved.get(mech)
    if kept is not None and kept[0] == key:
        return kept[1]
    checked = _check_case(mech, case)
    _solved[mech] = (key, checked)
    return checked


def _check_case(mech: Mechanism, case: StudyCase) -> OverviewCase:
    dofs = tuple(mech.task.dofs) if mech.task is not None else ()
    if not dofs and not case.empty:
        raise InvalidInput(
            f"{mech.name} has no task (`end_effector` in its sidecar): --load, --pose, --mode and slice "
            "ranges need one"
        )
    wrench = None
    if case.load is not None:
        wrench = np.asarray(case.load, dtype=float)
        if wrench.shape != (len(dofs),) or not np.all(np.isfinite(wrench)):
            raise InvalidInput(
                f"--load: give {len(dofs)} finite numbers, one per task coordinate "
                f"({','.join(load_names(mech))}) [N, N m], got {list(case.load)}"
            )
    slices = ((f"--{n}" if n in TASK_DOFS else f"--over {n}", n) for n in case.ranges)
    for option, name in (*(("--pose", n) for n in case.pose), *slices):
        if name not in dofs:
            raise InvalidInput(
                f"{option}: {name!r} is not a task coordinate of {mech.name}; they are {list(dofs)}"
            )
    if len(case.ranges) > 2:
        raise InvalidInput(f"the slice varies one or two task coordinates; got {list(case.ranges)}")
    try:
        mode = check_mode(mech, case.mode)
    except InvalidInput as exc:
        raise InvalidInput(f"--{exc}") from None
    q, where = mech.q_ref, REFERENCE
    if case.pose or mode is not None:
        x = task_pose(mech, mech.q_ref)
        for name, value in case.pose.items():
            x[dofs.index(name)] = value
        q = np.array(inverse_kinematics(mech, x, mode=mode).q)
        where = "the pose " + ", ".join(
            f"{d} = {value:.6g} {unit}"
            for d, v in zip(dofs, x, strict=True)
            for value, unit in [_display(mech, d, v)]
        )
        if mode is not None:
            where += " in working mode " + ",".join("+" if m > 0 else "-" for m in mode)
    ranges = {d: np.asarray(case.ranges[d], dtype=float) for d in dofs if d in case.ranges}
    return OverviewCase(q, where, wrench, mode, ranges)


def run(ctx: StudyContext) -> None:
    """Fill the overview report of ``ctx.target`` in the case ``ctx.case``."""
    mech = ctx.load()
    case = overview_case(mech, ctx.case)
    where = "the reference" if case.at_reference else "the pose"
    ctx.step(f"{mech.name}: mobility and singularity at {where}")
    square = mech.task is not None and len(mech.task.dofs) == mech.mobility
    _mobility(ctx.section("Mobility and redundancy"), mech, square, case)
    section = ctx.section("Workspace slice: manipulability and singularities")
    grid: WorkspaceSlice | None = None
    loci: list[SingularPoint] = []
    if square:
        ctx.step(f"{mech.name}: workspace slice")
        grid, loci = _workspace(section, mech, case)
    else:
        section.text(NEEDS_SQUARE_TASK.format(what="No workspace slice"))
    ctx.step(f"{mech.name}: static forces at {where}")
    forces = _statics(ctx.section(f"Static forces at {case.where}"), mech, case)
    section = ctx.section("Task-space dynamics and decoupling")
    if grid is not None:
        ctx.step(f"{mech.name}: decoupling")
        _decoupling(section, mech, grid)
    else:
        section.text(NEEDS_SQUARE_TASK.format(what="No decoupling check"))
    ctx.step(f"{mech.name}: stiffness")
    _stiffness(ctx.section("Stiffness and natural frequencies"), mech, grid, case)
    ctx.step(f"{mech.name}: passive simulation")
    title = "released under gravity" + ("" if case.wrench is None else " and the load")
    _simulation(ctx.section(f"Short simulation: {title}"), mech, case)
    ctx.step(f"{mech.name}: 3D scene")
    _scene(ctx.section("3D view"), mech, forces, case, grid, loci)


def _mobility(section: Section, mech: Mechanism, square: bool, case: OverviewCase) -> None:
    section.text(
        "Mobility is the dimension of the closure Jacobian's null space at a generic assembled "
        "configuration (`nv - rank J_phi`, SVD rank cut at the largest gap of the singular values, "
        "above the description's closure tolerance); redundancy is the number of actuators beyond it. "
        "The singularity margins are normalised smallest singular values (0 at a singularity): "
        "*constraint* for the closures, *inverse* (type 1) for `T = J_x N`, *direct* (type 2) for "
        "`C = S_a N`."
    )
    q = case.q
    at = "the reference" if case.at_reference else "the pose"
    rank = mech.closure_rank(q)
    rows: list[tuple[str, object, str]] = [
        ("configuration size nq", mech.nq, ""),
        ("velocity size nv", mech.nv, ""),
        ("closure rows", mech.n_closure_rows, ""),
        (f"rank of J_phi at {at}", rank, ""),
        ("closure tolerance", mech.closure_tol, "m, rad"),
        (
            "singular values around the rank cut",
            f"{mech.rank_gap.above:.3g} | {mech.rank_gap.below:.3g}" if mech.closures else "no closures",
            "",
        ),
        ("mobility (DOF)", mech.mobility, ""),
        ("actuators", mech.n_actuators, ""),
        ("redundancy", mech.redundancy, ""),
    ]
    if square:
        report = classify(mech, q)
        m = manipulability(mech, q)
        rows += [
            ("constraint margin", report.constraint_margin, "-"),
            ("inverse (type 1) margin", report.inverse_margin, "-"),
            ("direct (type 2) margin", report.direct_margin, "-"),
            (f"singular at {at}", report.singular, ""),
            ("manipulability w", m.w, manipulability_unit(mech)),
            ("condition number of J_ce", m.condition_number, "-"),
        ]
    section.table(f"Sizes, ranks and margins at {at}", ["quantity", "value", "unit"], rows, id="sizes")
    if mech.task is not None:
        x = task_pose(mech, q)
        joints = mech.task.frame is None
        kind = "Reference" if case.at_reference else "Studied"
        section.table(
            f"{kind} positions of the output joints (the task)"
            if joints
            else f"{kind} pose of the task frame {mech.task.frame}",
            ["coordinate", Column("value", fmt=".6g"), "unit"],
            [(dof, *_display(mech, dof, v)) for dof, v in zip(mech.task.dofs, x, strict=True)],
            note=(
                (
                    "Revolute joint angles, shown in degrees."
                    if joints
                    else "Angles are roll-pitch-yaw (R = Rz Ry Rx), shown in degrees."
                )
                if any(_is_angle(mech, dof) for dof in mech.task.dofs)
                else ""
            ),
        )
    if mech.task is not None:
        _assembly_modes(section, mech)
    if square and mech.n_actuators == mech.mobility:
        _transmission(section, mech, q, at)


def _assembly_modes(section: Section, mech: Mechanism) -> None:
    """Every assembly mode at the reference's actuator values, with the search's certificate."""
    assert mech.task is not None
    modes = forward_kinematics(mech, mech.actuator_positions(mech.q_ref), all_modes=True)
    how = (
        "parameter homotopy from the generic solve, each real mode proven by a Krawczyk interval test"
        if modes.method == "homotopy"
        else "multi-start Newton (no polynomial form), which cannot prove that none was missed"
    )
    section.text(
        f"Forward kinematics at the reference's actuator values: {modes.headline()}. Found by {how}; "
        "see the complete forward kinematics guide for what *certified* proves and assumes."
    )
    dofs = mech.task.dofs
    units = [_display(mech, dof, 0.0)[1] for dof in dofs]
    section.table(
        f"Assembly modes at the reference actuator values: {modes.headline()}",
        [
            "mode",
            *(Column(d, u, fmt=".6g") for d, u in zip(dofs, units, strict=True)),
            Column("closure residual", "m, rad", fmt=".1e"),
            "certificate",
        ],
        [
            (
                i + 1,
                *(_display(mech, d, v)[0] for d, v in zip(dofs, s.x, strict=True)),
                s.residual_norm,
                "Krawczyk" if s.certified else "none",
            )
            for i, s in enumerate(modes)
        ],
        id="assembly-modes",
    )


def _transmission(section: Section, mech: Mechanism, q: np.ndarray, at: str) -> None:
    """The transmission ratio, mechanical advantage and transmission indices at ``q`` (``at``: its name)."""
    try:
        t = transmission(mech, q)
    except SingularConfiguration as exc:
        section.text(f"No transmission at {at}: {exc}")
        return
    rows: list[tuple[str, str, float]] = []
    for i, dof in enumerate(t.dofs):
        for j, act in enumerate(t.actuators):
            rows.append((f"d {dof} / d {act}", "ratio", float(t.ratio[i, j])))
            rows.append(
                (f"{dof} force per {act} force", "mechanical advantage", float(t.mechanical_advantage[i, j]))
            )
    for name, index in t.transmission_index.items():
        for dof, value in zip(t.dofs, index, strict=True):
            rows.append((f"closure {name}, motion of {dof}", "transmission index", float(value)))
    section.table(
        f"Transmission at {at}",
        ["quantity", "kind", Column("value", fmt=".6g")],
        rows,
        id="transmission",
        note="Ratio: task rate per actuator rate; mechanical advantage: task force (torque) delivered per "
        "actuator force (torque), from the static balance; transmission index: |cos| of the angle between "
        "a closure's force and its motion (a four-bar: sin of the transmission angle; 0: dead centre).",
    )


def _workspace(
    section: Section, mech: Mechanism, case: OverviewCase
) -> tuple[WorkspaceSlice, list[SingularPoint]]:
    assert mech.task is not None
    dofs = mech.task.dofs
    x0 = task_pose(mech, case.q)
    if case.ranges:
        axes = tuple(case.ranges)
        values = list(case.ranges.values())
        around = "over the ranges asked for"
    else:
        axes = ("x", "y") if {"x", "y"} <= set(dofs) else tuple(dofs[:2])
        extent = float(np.max(np.ptp(_frame_origins(mech, case.q), axis=0)))
        values = []
        for a in axes:
            half = ANGLE_SPAN if _is_angle(mech, a) else LENGTH_SPAN * extent
            centre = x0[dofs.index(a)]
            values.append(np.linspace(centre - half, centre + half, GRID))
        around = "around the reference pose" if case.at_reference else "around the pose studied"
    kept = "of the reference" if case.at_reference else "of the pose studied"
    section.text(
        f"The slice varies {' and '.join(f'`{a}`' for a in axes)} {around}, the other task coordinates "
        f"fixed at {'the reference' if case.at_reference else 'the pose studied'}. Each point is solved by "
        f"inverse-kinematics continuation from its neighbours, keeping the working mode {kept}; blank "
        "points are not reachable in that mode. Singular points are located by root finding along lines "
        "of the slice."
    )
    mode = case.mode
    if len(axes) == 1:
        sweep = workspace_sweep(mech, axes[0], values[0], x0, guess=case.q, mode=mode)
        fig = plot_sweep(sweep, "manipulability", log=True, title=f"{mech.name}: manipulability")
        section.figure(fig, f"Manipulability along {axes[0]}.", {"slice": sweep.to_dict()})
        grid = sweep
        loci = []
    else:
        grid = workspace_map(mech, (axes[0], axes[1]), (values[0], values[1]), x0, guess=case.q, mode=mode)
        across = [float(v) for v in values[1][:: max(1, (values[1].size - 1) // (LOCI_LINES - 1))]]
        loci = singular_loci(mech, axes[0], values[0], axes[1], across, x0, guess=case.q, mode=mode)
        import matplotlib.pyplot as plt

        fig, (left, right) = plt.subplots(1, 2, figsize=(11.0, 4.5), layout="constrained")
        plot_map(grid, "manipulability", loci=loci, ax=left, log=True)
        plot_map(grid, "direct_margin", loci=loci, ax=right)
        section.figure(
            fig,
            "Manipulability (left, logarithmic colours) and direct-singularity margin (right) over the "
            "slice; markers are singular points found along its lines.",
            {"slice": grid.to_dict(), "singular_points": [p.to_dict() for p in loci]},
        )
    reached = grid.reachable
    w = grid.manipulability[reached]
    w_unit = manipulability_unit(mech)
    section.table(
        "Slice summary",
        ["quantity", "value", "unit"],
        [
            ("grid points", int(reached.size), ""),
            ("reachable fraction", grid.reachable_fraction, "-"),
            ("fraction reached within the joint limits", float(np.mean(grid.within_limits(mech))), "-"),
            ("fraction reached free of self-collision", float(np.mean(grid.collision_free(mech))), "-"),
            ("smallest manipulability reached", float(np.min(w)) if w.size else None, w_unit),
            ("largest manipulability reached", float(np.max(w)) if w.size else None, w_unit),
            (
                "smallest direct margin reached",
                float(np.min(grid.direct_margin[reached])) if w.size else None,
                "-",
            ),
            (
                "smallest inverse margin reached",
                float(np.min(grid.inverse_margin[reached])) if w.size else None,
                "-",
            ),
            ("singular points found", len(loci), ""),
        ],
        id="slice_summary",
    )
    touching = self_collisions(mech, case.q)
    if touching:
        section.text(
            f"At {case.where} these pairs of shapes already touch, so they count as "
            f"colliding everywhere they still do: {', '.join(f'{a}-{b}' for a, b in touching)}. A planar "
            "drawing puts every link in one plane; pairs that move in different planes are left out with "
            "the sidecar's `self_collision: {ignore: [[a, b]]}`."
        )
    if loci:
        i, j = (dofs.index(a) for a in axes)
        section.table(
            "Singular points found",
            [
                "kind",
                "method",
                *(Column(a, _display(mech, a, 0.0)[1], ".5g") for a in axes),
                Column("margin", "-"),
            ],
            [
                (
                    p.kind,
                    p.method,
                    _display(mech, axes[0], p.x[i])[0],
                    _display(mech, axes[1], p.x[j])[0],
                    p.margin,
                )
                for p in loci
            ],
        )
    return grid, loci


PRELOAD_STEPS = 5
"""Internal-force values of the preload table (from 0 to the largest, both signs)."""


def _stiffness(section: Section, mech: Mechanism, grid: WorkspaceSlice | None, case: OverviewCase) -> None:
    compliance = mech.sidecar.compliance
    if compliance is None or mech.task is None or mech.task.frame is None:
        section.text(
            "No stiffness: the description has no `compliance` section (drive stiffness under "
            "`compliance.actuators`) or no end-effector frame task."
        )
        return
    section.text(
        "The task stiffness K_x is the Hessian of the potential (springs, gravity, loads, and the "
        "constraint forces' curvature lambda^T d2phi) condensed on the closed chain, at the static "
        f"equilibrium under gravity{'' if case.wrench is None else ' and the load'} with minimum-norm "
        "actuator forces (`plm_pin.stiffness`). "
        "Eigen-stiffnesses are read under pure forces [N/m] and pure moments [N m/rad] apart. "
        f"Springs of the description: {compliance.source or 'as described'}."
    )
    q, at = case.q, "the reference" if case.at_reference else "the pose"
    try:
        res = stiffness(mech, q, case.wrench)
        vibration = natural_frequencies(mech, q, result=res)
    except PlmError as exc:
        section.text(f"No stiffness at {at}: {exc}", markdown=False)
        return
    rows: list[tuple[str, object, str]] = [
        (f"translational eigen-stiffness {i + 1}", v, "N/m") for i, v in enumerate(res.translational.values)
    ]
    rows += [
        (f"rotational eigen-stiffness {i + 1}", v, "N m/rad") for i, v in enumerate(res.rotational.values)
    ]
    rows += [(f"natural frequency {i + 1}", f, "Hz") for i, f in enumerate(vibration.frequencies)]
    section.table(
        f"Stiffness and natural frequencies at {at}",
        ["quantity", Column("value", fmt=".5g"), "unit"],
        rows,
        id="stiffness",
    )
    dofs = res.dofs
    section.table(
        f"Share of each source in the diagonal of K_x at {at}",
        ["source", *(Column(d, "N/m" if not d.startswith("r") else "N m/rad", ".4g") for d in dofs)],
        [(name, *np.diag(K).tolist()) for name, K in res.contributions.items()],
        note="The shares add up to K_x; the geometric ones (gravity, load, closures) may be negative.",
        id="stiffness_shares",
    )
    if mech.redundancy > 0:
        _preload_effect(section, mech, case)
    if grid is not None and len(grid.axes) == 2:
        smap = stiffness_map(mech, grid)
        import matplotlib.pyplot as plt

        fig, (left, right) = plt.subplots(1, 2, figsize=(11.0, 4.5), layout="constrained")
        plot_stiffness_map(smap, "min_translational_stiffness", ax=left)
        plot_stiffness_map(smap, "lowest_frequency", ax=right)
        section.figure(
            fig,
            "Smallest translational eigen-stiffness (left) and lowest natural frequency (right) over the "
            "workspace slice, under gravity with minimum-norm forces.",
            {"stiffness_map": smap.to_dict()},
        )


def _preload_effect(section: Section, mech: Mechanism, case: OverviewCase) -> None:
    """Stiffness along the first internal-force direction, both signs, up to 5 times the held forces."""
    held = static_forces(mech, case.q, case.wrench, limits=None).f_c
    scale = max(10.0, 5.0 * float(np.max(np.abs(held))))
    rows = []
    for y in np.linspace(-scale, scale, 2 * PRELOAD_STEPS - 1):
        coords = np.zeros(mech.redundancy)
        coords[0] = y
        try:
            res = stiffness(mech, case.q, case.wrench, internal=coords)
        except PlmError:
            continue
        rows.append((float(y), res.min_translational, *res.rotational.values[:1].tolist()))
    section.table(
        f"Preload: stiffness at {'the reference' if case.at_reference else 'the pose'} along the first "
        "internal-force direction",
        [
            Column("internal force coordinate", "N", ".4g"),
            Column("smallest translational eigen-stiffness", _K["translational"], ".6g"),
            Column("smallest rotational eigen-stiffness", _K["rotational"], ".6g"),
        ],
        rows,
        note="The internal force changes K_x only through the curvature of the constraint forces it causes "
        "(geometric stiffness); the springs are unchanged.",
        id="preload",
    )


def _decoupling_sample(grid: WorkspaceSlice) -> np.ndarray:
    """Task poses [m, rad] at the reachable points of a coarse sub-grid of the slice, shape (k, n_task)."""
    picks = [
        np.unique(np.rint(np.linspace(0, v.size - 1, DECOUPLING_POSES)).astype(int)) for v in grid.values
    ]
    poses = []
    for point in itertools.product(*picks):
        if grid.reachable[point]:
            pose = np.array(grid.pose, dtype=float)
            for axis, values, k in zip(grid.axes, grid.values, point, strict=True):
                pose[grid.dofs.index(axis)] = values[k]
            poses.append(pose)
    return np.array(poses)


def _decoupling(section: Section, mech: Mechanism, grid: WorkspaceSlice) -> None:
    sample = _decoupling_sample(grid)
    if sample.size == 0:
        section.text("No decoupling check: no point of the slice is reachable.")
        return
    report = decoupling_check(mech, sample, mode=grid.working_mode)
    section.text(
        f"The task-space dynamics M_x xdd + h_x + g_x = f_x (M_x = S^T M S) over {report.n_poses} "
        "reachable poses of the slice. An entry is *zero* when it stays within its tolerance of zero "
        f"at every pose (relative to its Cauchy-Schwarz bound, rtol = {report.rtol:g}), *constant* "
        "when its spread stays within that tolerance, and *varies* otherwise; the coupling is its "
        f"largest ratio to the bound (0 to 1). h_x is quadratic in the task velocity: it is evaluated at "
        f"the {len(report.velocities)} task velocities {report.velocity_text()}, which determine it, so "
        "*zero* there means zero at every velocity and *nonzero* gives its range over them. The spread "
        "(max - min) is compared with the tolerance."
    )
    section.table(
        "Decoupling table",
        [
            "entry",
            "behaviour",
            Column("min", fmt=".6g"),
            Column("max", fmt=".6g"),
            Column("spread (max - min)", fmt=".3g"),
            Column("tolerance", fmt=".3g"),
            "unit",
            Column("coupling", "-"),
        ],
        [
            (name, e.kind, e.minimum, e.maximum, e.spread, e.tolerance, e.unit, e.ratio)
            for name, e in report.entries()
        ],
        note="Decoupled with constant inertia: "
        + (", ".join(report.decoupled()) or "none")
        + f"; poses skipped: {len(report.unreachable)} unreachable, {len(report.singular)} singular.",
        id="decoupling",
    )


def _simulation(section: Section, mech: Mechanism, case: OverviewCase) -> None:
    run, failure = passive_motion(mech, case.q, case.wrench)
    if case.wrench is None:
        acting = "under gravity"
        energy = "With no friction and no input, the energy must stay constant."
    else:
        acting = f"under gravity and the constant load ({_load_text(mech, case.wrench)})"
        energy = "The load does work: the energy changes by that work."
    section.text(
        f"The mechanism released at rest from {case.where} with its actuators free, {acting}, for "
        f"{SIMULATION_TIME:g} s (one DOP853 run with dense output, rtol 1e-10, the samples projected back "
        f"onto the closures). {energy}"
    )
    if failure is not None:
        section.text(f"The simulation stopped at t = {failure.time:.4g} s: {failure}", markdown=False)
    drift = np.max(np.abs(run.energy - run.energy[0]))
    section.table(
        "Passive simulation",
        ["quantity", "value", "unit"],
        [
            ("time simulated", float(run.t[-1]), "s"),
            ("samples", int(run.t.size), ""),
            ("largest closure residual", run.max_residual, "m, rad"),
            ("energy drift (max |E - E(0)|)", float(drift), "J"),
            ("largest joint speed", float(np.max(np.abs(run.v))), "m/s, rad/s"),
        ],
        id="simulation",
    )
    if run.x is not None and run.t.size > 1:
        assert mech.task is not None
        curves = {}
        for k, dof in enumerate(mech.task.dofs):
            unit = _display(mech, dof, 0.0)[1]
            curves[f"{dof} [{unit}]"] = np.degrees(np.unwrap(run.x[:, k])) if unit == "deg" else run.x[:, k]
        fig, flat = plot_panels(run.t, curves, xlabel="t [s]")
        section.figure(
            fig,
            "Task coordinates during the passive simulation (angles unwrapped, not folded into +/-180 deg)."
            + flat,
            {"t": run.t, "x": run.x},
        )
    if run.t.size > 1:
        section.animation(Animation(mech, run.q, run.t, "The passive simulation: play it in the page."))


def _load_text(mech: Mechanism, wrench: np.ndarray) -> str:
    """The load as ``fx = 1 N, mz = 0.2 N m`` (a joint task: ``joint = value``)."""
    unit = {"f": "N", "m": "N m"}
    if mech.task is not None and mech.task.frame is None:
        return (
            ", ".join(f"{n} = {v:.6g}" for n, v in zip(load_names(mech), wrench, strict=True)) + " [N or N m]"
        )
    return ", ".join(f"{n} = {v:.6g} {unit[n[0]]}" for n, v in zip(load_names(mech), wrench, strict=True))


def _statics(section: Section, mech: Mechanism, case: OverviewCase) -> StaticForces | None:
    if case.wrench is None:
        acting = "Gravity only"
    elif mech.task is not None and mech.task.frame is None:
        acting = f"Gravity and the load along the output joints ({_load_text(mech, case.wrench)})"
    else:
        acting = f"Gravity and the load on the task frame ({_load_text(mech, case.wrench)}, world axes)"
    section.text(
        f"{acting}, at {case.where}: the actuator forces `f_c` of minimum norm that "
        "balance it, the axial force of every hinged link (tension positive), and the internal-force "
        "directions: actuator forces that balance only each other (one per degree of redundancy)."
    )
    try:
        sol = static_forces(mech, case.q, case.wrench)
    except PlmError as exc:
        section.text(f"No static solution: {exc}", markdown=False)
        return None
    units = {"prismatic": "N", "revolute": "N m"}
    section.table(
        "Actuator forces f_c",
        ["actuator", "kind", "f_c", "unit"],
        [(a.joint, a.kind, f, units.get(a.kind, "")) for a, f in zip(mech.actuators, sol.f_c, strict=True)],
        note=f"Objective: {sol.objective}; equilibrium residual {sol.residual:.2e} N (or N m).",
        id="actuator_forces",
    )
    links = sol.link_forces()
    if links:
        section.table(
            "Link forces",
            ["link", "proximal joint", Column("axial (tension +)", "N"), Column("shear", "N")],
            [(f.link, f.joint, f.axial, f.shear) for f in links.values()],
        )
    directions = sol.internal_directions()
    if directions:
        section.table(
            "Internal-force directions (unit vectors of the internal basis)",
            ["direction", *(Column(a.joint, units.get(a.kind, "")) for a in mech.actuators)],
            [(k + 1, *d.f_c) for k, d in enumerate(directions)],
            note="Any multiple of a direction can be added to f_c without moving the mechanism.",
            id="internal_directions",
        )
        names = list(directions[0].link_forces)
        if names:
            section.table(
                "Link axial forces caused by each internal-force direction",
                ["direction", *(Column(n, "N") for n in names)],
                [(k + 1, *(d.link_forces[n].axial for n in names)) for k, d in enumerate(directions)],
            )
        _internal_range(section, mech, sol, case)
    spread = np.ptp(_frame_origins(mech, case.q), axis=0)
    plane = "".join(sorted("xyz"[k] for k in np.argsort(spread)[-2:]))
    axes = plot_static_forces(sol, plane=plane, title=f"static forces in the {plane} plane")
    fig = axes.get_figure(root=True)
    if fig is None:
        raise PlmError("plot_static_forces drew on axes outside a figure")
    section.figure(
        fig,
        f"The mechanism projected on the {plane} plane with its static forces: actuator forces f_c, "
        "guide normal forces f_n, link axial forces f_l, loads.",
        {"forces": sol.to_dict(), "arrows": force_arrows(sol)},
    )
    return sol


def _internal_range(section: Section, mech: Mechanism, sol: StaticForces, case: OverviewCase) -> None:
    limits = actuator_limits(mech, "description")
    if not np.isfinite(limits).all():
        section.text(
            "Internal-force range: the description gives no effort limits for some actuators, so every "
            "internal force is admissible. Add `limits: [lo, hi]` to each actuator in the sidecar to see "
            "how far the actuators can preload the mechanism while holding it."
        )
        return
    try:
        span = internal_force_range(mech, case.q, case.wrench)
    except PlmError as exc:
        section.text(f"No internal-force range: {exc}", markdown=False)
        return
    section.table(
        "Internal-force range within the actuator limits, holding gravity"
        + ("" if case.wrench is None else " and the load"),
        [
            "direction",
            Column("lowest", "N or N m"),
            Column("min-norm", "N or N m"),
            Column("highest", "N or N m"),
        ],
        [(k + 1, span.lower[k], sol.internal[k], span.upper[k]) for k in range(span.lower.size)],
        note="Coordinates along the directions above (one linear programme per bound, the others free); "
        "multiply a direction's link forces by a coordinate to read the preload it stands for.",
        id="internal_range",
    )


def _scene(
    section: Section,
    mech: Mechanism,
    forces: StaticForces | None,
    case: OverviewCase,
    grid: WorkspaceSlice | None,
    loci: list[SingularPoint],
) -> None:
    viewer = MeshcatViewer(mech, static=True)
    q = case.q
    if forces is None:
        viewer.display(q)
        caption = f"The mechanism at {case.where}; closure points in green."
        arrows, scale = [], None
    else:
        arrows = force_arrows(forces)
        extent = float(np.max(np.ptp(_frame_origins(mech, q), axis=0)))
        biggest = max((float(np.linalg.norm(a.force)) for a in arrows), default=0.0)
        scale = 0.25 * extent / biggest if biggest > 0.0 else 1.0
        viewer.show_forces(q, arrows, scale)
        caption = (
            f"The mechanism at {case.where} with its static forces ({scale:.3g} m/N); "
            "closure points in green."
        )
    data: dict[str, Any] = {"q": q, "arrows": arrows, "scale": scale}
    if grid is not None and mech.task_frame_id is not None:  # the slice's overlays, at the task frame
        data["workspace_boundary"] = viewer.show_workspace(grid)
        data["singular_points"] = viewer.show_singular_points(loci)
        caption += " Dots: the task frame at the boundary of the workspace slice and at its singular points."
    section.scene(viewer.static_html(), caption, data)
