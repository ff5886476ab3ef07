"""Design sweeps of the Harada tables: where redundancy and the asymmetric rods of Harada 2015 pay.

Harada 2011 fixes l : 2 r_t = 2 : 1 for Fig. 6 and shows, at one height, that the 3D3M meets
its type-4 singularity at 28.7 deg while the redundant 3D4M does not; Harada 2015 makes two
rods shorter (l1 = l4 = 0.240 m, l2 = l3 = 0.170 m) so that assembly-mode changes avoid the
complex singularity of equal rods. This study sweeps, with :func:`plm_pin.sweep.sweep`, the ratio
l / r_t and the height y for both tables, and the inner rod length for the 2015 design, and
reads off the singularity-free rotation range, the manipulability and the reachable part of
a workspace box, each also with the carriages' self-collision excluded (sweep metric
``collision_free``). Every number it states is computed here.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

import plm_pin
from plm_pin import PlmError
from plm_pin.families.prrrp import complex_singularity_check
from plm_pin.families.prrrp.builder import CARRIAGE_SIZE
from plm_pin.report import Column, Comparison, Parameter, Section, StudyContext
from plm_pin.sweep import SweepResult, sweep
from plm_pin.tolerances import RANGE_XTOL
from plm_pin.viz import panel_grid, plot_sweep_heatmap, plot_sweep_lines

if TYPE_CHECKING:
    import xarray as xr

TITLE = "Design sweeps of the Harada tables: rotation range and manipulability against l / r_t, y and rods"
SUMMARY = (
    "plm_pin.sweep over l / r_t and the height (3D3M vs 3D4M) and over the inner rod length (Harada 2015): "
    "where redundancy and the asymmetric design pay."
)

L = 0.140
"""Rod length of Harada 2011 Table 1 [m], kept while r_t varies."""

RATIOS = (2.0, 2.8, 4.0, 5.6, 8.0)
"""l / r_t swept: 2.8 is Table 1 (r_t = 0.05 m), 4 is Fig. 6 (l : 2 r_t = 2 : 1)."""

FIG6_Y = (L + L / 4.0) * math.sin(math.radians(28.7))
"""The height where eq. (11.4) puts the 3D3M's type-4 singularity at 28.7 deg for l : 2 r_t = 2 : 1 [m]."""

HEIGHTS = np.sort(np.append(np.linspace(0.02, 0.13, 12), FIG6_Y))
"""Plate heights y swept [m] (the rods reach y < l = 0.14 m)."""

ANGLES = np.radians(np.linspace(-80.0, 80.0, 81))
"""Plate angles [rad]: Fig. 6's +/-80 deg in 2 deg samples, the brackets of the root search."""

WORK_ANGLE = math.radians(20.0)
"""Half-width of the working rotation over which the smallest manipulability is read [rad]."""

INNER = (0.14, 0.17, 0.20, 0.24)
"""Inner rod lengths l2 = l3 swept with the outer l1 = l4 = 0.24 m of Harada 2015 [m]."""


def run(ctx: StudyContext) -> None:
    """Fill the report."""
    for name in ("harada2011_3d3m", "harada2011_3d4m", "harada2015_asymmetric"):
        ctx.load(name)
    ctx.step("sweep l / r_t x y for the 3D3M and the 3D4M")
    ratio = sweep(
        "harada2011_3d4m",
        {"legs": [[1, 2, 4], [1, 2, 3, 4]], "half_plate": [L / r for r in RATIOS]},
        {"y": HEIGHTS, "rz": ANGLES},
        ["orientation_range", "manipulability", "min_manipulability", "collision_free"],
        pose=(0.0, 0.08, 0.0),
        options={"over": ["rz"], "xtol": RANGE_XTOL},
    )
    _complete(ratio)
    _redundancy(ctx.section("Redundancy: the 3D3M and the 3D4M against l / r_t and the height"), ratio)
    ctx.step("sweep the rod lengths of the Harada 2015 design")
    samples = [{"rod_lengths": [0.24, li, li, 0.24]} for li in INNER] + [{"rod_lengths": [0.17] * 4}]
    rods = sweep(
        "harada2015_asymmetric",
        samples,
        {"y": np.linspace(0.04, 0.22, 10), "rz": ANGLES},
        ["orientation_range", "min_manipulability"],
        pose=(0.0, 0.10, 0.0),
        options={"over": ["rz"], "xtol": RANGE_XTOL},
    )
    box = sweep(
        "harada2015_asymmetric",
        samples,
        {
            "x": np.linspace(-0.1, 0.1, 9),
            "y": np.linspace(0.02, 0.24, 12),
            "rz": np.radians(np.linspace(-60.0, 60.0, 13)),
        },
        ["reachable_fraction", "min_manipulability", "collision_free"],
        pose=(0.0, 0.10, 0.0),
    )
    _complete(rods)
    _complete(box)
    _asymmetry(
        ctx.section("Rod lengths: where the asymmetric design of Harada 2015 pays"), rods, box, samples
    )


