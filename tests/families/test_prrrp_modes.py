"""Assembly and working modes, the transition graph and the mode-change planners (Harada 2015)."""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.exceptions import InvalidInput, PoseUnreachable, SingularConfiguration
from plm_pin.families import prrrp as pm
from plm_pin.kinematics import classify, closed_chain_jacobians
from plm_pin.kinematics.paths import track_actuator_path
from plm_pin.kinematics.working_mode import working_mode
from plm_pin.tolerances import MODE_CHANGE_TOL, RANK_RTOL
from tests.conftest import preset, prrrp_paper_configuration

ASYM = "harada2015_asymmetric"
RT = 0.05
LENGTHS_2015 = (0.240, 0.170, 0.170, 0.240)
LEFT = (1, 2)


# ------------------------------------------------------------------ independent oracles


def _eq6_config(mech, pose, sigmas, lengths):
    """Configuration from Harada 2015 eqs. (1), (6): :func:`tests.conftest.prrrp_paper_configuration`."""
    q = prrrp_paper_configuration(mech, pose, lengths, RT, sigmas)
    assert np.max(np.abs(mech.closure_residual(q))) < 1e-12
    return q


def _frames(mech, q, names):
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    return [data.oMf[mech.model.getFrameId(n)].translation.copy() for n in names]


def _eq4_pair(c1, c2, l1, l2, sign):
    """Eq. (4): intersection of the circles (c1, l1), (c2, l2) on the side ``sign`` of the x axis."""
    p = (c1 + c2) / 2 - (l1**2 - l2**2) / (2 * (c1 - c2))
    return np.array([p, sign * math.sqrt(max(l1**2 - (c1 - p) ** 2, 0.0))])


def _paper_jx(mech, q, legs=(1, 2, 3, 4)):
    """Harada 2015 eq. (2) J_x rows [v_i^T, v_i^T E R s_i] from the frames (v_i: unit rod vector)."""
    pairs = {1: "plate_left", 2: "plate_left", 3: "plate_right", 4: "plate_right"}
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    centre = data.oMf[mech.model.getFrameId("plate_center")].translation[:2]
    rows = []
    for i in legs:
        pair = data.oMf[mech.model.getFrameId(pairs[i])].translation[:2]
        base = data.oMi[mech.model.getJointId(f"rod{i}_pivot")].translation[:2]
        v = (pair - base) / np.linalg.norm(pair - base)
        arm = pair - centre
        rows.append([v[0], v[1], v @ np.array([-arm[1], arm[0]])])
    return np.array(rows)


def _rank(A):
    s = np.linalg.svd(A, compute_uv=False)
    return int(np.sum(s > RANK_RTOL * s[0]))


# ------------------------------------------------------------------ fixtures


@pytest.fixture(scope="module")
def asym():
    return preset(ASYM)


@pytest.fixture(scope="module")
def graph(asym):
    return pm.assembly_mode_graph(asym)


@pytest.fixture(scope="module")
def route(asym, graph):
    return pm.plan_assembly_mode_change(asym, graph=graph)


@pytest.fixture(scope="module")
def flip(asym):
    return pm.plan_working_mode_change(asym, leg=3)


@pytest.fixture(scope="module")
def symmetric():
    return plm_pin.build_mechanism("harada2015_asymmetric", pm.symmetric_rods(0.240))


# ------------------------------------------------------------------ labels


