"""Polynomial form, compiled evaluation and interval certificates (plm_pin/kinematics/homotopy).

Oracles: finite differences for the Jacobians, the closure residual of plm_pin.core for the
entries, exact rational arithmetic for the interval enclosures, the complex evaluator for the
interval system, a shifted point for a Krawczyk test that must fail.
"""

from __future__ import annotations

import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest

from plm_pin.kinematics.homotopy import generic_solution, polynomial_form, prepared
from plm_pin.kinematics.homotopy.certify import (
    _fma2,
    _mm_into,
    certify,
    interval_system,
    parameter_intervals,
)
from plm_pin.kinematics.homotopy.evaluation import evaluate
from plm_pin.kinematics.homotopy.generic import canonical, solve_generic
from plm_pin.kinematics.homotopy.polynomial import from_configuration, to_configuration
from plm_pin.kinematics.homotopy.solve import _distinct, parameter_actuators
from plm_pin.tolerances import HOMOTOPY_SAME_ROOT_RTOL
from tests.conftest import preset

NAMES = ["fourbar", "harada2011_3d4m", "enferadi2017_star_triangle", "zhao2011_6pss", "stewart_6ups"]


@pytest.mark.parametrize("name", NAMES)
def test_jacobians_match_central_differences(name):
    """F_x and F_p equal central differences of F at a random complex point."""
    form = polynomial_form(preset(name))
    rng = np.random.default_rng(0)
    x = rng.normal(size=form.n) + 1j * rng.normal(size=form.n)
    p = rng.normal(size=form.n_params) + 1j * rng.normal(size=form.n_params)
    _, Jx, Jp = evaluate(form, x, p)
    h = 1e-6
    for k in range(form.n):
        e = np.eye(form.n)[k] * h
        fd = (evaluate(form, x + e, p)[0] - evaluate(form, x - e, p)[0]) / (2 * h)
        assert np.abs(fd - Jx[:, k]).max() <= 1e-7 * (1 + np.abs(Jx).max())
    for k in range(form.n_params):
        e = np.eye(form.n_params)[k] * h
        fd = (evaluate(form, x, p + e)[0] - evaluate(form, x, p - e)[0]) / (2 * h)
        assert np.abs(fd - Jp[:, k]).max() <= 1e-7 * (1 + np.abs(Jp).max())


@pytest.mark.parametrize("name", NAMES)
def test_reference_pose_solves_the_system_and_round_trips(name):
    """The reference configuration is a root; unknowns -> configuration -> unknowns is the identity."""
    mech = preset(name)
    form = polynomial_form(mech)
    x = from_configuration(form, mech, mech.q_ref)
    c = mech.actuator_positions(mech.q_ref)
    assert np.abs(evaluate(form, x, c)[0]).max() <= 1e-14
    q = to_configuration(form, mech, x, c)
    assert np.abs(from_configuration(form, mech, q) - x).max() <= 1e-14
    assert np.array_equal(to_configuration(form, mech, np.stack([x, x]), c), np.stack([q, q]))


@pytest.mark.parametrize("name", ["harada2011_3d4m", "harada2015_asymmetric"])
def test_redundant_actuation_takes_as_many_parameters_as_the_mobility(name):
    """A redundant preset: mobility-many actuators are parameters, the rest unknowns equal to their values.

    The reference root solves the reduced system; the actuators left unknown (sliders) hold their reference
    displacements; and a subset that fixes the configuration gives a non-singular Jacobian there.
    """
    mech = preset(name)
    subset = parameter_actuators(mech)
    assert subset is not None and len(subset) == mech.mobility < mech.n_actuators
    form = polynomial_form(mech, subset)
    assert form.n_params == mech.mobility and len(form.checked) == mech.n_actuators - mech.mobility
    x = from_configuration(form, mech, mech.q_ref)
    c = mech.actuator_positions(mech.q_ref)
    F, Jx, _ = evaluate(form, x, c[form.parameters])
    assert np.abs(F).max() <= 1e-14
    assert np.linalg.matrix_rank(Jx) == form.n
    for a, o, revolute in form.checked:  # Harada's sliders: prismatic
        assert revolute == 0 and mech.actuators[a].kind == "prismatic"
        assert abs(x[o] - c[a]) <= 1e-14
    assert parameter_actuators(preset("harada2011_3d3m")) is None  # not redundant: every actuator


def test_krawczyk_certifies_a_root_and_refuses_a_shifted_point():
    """A box about the reference root is certified; about a point 1e-3 away it is not.

    In one batch, the root again after the shifted point: each radius equals its row's certified
    alone (the workspace the rows share carries nothing from one row to the next).
    """
    mech = preset("harada2011_3d3m")
    form, _ = prepared(mech)
    x = from_configuration(form, mech, mech.q_ref)
    c = mech.actuator_positions(mech.q_ref)
    rows = np.stack([x, x + 1e-3, x])
    radii = certify(form, rows, c)
    assert np.isfinite(radii[0]) and np.isnan(radii[1])
    alone = np.concatenate([certify(form, row, c) for row in rows])
    assert np.array_equal(radii, alone, equal_nan=True)


