"""Harada 2011: kinetostatics and dynamics of the redundantly actuated planar 3D4M (and 3D3M).

Reproduces Fig. 6 (manipulability against the plate angle, the 3D3M's type-4 singularity at
28.7 deg), the static forces of section 4 with Fig. 8 (external and internal forces), the
decoupled dynamics of eq. (23), and simulations 1 and 2 (Tables 2-4, Figs. 10-13); adds the
force capability of the redundant and non-redundant tables and the loss of decoupling of
the asymmetric design of Harada 2015.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from plm_pin import Mechanism, PlmError, build_mechanism, load
from plm_pin.description.compliance import BeamSpec, ComplianceSpec
from plm_pin.dynamics import DecouplingReport, SimulationResult, decoupling_check, simulate
from plm_pin.models import PRESETS
from plm_pin.models.registry import HARADA2011_DRIVE_STIFFNESS
from plm_pin.report import Animation, Column, Comparison, Section, StudyContext
from plm_pin.results import units
from plm_pin.statics import force_capability, static_forces, wrench_polygon
from plm_pin.stiffness import StiffnessResult, Vibration, natural_frequencies, stiffness, stiffness_map
from plm_pin.viz import fig8, panel_grid, plot_panels, plot_skeletons, plot_sweep, shared_legend
from plm_pin.workspace import singular_points_along, workspace_sweep

from . import _harada2011_paper as paper

TITLE = "Harada 2011: kinetostatics and dynamics of a redundantly actuated planar PLM"
SUMMARY = "Fig. 6, statics eqs. (14)-(22) and Fig. 8, eq. (23) decoupling, simulations 1-2; force capability."

_K = units(StiffnessResult)
"""Units of the stiffness results' fields (eigen-stiffnesses: ``translational``, ``rotational``)."""

LIMIT = 10.0
"""Actuator force limit assumed for the capability section [N] (the paper gives none)."""

G = 9.8
"""Gravity of the paper's code (M.37) [m/s^2]."""

DURATION = 2.0
"""Length of simulations 1 and 2 [s] ((M.38))."""

SIM_DT = 0.01
"""Output step of simulations 1 and 2 [s] (samples of simulate's default DOP853 run)."""

SNAPSHOT_PERIOD = 0.2
"""Time between the skeletons of Figs. 11 and 13, as in the paper's code (M.42) [s]."""


def _fig6_variant(name: str) -> Mechanism:
    """The table of Fig. 6: l : 2 r_t = 2 : 1 (r_t = l / 4), other parameters of Table 1."""
    rod = float(PRESETS[name].parameters["rod_lengths"][0])
    return build_mechanism(name, {"half_plate": rod / 4.0}, name=f"fig6_{name}")


SIMULATIONS = {
    "simulation1": ("simulation 1 (Table 3)", 0.2, 0.0),
    "simulation2": ("simulation 2 (Table 4)", 0.0, 0.005),
}
"""Case: (label, f_x [N], tau_theta [N m]) of Tables 3, 4; f_y = (2 m_l + m_t) g balances gravity (M.30)."""


def simulate_case(mech: Mechanism, case: str) -> SimulationResult:
    """Simulation 1 or 2: constant task forces from the initial state of Table 2 ((M.38)), at rest, 2 s."""
    _, f_x, tau = SIMULATIONS[case]
    p = PRESETS["harada2011_3d4m"].parameters
    f_y = (2 * float(p["rod_masses"][0]) + float(p["plate_mass"])) * G
    return simulate(mech, mech.q_ref, duration=DURATION, dt=SIM_DT, wrench=[f_x, f_y, tau])


def _animation(case: str) -> Animation:
    mech = load("harada2011_3d4m")
    run = simulate_case(mech, case)
    return Animation(mech, run.q, run.t, f"Harada 2011 {SIMULATIONS[case][0]}, 2 s")


ANIMATIONS = {case: functools.partial(_animation, case) for case in SIMULATIONS}
"""The two simulations, for ``plm-pin view --animate harada2011:simulation1`` (or 2)."""