def _complete(result: SweepResult) -> None:
    if not result.complete:
        lines = "; ".join(f.describe() for f in result.failures)
        raise PlmError(f"the sweep of {result.spec.label} did not complete: {lines}")


def _deg(value: float) -> float:
    return math.degrees(value)


def _redundancy(section: Section, result: SweepResult) -> None:
    import matplotlib.pyplot as plt

    ds = result.dataset.assign_coords(ratio=("half_plate", [L / r for r in result.dataset.half_plate.values]))
    ds = ds.swap_dims({"half_plate": "ratio"})
    labels = {"(1, 2, 4)": "3D3M", "(1, 2, 3, 4)": "3D4M"}
    half = ds.orientation_halfwidth
    section.text(
        "The *rotation range* at a height y is the largest interval of the plate angle theta holding "
        "theta = 0 over which the table stays reachable in its working mode (- + - +) and non-singular; "
        "its ends are singular points or reach limits located by root finding (Brent) to 1e-9 rad, "
        "bracketed by 2 deg samples over Fig. 6's +/-80 deg (a range reaching 80 deg is at least that wide). "
        "The *half-width* is the largest symmetric turn +/-d about theta = 0 inside it. The rod length "
        "stays l = 0.14 m (Table 1); r_t = l / ratio. Manipulability w = sqrt(det(J_ce^T J_ce)) (eq. (13)); "
        "its smallest value is read over |theta| <= 20 deg and over +/-80 deg."
    )
    four = ds.sel(legs="(1, 2, 3, 4)", ratio=4.0, y=FIG6_Y)
    three = ds.sel(legs="(1, 2, 4)", ratio=4.0, y=FIG6_Y)
    kinds = three.orientation_lower_end.attrs["flag_meanings"].split()
    singular_ends = {"constraint", "inverse", "direct"}
    four_ends = {kinds[int(four.orientation_lower_end)], kinds[int(four.orientation_upper_end)]}
    section.comparison(
        "Fig. 6 and eq. (11.4) at l : 2 r_t = 2 : 1, y = 0.084039 m",
        [
            Comparison(
                "3D3M: |theta| of the type-4 singularity ending the range below theta = 0",
                28.7,
                abs(_deg(float(three.orientation_lower))),
                "deg",
                rtol=2e-3,
            ),
            Comparison(
                "3D3M: the range ends below at a direct singularity",
                "yes",
                "yes" if kinds[int(three.orientation_lower_end)] == "direct" else "no",
            ),
            Comparison("3D4M: singular within +/-80 deg", "no", "yes" if four_ends & singular_ends else "no"),
        ],
        note=f"plm_pin locates the 3D3M's end at {_deg(float(three.orientation_lower)):.9f} deg; eq. (11.4) "
        f"gives -acos(sqrt((l + r_t)^2 - y^2) / (l + r_t)) = -28.7 deg there.",
    )
    fig, axes = panel_grid(2, width=4.6, height=3.8, sharey=True)
    for ax, (legs, name) in zip(axes, labels.items(), strict=True):
        plot_sweep_heatmap(
            half.sel(legs=legs), "ratio", "y", ax=ax, vmin=0.0, vmax=80.0, title=name, colorbar=False
        )
        ax.axhline(FIG6_Y, color="white", linewidth=0.6, linestyle=":")
        ax.set_xlabel("l / r_t [-]")
    axes[1].set_ylabel("")
    fig.colorbar(axes[0].collections[0], ax=axes, label="rotation half-width [deg]")
    section.figure(
        fig,
        "Singularity-free rotation half-width against l / r_t and the height y (dotted: the height of "
        "Fig. 6). Blank: the plate angle 0 is out of reach.",
        {
            "ratio": list(RATIOS),
            "y": HEIGHTS,
            **{name: np.degrees(half.sel(legs=legs).values) for legs, name in labels.items()},
        },
    )
    fig, ax = plt.subplots(figsize=(7.0, 4.2), layout="constrained")
    for legs, name, style in (("(1, 2, 4)", "3D3M", "-"), ("(1, 2, 3, 4)", "3D4M", "--")):
        ax.set_prop_cycle(None)  # the same colour for a ratio on both tables
        plot_sweep_lines(
            half.sel(legs=legs).transpose("y", "ratio"),
            "y",
            "ratio",
            ax=ax,
            label=f"{name}, l/r_t = {{value}}",
            linestyle=style,
            marker=".",
        )
    ax.set_ylabel("rotation half-width [deg]")
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small")
    section.figure(
        fig,
        "Half-width against the height: the 3D3M (solid) and the 3D4M (dashed), one colour per l / r_t; "
        "80 deg is the edge of the samples.",
        {name: np.degrees(half.sel(legs=legs).values) for legs, name in labels.items()},
    )
    rows = []
    for r in RATIOS:
        h3 = np.degrees(half.sel(legs="(1, 2, 4)", ratio=r).values)
        h4 = np.degrees(half.sel(legs="(1, 2, 3, 4)", ratio=r).values)
        best = int(np.nanargmax(h3))
        gain = h4 - h3
        wider = HEIGHTS[gain > 1e-6]
        equal = HEIGHTS[np.abs(gain) <= 1e-6]
        rows.append(
            (
                r,
                L / r,
                float(h3[best]),
                float(HEIGHTS[best]),
                float(h4[best]),
                float(np.nanmax(gain)),
                float(wider.min()) if wider.size else None,
                float(wider.max()) if wider.size else None,
                float(equal.min()) if equal.size else None,
            )
        )
    section.table(
        "Rotation half-width: the 3D3M at its best height, the 3D4M there, where the fourth motor widens it",
        [
            "l / r_t",
            Column("r_t", "m"),
            Column("3D3M widest", "deg"),
            Column("at y", "m"),
            Column("3D4M at that y", "deg"),
            Column("largest gain", "deg"),
            Column("3D4M wider from y", "m"),
            Column("to y", "m"),
            Column("equal from y", "m"),
        ],
        rows,
        note="Gain: 3D4M minus 3D3M half-width at one height. 'Equal': both ranges end at the same reach "
        "limits (a rod normal to the stator, eq. (9)); 80 deg is the edge of the samples.",
        id="redundancy",
    )
    work = ds.manipulability.where(np.abs(ds.rz) <= WORK_ANGLE + 1e-12).min("rz")
    table = []
    for r in RATIOS:
        for y in (HEIGHTS[2], FIG6_Y, HEIGHTS[-2]):
            w3 = float(work.sel(legs="(1, 2, 4)", ratio=r, y=y))
            w4 = float(work.sel(legs="(1, 2, 3, 4)", ratio=r, y=y))
            wall = float(ds.min_manipulability.sel(legs="(1, 2, 3, 4)", ratio=r, y=y))
            table.append((r, float(y), w3, w4, w4 / w3 if w3 > 0 else None, wall))
    section.table(
        "Smallest manipulability w over the plate angles",
        [
            "l / r_t",
            Column("y", "m"),
            Column("3D3M, |theta| <= 20 deg", "m/rad"),
            Column("3D4M, |theta| <= 20 deg", "m/rad"),
            "ratio 3D4M / 3D3M",
            Column("3D4M, +/-80 deg", "m/rad"),
        ],
        table,
        note="Over reached samples (2 deg apart); near a singularity between samples the 3D3M's value is "
        "small but not zero.",
    )
    fig, ax = plt.subplots(figsize=(7.0, 4.2), layout="constrained")
    plot_sweep_lines(
        ds.min_manipulability.sel(legs="(1, 2, 3, 4)").transpose("y", "ratio"),
        "y",
        "ratio",
        ax=ax,
        label="3D4M, l/r_t = {value}",
        marker=".",
    )
    ax.set_yscale("log")
    ax.set_ylabel("smallest manipulability w [m/rad]")  # linear actuators, x-y-theta task
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small")
    section.figure(
        fig,
        "The 3D4M's smallest manipulability over +/-80 deg against the height, one line per l / r_t.",
        {"y": HEIGHTS, "ratio": list(RATIOS), "w_min": ds.min_manipulability.sel(legs="(1, 2, 3, 4)").values},
    )
    fig6 = next(row for row in rows if row[0] == 4.0)
    h3 = half.sel(legs="(1, 2, 4)")
    ends3 = ds.orientation_lower_end.sel(legs="(1, 2, 4)").values
    direct = int(np.sum(ends3 == kinds.index("direct")))
    widens = bool(np.all(np.diff(h3.transpose("y", "ratio").values, axis=1) >= -1e-9))
    higher = all(row[4] is not None and row[4] > 1.0 for row in table)
    gains = (half.sel(legs="(1, 2, 3, 4)") - h3).transpose("ratio", "y").values
    lowest = bool(np.all(np.nanargmax(gains, axis=1) == 0))
    not_singular = [kinds.index(k) for k in ("boundary", "grid", "unreachable")]
    reach_only = all(
        bool(np.isin(ds[end].sel(legs="(1, 2, 3, 4)").values, not_singular).all())
        for end in ("orientation_lower_end", "orientation_upper_end")
    )
    kept = _collision_free_table(section, half, ds.collision_free)
    kept3, kept4 = next((row[3] or math.nan, row[5] or math.nan) for row in kept if row[:2] == (4.0, FIG6_Y))
    wider = sum(1 for row in kept if None not in (row[3], row[5]) and row[5] > row[3] + 1e-9)
    touching = sum(1 for row in kept if row[5] is None and row[3] is not None)
    section.text(
        "**Where redundancy pays.** Below theta = 0 the 3D3M's range ends at its direct (type-4, eq. (11.4)) "
        f"singularity at {direct} of the {ends3.size} (l / r_t, y) pairs swept, the others at the reach "
        "limit shared with the 3D4M; "
        + ("it widens with l / r_t (a shorter plate) at every height, " if widens else "")
        + f"and at l : 2 r_t = 2 : 1 it is at most {fig6[2]:.1f} deg (y = {fig6[3]:.3f} m), where the 3D4M "
        f"turns {fig6[4]:.1f} deg. "
        + (
            "The fourth motor removes the singularity: no 3D4M range swept ends at one, so its range is "
            "bounded by the reach of its rods alone"
            if reach_only
            else "The fourth motor moves the singularities"
        )
        + (": the gain is largest at the lowest height swept for every ratio" if lowest else "")
        + " and vanishes from the heights of the 'equal from y' column, where both stop at one reach limit. "
        + (
            "Over |theta| <= 20 deg the 3D4M's smallest manipulability is above the 3D3M's at every ratio "
            "and height of the manipulability table. "
            if higher
            else ""
        )
        + f"Sliders on one stator cannot pass each other: their carriages, {CARRIAGE_SIZE[0] * 100:.0f} cm "
        "long, collide first. The "
        "sweep checks every pose for self-collision (metric collision_free, plm_pin.kinematics.collisions "
        "on the carriage boxes), and with collisions excluded the half-widths at l : 2 r_t = 2 : 1 and "
        f"y = 0.084 m are {kept3:.0f} deg (3D3M) and {kept4:.0f} deg (3D4M) on the 2 deg samples"
        + (", so redundancy still pays there." if kept4 > kept3 else ", so redundancy gains nothing there.")
        + f" Of the {len(kept)} rows of that table the 3D4M turns further than the 3D3M at {wider}"
        + (
            f", and at {touching} the carriage of slider 3, which the 3D3M lacks, already overlaps a "
            "neighbour at theta = 0. "
            if touching
            else ". "
        )
        + "Earlier versions of this study only kept the sliders' order along the stator (sliders of no "
        "length, from eq. (2)). Carriages that have a length touch before they would pass, so the "
        "collision check stops the ranges earlier, the more so for a short plate (large l / r_t), whose "
        "pairs lie only 2 r_t apart on the stator; where two carriages overlap at theta = 0 there is no "
        "collision-free range."
    )
    section.assumptions(
        "Assumptions",
        [
            "Working mode (- + - +) of Harada 2011 (M.5), kept by continuation from the reference "
            "configuration.",
            "Plate angles sampled every 2 deg over +/-80 deg (Fig. 6's range): two singular points closer "
            "than that can be missed, and a range reaching 80 deg is at least that wide.",
            "Self-collision: only the carriages (3 cm boxes on the one stator) can collide; each rod "
            "moves in a layer of its own above them and the plate above the rods (the presets' "
            "self_collision.ignore), so rods crossing in the plane do not collide.",
            "Rod length 0.14 m and the other parameters of Table 1; only r_t (and the motors) change.",
        ],
    )
    section.parameters(
        "Sweep",
        [
            Parameter("l / r_t", list(RATIOS), "", "l = 0.14 m fixed"),
            Parameter("heights y", [round(float(y), 6) for y in HEIGHTS], "m"),
            Parameter("plate angles", [-80.0, 80.0, 81], "deg", "first, last, number"),
            Parameter("root tolerance", RANGE_XTOL, "rad"),
            Parameter("poses evaluated", result.spec.n_points * result.spec.n_poses, ""),
            Parameter("throughput of this run", round(result.poses_per_second()), "poses/s", "in-process"),
        ],
    )