def test_layout_reads_the_2015_rods_and_stator(asym):
    """The layout finds legs 1-2 on the left pair, 3-4 on the right, rods 0.240/0.170 m, stator along x."""
    lay = pm.prrrp_layout(asym)
    assert [g.index for g in lay.legs] == [1, 2, 3, 4]
    np.testing.assert_allclose([g.length for g in lay.legs], LENGTHS_2015, atol=1e-12)
    assert [s.legs for s in lay.subs] == [(1, 2), (3, 4)]
    np.testing.assert_allclose(lay.direction, [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(lay.normal, [0, 1, 0], atol=1e-15)
    assert lay.half_plate == pytest.approx(RT, abs=1e-15)


def test_mode_labels_on_hand_built_configurations(asym):
    """Eq. (6) by hand: [+ +], its mirror [- -] with the same sliders, [+ 0], and the fold (- + 0 +)."""
    sig = (-1, 1, -1, 1)
    up = _eq6_config(asym, (0.0, 0.10, 0.0), sig, LENGTHS_2015)
    down = _eq6_config(asym, (0.0, -0.10, 0.0), sig, LENGTHS_2015)
    np.testing.assert_allclose(asym.actuator_positions(up), asym.actuator_positions(down), atol=1e-15)
    assert pm.assembly_mode(asym, up) == (1, 1)
    assert pm.assembly_mode(asym, down) == (-1, -1)
    assert pm.paper_working_modes(asym, up) == pm.paper_working_modes(asym, down) == sig
    th = math.radians(-30.0)
    right_on_stator = _eq6_config(asym, (0.0, -RT * math.sin(th), th), sig, LENGTHS_2015)
    assert pm.assembly_mode(asym, right_on_stator) == (1, 0)
    th = math.radians(30.0)
    fold = _eq6_config(
        asym, (RT - RT * math.cos(th), 0.170 - RT * math.sin(th), th), (-1, 1, 0, 1), LENGTHS_2015
    )
    assert pm.paper_working_modes(asym, fold) == (-1, 1, 0, 1)
    assert pm.mode_label((1, 0)) == "[+ 0]"
    assert pm.working_mode_label((-1, 1, 0, 1)) == "(- + 0 +)"


def test_paper_working_modes_are_minus_the_leg_block_signs(asym, flip):
    """The eq. (6) sign is -sign(z_i^T a), the opposite of legs.working_mode, and 0 at the same fold."""
    for k in (0, flip.fold_index - 7, flip.fold_index, flip.fold_index + 7, flip.path.n_samples - 1):
        q = flip.path.q[k]
        assert pm.paper_working_modes(asym, q) == tuple(-v for v in working_mode(asym, q))


def test_pair_solutions_are_eq4_and_match_the_assembled_pairs(asym, route):
    """The closed form of eq. (4) gives the assembled pair positions, on the side its label says."""
    for k in range(0, route.path.n_samples, 17):
        q, c = route.path.q[k], route.path.actuators[k]
        pairs = _frames(asym, q, ["plate_left", "plate_right"])
        for j, (a, b) in enumerate(((0, 1), (2, 3))):
            sol = pm.pair_solutions(c[a], c[b], LENGTHS_2015[a], LENGTHS_2015[b])
            side = route.assembly_modes[k][j]
            expected = _eq4_pair(c[a], c[b], LENGTHS_2015[a], LENGTHS_2015[b], side)
            np.testing.assert_allclose(pairs[j][:2], expected, atol=1e-9)
            assert sol.kind == ("two" if side else "touching")
            np.testing.assert_allclose(sol.points[0 if side >= 0 else 1], expected, atol=1e-9)


def test_pair_solutions_edge_cases():
    """Eq. (4): touching circles give one point on the axis, equal coincident circles are indefinite."""
    assert pm.pair_solutions(0.0, 0.41, 0.24, 0.17).kind == "touching"
    np.testing.assert_allclose(pm.pair_solutions(0.0, 0.41, 0.24, 0.17).points, [[0.24, 0.0]], atol=1e-12)
    assert pm.pair_solutions(0.0, 0.07, 0.24, 0.17).kind == "touching"  # internal tangency
    assert pm.pair_solutions(0.0, 0.5, 0.24, 0.17).kind == "none"
    assert pm.pair_solutions(0.1, 0.1, 0.24, 0.24).kind == "coincident"
    assert pm.pair_solutions(0.1, 0.1, 0.24, 0.17).kind == "none"  # concentric, unequal: no assembly


# ------------------------------------------------------------------ the graph


def test_nine_modes_with_rank_three_except_00(asym, graph):
    """Section III: rank J_x = 3 in 8 modes and < 3 in [0 0], by C and by the paper's J_x alike."""
    assert [n.mode for n in graph.nodes] == list(pm.ASSEMBLY_MODES)
    assert len(set(pm.ASSEMBLY_MODES)) == 9
    for node in graph.nodes:
        assert pm.assembly_mode(asym, node.q) == node.mode
        paper_rank = _rank(_paper_jx(asym, node.q))
        assert node.rank == paper_rank == (1 if node.mode == (0, 0) else 3)
        assert node.singular == (node.mode == (0, 0))
    assert graph.singular_modes == ((0, 0),)


def test_modes_on_the_stator_lose_redundancy_not_rank(asym, graph):
    """[+ 0], [0 -], ...: C keeps rank 3 but dropping a slider of the other pair makes it singular."""
    for node in graph.nodes:
        C = closed_chain_jacobians(asym, node.q).C
        drops = [_rank(np.delete(C, k, axis=0)) for k in range(4)]
        if 0 in node.mode and node.mode != (0, 0):
            assert node.redundancy_margin < 1e-12
            assert min(drops) == 2 and node.direct_margin > 1e-3
        elif node.mode != (0, 0):
            assert node.redundancy_margin > 1e-3 and drops == [3, 3, 3, 3]


# ------------------------------------------------------------------ assembly-mode change


def test_assembly_mode_change_follows_the_paper_route(asym, route):
    """[+ +] -> [+ 0] -> [+ -] -> [0 -] -> [- -], never [0 0], ending in the mirror with the same sliders."""
    assert route.route == pm.PAPER_ASSEMBLY_ROUTE
    assert route.visited == pm.PAPER_ASSEMBLY_ROUTE
    assert (0, 0) not in {tuple(m) for m in route.assembly_modes}
    assert pm.assembly_mode(asym, route.path.q[0]) == (1, 1)
    assert pm.assembly_mode(asym, route.path.q[-1]) == (-1, -1)
    np.testing.assert_allclose(route.path.actuators[0], route.path.actuators[-1], atol=1e-10)
    first = np.array(_frames(asym, route.path.q[0], ["plate_left", "plate_right"]))
    last = np.array(_frames(asym, route.path.q[-1], ["plate_left", "plate_right"]))
    np.testing.assert_allclose(last * [1, -1, 1], first, atol=1e-10)
    assert route.ok
    assert route.path.n_samples == 203
    assert {tuple(w) for w in route.working_modes} == {(-1, 1, -1, 1)}


def test_assembly_mode_change_closes_loops_and_stays_nonsingular(asym, route):
    """At every sample: loops closed to 1e-10, classify's direct margin above the stated tolerance."""
    assert route.path.tol == MODE_CHANGE_TOL
    for k in range(route.path.n_samples):
        q = route.path.q[k]
        assert np.max(np.abs(asym.closure_residual(q))) <= 1e-10
        np.testing.assert_allclose(asym.actuator_positions(q), route.path.actuators[k], atol=1e-12)
        report = classify(asym, q)
        assert report.direct_margin > MODE_CHANGE_TOL
        assert report.constraint_margin > MODE_CHANGE_TOL
        assert report.direct_margin == pytest.approx(route.path.direct_margin[k], rel=1e-9)
        assert _rank(_paper_jx(asym, q)) == 3
    assert route.path.min_direct_margin > 0.02


def test_assembly_mode_change_is_continuous(route):
    """No jump between samples: the plate moves less than 5 mm and 2 deg per step."""
    step = np.abs(np.diff(route.path.x, axis=0))
    assert np.all(step[:, :2] < 5e-3)
    assert np.all(step[:, 2] < math.radians(2.0))
    assert route.max_deviation < 1e-9


def test_each_sub_mechanism_passes_its_own_zero(asym, route):
    """Right pair at [0] then left pair: circles tangent (eq. (4)), sub singular, mechanism not."""
    assert [(c.sub, c.mode) for c in route.crossings] == [("right", (1, 0)), ("left", (0, -1))]
    assert route.crossings[0].index < route.crossings[1].index
    for c in route.crossings:
        a, b = (2, 3) if c.sub == "right" else (0, 1)
        gap = abs(c.actuators[a] - c.actuators[b])
        assert gap == pytest.approx(LENGTHS_2015[a] + LENGTHS_2015[b], abs=1e-9)
        assert c.sub_direct_margin < 1e-12
        assert c.redundancy_margin < 1e-12
        assert c.direct_margin > MODE_CHANGE_TOL
        assert abs(c.x[2]) > math.radians(20.0)  # the plate is tilted, so the other pair holds it


def test_3d4m_can_change_assembly_mode():
    """The 2011 3D4M (equal rods, redundant) has the same graph and also crosses without singularity."""
    mech = preset("harada2011_3d4m")
    plan = pm.plan_assembly_mode_change(mech)
    assert plan.ok and plan.visited == pm.PAPER_ASSEMBLY_ROUTE
    assert plan.graph.singular_modes == ((0, 0),)
    assert plan.path.min_direct_margin > 0.01


def test_3d3m_cannot_change_assembly_mode():
    """The non-redundant 3D3M is direct-singular at [0 +] and [0 -]: no route avoids singular modes."""
    mech = preset("harada2011_3d3m")
    graph = pm.assembly_mode_graph(mech)
    assert set(graph.singular_modes) == {(0, 1), (0, -1), (0, 0)}
    for mode in ((0, 1), (0, -1)):
        assert _rank(_paper_jx(mech, graph.node(mode).q, legs=(1, 2, 4))) == 2
    assert graph.routes((1, 1), (-1, -1)) == []
    with pytest.raises(SingularConfiguration, match=r"no route from \[\+ \+\] to \[- -\] avoids"):
        pm.plan_assembly_mode_change(mech, graph=graph)


# ------------------------------------------------------------------ working-mode change


def test_working_mode_change_visits_the_paper_modes(asym, flip):
    """(- + - +) -> (- + 0 +) -> (- + + +), plate back at its start pose, never direct-singular."""
    assert flip.route == pm.PAPER_WORKING_ROUTE
    assert flip.visited == pm.PAPER_WORKING_ROUTE
    assert flip.ok
    np.testing.assert_allclose(flip.path.x[-1], flip.path.x[0], atol=1e-10)
    assert {tuple(m) for m in flip.assembly_modes} == {(1, 1)}
    for k in range(flip.path.n_samples):
        q = flip.path.q[k]
        assert np.max(np.abs(asym.closure_residual(q))) <= 1e-10
        report = classify(asym, q)
        assert report.direct_margin > MODE_CHANGE_TOL
        assert report.constraint_margin > MODE_CHANGE_TOL


def test_working_mode_change_crosses_the_actuator_singularity_of_leg_3(asym, flip):
    """At the fold rod 3 is vertical (c3 under the pair, height l3): inverse-singular only."""
    k = flip.fold_index
    q = flip.path.q[k]
    (pair,) = _frames(asym, q, ["plate_right"])
    c = flip.path.actuators[k]
    assert c[2] == pytest.approx(pair[0], abs=1e-12)
    assert pair[1] == pytest.approx(0.170, abs=1e-12)
    assert classify(asym, q).kinds == ("inverse",)
    pair0 = _frames(asym, flip.path.q[0], ["plate_right"])[0]
    assert flip.path.actuators[-1][2] == pytest.approx(2 * pair0[0] - flip.path.actuators[0][2], abs=1e-12)
    # the two sliders of the right pair never meet: |c3 - c4| >= |l4 - l3| (no complex singularity)
    assert np.all(flip.slider_gap > 0.070)


def test_only_the_shorter_rod_can_fold():
    """Leg 4 (0.240 m) cannot fold: leg 3 (0.170 m) cannot reach 0.240 m; the message says so."""
    with pytest.raises(PoseUnreachable, match=r"leg 3 \(l = 0.17 m\) cannot reach the height 0.24 m"):
        pm.plan_working_mode_change(preset(ASYM), leg=4)


# ------------------------------------------------------------------ complex singularity


def test_complex_singularity_with_equal_rods_not_with_the_asymmetric_design(asym, symmetric):
    """Rod 3 perpendicular: equal rods force rod 4 too, c3 = c4, circles coincide, J_phi loses rank."""
    for mech in (symmetric, preset("harada2011_3d4m")):
        case = pm.complex_singularity_check(mech, leg=3)
        assert case.admits_complex_singularity
        assert "constraint" in classify(mech, case.q_fold).kinds
        c = mech.actuator_positions(case.q_fold)
        assert c[2] == pytest.approx(c[3], abs=1e-15)
        assert case.circles == "coincident"
        assert _rank(mech.closure_jacobian(case.q_fold)) == case.closure_rank == mech.nv - mech.mobility - 1
    case = pm.complex_singularity_check(asym, leg=3)
    assert not case.admits_complex_singularity
    report = classify(asym, case.q_fold)
    assert report.kinds == ("inverse",) and report.constraint_margin > MODE_CHANGE_TOL
    assert _rank(asym.closure_jacobian(case.q_fold)) == asym.nv - asym.mobility
    assert case.slider_gap >= case.min_slider_gap == pytest.approx(0.070, abs=1e-12)
    assert case.circles == "two" and case.coincident == ()


def test_coincident_circles_leave_the_pair_free_with_both_sliders_locked(symmetric):
    """Equal rods, c3 = c4: locking both sliders removes one DOF only; the pair moves on the circle."""
    case = pm.complex_singularity_check(symmetric, leg=3)
    off_fold = [s for s in case.coincident if s.rod_angle < math.pi / 2 - 1e-9]
    assert len(off_fold) == 2
    for sample in off_fold:
        assert sample.slider_gap < 1e-12 and sample.sub_rank == 1
        assert sample.sub_direct_margin < 1e-12
        assert sample.report.direct_margin > MODE_CHANGE_TOL  # the whole mechanism still holds the plate
    # rebuild the 70 deg configuration by hand and move it with sliders 3 and 4 locked
    th = math.radians(30.0)
    x_pair = pm.prrrp_state(symmetric, symmetric.q_ref).pairs[1][0]
    h = 0.240 * math.sin(math.radians(70.0))
    q = _eq6_config(
        symmetric, (x_pair - RT * math.cos(th), h - RT * math.sin(th), th), (-1, 1, -1, -1), (0.240,) * 4
    )
    jac = closed_chain_jacobians(symmetric, q)
    _, s, Vt = np.linalg.svd(jac.C[[2, 3]])
    assert s[1] < 1e-12 * s[0]
    motion = jac.N @ Vt[-1]  # C rows 3, 4 vanish on the last two right singular vectors
    data = symmetric.model.createData()
    pin.computeJointJacobians(symmetric.model, data, q)
    pin.updateFramePlacements(symmetric.model, data)
    fid = symmetric.model.getFrameId("plate_right")
    v_pair = pin.getFrameJacobian(symmetric.model, data, fid, pin.LOCAL_WORLD_ALIGNED)[:2] @ motion
    rod = pm.prrrp_state(symmetric, q).rods[2][:2]
    assert np.linalg.norm(v_pair) > 1e-3 and abs(v_pair @ rod) < 1e-12  # tangent to the circle


def test_symmetric_working_mode_change_runs_into_the_complex_singularity(symmetric):
    """With equal rods the flip of leg 3 drags leg 4 through the fold too: constraint margin collapses."""
    plan = pm.plan_working_mode_change(symmetric, leg=3)
    assert not plan.ok
    assert plan.path.min_constraint_margin < 1e-6
    assert plan.visited[-1] != pm.PAPER_WORKING_ROUTE[-1]
    assert plan.visited[-1][3] == -1  # leg 4 flipped as well


# ------------------------------------------------------------------ results and input checks


def test_results_serialise_to_strict_json(asym, graph, route, flip, symmetric):
    """Every result's to_dict() is plain JSON (no NaN)."""
    for obj in (
        graph,
        route,
        flip,
        pm.complex_singularity_check(symmetric),
        pm.prrrp_layout(asym),
        pm.prrrp_state(preset("harada2011_3d3m"), preset("harada2011_3d3m").q_ref),
        pm.pair_solutions(0.0, 0.3, 0.24, 0.17),
    ):
        json.dumps(obj.to_dict(), allow_nan=False)
    data = route.to_dict()
    assert data["route"] == [list(m) for m in route.route] and data["ok"] == route.ok
    assert [c["label"] for c in data["crossings"]] == [pm.mode_label(c.mode) for c in route.crossings]
    assert data["crossings"] and data["graph"] == graph.to_dict()
    assert flip.to_dict()["visited"] == [list(m) for m in flip.visited]
    mech3 = preset("harada2011_3d3m")
    state = pm.prrrp_state(mech3, mech3.q_ref)
    data = state.to_dict()
    assert data["assembly_mode_label"] == pm.mode_label(state.assembly_mode)
    assert data["working_mode_label"] == pm.working_mode_label(state.working_mode)
    assert "nan" in data["sub_direct_margin"]  # a pair held by one leg
    case = pm.complex_singularity_check(symmetric)
    data = case.to_dict()
    assert data["admits_complex_singularity"] == case.admits_complex_singularity
    assert [c["sub_rank"] for c in data["coincident"]] == [c.sub_rank for c in case.coincident]
    assert pm.pair_solutions(0.0, 0.3, 0.24, 0.17).to_dict()["kind"] == "two"
    layout = pm.prrrp_layout(asym)
    data = layout.to_dict()
    assert data["legs"][0] == {
        "index": layout.legs[0].index,
        "slider": layout.legs[0].slider,
        "rod": layout.legs[0].rod,
        "pair": layout.legs[0].pair,
        "length": layout.legs[0].length,
        "actuator": layout.legs[0].actuator,
    }
    assert data["subs"][0]["legs"] == list(layout.subs[0].legs) and data["half_plate"] == layout.half_plate


def test_bad_input_is_refused_with_clear_messages(asym, graph):
    """Wrong mechanism, route, start or shapes raise InvalidInput naming the problem."""
    with pytest.raises(InvalidInput, match=r"fourbar is not a 2-PRRRP"):
        pm.prrrp_layout(preset("fourbar"))
    bad_route = [(1, 1), (0, 0), (-1, -1)]
    with pytest.raises(InvalidInput, match=r"route passes the singular modes \['\[0 0\]'\]"):
        pm.plan_assembly_mode_change(asym, route=bad_route, graph=graph)
    with pytest.raises(InvalidInput, match=r"route step \[\+ \+\] -> \[- -\] is not an edge"):
        pm.plan_assembly_mode_change(asym, route=[(1, 1), (-1, -1)], graph=graph)
    on_stator = graph.node((1, 0)).q
    with pytest.raises(InvalidInput, match=r"start configuration is in \[\+ 0\]"):
        pm.plan_assembly_mode_change(asym, on_stator, graph=graph)
    with pytest.raises(InvalidInput, match=r"actuators must be finite with shape \(N, 4\)"):
        track_actuator_path(asym, np.zeros((3, 2)), asym.q_ref)
    with pytest.raises(InvalidInput, match=r"actuators must be finite"):
        track_actuator_path(asym, np.full((3, 4), np.nan), asym.q_ref)