def run(ctx: StudyContext) -> None:
    """Fill the Harada 2011 report."""
    four = ctx.load("harada2011_3d4m")
    three = ctx.load("harada2011_3d3m")
    ctx.step("Fig. 6: manipulability against the plate angle")
    _fig6(ctx, ctx.section("Manipulability and singularity (Fig. 6, eq. (11.4))"))
    ctx.step("statics: eqs. (14)-(22), Fig. 8")
    _statics(ctx.section("Static forces (section 4, Fig. 8)"), four, three)
    ctx.step("force capability")
    _capability(ctx.section("Force capability: redundant vs non-redundant (beyond the paper)"), four, three)
    ctx.step("stiffness: preload and redundancy")
    _stiffness(ctx.section("Stiffness: internal preload and redundancy (beyond the paper)"), four, three)
    ctx.step("task-space dynamics and decoupling")
    _decoupling(ctx.section("Decoupled dynamics (eq. (23))"), four, ctx.load("harada2015_asymmetric"))
    ctx.step("simulations 1 and 2")
    _simulations(ctx.section("Simulations 1 and 2 (Tables 2-4, Figs. 10-13)"), four)


def _fig6(ctx: StudyContext, section: Section) -> None:
    import matplotlib.pyplot as plt

    m4 = ctx.load(_fig6_variant("harada2011_3d4m"))
    m3 = ctx.load(_fig6_variant("harada2011_3d3m"))
    l = float(PRESETS["harada2011_3d3m"].parameters["rod_lengths"][0])
    rt = l / 4.0
    y = (l + rt) * math.sin(math.radians(28.7))  # where eq. (11.4) gives 28.7 deg
    thetas = np.radians(np.linspace(-80.0, 80.0, 161))
    pose = (0.0, y, 0.0)
    s3 = workspace_sweep(m3, "rz", thetas, pose)
    s4 = workspace_sweep(m4, "rz", thetas, pose)
    loci = singular_points_along(m3, "rz", thetas[::4], pose)
    fig, ax = plt.subplots(figsize=(6.5, 4.0), layout="constrained")
    plot_sweep(s3, singular=loci, ax=ax, label="3D3M (non-redundant)")
    plot_sweep(s4, ax=ax, label="3D4M (redundant)")
    section.figure(
        fig,
        f"Fig. 6: manipulability w against the plate angle at y = {y:.6f} m, l : 2 r_t = 2 : 1.",
        {"theta": thetas, "w_3d3m": s3.manipulability, "w_3d4m": s4.manipulability, "y": y},
    )
    type4 = [p for p in loci if p.kind == "direct"]
    found = min(type4, key=lambda p: abs(abs(p.parameter) - math.radians(28.7)))
    w4 = s4.manipulability[s4.reachable]
    section.comparison(
        "Fig. 6 and eq. (11.4)",
        [
            Comparison(
                "3D3M type-4 singular angle |theta| at that y",
                28.7,
                abs(math.degrees(found.parameter)),
                "deg",
                rtol=1e-8,  # y is placed by eq. (11.4) at 28.7 deg; the root is found to 1e-9 rad
            ),
            Comparison("3D4M singular anywhere on the sweep", "no", "yes" if np.min(w4) < 1e-6 else "no"),
        ],
        note=f"plm_pin finds the root at {math.degrees(found.parameter):.4f} deg (negative for y > 0, the "
        f"sign (11.4) leaves open); the 3D4M's smallest w on the sweep is {np.min(w4):.4g}.",
    )


STATIC_CASES = (
    ("f_e = (1, 0, 0)", (1.0, 0.0, 0.0), 0.0),
    ("f_e = (0, 1, 0)", (0.0, 1.0, 0.0), 0.0),
    ("f_e = (0, 0, 1 N m)", (0.0, 0.0, 1.0), 0.0),
    ("f_i = 1 N (no load)", (0.0, 0.0, 0.0), 1.0),
)
"""Unit loads f_e the actuators exert on the plate [N, N m], and unit plate compression f_i [N]."""


def _legs(mech: Mechanism) -> tuple[int, ...]:
    return tuple(int(a.joint.removeprefix("slider")) for a in mech.actuators)