def _collision_free(free: np.ndarray) -> float | None:
    """Largest +/-d [deg] on the angle samples about theta = 0 reached free of self-collision.

    ``free`` holds the sweep's ``collision_free`` flag per sample of :data:`ANGLES`;
    None when theta = 0 itself is unreached or colliding.
    """
    zero = int(np.argmin(np.abs(ANGLES)))
    if not free[zero]:
        return None
    ends = []
    for step in (1, -1):
        k = zero
        while 0 <= k + step < ANGLES.size and free[k + step]:
            k += step
        ends.append(abs(math.degrees(float(ANGLES[k]))))
    return min(ends)


def _collision_free_table(section: Section, half: xr.DataArray, free: xr.DataArray) -> list[tuple[Any, ...]]:
    """Add the table of half-widths free of self-collision and return its rows."""
    rows: list[tuple[Any, ...]] = []
    for r in RATIOS:
        for y in (HEIGHTS[2], FIG6_Y, HEIGHTS[-2]):
            free3 = math.degrees(float(half.sel(legs="(1, 2, 4)", ratio=r, y=y)))
            free4 = math.degrees(float(half.sel(legs="(1, 2, 3, 4)", ratio=r, y=y)))
            kept3 = _collision_free(free.sel(legs="(1, 2, 4)", ratio=r, y=y).values)
            kept4 = _collision_free(free.sel(legs="(1, 2, 3, 4)", ratio=r, y=y).values)
            rows.append(
                (
                    r,
                    float(y),
                    free3,
                    None if kept3 is None else min(free3, kept3),
                    free4,
                    None if kept4 is None else min(free4, kept4),
                )
            )
    section.table(
        "Rotation half-width without and with self-collision (carriages on one stator cannot pass)",
        [
            "l / r_t",
            Column("y", "m"),
            Column("3D3M singularity-free", "deg"),
            Column("3D3M, collision-free", "deg"),
            Column("3D4M singularity-free", "deg"),
            Column("3D4M, collision-free", "deg"),
        ],
        rows,
        note="Collision-free: the largest +/-d on the 2 deg samples over which every pose is reached without "
        "two carriages (3 cm boxes) touching, capped by the singularity-free half-width; empty when the "
        "carriages already touch at theta = 0.",
        id="collision",
    )
    return rows


