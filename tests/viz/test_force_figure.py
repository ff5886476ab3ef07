"""The Fig. 8 helper draws the forces of a static solution where and as they act."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from plm_pin.exceptions import InvalidInput
from plm_pin.statics import static_forces
from plm_pin.viz import fig8, force_arrows, plot_static_forces
from tests.conftest import preset


def test_arrows_carry_the_solution_forces():
    """f_c along each slider axis, f_n normal to it, f_l along each link, the load at its frame."""
    mech = preset("harada2011_3d4m")
    sol = static_forces(mech, mech.q_ref, [0.0, -1.0, 0.0], gravity=False)
    arrows = force_arrows(sol)
    kinds = [a.kind for a in arrows]
    assert kinds.count("f_c") == 4 and kinds.count("f_n") == 4 and kinds.count("load") == 1
    assert kinds.count("f_l") == len(sol.link_forces())
    for a in arrows:
        if a.kind == "f_c":  # the sliders run along world x (eq. (1): a = (1, 0))
            f = sol.f_c[[act.joint for act in mech.actuators].index(a.name)]
            np.testing.assert_allclose(a.force, [f, 0.0, 0.0], atol=1e-12)
        if a.kind == "f_n":
            assert a.force[0] == pytest.approx(0.0, abs=1e-12)
        if a.kind == "f_l":
            lf = sol.link_forces()[a.name]
            np.testing.assert_allclose(np.linalg.norm(a.force), abs(lf.axial), atol=1e-12)
        if a.kind == "load":
            np.testing.assert_allclose(a.force, [0.0, -1.0, 0.0])
    # per slider, eq. (16): f_c a + f_n n + f_l z = 0 (massless slider, no gravity)
    by = {(a.kind, a.name): a.force for a in arrows}
    for i in range(1, 5):
        total = by[("f_c", f"slider{i}")] + by[("f_n", f"slider{i}")] + by[("f_l", f"rod{i}")]
        np.testing.assert_allclose(total, 0.0, atol=1e-12)


def test_fig8_draws_both_panels(tmp_path):
    """Fig. 8 (a) and (b): solid arrows for the totals, broken ones for the internal force in (b)."""
    mech = preset("harada2011_3d4m")
    ax_a, ax_b = fig8(mech, mech.q_ref, [0.0, 1.0, 0.0], f_i=1.0)
    styles_a = [t.arrow_patch.get_linestyle() for t in ax_a.texts]
    styles_b = [t.arrow_patch.get_linestyle() for t in ax_b.texts]
    sol = static_forces(mech, mech.q_ref, [0.0, -1.0, 0.0], gravity=False)
    assert styles_a == ["-"] * len(force_arrows(sol))
    assert styles_b.count("-") == len(styles_a) and styles_b.count("--") == len(styles_a) - 1  # no load
    ax_a.figure.savefig(tmp_path / "fig8.png")
    assert (tmp_path / "fig8.png").stat().st_size > 10_000
    (legend,) = ax_a.figure.legends  # one legend for both panels, none inside them
    assert ax_a.get_legend() is None and ax_b.get_legend() is None
    assert [t.get_text() for t in legend.get_texts()] == ["f_c", "f_n", "f_l", "load"]


def test_bad_plane_is_refused():
    """An unknown projection plane is refused naming the choices."""
    mech = preset("harada2011_3d4m")
    with pytest.raises(InvalidInput, match=r"plane 'xw' is not one of \['xy', 'xz', 'yz'\]"):
        plot_static_forces(static_forces(mech, mech.q_ref), plane="xw")
