"""The Harada 2011 study (analyses/harada2011.py): figures, statics, decoupling and simulations."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

pytestmark = pytest.mark.slow

M_L, M_M, M_T, L, RT = 0.026, 0.375, 0.132, 0.14, 0.05  # Table 1 [kg, kg, kg, m, m]


@pytest.fixture(scope="module")
def result(report_all):
    """The study's result, from the session's one ``plm-pin report all``."""
    return report_all.study("harada2011")


def _figures(result) -> dict:
    return {b.caption.split(":")[0]: b for s in result.sections for b in s.blocks if b.kind == "figure"}


def test_every_comparison_agrees_with_the_closed_forms(result):
    """All rows agree: eqs. (15)-(22) per leg and case, (11.4), (M.30), eq. (26), Tables 2-4."""
    tables = result.comparisons()
    rows = [r for t in tables for r in t.rows]
    assert all(r.agrees for r in rows), [r.quantity for r in rows if not r.agrees]
    quantities = {r.quantity for r in rows}
    assert sum(q.endswith("eq. (20)-(22)") for q in quantities) == 16  # 4 legs x (3 loads + f_i)
    assert sum(q.endswith("eq. (15)") for q in quantities) == 9  # 3 legs x 3 loads


def test_fig6_finds_the_type4_singularity_of_eq_11_4(result):
    """The 3D3M's w vanishes at |theta| = 28.7 deg for y = (l + r_t) sin 28.7 deg; the 3D4M's does not."""
    data = _figures(result)["Fig. 6"].data
    assert data["y"] == pytest.approx((L + L / 4) * math.sin(math.radians(28.7)))
    theta = np.degrees(data["theta"])
    w3, w4 = np.asarray(data["w_3d3m"]), np.asarray(data["w_3d4m"])
    k = int(np.argmin(np.abs(theta + 28.7)))  # the sweep holds -28.7 deg within half a degree
    assert w3[k] < 0.02 * np.nanmax(w3)
    assert np.nanmin(w4) > 0.1


def test_simulation_snapshots_follow_the_closed_form(result):
    """Figs. 11 and 13: 11 skeletons each, 0.2 s apart; x of simulation 1 is f_x t^2 / (2 m_xx)."""
    data = _figures(result)["Figs. 11 and 13"].data
    one = data["simulation 1 (Table 3)"]
    np.testing.assert_allclose(one["t"], np.arange(11) * 0.2, atol=1e-12)
    m_xx = 4 * M_L + 4 * M_M + M_T  # eq. (26)
    np.testing.assert_allclose(
        np.asarray(one["x"])[:, 0], 0.2 * np.asarray(one["t"]) ** 2 / (2 * m_xx), atol=1e-9
    )
    np.testing.assert_allclose(data["simulation 2 (Table 4)"]["t"], np.arange(11) * 0.2, atol=1e-12)


def test_report_has_every_figure_and_the_animation(result):
    """Figs. 6, 8, 10-13 and the capability polygon are drawn; simulation 2 is animated in the page."""
    figures = _figures(result)
    for caption in ("Fig. 6", "Fig. 8", "Figs. 10 and 12", "Figs. 11 and 13"):
        assert caption in figures
    scenes = [b for s in result.sections for b in s.blocks if b.kind == "scene"]
    (scene,) = scenes
    assert len(scene.data["qs"]) == len(scene.data["times"]) > 50
    assert scene.data["times"][-1] == pytest.approx(2.0)


def test_stiffness_of_the_3d4m_is_the_drives_k_j_ce_t_j_ce_and_compression_softens_it(result):
    """f_i = 0: smallest translational eigen-stiffness of k J_ce^T J_ce (eq. (12)); falls as f_i grows.

    Within the gravity term (|dg/dq| ~ 20 N/m on 1.7e6 N/m: 1e-4).
    """
    from analyses import _harada2011_paper as paper

    rows = result.block("stiffness").rows
    four = [r for r in rows if r[0] == "3D4M" and r[1] == 1.0e6]
    pose, legs = (0.0, 0.08, math.radians(-20.0)), (1, 2, 3, 4)
    J = paper.J_ce(pose, paper.slider_positions(pose, L, RT, legs), L, RT, legs)
    C = np.linalg.inv(1.0e6 * J.T @ J)
    assert four[0][2] == 0.0
    assert four[0][3] == pytest.approx(1.0 / np.linalg.eigvalsh(C[:2, :2]).max(), rel=1e-4)
    stiff = [r[3] for r in four]
    assert all(a > b for a, b in itertools.pairwise(stiff))
    three = [r for r in rows if r[0] == "3D3M"]
    assert three[0][6] and not three[1][6]  # the 3D3M on soft drives cannot hold its plate under gravity
    assert "Stiffness and lowest natural frequency against the plate angle at x = 0, y = 0.08 m" in _figures(
        result
    )


def test_flexible_rods_soften_the_3d4m_and_add_out_of_plane_modes(result):
    """Rods as beams: every eigen-stiffness drops; the full model's lowest mode is below the task model's."""
    rods = {r[0]: r for r in result.block("flexible_rods").rows}
    assert all(f < r for f, r in zip(rods["flexible"][1:], rods["rigid"][1:], strict=True))
    freq = {(r[0], r[1]): r[2] for r in result.block("frequencies").rows}
    assert (
        freq[("3D4M, flexible rods", "full")] < freq[("3D4M, flexible rods", "task")] < freq[("3D4M", "task")]
    )