def _asymmetry(
    section: Section,
    rods: SweepResult,
    box: SweepResult,
    samples: list[dict[str, list[float]]],
) -> None:
    import matplotlib.pyplot as plt

    names = [f"l1 = l4 = 0.24, l2 = l3 = {li:g} m" for li in INNER] + ["all 0.17 m (symmetric)"]
    section.text(
        "Harada 2015 keeps the outer rods at 0.24 m and shortens the inner ones to 0.17 m, so that the two "
        "sliders of a pair can never coincide and the complex (constraint) singularity of equal rods cannot "
        "occur during a mode change. Swept here: the inner length l2 = l3 with l1 = l4 = 0.24 m, and the "
        "symmetric 0.17 m table, in the working mode (- + - +), r_t = 0.05 m. The box is x in [-0.1, 0.1] m, "
        "y in [0.02, 0.24] m, theta in [-60, 60] deg (9 x 12 x 13 poses)."
    )
    half = rods.dataset.orientation_halfwidth
    heights = rods.dataset.y.values
    fig, ax = plt.subplots(figsize=(7.0, 4.2), layout="constrained")
    for k, name in enumerate(names):
        ax.plot(heights, np.degrees(half.values[k]), marker=".", label=name)
    ax.set_xlabel("y [m]")
    ax.set_ylabel("rotation half-width [deg]")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small")
    section.figure(
        fig,
        "Rotation half-width against the height for each rod set (gaps: theta = 0 out of reach)"
        + (
            "; the 0.24 / 0.17 m and the all-0.17 m curves coincide."
            if np.array_equal(half.values[1], half.values[-1], equal_nan=True)
            else "."
        ),
        {"y": heights, "halfwidth_deg": np.degrees(half.values), "designs": names},
    )
    rows = []
    for k, (name, sample) in enumerate(zip(names, samples, strict=True)):
        mech = plm_pin.build_mechanism("harada2015_asymmetric", sample)
        case = complex_singularity_check(mech)
        h = np.degrees(half.values[k])
        full = heights[h >= 80.0 - 1e-9]
        rows.append(
            (
                name,
                float(box.dataset.reachable_fraction.values[k]),
                float(box.dataset.min_manipulability.values[k]),
                float(full.max()) if full.size else None,
                float(np.nanmax(heights[np.isfinite(h)])),
                "yes" if "constraint" in case.report.kinds else "no",
                case.min_slider_gap,
                float(np.mean(box.dataset.collision_free.values[k])),
            )
        )
    section.table(
        "Rod sets compared: reach, manipulability, rotation range, complex singularity",
        [
            "rods",
            "box reached",
            Column("min w in the box", "m/rad"),
            Column("+/-80 deg up to y", "m"),
            Column("theta = 0 reached up to y", "m"),
            "complex singularity",
            Column("least slider gap", "m"),
            "box reached collision-free",
        ],
        rows,
        note="Complex singularity: plm_pin.kinematics.complex_singularity_check brings rod 3 normal to the "
        "stator; equal rods on a pair then coincide and the closure Jacobian loses rank. The least slider "
        "gap of a pair is |l3 - l4|. Collision-free: reached without two carriages (3 cm boxes on the "
        "stator) touching.",
        id="rod_sets",
    )
    asym, sym = rows[1], rows[-1]
    longest = rows[3]
    section.comparison(
        "Harada 2015, Sec. IV",
        [
            Comparison("equal rods admit the complex singularity", "yes", longest[5]),
            Comparison("the asymmetric design (0.24 / 0.17 m) does not", "no", asym[5]),
        ],
    )
    same = asym[1] == sym[1] and asym[3] == sym[3]
    section.text(
        "**Where the asymmetric design pays.** In one working mode the shorter inner rods set the reach: the "
        f"0.24 / 0.17 m table reaches {asym[1]:.3f} of the box and keeps +/-80 deg up to y = "
        f"{asym[3]:.3f} m, "
        + ("the same as " if same else "against ")
        + f"the all-0.17 m table ({sym[1]:.3f}, {sym[3]:.3f} m), while the all-0.24 m table reaches "
        f"{longest[1]:.3f} of it and keeps +/-80 deg up to {longest[3]:.3f} m. The asymmetric table's "
        f"smallest w in the box is {asym[2]:.3g} against {sym[2]:.3g} m/rad for the all-0.17 m table. "
        f"Counting carriage collisions, it reaches {asym[7]:.3f} of the box collision-free against "
        f"{sym[7]:.3f} for the all-0.17 m table and {longest[7]:.3f} for the all-0.24 m one"
        + (
            f": its least slider gap on a pair ({asym[6]:.3f} m) exceeds the carriage length "
            f"({CARRIAGE_SIZE[0]:.2f} m), so the two carriages of a pair never touch, which equal rods "
            "allow. "
            if asym[6] > CARRIAGE_SIZE[0]
            else ". "
        )
        + "What the unequal rods buy is a "
        f"least slider gap of {asym[6]:.3f} m on a pair instead of 0: the complex singularity, which both "
        "symmetric tables admit, cannot occur, and that is what lets Harada 2015 change assembly and "
        "working modes without a singularity (its report). So the asymmetric design pays where mode changes "
        "are needed; for work in one mode it gives the reach of its short rods, less than equal long rods"
        + (
            ", though with carriages that have a length it works collision-free over more of the box than "
            "equal short rods."
            if asym[7] > sym[7]
            else "."
        )
    )
