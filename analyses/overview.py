"""Overview of any mechanism plm_pin loads: mobility, workspace slice, statics, 3D view.

``plm-pin report overview --mechanism path/to/robot.urdf`` (or ``plm-pin report
path/to/robot.urdf``) runs it on a user's description; ``plm-pin report all`` on
:data:`MECHANISM`.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from plm_pin import Mechanism, PlmError
from plm_pin.analysis import manipulability, singular_loci, workspace_map, workspace_sweep
from plm_pin.kinematics import classify, task_pose
from plm_pin.report import Column, Section, StudyContext
from plm_pin.statics import StaticForces, static_forces
from plm_pin.viz import MeshcatViewer, force_arrows, plot_map, plot_static_forces, plot_sweep

TITLE = "Overview"
SUMMARY = "Mobility, redundancy, a workspace slice, statics at the reference pose and a 3D view."
MECHANISM = "harada2011_3d4m"

ANGLE_SPAN = np.radians(30.0)
"""Half-width of the slice along an angle [rad]."""

LENGTH_SPAN = 0.25
"""Half-width of the slice along a translation, as a fraction of the mechanism's extent [-]."""

GRID = 41
"""Samples per slice axis."""

LOCI_LINES = 11
"""Lines of the slice searched for singular points."""


def _display(dof: str, value: float) -> tuple[float, str]:
    """A task coordinate in report units: degrees for angles (said so), metres otherwise."""
    return (float(np.degrees(value)), "deg") if dof.startswith("r") else (float(value), "m")


def _frame_origins(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """World positions of every frame [m], shape (n_frames, 3)."""
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    return np.array([M.translation for M in data.oMf])


def run(ctx: StudyContext) -> None:
    """Fill the overview report of ``ctx.target``."""
    mech = ctx.load()
    ctx.step(f"{mech.name}: mobility and singularity at the reference")
    square = mech.task is not None and len(mech.task.dofs) == mech.mobility
    _mobility(ctx.section("Mobility and redundancy"), mech, square)
    section = ctx.section("Workspace slice: manipulability and singularities")
    if square:
        ctx.step(f"{mech.name}: workspace slice")
        _workspace(section, mech)
    else:
        section.text(
            "No workspace slice: it needs a task (`end_effector` in the sidecar) with as many "
            "coordinates as the mechanism has degrees of freedom."
        )
    ctx.step(f"{mech.name}: static forces at the reference")
    forces = _statics(ctx.section("Static forces at the reference configuration"), mech)
    ctx.step(f"{mech.name}: 3D scene")
    _scene(ctx.section("3D view"), mech, forces)


def _mobility(section: Section, mech: Mechanism, square: bool) -> None:
    section.text(
        "Mobility is the dimension of the closure Jacobian's null space at a generic assembled "
        "configuration (`nv - rank J_phi`, SVD rank); redundancy is the number of actuators beyond it. "
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
            ("manipulability w", m.w, "product of J_ce column units"),
            ("condition number of J_ce", m.condition_number, "-"),
        ]
    section.table("Sizes, ranks and margins at the reference", ["quantity", "value", "unit"], rows)
    if mech.task is not None:
        x = task_pose(mech, q)
        section.table(
            f"Reference pose of the task frame {mech.task.frame}",
            ["coordinate", Column("value", fmt=".6g"), "unit"],
            [(dof, *_display(dof, v)) for dof, v in zip(mech.task.dofs, x, strict=True)],
            note="Angles are roll-pitch-yaw (R = Rz Ry Rx), shown in degrees.",
        )


def _workspace(section: Section, mech: Mechanism) -> None:
    assert mech.task is not None
    dofs = mech.task.dofs
    axes = ("x", "y") if {"x", "y"} <= set(dofs) else tuple(dofs[:2])
    x0 = task_pose(mech, mech.q_ref)
    extent = float(np.max(np.ptp(_frame_origins(mech, mech.q_ref), axis=0)))
    values = []
    for a in axes:
        half = ANGLE_SPAN if a.startswith("r") else LENGTH_SPAN * extent
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
        across = values[1][:: max(1, (GRID - 1) // (LOCI_LINES - 1))]
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
    section.table(
        "Slice summary",
        ["quantity", "value", "unit"],
        [
            ("grid points", int(reached.size), ""),
            ("reachable fraction", grid.reachable_fraction, "-"),
            ("smallest manipulability reached", float(np.min(w)) if w.size else None, "J_ce units"),
            ("largest manipulability reached", float(np.max(w)) if w.size else None, "J_ce units"),
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
    )
    if loci:
        i, j = (dofs.index(a) for a in axes)
        section.table(
            "Singular points found",
            ["kind", "method", *(Column(a, _display(a, 0.0)[1], ".5g") for a in axes), Column("margin", "-")],
            [
                (p.kind, p.method, _display(axes[0], p.x[i])[0], _display(axes[1], p.x[j])[0], p.margin)
                for p in loci
            ],
        )


def _statics(section: Section, mech: Mechanism) -> StaticForces | None:
    section.text(
        "Gravity only, at the reference configuration: the actuator forces `f_c` of minimum norm that "
        "balance it, the axial force of every hinged link (tension positive), and the internal-force "
        "modes: actuator forces that balance only each other (one per degree of redundancy)."
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
    )
    links = sol.link_forces()
    if links:
        section.table(
            "Link forces",
            ["link", "proximal joint", Column("axial (tension +)", "N"), Column("shear", "N")],
            [(f.link, f.joint, f.axial, f.shear) for f in links.values()],
        )
    modes = sol.internal_modes()
    if modes:
        section.table(
            "Internal-force modes (unit vectors of the internal basis)",
            ["mode", *(Column(a.joint, units.get(a.kind, "")) for a in mech.actuators)],
            [(k + 1, *m.f_c) for k, m in enumerate(modes)],
            note="Any multiple of a mode can be added to f_c without moving the mechanism.",
        )
        names = list(modes[0].link_forces)
        if names:
            section.table(
                "Link axial forces caused by each internal mode",
                ["mode", *(Column(n, "N") for n in names)],
                [(k + 1, *(m.link_forces[n].axial for n in names)) for k, m in enumerate(modes)],
            )
    spread = np.ptp(_frame_origins(mech, mech.q_ref), axis=0)
    plane = "".join(sorted("xyz"[k] for k in np.argsort(spread)[-2:]))
    axes = plot_static_forces(sol, plane=plane, title=f"static forces in the {plane} plane")
    section.figure(
        axes.figure,
        f"The mechanism projected on the {plane} plane with its static forces: actuator forces f_c, "
        "guide normal forces f_n, link axial forces f_l, loads.",
        {"forces": sol.to_dict(), "arrows": force_arrows(sol)},
    )
    return sol


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
