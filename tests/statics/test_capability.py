"""Force capability against closed forms (non-redundant), HiGHS (redundant) and the allocation itself."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from analyses import _harada2011_paper as paper
from plm_pin.exceptions import AllocationInfeasible, InvalidInput
from plm_pin.statics import (
    force_capability,
    internal_force_range,
    static_balance,
    static_forces,
    wrench_polygon,
)
from tests.conftest import preset, prrrp_paper_configuration

POSE = (0.01, 0.09, np.radians(10.0))
LIMITS = (-8.0, 10.0)
DIRECTIONS = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.6, 0.8, -0.05]]


def _q(mech):
    return prrrp_paper_configuration(mech, POSE, (0.14,) * 4, 0.05, (-1, 1, -1, 1))


@pytest.mark.parametrize("d", DIRECTIONS)
def test_3d3m_capability_is_the_closed_form_ratio(d):
    """Non-redundant: alpha = min_i of the room left on actuator i over f_i per unit load, f = -J_ce^-T d."""
    mech = preset("harada2011_3d3m")
    c = paper.slider_positions(POSE, 0.14, 0.05, (1, 2, 4))
    f_unit = np.linalg.solve(paper.J_ce(POSE, c, 0.14, 0.05, (1, 2, 4)).T, -np.asarray(d))  # load = -f_e
    room = np.where(f_unit > 0, LIMITS[1] / f_unit, LIMITS[0] / f_unit)
    cap = force_capability(mech, _q(mech), d, gravity=False, limits=[LIMITS] * 3)
    assert cap.alpha == pytest.approx(np.min(room), rel=1e-10)
    assert cap.saturated == (mech.actuators[int(np.argmin(room))].joint,)


@pytest.mark.parametrize("d", DIRECTIONS)
@pytest.mark.parametrize("gravity", [False, True])
def test_3d4m_capability_matches_highs(d, gravity):
    """Redundant: the LP optimum equals HiGHS's on max alpha s.t. C^T f = N^T(tau_g + alpha tau_d), limits."""
    mech = preset("harada2011_3d4m")
    q = _q(mech)
    g = static_balance(mech, q, gravity=gravity)
    unit = static_balance(mech, q, d, gravity=False)
    A = g.C.T
    n = mech.n_actuators
    lp = linprog(
        np.r_[np.zeros(n), -1.0],
        A_eq=np.hstack([A, -(g.N.T @ unit.tau)[:, None]]),
        b_eq=g.N.T @ g.tau,
        bounds=[LIMITS] * n + [(0.0, None)],
        method="highs",
    )
    assert lp.status == 0
    cap = force_capability(mech, q, d, gravity=gravity, limits=[LIMITS] * n)
    assert cap.alpha == pytest.approx(lp.x[-1], rel=1e-9)
    held = static_forces(mech, q, cap.alpha * np.asarray(d), gravity=gravity, limits=[LIMITS] * n)
    assert held.residual <= 1e-10
    with pytest.raises(AllocationInfeasible):
        static_forces(mech, q, 1.001 * cap.alpha * np.asarray(d), gravity=gravity, limits=[LIMITS] * n)


@pytest.mark.parametrize("d", DIRECTIONS)
def test_redundancy_never_lowers_capability_3d4m_vs_3d3m(d):
    """The 3D4M can leave actuator 3 idle, so it holds at least what the 3D3M holds (no gravity)."""
    four, three = preset("harada2011_3d4m"), preset("harada2011_3d3m")
    a4 = force_capability(four, _q(four), d, gravity=False, limits=[LIMITS] * 4).alpha
    a3 = force_capability(three, _q(three), d, gravity=False, limits=[LIMITS] * 3).alpha
    assert a4 >= a3 * (1 - 1e-9)


@pytest.mark.parametrize("k", range(6))
def test_redundancy_never_lowers_capability_8pss_vs_6pss(k):
    """The 8-PSS can leave legs 1 and 8 idle, so it holds at least what the 6-PSS holds (no gravity)."""
    eight, six = preset("zhao2011_8pss"), preset("zhao2011_6pss")
    d = np.eye(6)[k]
    a8 = force_capability(eight, eight.q_ref, d, gravity=False, limits=[(-2000.0, 2000.0)] * 8).alpha
    a6 = force_capability(six, six.q_ref, d, gravity=False, limits=[(-2000.0, 2000.0)] * 6).alpha
    assert a8 >= a6 * (1 - 1e-9)