def test_a_quaternion_and_its_negative_get_one_sign_even_at_a_half_turn():
    """canonical() maps q and -q to one row, with w zero up to rounding (a half turn) and complex q.

    At a half turn about z, w is 0 or -0 or 1e-17 of either sign from one path to the next; a sign
    read from w would keep both copies of the root.
    """
    form = polynomial_form(preset("delta"))  # a free flyer: translation, then a quaternion
    o = int(form.unit_offsets[form.unit_sizes == 4][0])
    rng = np.random.default_rng(4)
    rows = []
    for w in (0.0, -0.0, 1e-17, -1e-17):
        q = np.array([w, 1e-17, -1e-17, 1.0])
        rows += [q, -q]
    c = rng.normal(size=4) + 1j * rng.normal(size=4)
    rows += [c, -c, 1j * np.array([0.0, 0.6, 0.0, -0.8]), -1j * np.array([1e-17, 0.6, 0.0, -0.8])]
    X = np.zeros((len(rows), form.n), dtype=np.complex128)
    X[:, o : o + 4] = rows
    Q = canonical(form, X)[:, o : o + 4]
    assert np.abs(Q[:8] - Q[0]).max() <= 1e-16 and Q[0, 3] == 1.0
    assert np.array_equal(Q[8], Q[9]) and np.abs(Q[10] - Q[11]).max() <= 1e-16
    assert np.array_equal(canonical(form, X), canonical(form, canonical(form, X)))
    assert canonical(form, X[:0]).shape == (0, form.n)  # no root reached


def test_distinct_roots_compare_each_row_with_the_rows_kept_before_it():
    """A row near a kept earlier row is dropped; a row near only a dropped one is kept.

    Rows of largest entry 2, so the same root within 3 HOMOTOPY_SAME_ROOT_RTOL: the second row is
    2 of those from the first (dropped), the third 2 from the second but 4 from the first (kept),
    the fourth the first again (dropped), the fifth far from all (kept).
    """
    a = np.array([1.0 + 1.0j, 2.0, -0.5j])
    tol = HOMOTOPY_SAME_ROOT_RTOL
    X = np.stack([a, a + 2 * tol, a + 4 * tol, a, a + 1.0])
    assert _distinct(X).tolist() == [True, False, True, False, True]


def test_condition_number_is_numpys_1_norm_condition_and_infinite_where_singular():
    """Equal to numpy's cond(A, 1) on random and ill-conditioned matrices; infinite on singular ones."""
    from plm_pin.kinematics.homotopy.tracking import condition_number

    rng = np.random.default_rng(5)
    for n in (2, 7, 11):
        A = rng.normal(size=(n, n)) + 1j * rng.normal(size=(n, n))
        A[:, 0] *= 1e-6  # ill-conditioned
        assert condition_number(A) == pytest.approx(np.linalg.cond(A, 1), rel=1e-9)
    singular = np.ones((3, 3), dtype=np.complex128)
    assert condition_number(singular) == np.inf
    assert condition_number(np.full((2, 2), np.nan + 0j)) == np.inf


@pytest.mark.parametrize("name", NAMES)
def test_interval_system_encloses_the_complex_evaluation(name):
    """F and F_x over a box (or a point) hold the complex evaluator's values at its midpoint and inside it.

    The interval system (plm_pin/kinematics/homotopy/certify.py) and the evaluator (evaluation.py) are
    separate codes; boxes of half-widths 0 (a point), 1e-9 and 1e-4 about random real points and
    parameters, the evaluator at the midpoint and at random points strictly inside.
    """
    form = polynomial_form(preset(name))
    rng = np.random.default_rng(2)
    args = form.kernel_args()
    for _ in range(4):
        x = rng.normal(size=form.n)
        p = rng.normal(size=form.n_params)
        pi = parameter_intervals(form, p)
        for width in (0.0, 1e-9, 1e-4):
            half = width * rng.uniform(0.5, 1.0, size=form.n)
            box = np.stack([x - half, x + half], axis=-1)
            F, J = interval_system(box, pi, *args)
            assert np.all(F[:, 0] <= F[:, 1]) and np.all(J[..., 0] <= J[..., 1])
            inside = [0.5 * (box[:, 0] + box[:, 1])]  # the float midpoint
            inside += [x + half * rng.uniform(-0.5, 0.5, size=form.n) for _ in range(3)]
            for y in inside:
                Fy, Jy, _ = evaluate(form, y, p)
                assert np.all(F[:, 0] <= Fy.real) and np.all(Fy.real <= F[:, 1])
                assert np.all(J[..., 0] <= Jy.real) and np.all(Jy.real <= J[..., 1])


def _exact_range(alo, ahi, blo, bhi):
    """Exact range of ``a b`` over [alo, ahi] x [blo, bhi]: a bilinear product's extremes are at vertices."""
    vertices = [Fraction(a) * Fraction(b) for a in (alo, ahi) for b in (blo, bhi)]
    return min(vertices), max(vertices)


