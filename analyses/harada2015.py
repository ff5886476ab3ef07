"""Harada 2015, "Mode changes of a planar 3 DOF redundantly actuated parallel robot".

What the paper shows and plm_pin computes (:mod:`plm_pin.families.prrrp`): the 9
assembly modes of the 2-PRRRP and their transition graph (Sec. III, Fig. 5), the
singularity-free assembly-mode change ``[+ +] -> [+ 0] -> [+ -] -> [0 -] -> [- -]`` (Fig. 6,
Sec. V), the working-mode change ``(- + - +) -> (- + 0 +) -> (- + + +)`` (Fig. 7, Sec. V),
the complex singularity that equal rods admit and the asymmetric design avoids, and (from
the introduction) that the non-redundant version cannot change assembly mode without a
singularity. The paper prints few numbers: the rod lengths (Fig. 2), the number of modes and
the ranks of :math:`J_x`; the rest of its claims are compared as yes/no or as mode sequences.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence

import numpy as np

from plm_pin import Mechanism, build_mechanism, load
from plm_pin.exceptions import PoseUnreachable
from plm_pin.families.prrrp import (
    PAPER_ASSEMBLY_ROUTE,
    PAPER_WORKING_ROUTE,
    AssemblyModeChange,
    ComplexSingularityCase,
    PrrrpLayout,
    WorkingModeChange,
    assembly_mode_graph,
    complex_singularity_check,
    mode_label,
    plan_assembly_mode_change,
    plan_working_mode_change,
    prrrp_layout,
    prrrp_state,
    symmetric_rods,
    working_mode_label,
)
from plm_pin.kinematics import ModeGraph, forward_kinematics
from plm_pin.report import Animation, Column, Comparison, Section, StudyContext
from plm_pin.tolerances import SINGULARITY_TOL
from plm_pin.viz import panel_grid

TITLE = "Harada 2015: mode changes of the asymmetric 2-PRRRP"
SUMMARY = (
    "Assembly-mode graph (Fig. 5), singularity-free assembly- and working-mode changes (Figs. 6-7), "
    "complex singularity of equal rods."
)

ASSEMBLY_DURATION = 8.0
"""Duration given to the assembly-mode change in its animation [s] (the paper gives none)."""

WORKING_DURATION = 5.0
"""Duration given to the working-mode change in its animation [s]."""

ARROW = " → "

SYMMETRIC_ROD = 0.240
"""Rod length of the equal-rod variant whose complex singularity is checked [m]."""


def _route(modes: Sequence[Sequence[int]], label: Callable[[Sequence[int]], str] = mode_label) -> str:
    return ARROW.join(label(m) for m in modes)


def assembly_animation(mech: Mechanism, change: AssemblyModeChange) -> Animation:
    """The assembly-mode change, its samples spread evenly over :data:`ASSEMBLY_DURATION`."""
    path = change.path
    return Animation(
        mech,
        path.q,
        np.linspace(0.0, ASSEMBLY_DURATION, path.n_samples),
        f"The assembly-mode change as an animation ({ASSEMBLY_DURATION:g} s): open the controls and play it.",
    )


def working_animation(mech: Mechanism, flip: WorkingModeChange) -> Animation:
    """The working-mode change of leg 3, its samples spread evenly over :data:`WORKING_DURATION`."""
    path = flip.path
    return Animation(
        mech,
        path.q,
        np.linspace(0.0, WORKING_DURATION, path.n_samples),
        f"The working-mode change as an animation ({WORKING_DURATION:g} s); open the controls to replay it.",
    )


def _plan_assembly() -> Animation:
    mech = load("harada2015_asymmetric")
    return assembly_animation(mech, plan_assembly_mode_change(mech))


def _plan_working() -> Animation:
    mech = load("harada2015_asymmetric")
    return working_animation(mech, plan_working_mode_change(mech, leg=3))


ANIMATIONS = {"assembly": _plan_assembly, "working": _plan_working}
"""The two mode changes, for ``plm-pin view --animate harada2015:assembly`` (or ``working``)."""


def run(ctx: StudyContext) -> None:
    """Compute the modes, plan both mode changes and compare with the paper."""
    mech = ctx.load("harada2015_asymmetric")
    layout = prrrp_layout(mech)
    ctx.step("assembly-mode graph")
    graph = assembly_mode_graph(mech, layout=layout)
    ctx.step("assembly-mode change")
    change = plan_assembly_mode_change(mech, graph=graph)
    ctx.step("working-mode change")
    flip = plan_working_mode_change(mech, leg=3)
    ctx.step("complex singularity: equal and unequal rods")
    symmetric = ctx.load(
        build_mechanism(
            "harada2015_asymmetric",
            symmetric_rods(SYMMETRIC_ROD),
            name="harada2015_asymmetric_symmetric_240mm",
        )
    )
    cases = [complex_singularity_check(symmetric, leg=3), complex_singularity_check(mech, leg=3)]
    ctx.step("non-redundant 3D3M graph")
    non_redundant = ctx.load("harada2011_3d3m")
    graph_3d3m = assembly_mode_graph(non_redundant)

    section = ctx.section("Paper vs plm_pin")
    section.text(
        "The paper's claims side by side with what plm_pin computes. `J_x` of eq. (2) has rank 3 "
        "exactly when plm_pin's closed-chain direct Jacobian `C = S_a N` has rank 3 (the mobility); "
        "*redundancy lost* means that some slider cannot be dropped without `C` losing rank "
        "(redundancy margin zero)."
    )
    section.comparison(
        "Harada 2015 and plm_pin", _comparisons(layout, graph, change, flip, cases, graph_3d3m)
    )

    ctx.step("figures and scenes")
    _graph_section(ctx.section("Assembly modes and their transition graph (Sec. III, Fig. 5)"), mech, graph)
    _assembly_section(
        ctx.section("Singularity-free assembly-mode change (Fig. 6, Sec. V)"), mech, layout, change
    )
    _working_section(ctx.section("Working-mode change of leg 3 (Fig. 7, Sec. V)"), mech, layout, flip)
    _complex_section(ctx.section("Complex singularity: equal rods against the asymmetric design"), cases)
    section = ctx.section("Non-redundant version: the 3D3M cannot change assembly mode")
    section.text(
        "Without slider 3 (Harada 2011's 3D3M, rods 0.140 m) the left pair on the stator is a direct "
        "singularity of the whole mechanism: every route from [+ +] to [- -] passes a singular mode."
    )
    section.table(
        "3D3M assembly modes",
        ["mode", "rank of C", "singular", Column("direct margin", "-")],
        [(n.label, n.rank, n.singular, n.direct_margin) for n in graph_3d3m.nodes],
    )


def _comparisons(
    layout: PrrrpLayout,
    graph: ModeGraph,
    change: AssemblyModeChange,
    flip: WorkingModeChange,
    cases: Sequence[ComplexSingularityCase],
    graph_3d3m: ModeGraph,
) -> list[Comparison]:
    off = [n for n in graph.nodes if 0 not in n.mode]
    on = [n for n in graph.nodes if 0 in n.mode and n.mode != (0, 0)]
    lengths = [
        Comparison(f"rod length l{g.index} (Fig. 2)", paper, g.length, "m", rtol=1e-9, source="input")
        for g, paper in zip(layout.legs, (0.240, 0.170, 0.170, 0.240), strict=True)
    ]
    return [
        *lengths,
        Comparison("assembly modes of the 2-PRRRP (Sec. III)", 9, len(graph.nodes)),
        Comparison(
            "rank of J_x in [+ +], [+ -], [- +], [- -] (Sec. III)", 3, min(n.rank for n in off), rtol=0.0
        ),
        Comparison(
            "rank of J_x in [+ 0], [- 0], [0 +], [0 -] (Sec. III)", 3, min(n.rank for n in on), rtol=0.0
        ),
        Comparison("rank of J_x in [0 0] below 3 (Sec. III)", True, graph.node((0, 0)).rank < 3),
        Comparison(
            "redundancy lost in [+ 0], [- 0], [0 +], [0 -] (Sec. III)",
            True,
            all(n.redundancy_margin <= SINGULARITY_TOL for n in on),
        ),
        Comparison(
            "singularity-free route [+ +] to [- -] (Fig. 6, Sec. V)",
            _route(PAPER_ASSEMBLY_ROUTE),
            _route(change.visited),
        ),
        Comparison("assembly-mode change free of direct and constraint singularities", True, change.ok),
        Comparison(
            "at the [0] crossings: redundancy lost, mechanism non-singular (Sec. V)",
            True,
            all(c.redundancy_margin <= SINGULARITY_TOL < c.direct_margin for c in change.crossings),
        ),
        Comparison(
            "working-mode change (Fig. 7, Sec. V)",
            _route(PAPER_WORKING_ROUTE, working_mode_label),
            _route(flip.visited, working_mode_label),
        ),
        Comparison(
            "singularity at the (0) state of leg 3: actuator (inverse) only (Sec. IV)",
            "inverse",
            ", ".join(flip.path.report(flip.fold_index).kinds),
        ),
        Comparison("working-mode change free of direct and constraint singularities", True, flip.ok),
        Comparison(
            "equal rods admit the complex singularity (Sec. III, Fig. 7(a))",
            True,
            cases[0].admits_complex_singularity,
        ),
        Comparison("the asymmetric rods admit it (Fig. 7(b))", False, cases[1].admits_complex_singularity),
        Comparison(
            "non-redundant version changes assembly mode without singularity (Sec. I)",
            False,
            bool(graph_3d3m.routes((1, 1), (-1, -1))),
        ),
    ]


def _modes_at_sliders(mech: Mechanism, q: np.ndarray) -> str:
    """Every assembly mode at the slider positions of ``q`` (complete forward kinematics), in a few words."""
    try:
        modes = forward_kinematics(mech, mech.actuator_positions(q))
    except PoseUnreachable:
        return "none"
    if modes.complete:
        return f"all {len(modes)} (certified)"
    return f"{len(modes)} found, not proven complete"


def _graph_section(section: Section, mech: Mechanism, graph: ModeGraph) -> None:
    section.text(
        "plm_pin derives the graph by computation: a representative configuration of each mode "
        "(pair heights ±r_t/2 or 0, reached by inverse-kinematics continuation), the rank of `C` "
        "there, and an edge between two modes when a straight walk in pair-height space from one "
        "representative to the other, assembled at every sample, visits no third mode."
    )
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 5.0))
    route = set(itertools.pairwise(PAPER_ASSEMBLY_ROUTE))
    for e in graph.edges:
        on_route = (e.a, e.b) in route or (e.b, e.a) in route
        singular = graph.node(e.a).singular or graph.node(e.b).singular
        ax.plot(
            [e.a[0], e.b[0]],
            [e.a[1], e.b[1]],
            color="tab:blue" if on_route else ("0.75" if singular else "0.35"),
            lw=3.0 if on_route else 1.2,
            ls=":" if singular else "-",
            zorder=1,
        )
    for n in graph.nodes:
        left, right = n.mode  # signs of the left and right pairs
        ax.scatter(left, right, s=900, color="tab:red" if n.singular else "white", edgecolors="k", zorder=2)
        ax.annotate(n.label, (left, right), ha="center", va="center", fontsize=9, zorder=3)
    ax.set_xlim(-1.5, 1.5)
    ax.set_ylim(-1.5, 1.5)
    ax.set_xticks([-1, 0, 1], ["-", "0", "+"])
    ax.set_yticks([-1, 0, 1], ["-", "0", "+"])
    ax.set_xlabel("left pair (legs 1, 2)")
    ax.set_ylabel("right pair (legs 3, 4)")
    ax.set_aspect("equal")
    section.figure(
        fig,
        "Computed transition graph of the assembly modes (Fig. 5): red = rank of C below 3 (singular), "
        "dotted = edges to it, blue = the paper's singularity-free route.",
        {"graph": graph.to_dict()},
    )
    section.table(
        "Assembly modes at their representatives",
        [
            "mode",
            "rank of C",
            "full rank",
            "singular",
            Column("direct margin", "-"),
            Column("redundancy margin", "-"),
            "assembly modes at its sliders",
        ],
        [
            (
                n.label,
                n.rank,
                n.full_rank,
                n.singular,
                n.direct_margin,
                n.redundancy_margin,
                _modes_at_sliders(mech, n.q),
            )
            for n in graph.nodes
        ],
        note="Margins are normalised smallest singular values; 0 means rank lost. The last column lists "
        "every assembly mode at the representative's slider positions (complete forward kinematics by "
        "homotopy; 'certified' when proven that none was missed).",
    )
    section.table(
        "Edges of the graph",
        ["from", "to", Column("smallest direct margin on the walk", "-"), "samples"],
        [(mode_label(e.a), mode_label(e.b), e.min_direct_margin, e.samples) for e in graph.edges],
    )


def _snapshots(
    section: Section,
    mech: Mechanism,
    layout: PrrrpLayout,
    qs: Sequence[np.ndarray],
    titles: Sequence[str],
    caption: str,
) -> None:
    """Skeletons of a 2-PRRRP at a few configurations, at most three a row (the paper's Fig. 8 snapshots)."""
    fig, axes = panel_grid(len(qs), width=4.0, height=1.9, sharex=True, sharey=True)
    drawn = []
    for ax, q, title in zip(axes, qs, titles, strict=True):
        state = prrrp_state(mech, q, layout)
        c = mech.actuator_positions(q)
        pairs = state.pairs[:, :2]
        ax.axhline(0.0, color="0.6", lw=3, zorder=0)
        for leg in layout.legs:
            pair = pairs[0 if leg.pair == "plate_left" else 1]
            ci = c[leg.actuator]
            ax.plot([ci, pair[0]], [0.0, pair[1]], color="tab:orange", lw=2)
            ax.plot(ci, 0.0, "s", color="tab:blue", ms=7)
        ax.plot(pairs[:, 0], pairs[:, 1], color="k", lw=4, solid_capstyle="round")
        ax.set_title(title, fontsize=9)
        ax.set_aspect("equal")
        ax.tick_params(labelbottom=True)  # a panel over a hidden cell keeps its x ticks
        drawn.append({"title": title, "actuators": c, "pairs": pairs})
    fig.supxlabel("x [m]")
    fig.supylabel("y [m]")
    section.figure(fig, caption, {"snapshots": drawn})


def _assembly_section(
    section: Section, mech: Mechanism, layout: PrrrpLayout, change: AssemblyModeChange
) -> None:
    section.text(
        "The plate goes from [+ +] to its mirror image [- -] (the other solution of the direct kinematics "
        "for the same slider positions) along the paper's route: each pair crosses the stator in turn "
        "while the plate is tilted, so the other pair holds it. The actuator path is planned by "
        "inverse-kinematics continuation and then followed by forward-kinematics continuation, which is "
        "what the sliders alone impose."
    )
    path = change.path
    import matplotlib.pyplot as plt

    fig, (top, middle, bottom) = plt.subplots(3, 1, figsize=(8.0, 8.0), sharex=True, layout="constrained")
    top.plot(path.s, change.heights[:, 0], label="left pair q_L")
    top.plot(path.s, change.heights[:, 1], label="right pair q_R")
    top.set_ylabel("pair height [m]")
    top.legend(loc="best", fontsize="small")
    for k in range(path.actuators.shape[1]):
        middle.plot(path.s, path.actuators[:, k], label=f"c{layout.legs[k].index}")
    middle.set_ylabel("slider position [m]")
    middle.legend(loc="best", fontsize="small", ncol=4)
    bottom.semilogy(path.s, path.direct_margin, label="direct margin (C)")
    bottom.semilogy(path.s, np.maximum(path.redundancy_margin, 1e-18), label="redundancy margin")
    bottom.axhline(path.tol, color="red", ls=":", lw=1, label="tolerance")
    bottom.set_ylabel("margin [-]")
    bottom.set_xlabel("path parameter s [-]")
    bottom.legend(loc="best", fontsize="small")
    for c in change.crossings:
        for ax in (top, middle, bottom):
            ax.axvline(c.s, color="0.5", ls="--", lw=0.8)
        top.annotate(mode_label(c.mode), (c.s, 1.0), xycoords=("data", "axes fraction"), va="top", fontsize=8)
    section.figure(
        fig,
        "Assembly-mode change: pair heights, slider positions and margins along the path; dashed lines "
        "at the [0] crossings, where the redundancy margin is zero and the direct margin is not "
        "(redundancy margins below 1e-18 drawn at 1e-18).",
        {"change": change.to_dict()},
    )
    picks = [0, *(c.index for c in change.crossings), path.n_samples - 1]
    between = [(a + b) // 2 for a, b in itertools.pairwise(picks)]
    order = sorted({*picks, *between})
    _snapshots(
        section,
        mech,
        layout,
        [path.q[k] for k in order],
        [mode_label(change.assembly_modes[k]) for k in order],
        "Snapshots of the assembly-mode change (cf. Fig. 8): sliders (squares) on the stator, rods, plate.",
    )
    section.table("Assembly-mode change", ["quantity", "value", "unit"], _change_rows(change, []))
    section.table(
        "Where each pair crosses the stator ([0])",
        [
            "sample",
            Column("s", "-"),
            "pair",
            "mode",
            Column("x", "m"),
            Column("y", "m"),
            Column("theta", "deg"),
            Column("direct margin", "-"),
            Column("pair's own direct margin", "-"),
            Column("redundancy margin", "-"),
        ],
        [
            (
                c.index,
                c.s,
                c.sub,
                mode_label(c.mode),
                c.x[0],
                c.x[1],
                float(np.degrees(c.x[2])),
                c.direct_margin,
                c.sub_direct_margin,
                c.redundancy_margin,
            )
            for c in change.crossings
        ],
    )
    section.animation(assembly_animation(mech, change))


def _working_section(section: Section, mech: Mechanism, layout: PrrrpLayout, flip: WorkingModeChange) -> None:
    section.text(
        "Slider 3 moves through the position under its pair, where rod 3 is perpendicular to the stator "
        "(the actuator singularity, state (0)), to its mirror image; the plate tilts meanwhile so that "
        "rod 4 (0.240 m, longer than rod 3) holds the pair, and ends where it started."
    )
    path = flip.path
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8.0, 5.5), sharex=True, layout="constrained")
    for k in range(path.actuators.shape[1]):
        top.plot(path.s, path.actuators[:, k], label=f"c{layout.legs[k].index}")
    top.set_ylabel("slider position [m]")
    top.legend(loc="best", fontsize="small", ncol=4)
    bottom.semilogy(path.s, np.maximum(path.inverse_margin, 1e-18), label="inverse margin (T)")
    bottom.semilogy(path.s, path.direct_margin, label="direct margin (C)")
    bottom.semilogy(path.s, path.constraint_margin, label="constraint margin")
    bottom.axhline(path.tol, color="red", ls=":", lw=1, label="tolerance")
    bottom.set_ylabel("margin [-]")
    bottom.set_xlabel("path parameter s [-]")
    bottom.legend(loc="best", fontsize="small")
    for ax in (top, bottom):
        ax.axvline(path.s[flip.fold_index], color="0.5", ls="--", lw=0.8)
    section.figure(
        fig,
        "Working-mode change: slider positions and margins; at the dashed line rod 3 is perpendicular "
        "to the stator: the inverse margin vanishes, the direct and constraint margins do not "
        "(inverse margins below 1e-18 drawn at 1e-18).",
        {"change": flip.to_dict()},
    )
    order = [
        0,
        flip.fold_index // 2,
        flip.fold_index,
        (flip.fold_index + path.n_samples - 1) // 2,
        path.n_samples - 1,
    ]
    _snapshots(
        section,
        mech,
        layout,
        [path.q[k] for k in order],
        [working_mode_label(flip.working_modes[k]) for k in order],
        "Snapshots of the working-mode change (cf. Fig. 7 (b) and Fig. 8).",
    )
    fold = path.report(flip.fold_index)
    section.table(
        "Working-mode change",
        ["quantity", "value", "unit"],
        _change_rows(
            flip,
            [
                ("sample at the fold", flip.fold_index, ""),
                ("inverse margin at the fold", fold.inverse_margin, "-"),
                ("direct margin at the fold", fold.direct_margin, "-"),
                ("smallest gap between sliders 3 and 4", float(np.min(flip.slider_gap)), "m"),
            ],
        ),
    )
    section.animation(working_animation(mech, flip))


