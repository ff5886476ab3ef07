"""The Delta optimisation study (analyses/delta_optimize.py) against Clavel's closed-form IK."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from analyses.delta_optimize import ANGLES, CUBE, SEARCH_CUBE, VARIABLES
from plm_pin.models import PRESETS

pytestmark = pytest.mark.slow

PLATFORM_RADIUS = float(np.hypot(*PRESETS["delta"].parameters["platform"][0][:2]))
"""The platform points' circle [m] (the preset's, which the study keeps)."""

E = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.radians(ANGLES)])
"""Outward radial direction e_i of each arm."""

Z = np.array([0.0, 0.0, 1.0])


def inverse_conditions(radius, arm, forearm, cube) -> np.ndarray:
    """1 / cond(J) of designs (arrays of R, l_a, l_b) at the cube's positions (0 where a leg cannot reach).

    Clavel's closed form: with d = p + (r - R) e_i, in the crank plane d_x = d.e_i, d_y = -d.z, the
    arm angle solves d_x cos(t) + d_y sin(t) = K, K = (|d|^2 + l_a^2 - l_b^2) / (2 l_a), elbows out
    (the larger cos(t)); the rod u_i = d - l_a (cos(t) e_i - sin(t) z) gives u_i . dp = u_i . dE_i/dt dt.
    """
    radius, arm, forearm = (np.asarray(v, dtype=float)[:, None] for v in (radius, arm, forearm))
    poses = np.array(list(itertools.product(*cube.values())))  # (m, 3)
    rows, diag, reached = [], [], np.ones(np.broadcast_shapes(radius.shape, (1, len(poses))), dtype=bool)
    for e in E:
        d = poses[None, :, :] + ((PLATFORM_RADIUS - radius)[..., None] * e)  # (n, m, 3)
        dx, dy = d @ e, -(d @ Z)
        rho = np.hypot(dx, dy)
        k = (np.einsum("...i,...i", d, d) + arm**2 - forearm**2) / (2.0 * arm)
        reached &= np.abs(k) <= rho
        spread = np.arccos(np.clip(k / rho, -1.0, 1.0))
        phi = np.arctan2(dy, dx)
        t = np.where(np.cos(phi + spread) >= np.cos(phi - spread), phi + spread, phi - spread)
        elbow = arm[..., None] * (np.cos(t)[..., None] * e - np.sin(t)[..., None] * Z)
        u = d - elbow
        rows.append(u)
        diag.append(
            np.einsum("...i,...i", u, arm[..., None] * (-np.sin(t)[..., None] * e - np.cos(t)[..., None] * Z))
        )
    jx = np.stack(rows, axis=-2)  # (n, m, 3, 3)
    jq = np.stack(diag, axis=-1)[..., None, :] * np.eye(3)
    with np.errstate(all="ignore"):
        s = np.linalg.svd(np.linalg.solve(jx, jq), compute_uv=False)
        return np.where(reached, s[..., -1] / s[..., 0], 0.0)


def gci(design, cube) -> float:
    """The closed-form GCI of one design (R, l_a, l_b) over ``cube``."""
    return float(inverse_conditions(*([v] for v in design), cube).mean())


@pytest.fixture(scope="module")
def study(report_all):
    """The study's result, from the session's one ``plm-pin report all``."""
    return report_all.study("delta_optimize")


def test_the_gci_of_the_start_and_the_optimum_is_clavel_s(study):
    """The GCI of the preset's design and of the optimum agree with the closed form to 1e-9 (both cubes)."""
    rows = {row[0]: row for row in study.block("optimization-designs").rows}
    full = {row[0]: row for row in study.block("full-cube").rows}
    assert rows["start"][1:4] == pytest.approx((0.20, 0.30, 0.60), rel=1e-15)
    for label in ("start", "best 1"):
        assert rows[label][4] == pytest.approx(gci(rows[label][1:4], SEARCH_CUBE), rel=1e-9)
    for label in ("optimum", "preset"):
        *design, value, verdict = full[label][1:]
        assert verdict == "feasible" and value == pytest.approx(gci(design, CUBE), rel=1e-9)
    assert full["optimum"][1:4] == pytest.approx(rows["best 1"][1:4], rel=1e-15)


def test_the_optimum_reaches_the_cube_and_is_within_1_percent_of_a_brute_force_grid(study):
    """Clavel's IK reaches the fine cube; no design of an 11^3 grid beats the optimum's GCI by over 1 %.

    The grid spans the bounds; its designs count when they reach the whole search cube.
    """
    best = {row[0]: row for row in study.block("optimization-designs").rows}["best 1"]
    design = best[1:4]
    assert np.all(inverse_conditions(*([v] for v in design), CUBE) > 0.0)
    grid = np.array(list(itertools.product(*(np.linspace(*VARIABLES[n], 11) for n in VARIABLES))))
    values = inverse_conditions(*grid.T, SEARCH_CUBE)
    feasible = np.all(values > 0.0, axis=1)
    brute = values[feasible].mean(axis=1).max()
    assert best[4] >= 0.99 * brute