def _interval_entries(rng, shape):
    """Random intervals (lo, hi on the last axis): point, narrow and wide ones, some exactly zero."""
    lo = rng.normal(size=shape)
    width = rng.choice([0.0, 1e-3, 1.0], size=shape) * rng.uniform(0, 1, size=shape)
    box = np.stack([lo, lo + width], axis=-1)
    box[rng.random(size=shape) < 0.2] = 0.0
    return box


def test_interval_products_enclose_the_exact_product():
    """_fma2 and _mm_into contain the exact rational result for every point of the boxes.

    Each entry of the product is a sum of terms with independent factors, so its exact range over
    the boxes is the sum of each term's exact range; the computed bounds must lie outside it
    (outward rounding) and within round-off of it.
    """
    rng = np.random.default_rng(1)
    for _ in range(200):
        s, a, b = _interval_entries(rng, (3,))
        lo, hi = _fma2(s[0], s[1], a[0], a[1], b[0], b[1])
        plo, phi = _exact_range(*a, *b)
        exact = (Fraction(s[0]) + plo, Fraction(s[1]) + phi)
        assert Fraction(lo) <= exact[0] and exact[1] <= Fraction(hi)
        assert exact[0] - Fraction(lo) <= 1e-12 and Fraction(hi) - exact[1] <= 1e-12
    for _ in range(20):
        A = _interval_entries(rng, (3, 4, 4))
        B = _interval_entries(rng, (2, 4, 4))
        C = np.full((3, 4, 4, 2), np.nan)
        _mm_into(A, 2, B, 1, C, 1)
        assert np.isnan(C[[0, 2]]).all()  # the other matrices of the stack are untouched
        for i in range(4):
            for j in range(4):
                ranges = [_exact_range(*A[2, i, r], *B[1, r, j]) for r in range(4)]
                exact = (sum(r[0] for r in ranges), sum(r[1] for r in ranges))
                lo, hi = Fraction(C[1, i, j, 0]), Fraction(C[1, i, j, 1])
                assert lo <= exact[0] and exact[1] <= hi
                assert exact[0] - lo <= 1e-12 and hi - exact[1] <= 1e-12


def test_import_plm_pin_does_not_import_numba():
    """Numba loads only when the homotopy first runs."""
    code = (
        "import sys, plm_pin, plm_pin.kinematics, plm_pin.kinematics.homotopy; print('numba' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize(
    ("name", "count"), [("fourbar", 2), ("harada2011_3d3m", 4), ("enferadi2017_star_triangle", 2)]
)
def test_generic_count_from_scratch_equals_the_closed_form_count(name, count):
    """Monodromy without the disk cache finds the closed-form count.

    Four-bar: two circle intersections; 3D3M: two, then two for the plate; star-triangle:
    the platform and its half-turn (the prismatic arms through the centre change sign).
    """
    assert solve_generic(polynomial_form(preset(name))).count == count


def test_the_chosen_start_holds_every_generic_root():
    """The start carried to the cheapest of the candidate parameters keeps the count, every root regular.

    On the Harada 3D4M (whose paths the choice shortens most): with the reference as a seed, the
    stored parameter is complex, each of its roots solves the system there (the generic
    evaluation, not the trackers) with a non-singular Jacobian, and they are as many as the
    monodromy finds without the seed (and so without the choice).
    """
    from plm_pin.kinematics.homotopy.tracking import condition_number

    mech = preset("harada2011_3d4m")
    form = polynomial_form(mech, parameter_actuators(mech))
    seed = (from_configuration(form, mech, mech.q_ref), mech.actuator_positions(mech.q_ref)[form.parameters])
    chosen = solve_generic(form, seed)
    assert chosen.count == solve_generic(form).count == 8
    assert np.all(np.abs(chosen.p.imag) > 0)
    for x in chosen.x:
        F, Jx, _ = evaluate(form, x, chosen.p)
        assert np.abs(F).max() <= 1e-10 * (1 + np.abs(x).max())
        assert condition_number(np.ascontiguousarray(Jx)) < 1e8
    assert _distinct(canonical(form, chosen.x)).all()


@pytest.mark.slow
def test_generic_count_of_the_6_6_platform_is_40():
    """Monodromy without the disk cache finds the 40 roots of a general 6-6 Stewart-Gough platform."""
    assert solve_generic(polynomial_form(preset("zhao2011_6pss"))).count == 40


def test_generic_solve_is_stored_and_read_back(tmp_path, monkeypatch):
    """The generic solve is written under $PLM_PIN_CACHE and read back equal."""
    monkeypatch.setenv("PLM_PIN_CACHE", str(tmp_path))
    form = polynomial_form(preset("fourbar"))
    first = generic_solution(form)
    assert len(list((tmp_path / "homotopy").glob(f"{form.digest}.v*.npz"))) == 1
    again = generic_solution(form)
    assert np.array_equal(first.x, again.x) and np.array_equal(first.p, again.p)