def _change_rows(
    change: AssemblyModeChange | WorkingModeChange, own: Sequence[tuple[str, object, str]]
) -> list[tuple[str, object, str]]:
    """The summary rows of a mode change: its sample count, ``own`` rows, then margins, residual, route."""
    path = change.path
    return [
        ("samples", path.n_samples, ""),
        *own,
        ("smallest direct margin", path.min_direct_margin, "-"),
        ("smallest constraint margin", path.min_constraint_margin, "-"),
        ("largest closure residual", path.max_residual, "m, rad"),
        ("largest planned-to-tracked frame distance", change.max_deviation, "m"),
        ("route followed, non-singular", change.ok, ""),
    ]


def _complex_section(section: Section, cases: Sequence[ComplexSingularityCase]) -> None:
    section.text(
        "Rod 3 is brought perpendicular to the stator at the halfway pose of the working-mode change. "
        "With equal rods (every rod 0.240 m) rod 4 must be perpendicular too: both sliders sit at one "
        "position, the two circles of eq. (4) coincide and the closure Jacobian loses rank (the complex "
        "singularity). With the paper's rods (l3 = 0.170 m, l4 = 0.240 m) the sliders stay at least "
        "|l4 - l3| apart."
    )
    section.table(
        "Leg 3 perpendicular to the stator",
        [
            "mechanism",
            Column("l3", "m"),
            Column("l4", "m"),
            Column("slider gap", "m"),
            Column("smallest possible gap", "m"),
            "circles of eq. (4)",
            "rank of J_phi",
            "generic rank",
            "singularity kinds",
            "complex singularity",
        ],
        [
            (
                c.name,
                c.rod_lengths[0],
                c.rod_lengths[1],
                c.slider_gap,
                c.min_slider_gap,
                c.circles,
                c.closure_rank,
                c.generic_closure_rank,
                ", ".join(c.report.kinds),
                c.admits_complex_singularity,
            )
            for c in cases
        ],
    )
