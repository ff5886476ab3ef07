"""The overview study: mobility, workspace slice, statics, decoupling, motion and 3D view of any mechanism.

The library's own study (the paper studies are in the checkout's ``analyses/``), so that an
installed wheel writes the report of any description: ``plm-pin report overview --mechanism
path/to/robot.urdf`` (or ``plm-pin report path/to/robot.urdf``); ``plm-pin report all`` runs it
on :data:`MECHANISM`.
"""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin

from ..core.mechanism import Mechanism
from ..dynamics import SimulationResult, decoupling_check, simulate
from ..exceptions import PlmError, SimulationFailed, SingularConfiguration
from ..kinematics import classify, forward_kinematics, task_pose
from ..kinematics.collisions import self_collisions
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
    WorkspaceSlice,
    manipulability,
    manipulability_unit,
    singular_loci,
    workspace_map,
    workspace_sweep,
)
from .animation import Animation
from .content import Column, Section
from .study import StudyContext

TITLE = "Overview"
SUMMARY = (
    "Mobility, redundancy, a workspace slice, statics with the internal-force range, decoupling, "
    "a short simulation and a 3D view."
)
MECHANISM = "harada2011_3d4m"

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


def passive_motion(mech: Mechanism) -> tuple[SimulationResult, SimulationFailed | None]:
    """The mechanism released at rest from its reference configuration, actuators free, under gravity.

    Returns:
        The samples (up to the failure, if any) and the failure (None when the run completed).
    """
    try:
        return simulate(mech, mech.q_ref, duration=SIMULATION_TIME, dt=SIMULATION_DT), None
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


def run(ctx: StudyContext) -> None:
    """Fill the overview report of ``ctx.target``."""
    mech = ctx.load()
    ctx.step(f"{mech.name}: mobility and singularity at the reference")
    square = mech.task is not None and len(mech.task.dofs) == mech.mobility
    _mobility(ctx.section("Mobility and redundancy"), mech, square)
    section = ctx.section("Workspace slice: manipulability and singularities")
    grid = None
    if square:
        ctx.step(f"{mech.name}: workspace slice")
        grid = _workspace(section, mech)
    else:
        section.text(NEEDS_SQUARE_TASK.format(what="No workspace slice"))
    ctx.step(f"{mech.name}: static forces at the reference")
    forces = _statics(ctx.section("Static forces at the reference configuration"), mech)
    section = ctx.section("Task-space dynamics and decoupling")
    if grid is not None:
        ctx.step(f"{mech.name}: decoupling")
        _decoupling(section, mech, grid)
    else:
        section.text(NEEDS_SQUARE_TASK.format(what="No decoupling check"))
    ctx.step(f"{mech.name}: stiffness")
    _stiffness(ctx.section("Stiffness and natural frequencies"), mech, grid)
    ctx.step(f"{mech.name}: passive simulation")
    _simulation(ctx.section("Short simulation: released under gravity"), mech)
    ctx.step(f"{mech.name}: 3D scene")
    _scene(ctx.section("3D view"), mech, forces)


def _mobility(section: Section, mech: Mechanism, square: bool) -> None:
    section.text(
        "Mobility is the dimension of the closure Jacobian's null space at a generic assembled "
        "configuration (`nv - rank J_phi`, SVD rank cut at the largest gap of the singular values, "
        "above the description's closure tolerance); redundancy is the number of actuators beyond it. "
        "The singularity margins are normalised smallest singular values (0 at a singularity): "
        "*constraint* for the closures, *inverse* (type 1) for `T = J_x N`, *direct* (type 2) for "
        "`C = S_a N`."
    )
    q = mech.q_ref
    rank = mech.closure_rank(q)
    rows: list[tuple[str, object, str]] = [
        ("configuration size nq", mech.nq, ""),
        ("velocity size nv", mech.nv, ""),
        ("closure rows", mech.n_closure_rows, ""),
        ("rank of J_phi at the reference", rank, ""),
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
            ("singular at the reference", report.singular, ""),
            ("manipulability w", m.w, manipulability_unit(mech)),
            ("condition number of J_ce", m.condition_number, "-"),
        ]
    section.table(
        "Sizes, ranks and margins at the reference", ["quantity", "value", "unit"], rows, id="sizes"
    )
    if mech.task is not None:
        x = task_pose(mech, q)
        joints = mech.task.frame is None
        section.table(
            "Reference positions of the output joints (the task)"
            if joints
            else f"Reference pose of the task frame {mech.task.frame}",
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
        _transmission(section, mech, q)


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
    certificate = "Krawczyk" if modes.method == "homotopy" else "none"
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
                certificate,
            )
            for i, s in enumerate(modes)
        ],
        id="assembly-modes",
    )