def _statics_rows(mech: Mechanism, pose: tuple[float, float, float]) -> tuple[list, list[Comparison]]:
    """Table rows (case, leg, f_c, f_n, f_l) and the comparisons with eqs. (15)-(22) at ``pose``."""
    params = PRESETS[mech.name].parameters
    l, rt = float(params["rod_lengths"][0]), float(params["half_plate"])
    legs = _legs(mech)
    rows, comparisons, worst = [], [], 0.0
    for label, f_e, f_i in STATIC_CASES:
        if f_i and mech.redundancy == 0:
            continue
        sol = static_forces(
            mech, mech.q_ref, -np.asarray(f_e), gravity=False, internal={"plate": -f_i} if f_i else None
        )
        f_c, f_l, f_n = paper.statics(pose, f_e, l, rt, legs, f_i)
        links, normals = sol.link_forces(), sol.slider_normal_forces()
        for k, (leg, act) in enumerate(zip(legs, mech.actuators, strict=True)):
            ours_l, ours_n = links[f"rod{leg}"].axial, float(normals[act.joint][1])
            rows.append((label, leg, float(sol.f_c[k]), ours_n, ours_l))
            worst = max(worst, abs(ours_l - f_l[k]), abs(ours_n - f_n[k]))
            equation = "(15)" if mech.redundancy == 0 else "(20)-(22)"
            comparisons.append(
                Comparison(
                    f"{label}: f_c{leg}, eq. {equation}",
                    float(f_c[k]),
                    float(sol.f_c[k]),
                    "N",
                    atol=1e-10,
                    source="closed form",
                )
            )
    comparisons.append(
        Comparison(
            "largest |f_l, f_n - eq. (19)| over the cases and legs",
            0.0,
            worst,
            "N",
            atol=1e-10,
            source="closed form",
        )
    )
    return rows, comparisons


def _statics(section: Section, four: Mechanism, three: Mechanism) -> None:
    import matplotlib.pyplot as plt

    q = four.q_ref
    x, y, theta = (float(v) for v in PRESETS[four.name].parameters["reference_pose"])
    pose = (x, y, theta)
    section.text(
        "Harada's f_e = J_ce^T f_c is the force the actuators exert on the plate; plm_pin takes the load "
        "applied to the plate, so the paper's unit f_e is the load -f_e, without gravity as in the paper. "
        "The *paper* columns are the paper's closed forms, eqs. (15)-(22), evaluated independently of "
        "plm_pin (analyses/_harada2011_paper.py); the tests check them at several poses to 1e-10. "
        "Eq. (22) is misprinted: `J_ce43^T J_i^-1 f_i` is a 3-vector where f_c has 4 entries; with eqs. "
        "(18) and (21) the internal part is `-J_c4 J_i^-1 f_i`, which is what plm_pin reproduces."
    )
    for mech in (four, three):
        rows, comparisons = _statics_rows(mech, pose)
        name = "3D4M" if mech.redundancy else "3D3M"
        section.table(
            f"{name}: actuator, guide-normal and rod-axial forces at the reference pose (0, 0.08 m, -20 deg)",
            ["case", "leg", Column("f_c", "N"), Column("f_n (along y)", "N"), Column("f_l (tension)", "N")],
            rows,
        )
        section.comparison(f"{name}: eqs. (15)-(22) and plm_pin", comparisons)
    sol = static_forces(four, q, gravity=False)
    (direction,) = sol.internal_directions()
    on_right = [direction.lam[c.rows] for c in four.closures if c.name.endswith("right")]
    if not on_right:
        raise PlmError(f"{four.name}: no closure at the plate's right end")
    right = sum(on_right[1:], on_right[0])
    along = abs(float(np.cross(right[:2], [math.cos(theta), math.sin(theta)]))) / float(np.linalg.norm(right))
    section.comparison(
        "Internal force (eq. (21))",
        [
            Comparison("dimension of the internal forces of the 3D4M", 1, sol.internal.size),
            Comparison("internal force along the end plate", "yes", "yes" if along < 1e-9 else "no"),
        ],
        note=f"sine of the angle between the internal force on the plate's right end and the plate: "
        f"{along:.1e}.",
    )
    ax_a, _ = fig8(four, q, [0.0, 1.0, 0.0], f_i=1.0)
    fig = ax_a.get_figure(root=True)
    if fig is None:
        raise PlmError("fig8 drew on axes outside a figure")
    section.figure(
        fig,
        "Fig. 8: (a) unit external force f_e = (0, 1, 0), no internal force; (b) with a unit internal force "
        "compressing the plate (broken: the internal force's own share).",
        {"f_e": [0.0, 1.0, 0.0], "f_i": 1.0},
    )
    plt.close("all")


