"""Enferadi 2017: inverse and direct dynamics of the star-triangle (3-PRP) planar manipulator.

Reproduces section 6: the actuator forces of the two case-study paths (vertical line and
circle, Figs. 5 and 7), then the direct dynamics driven by those forces, which must retrace
the path (Figs. 6 and 8). The paper's figures carry no numbers; the reference values are the
paper's own equations (25)-(31), corrected, evaluated in ``analyses/specs/enferadi2017.md``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np
from scipy.interpolate import CubicSpline

from plm_pin import Mechanism, PlmError, load
from plm_pin.dynamics import JointTrajectory, inverse_dynamics, simulate, task_trajectory
from plm_pin.report import Animation, Column, Comparison, Section, StudyContext
from plm_pin.viz import flat, flat_note, panel_grid, shared_legend

from ._enferadi2017_paper import enferadi2017_circle, enferadi2017_line

TITLE = "Enferadi 2017: dynamics of a star-triangle 3-PRP planar manipulator"
SUMMARY = "Section 6: forces along a line and a circle, and the direct-dynamics round trip."

REFERENCE = {
    "line": {1.0: (-0.239237, 0.239237, 0.0), 4.0: (0.338332, -0.338332, 0.0)},
    "circle": {
        0.0: (-2.254403, -2.254403, 3.605675),
        0.25: (-3.986470, 0.798263, 2.549597),
        0.5: (-3.383317, 3.383317, 0.0),
    },
}
"""Forces [N] of the corrected eqs. (25)-(31) (spec, section 5), printed to 6 decimals."""

PATHS: dict[str, tuple[Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]], float, str]] = {
    "line": (enferadi2017_line, 8.0, "Figs. 5, 6: vertical line y = 0.25 + 0.1 cos(pi t / 4) m"),
    "circle": (enferadi2017_circle, 2.0, "Figs. 7, 8: circle of radius 0.0625 m, one turn"),
}


SAMPLE_STEP = 0.01
"""Time between the samples of the inverse dynamics [s]."""


def path_trajectory(mech: Mechanism, name: str) -> JointTrajectory:
    """The case-study path ``name`` (a key of :data:`PATHS`) sampled every :data:`SAMPLE_STEP`."""
    profile, duration, _ = PATHS[name]
    return task_trajectory(mech, profile, np.linspace(0.0, duration, round(duration / SAMPLE_STEP) + 1))


def _animation(name: str) -> Animation:
    mech = load("enferadi2017_star_triangle")
    traj = path_trajectory(mech, name)
    return Animation(mech, traj.q, traj.t, f"Enferadi 2017, {PATHS[name][2]}")


ANIMATIONS = {name: functools.partial(_animation, name) for name in PATHS}
"""Both paths, for ``plm-pin view --animate enferadi2017:line`` (or ``circle``)."""


def run(ctx: StudyContext) -> None:
    """Fill the Enferadi 2017 report."""
    mech = ctx.load("enferadi2017_star_triangle")
    section = ctx.section("Model")
    section.assumptions(
        "Reconstruction (analyses/specs/enferadi2017.md)",
        [
            "Geometry rebuilt from the constraint equations (1)-(2); the figures are missing.",
            "Typos corrected: q1 for a1 in Gamma_2, the sign of theta_2 in Lambda_4, M and N swapped in "
            "(31), (33), (34), the slider mass m_a + m_il.",
            "Inertias 37.5 and 25 kg m^2 kept as printed although implausible (radius of gyration 3.5 m); "
            "with phi held at pi/2 they do not enter the forces.",
            "Horizontal plane: gravity does no work.",
        ],
    )
    for name, (profile, duration, caption) in PATHS.items():
        ctx.step(f"{name}: inverse dynamics and round trip")
        _path(ctx.section(f"Path: {name}"), mech, name, profile, duration, caption)


def _path(
    section: Section,
    mech: Mechanism,
    name: str,
    profile: Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]],
    duration: float,
    caption: str,
) -> None:
    traj = path_trajectory(mech, name)
    t = traj.t
    idr = inverse_dynamics(mech, traj)
    forces = CubicSpline(t, idr.f_c)
    run = simulate(
        mech,
        traj.q[0],
        traj.v[0],
        duration=duration,
        dt=duration / 100,
        actuator_forces=lambda time, q, v: forces(time),
        method="adaptive",
        rtol=1e-11,
        atol=1e-13,
    )
    if run.x is None:
        raise PlmError(f"{mech.name}: the simulation recorded no task coordinates (no task)")
    x = run.x
    target = np.array([profile(s)[0] for s in run.t])
    error = np.max(np.linalg.norm((x - target)[:, :2], axis=1))
    fig, axes = panel_grid(3, height=3.4)
    for i in range(3):
        axes[0].plot(t, idr.f_c[:, i], label=f"leg {i + 1}")
        axes[1].plot(t, traj.c[:, i], label=f"leg {i + 1}")
    axes[0].set(xlabel="t [s]", ylabel="actuator force [N]", title="inverse dynamics")
    axes[1].set(xlabel="t [s]", ylabel="slider position [m]", title="actuators")
    # a path along y keeps x constant to round-off: y against time then, x said in the caption
    along_y = flat("x", np.concatenate([target[:, 0], x[:, 0]]), "m", scale=float(np.abs(target).max()))
    u, v = (run.t, "t [s]") if along_y else (None, "x [m]")
    axes[2].plot(target[:, 0] if u is None else u, target[:, 1], "k-", lw=4, alpha=0.3, label="path")
    axes[2].plot(x[:, 0] if u is None else u, x[:, 1], "r--", label="direct dynamics")
    axes[2].set(xlabel=v, ylabel="y [m]", title="round trip")
    if u is None:
        axes[2].set_aspect("equal")
    for ax in axes:
        ax.grid(alpha=0.3)
    shared_legend(fig, axes)
    section.figure(
        fig,
        f"{caption}: forces, slider positions, and the path retraced by direct dynamics."
        + flat_note([along_y] if along_y else []),
        {"t": t, "f_c": idr.f_c, "q": traj.c, "x_direct": x, "t_direct": run.t},
    )
    rows = []
    for time, expected in REFERENCE[name].items():
        k = int(np.argmin(np.abs(t - time)))
        for i in range(3):
            rows.append(
                Comparison(
                    f"f_{i + 1}(t = {time:g} s), corrected eqs. (25)-(31)",
                    expected[i],
                    float(idr.f_c[k, i]),
                    "N",
                    rtol=0.0,
                    atol=1e-6,
                    source="closed form",
                    fmt=".6f",
                )
            )
    rows.append(
        Comparison("round trip: largest path error of the direct dynamics", 0.0, float(error), "m", atol=1e-6)
    )
    section.comparison(
        f"{name}: forces and round trip",
        rows,
        note="The paper's figures give no numbers.",
        id=f"{name}_forces",
    )
    section.table(
        f"{name}: extremes",
        ["actuator", Column("min f", "N"), Column("max f", "N"), Column("min q", "m"), Column("max q", "m")],
        [
            (
                i + 1,
                float(idr.f_c[:, i].min()),
                float(idr.f_c[:, i].max()),
                float(traj.c[:, i].min()),
                float(traj.c[:, i].max()),
            )
            for i in range(3)
        ],
    )
    section.animation(Animation(mech, traj.q, t, f"{name}: the motion, to rotate and play in the page."))