def _transmission(section: Section, mech: Mechanism, q: np.ndarray) -> None:
    """The transmission ratio, mechanical advantage and transmission indices at ``q``."""
    try:
        t = transmission(mech, q)
    except SingularConfiguration as exc:
        section.text(f"No transmission at the reference: {exc}")
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
        "Transmission at the reference",
        ["quantity", "kind", Column("value", fmt=".6g")],
        rows,
        id="transmission",
        note="Ratio: task rate per actuator rate; mechanical advantage: task force (torque) delivered per "
        "actuator force (torque), from the static balance; transmission index: |cos| of the angle between "
        "a closure's force and its motion (a four-bar: sin of the transmission angle; 0: dead centre).",
    )


def _workspace(section: Section, mech: Mechanism) -> WorkspaceSlice:
    assert mech.task is not None
    dofs = mech.task.dofs
    axes = ("x", "y") if {"x", "y"} <= set(dofs) else tuple(dofs[:2])
    x0 = task_pose(mech, mech.q_ref)
    extent = float(np.max(np.ptp(_frame_origins(mech, mech.q_ref), axis=0)))
    values = []
    for a in axes:
        half = ANGLE_SPAN if _is_angle(mech, a) else LENGTH_SPAN * extent
        centre = x0[dofs.index(a)]
        values.append(np.linspace(centre - half, centre + half, GRID))
    section.text(
        f"The slice varies {' and '.join(f'`{a}`' for a in axes)} around the reference pose, the other "
        "task coordinates fixed. Each point is solved by inverse-kinematics continuation from its "
        "neighbours, keeping the working mode of the reference; blank points are not reachable in "
        "that mode. Singular points are located by root finding along lines of the slice."
    )
    if len(axes) == 1:
        sweep = workspace_sweep(mech, axes[0], values[0], x0)
        fig = plot_sweep(sweep, "manipulability", log=True, title=f"{mech.name}: manipulability")
        section.figure(fig, f"Manipulability along {axes[0]}.", {"slice": sweep.to_dict()})
        grid = sweep
        loci = []
    else:
        grid = workspace_map(mech, (axes[0], axes[1]), (values[0], values[1]), x0)
        across = [float(v) for v in values[1][:: max(1, (GRID - 1) // (LOCI_LINES - 1))]]
        loci = singular_loci(mech, axes[0], values[0], axes[1], across, x0)
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
    touching = self_collisions(mech, mech.q_ref)
    if touching:
        section.text(
            "At the reference configuration these pairs of shapes already touch, so they count as "
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
    return grid


PRELOAD_STEPS = 5
"""Internal-force values of the preload table (from 0 to the largest, both signs)."""


def _stiffness(section: Section, mech: Mechanism, grid: WorkspaceSlice | None) -> None:
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
        "equilibrium under gravity with minimum-norm actuator forces (`plm_pin.stiffness`). "
        "Eigen-stiffnesses are read under pure forces [N/m] and pure moments [N m/rad] apart. "
        f"Springs of the description: {compliance.source or 'as described'}."
    )
    q = mech.q_ref
    try:
        res = stiffness(mech, q)
        vibration = natural_frequencies(mech, q, result=res)
    except PlmError as exc:
        section.text(f"No stiffness at the reference: {exc}", markdown=False)
        return
    rows: list[tuple[str, object, str]] = [
        (f"translational eigen-stiffness {i + 1}", v, "N/m") for i, v in enumerate(res.translational.values)
    ]
    rows += [
        (f"rotational eigen-stiffness {i + 1}", v, "N m/rad") for i, v in enumerate(res.rotational.values)
    ]
    rows += [(f"natural frequency {i + 1}", f, "Hz") for i, f in enumerate(vibration.frequencies)]
    section.table(
        "Stiffness and natural frequencies at the reference",
        ["quantity", Column("value", fmt=".5g"), "unit"],
        rows,
        id="stiffness",
    )
    dofs = res.dofs
    section.table(
        "Share of each source in the diagonal of K_x at the reference",
        ["source", *(Column(d, "N/m" if not d.startswith("r") else "N m/rad", ".4g") for d in dofs)],
        [(name, *np.diag(K).tolist()) for name, K in res.contributions.items()],
        note="The shares add up to K_x; the geometric ones (gravity, load, closures) may be negative.",
        id="stiffness_shares",
    )
    if mech.redundancy > 0:
        _preload_effect(section, mech)
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


def _preload_effect(section: Section, mech: Mechanism) -> None:
    """Stiffness along the first internal-force direction, both signs, up to 5 times the weight's forces."""
    scale = max(10.0, 5.0 * float(np.max(np.abs(static_forces(mech, mech.q_ref, limits=None).f_c))))
    rows = []
    for y in np.linspace(-scale, scale, 2 * PRELOAD_STEPS - 1):
        coords = np.zeros(mech.redundancy)
        coords[0] = y
        try:
            res = stiffness(mech, mech.q_ref, internal=coords)
        except PlmError:
            continue
        rows.append((float(y), res.min_translational, *res.rotational.values[:1].tolist()))
    section.table(
        "Preload: stiffness at the reference along the first internal-force direction",
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


def _simulation(section: Section, mech: Mechanism) -> None:
    run, failure = passive_motion(mech)
    section.text(
        f"The mechanism released at rest from its reference configuration with its actuators free, "
        f"under gravity, for {SIMULATION_TIME:g} s (one DOP853 run with dense output, rtol 1e-10, the "
        "samples projected back onto the closures). With no friction and no input, the energy must stay "
        "constant."
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


def _statics(section: Section, mech: Mechanism) -> StaticForces | None:
    section.text(
        "Gravity only, at the reference configuration: the actuator forces `f_c` of minimum norm that "
        "balance it, the axial force of every hinged link (tension positive), and the internal-force "
        "directions: actuator forces that balance only each other (one per degree of redundancy)."
    )
    try:
        sol = static_forces(mech, mech.q_ref)
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
        _internal_range(section, mech, sol)
    spread = np.ptp(_frame_origins(mech, mech.q_ref), axis=0)
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


def _internal_range(section: Section, mech: Mechanism, sol: StaticForces) -> None:
    limits = actuator_limits(mech, "description")
    if not np.isfinite(limits).all():
        section.text(
            "Internal-force range: the description gives no effort limits for some actuators, so every "
            "internal force is admissible. Add `limits: [lo, hi]` to each actuator in the sidecar to see "
            "how far the actuators can preload the mechanism while holding it."
        )
        return
    try:
        span = internal_force_range(mech, mech.q_ref)
    except PlmError as exc:
        section.text(f"No internal-force range: {exc}", markdown=False)
        return
    section.table(
        "Internal-force range within the actuator limits, holding gravity",
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


def _scene(section: Section, mech: Mechanism, forces: StaticForces | None) -> None:
    viewer = MeshcatViewer(mech, static=True)
    q = mech.q_ref
    if forces is None:
        viewer.display(q)
        caption = "The mechanism at the reference configuration; closure points in green."
        arrows, scale = [], None
    else:
        arrows = force_arrows(forces)
        extent = float(np.max(np.ptp(_frame_origins(mech, q), axis=0)))
        biggest = max((float(np.linalg.norm(a.force)) for a in arrows), default=0.0)
        scale = 0.25 * extent / biggest if biggest > 0.0 else 1.0
        viewer.show_forces(q, [(a.point, a.force, f"{a.kind} {a.name}") for a in arrows], scale)
        caption = (
            f"The mechanism at the reference configuration with its static forces ({scale:.3g} m/N); "
            "closure points in green."
        )
    section.scene(viewer.static_html(), caption, {"q": q, "arrows": arrows, "scale": scale})