def test_structure_holds_out_of_plane_loads_and_gravity_must_be_held():
    """A force normal to the 3D4M plane costs no actuator force (inf); limits below gravity are refused."""
    mech = preset("harada2011_3d4m")
    cap = force_capability(mech, mech.q_ref, [0, 0, 1.0, 0, 0, 0], limits=[LIMITS] * 4)
    assert cap.alpha == np.inf
    with pytest.raises(AllocationInfeasible):
        force_capability(mech, mech.q_ref, [1.0, 0.0, 0.0], limits=[(-1e-3, 1e-3)] * 4)
    with pytest.raises(InvalidInput, match="finite effort limits on every actuator"):
        force_capability(mech, mech.q_ref, [1.0, 0.0, 0.0])


def test_wrench_polygon_is_the_convex_boundary_of_held_loads():
    """Each polygon point is held by the allocation, 0.1 % beyond it is not, and the polygon is convex."""
    mech = preset("harada2011_3d4m")
    q = _q(mech)
    P = wrench_polygon(mech, q, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], n=12, limits=[LIMITS] * 4)
    for a, b in P:
        static_forces(mech, q, [a, b, 0.0], limits=[LIMITS] * 4)
        with pytest.raises(AllocationInfeasible):
            static_forces(mech, q, [1.001 * a, 1.001 * b, 0.0], limits=[LIMITS] * 4)
    edges = np.roll(P, -1, axis=0) - P
    turns = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
    assert np.all(turns >= -1e-9)


@pytest.mark.parametrize(
    ("name", "load"),
    [("harada2011_3d4m", [0.3, -1.0, 0.01]), ("zhao2011_8pss", [0.0, 0.0, -500.0, 0.0, 20.0, 0.0])],
)
def test_internal_range_matches_highs(name, load):
    """Each end of the range is HiGHS's min / max of g_k . f_c s.t. C^T f_c = N^T tau and the limits."""
    mech = preset(name)
    q = _q(mech) if name == "harada2011_3d4m" else mech.q_ref
    n = mech.n_actuators
    limits = [(-8.0, 10.0)] * n if n == 4 else [(-6000.0, 6000.0)] * n
    balance = static_balance(mech, q, load)
    r = internal_force_range(mech, q, load, limits=limits)
    assert r.lower.shape == r.upper.shape == (mech.redundancy,)
    for k in range(mech.redundancy):
        g = balance.internal_basis[:, k]
        for sign, end, forces in ((1.0, r.lower[k], r.f_lower[k]), (-1.0, r.upper[k], r.f_upper[k])):
            lp = linprog(sign * g, A_eq=balance.C.T, b_eq=balance.N.T @ balance.tau, bounds=limits)
            assert lp.status == 0
            assert end == pytest.approx(g @ lp.x, abs=1e-8 * 6000.0)
            assert g @ forces == pytest.approx(end, abs=1e-8 * 6000.0)
            held = static_forces(mech, q, load, internal=forces @ balance.internal_basis)
            np.testing.assert_allclose(held.f_c, forces, atol=1e-8 * 6000.0)
            assert np.all(forces >= np.array(limits)[:, 0] - 1e-9 * 6000.0)
            assert np.all(forces <= np.array(limits)[:, 1] + 1e-9 * 6000.0)


def test_internal_range_refuses_what_has_no_answer():
    """No redundancy, no limits, or limits below the load: typed errors naming the problem."""
    three = preset("harada2011_3d3m")
    with pytest.raises(InvalidInput, match=r"harada2011_3d3m has no internal forces \(redundancy 0\)"):
        internal_force_range(three, three.q_ref, limits=[(-5.0, 5.0)] * 3)
    four = preset("harada2011_3d4m")
    with pytest.raises(InvalidInput, match="the internal-force range needs finite effort limits"):
        internal_force_range(four, four.q_ref)
    with pytest.raises(AllocationInfeasible):
        internal_force_range(four, four.q_ref, [0.0, -50.0, 0.0], limits=[(-0.1, 0.1)] * 4)


def test_linear_programmes_print_nothing():
    """The first LP of a process writes nothing to stdout (no highspy banner): piped output stays clean."""
    script = (
        "import numpy as np\n"
        "from plm_pin.statics import force_capability\n"
        "from tests.conftest import preset\n"
        "from tests.statics.test_capability import LIMITS, _q\n"
        "mech = preset('harada2011_3d4m')\n"
        "cap = force_capability(mech, _q(mech), [1.0, 0.0, 0.0], limits=[LIMITS] * mech.n_actuators)\n"
        "assert np.isfinite(cap.alpha) and cap.alpha > 0\n"
    )
    root = Path(__file__).resolve().parents[2]
    out = subprocess.run(
        [sys.executable, "-c", script], cwd=root, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout == ""