def _capability(section: Section, four: Mechanism, three: Mechanism) -> None:
    import matplotlib.pyplot as plt

    limits4, limits3 = [(-LIMIT, LIMIT)] * 4, [(-LIMIT, LIMIT)] * 3
    rows = []
    for label, d in (("f_x", [1.0, 0.0, 0.0]), ("f_y", [0.0, 1.0, 0.0]), ("tau", [0.0, 0.0, 1.0])):
        c4 = force_capability(four, four.q_ref, d, limits=limits4)
        c3 = force_capability(three, three.q_ref, d, limits=limits3)
        rows.append((label, c4.alpha, c3.alpha, c4.alpha / c3.alpha, ", ".join(c4.saturated)))
    section.table(
        f"Largest load held at the reference pose, gravity included, |f_c| <= {LIMIT:g} N (an assumption)",
        ["load", Column("3D4M", "N or N m"), Column("3D3M", "N or N m"), "ratio", "3D4M saturated"],
        rows,
        note="The 3D4M can always leave actuator 3 idle, so it never holds less than the 3D3M (tested).",
    )
    fig, ax = plt.subplots(figsize=(5.5, 5.0), layout="constrained")
    polygons = {}
    for name, mech, lim in (("3D4M", four, limits4), ("3D3M", three, limits3)):
        P = wrench_polygon(mech, mech.q_ref, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], n=72, limits=lim)
        polygons[name] = P
        closed = np.vstack([P, P[:1]])
        ax.plot(closed[:, 0], closed[:, 1], label=name)
    ax.set_xlabel("f_x [N]")
    ax.set_ylabel("f_y [N]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend()
    section.figure(fig, "Loads (f_x, f_y) on the plate centre held within the limits (moment 0).", polygons)


PRELOADS = (0.0, 2.0, 5.0, 10.0, 20.0)
"""Plate compressions f_i of the preload table [N] (Harada 2011 eqs. (20)-(22), Fig. 8)."""

SOFT_DRIVE = 1.0e4
"""A soft drive stiffness [N/m] for which the geometric stiffness of the preload shows (an assumption)."""

STIFFNESS_ANGLES = np.radians(np.linspace(-40.0, 40.0, 81))
"""Plate angles of the stiffness sweep [rad]."""


def _drives(mech: Mechanism, k: float) -> ComplianceSpec:
    return ComplianceSpec(
        actuators={a.joint: k for a in mech.actuators}, source=f"drives {k:g} N/m (assumed)"
    )


def _stiffness(section: Section, four: Mechanism, three: Mechanism) -> None:
    compliance = four.sidecar.compliance
    k = HARADA2011_DRIVE_STIFFNESS
    section.text(
        "The paper gives no stiffness. Each linear motor is assumed to hold its slider with "
        f"k = {k:g} N/m ({compliance.source if compliance else 'preset'}); rods and plate rigid. The task "
        "stiffness is the Hessian of the potential condensed on the closed chain (`plm_pin.stiffness`): "
        "the drives' part k J_ce^T J_ce, plus the geometric stiffness of gravity and of the constraint "
        "forces, which is where the internal force f_i enters. The plate compression f_i (eqs. (20)-(22)) "
        "is applied as `internal={'plate': -f_i}` on top of gravity."
    )
    rows: list[tuple[str, float, float | None, float, float, float, bool]] = []
    data: dict[str, object] = {}
    for drive in (k, SOFT_DRIVE):
        base3 = stiffness(three, three.q_ref, compliance=_drives(three, drive))
        rows.append(
            ("3D3M", drive, None, base3.min_translational, base3.rotational.values[0], 1.0, _stable(base3))
        )
        base4 = None
        for f_i in PRELOADS:
            res = stiffness(four, four.q_ref, internal={"plate": -f_i}, compliance=_drives(four, drive))
            base4 = res if base4 is None else base4
            rows.append(
                (
                    "3D4M",
                    drive,
                    f_i,
                    res.min_translational,
                    res.rotational.values[0],
                    res.min_translational / base3.min_translational,
                    _stable(res),
                )
            )
            data[f"3D4M k={drive:g} f_i={f_i:g}"] = res.to_dict()
        data[f"3D3M k={drive:g}"] = base3.to_dict()
    section.table(
        "Eigen-stiffness at the reference pose (x = 0, y = 0.08 m, theta = -20 deg), gravity included",
        [
            "table",
            Column("drive stiffness", "N/m", ".3g"),
            Column("f_i", "N", ".3g"),
            Column("smallest translational", _K["translational"], ".7g"),
            Column("rotational", _K["rotational"], ".7g"),
            Column("translational / 3D3M", "-", ".5g"),
            "stable",
        ],
        rows,
        note="The compression f_i lowers the stiffness (compressed links soften, tension would stiffen); "
        "with the assumed drives its geometric stiffness, of order f_i / l, is about 1e-4 of the drives' "
        "and the fourth drive is what stiffens the 3D4M. With soft drives the 3D3M is unstable under "
        "gravity (K_x not positive definite, eigen-stiffnesses then meaningless). Preload's practical "
        "benefit, removing backlash, is not in this model.",
        id="stiffness",
    )
    flexible = _flexible_rods(four, k)
    rigid = stiffness(four, four.q_ref, compliance=_drives(four, k))
    bent = stiffness(four, four.q_ref, compliance=flexible)
    section.table(
        "3D4M with flexible rods (aluminium 8 x 4 mm beams, an assumption; virtual joints)",
        [
            "rods",
            Column("smallest translational", _K["translational"], ".7g"),
            Column("largest translational", _K["translational"], ".7g"),
            Column("rotational", _K["rotational"], ".7g"),
        ],
        [
            (label, r.translational.values[0], r.translational.values[-1], r.rotational.values[0])
            for label, r in (("rigid", rigid), ("flexible", bent))
        ],
        note=f"E = {ROD_SECTION[0]:g} Pa, G = {ROD_SECTION[1]:g} Pa, A = {ROD_SECTION[2]:g} m^2, "
        f"I = {ROD_SECTION[3]:g} (out of plane), {ROD_SECTION[4]:g} (in plane) m^4, "
        f"J = {ROD_SECTION[5]:g} m^4. "
        "The pin-jointed rods add their axial compliance L/EA in series with the drives.",
        id="flexible_rods",
    )
    data["3D4M flexible rods"] = bent.to_dict()
    rows = []
    for name, mech, spec, model in (
        ("3D4M", four, _drives(four, k), "task"),
        ("3D3M", three, _drives(three, k), "task"),
        ("3D4M, flexible rods", four, flexible, "task"),
        ("3D4M, flexible rods", four, flexible, "full"),
    ):
        m = natural_frequencies(mech, mech.q_ref, model=model, compliance=spec)
        rows.append((name, model, *m.frequencies[:3].tolist()))
    section.table(
        f"Lowest natural frequencies at the reference pose (drives {k:g} N/m)",
        [
            "table",
            "model",
            *(Column(f"f{i + 1}", units(Vibration)["frequencies"], ".5g") for i in range(3)),
        ],
        rows,
        note="'task': M_x and K_x (the plane's three motions); 'full': every motion of the compliant model, "
        "here with the rods' out-of-plane bending, which lets the plate move out of the plane.",
        id="frequencies",
    )
    _stiffness_sweep(section, four, three, data)


ROD_SECTION = (7.0e10, 2.6e10, 3.2e-5, 4.3e-11, 1.7e-10, 1.17e-10)
"""Assumed rod beams: aluminium 8 x 4 mm, E, G [Pa], A [m^2], Iy (out of plane), Iz (in plane), J [m^4]."""


def _flexible_rods(four: Mechanism, k: float) -> ComplianceSpec:
    """Drives of stiffness k and the four rods as beams (rod 1's tip: the plate's joint)."""
    tips = {1: "plate_pivot", 2: "rod2_tip", 3: "rod3_tip", 4: "rod4_tip"}
    beams = tuple(BeamSpec(f"rod{i}", tip, ROD_SECTION, y_axis=(0.0, 1.0, 0.0)) for i, tip in tips.items())
    return ComplianceSpec(actuators={a.joint: k for a in four.actuators}, links=beams, source="assumed")


def _stable(res: StiffnessResult) -> bool:
    """Whether K_x is positive definite (a stable equilibrium)."""
    return bool(np.linalg.eigvalsh(0.5 * (res.K_x + res.K_x.T)).min() > 0.0)


def _stiffness_sweep(
    section: Section, four: Mechanism, three: Mechanism, reference: dict[str, object]
) -> None:

    fig, (left, right) = panel_grid(2, width=5.0, height=3.8)
    curves: dict[str, object] = {
        "theta_deg": np.degrees(STIFFNESS_ANGLES).tolist(),
        "reference_pose": reference,
    }
    for name, mech in (("3D4M", four), ("3D3M", three)):
        line = workspace_sweep(mech, "rz", STIFFNESS_ANGLES)
        smap = stiffness_map(mech, line)
        left.semilogy(np.degrees(STIFFNESS_ANGLES), smap.min_translational_stiffness, label=name)
        right.plot(np.degrees(STIFFNESS_ANGLES), smap.lowest_frequency, label=name)
        curves[name] = smap.to_dict()
    left.set_xlabel("theta [deg]")
    left.set_ylabel("smallest translational eigen-stiffness [N/m]")
    right.set_xlabel("theta [deg]")
    right.set_ylabel("lowest natural frequency [Hz]")
    for ax in (left, right):
        ax.grid(alpha=0.3)
    shared_legend(fig, (left, right))
    section.figure(
        fig,
        "Stiffness and lowest natural frequency against the plate angle at x = 0, y = 0.08 m: the 3D3M "
        "softens towards its direct singularity, the redundant 3D4M does not.",
        curves,
    )


def _decoupling(section: Section, four: Mechanism, asym: Mechanism) -> None:
    p = PRESETS["harada2011_3d4m"].parameters
    m_l, m_m, m_t = float(p["rod_masses"][0]), float(p["slider_mass"]), float(p["plate_mass"])
    xs = np.linspace(-0.02, 0.02, 3)
    ys = np.linspace(0.07, 0.09, 3)
    ths = np.radians(np.linspace(-30.0, 10.0, 5))
    sample = np.array([(x, y, t) for x in xs for y in ys for t in ths])
    rep = decoupling_check(four, sample)
    section.text(
        f"Task-space dynamics M_x = S^T M S, h_x, g_x over {len(rep.poses)} poses "
        f"(x in [-0.02, 0.02] m, y in [0.07, 0.09] m, theta in [-30, 10] deg)."
    )
    mxx = rep.inertia("x", "x")
    section.comparison(
        "Eq. (23) and (M.30)",
        [
            Comparison(
                "m_xx = 4 m_l + 4 m_m + m_t, constant",
                4 * m_l + 4 * m_m + m_t,
                mxx.value,
                "kg",
                rtol=1e-9,
                source="closed form",
            ),
            Comparison("m_xx constant over the workspace", "yes", "yes" if mxx.kind == "constant" else "no"),
            Comparison("m_xy vanishes", "yes", "yes" if rep.inertia("x", "y").kind == "zero" else "no"),
            Comparison("m_x theta vanishes", "yes", "yes" if rep.inertia("x", "rz").kind == "zero" else "no"),
            Comparison(
                "g_y = (2 m_l + m_t) g",
                (2 * m_l + m_t) * G,
                rep.gravity("y").value,
                "N",
                rtol=1e-9,
                source="closed form",
            ),
            Comparison(
                "gravity acts only along y",
                "yes",
                "yes" if rep.gravity("x").kind == rep.gravity("rz").kind == "zero" else "no",
            ),
        ],
    )
    section.table(
        "Decoupling table of the 3D4M",
        ["entry", "behaviour"],
        _entries(rep),
        note=f"h_x at the {len(rep.velocities)} task velocities {rep.velocity_text()}, which determine the "
        "quadratic h_x: zero there is zero at every velocity.",
    )
    asym_rep = decoupling_check(asym, sample + np.array([0.0, 0.01, 0.0]))
    section.table(
        "The asymmetric design of Harada 2015 (unequal rods) loses the decoupling",
        ["entry", "behaviour"],
        _entries(asym_rep),
        note="Entries that vanish or stay constant on the 3D4M vary here; the ratio column of results.json "
        "gives how strongly each off-diagonal inertia couples two coordinates (0 to 1).",
    )


def _entries(rep: DecouplingReport) -> list[tuple[str, str]]:
    return [(name, f"{e.kind}: {e.describe()} (coupling {e.ratio:.2g})") for name, e in rep.entries()]


def _task_path(mech: Mechanism, run: SimulationResult) -> np.ndarray:
    """Task coordinates of ``run`` (x, y, theta), shape (n, 3); refused if the simulation recorded none."""
    if run.x is None:
        raise PlmError(f"{mech.name}: the simulation recorded no task coordinates (no task)")
    return run.x


def _simulations(section: Section, mech: Mechanism) -> None:

    p = PRESETS["harada2011_3d4m"].parameters
    m_l, m_m, m_t = float(p["rod_masses"][0]), float(p["slider_mass"]), float(p["plate_mass"])
    runs = {SIMULATIONS[case][0]: simulate_case(mech, case) for case in SIMULATIONS}
    paths = {name: _task_path(mech, run) for name, run in runs.items()}
    curves = {}
    for name, x in paths.items():
        curves[f"{name}: x [m]"] = x[:, 0]
        curves[f"{name}: y [m]"] = x[:, 1]
        curves[f"{name}: theta [deg]"] = np.degrees(x[:, 2])
    t = next(iter(runs.values())).t
    fig, flat = plot_panels(t, curves, xlabel="t [s]")
    section.figure(
        fig,
        "Figs. 10 and 12: x, y, theta under constant task forces from (0, 0.08 m, -20 deg) at rest, 2 s."
        + flat,
        {name: {"t": r.t, "x": paths[name]} for name, r in runs.items()},
    )
    fig, axes = panel_grid(2, width=5.0, height=2.6)
    snapshots = {}
    for ax, (name, run), number in zip(axes, runs.items(), (11, 13), strict=True):
        every = slice(None, None, round(SNAPSHOT_PERIOD / SIM_DT))
        plot_skeletons(mech, run.q[every], ax=ax, title=f"Fig. {number}: {name}")
        snapshots[name] = {"t": run.t[every], "x": paths[name][every]}
    section.figure(
        fig,
        f"Figs. 11 and 13: the table every {SNAPSHOT_PERIOD:g} s (light: t = 0, black: t = 2 s), as drawn "
        "by the paper's code (M.42).",
        snapshots,
    )
    _, two = runs.values()
    x_one, x_two = paths.values()
    expected = SIMULATIONS["simulation1"][1] / (4 * m_l + 4 * m_m + m_t) * DURATION**2 / 2
    section.comparison(
        "Simulations (Tables 2-4)",
        [
            Comparison(
                "simulation 1: x(2 s) = f_x / m_xx t^2 / 2",
                expected,
                float(x_one[-1, 0]),
                "m",
                rtol=1e-9,
                source="closed form",
            ),
            Comparison("simulation 1: y stays 0.08 m", 0.08, float(x_one[-1, 1]), "m", rtol=1e-9),
            Comparison("simulation 2: x stays 0", 0.0, float(x_two[-1, 0]), "m", atol=1e-9),
            Comparison(
                "simulation 2: theta accelerates", "yes", "yes" if x_two[-1, 2] > x_two[0, 2] else "no"
            ),
        ],
        note=f"Largest closure residual {max(r.max_residual for r in runs.values()):.1e} m; "
        f"in simulation 2, theta reaches {np.degrees(x_two[-1, 2]):.1f} deg at 2 s and y stays within "
        f"[{x_two[:, 1].min() * 1e3:.1f}, {x_two[:, 1].max() * 1e3:.1f}] mm: the slight motion of "
        "Fig. 12 (b), whose axis spans -0.1 to 0.3 m ((M.40)).",
    )
    section.animation(
        Animation(mech, two.q, two.t, "Simulation 2 animated: rotate, zoom and play in the page.")
    )
