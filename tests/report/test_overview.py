"""The overview study (plm_pin/report/overview.py) on a user's description."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import yaml

import plm_pin
from plm_pin.report import find_study, run_study
from plm_pin.warnings import ReferenceWarning
from tests.report.conftest import rename

SECTIONS = [
    "Mobility and redundancy",
    "Workspace slice: manipulability and singularities",
    "Static forces at the reference configuration",
    "Task-space dynamics and decoupling",
    "Stiffness and natural frequencies",
    "Short simulation: released under gravity",
    "3D view",
]


def _blocks(result, kind):
    """The figures or scenes of ``result``, by caption."""
    return {b.caption: b for s in result.sections for b in s.blocks if b.kind == kind}


def _rows(table) -> dict:
    return {row[0]: row[1] for row in table.rows}


@pytest.fixture(scope="module")
def fivebar_overview(tmp_path_factory):
    """The overview of a copy of the five-bar, renamed, as a user's description."""
    import shutil

    from plm_pin.models import urdf_folder

    folder = tmp_path_factory.mktemp("user")
    for suffix in (".urdf", ".plm.yaml"):
        shutil.copy(urdf_folder() / f"fivebar{suffix}", folder / f"myfivebar{suffix}")
    rename(folder / "myfivebar.urdf", "my five-bar")
    return folder / "myfivebar.urdf", run_study(find_study("overview"), folder / "myfivebar.urdf")


def test_overview_sections_and_mobility(fivebar_overview):
    """Six sections; mobility 2 and redundancy 0 of the RRRRR five-bar (2 motors, one point closure)."""
    _, result = fivebar_overview
    assert [s.title for s in result.sections] == SECTIONS
    assert result.folder == "overview-my_five-bar"
    assert result.mechanisms[0].name == "my five-bar"
    rows = _rows(result.block("sizes"))
    # 4 revolutes, a planar point closure: 3 rows of rank 2
    assert (rows["velocity size nv"], rows["closure rows"], rows["rank of J_phi at the reference"]) == (
        4,
        3,
        2,
    )
    assert (rows["mobility (DOF)"], rows["redundancy"]) == (2, 0)
    assert rows["singular at the reference"] is False
    # two motor angles per two tip coordinates: w in rad^2/m^2, stated in SI, not "J_ce units"
    units = {r[0]: r[2] for r in result.block("sizes").rows}
    assert units["manipulability w"] == "rad^2/m^2"


def test_overview_static_forces_balance_gravity(fivebar_overview):
    """The report's f_c balances Pinocchio's generalized gravity with some closure force (least squares)."""
    path, result = fivebar_overview
    mech = plm_pin.load(path)
    table = result.block("actuator_forces")
    f_c = np.array([row[2] for row in table.rows])
    assert [row[0] for row in table.rows] == ["left_motor", "right_motor"]
    q = mech.q_ref
    g = pin.computeGeneralizedGravity(mech.model, mech.model.createData(), q)  # (nv,)
    B = np.zeros((mech.nv, mech.n_actuators))
    B[mech.actuated_v_indices, np.arange(mech.n_actuators)] = 1.0
    J = mech.closure_jacobian(q)
    lam, *_ = np.linalg.lstsq(J.T, g - B @ f_c, rcond=None)
    assert np.max(np.abs(B @ f_c + J.T @ lam - g)) < 1e-10
    assert np.max(np.abs(f_c)) > 0.1  # gravity does load the motors


def test_overview_map_figure_and_scene(fivebar_overview):
    """The slice figure stores its grid; the scene shows the reference configuration with force arrows."""
    _, result = fivebar_overview
    figure = next(iter(_blocks(result, "figure").values()))
    data = figure.data["slice"]
    assert data["axes"] == ["x", "y"]
    assert np.shape(data["manipulability"]) == tuple(len(v) for v in data["values"])
    summary = _rows(result.block("slice_summary"))
    assert summary["grid points"] == np.size(data["manipulability"])
    assert 0.0 < summary["reachable fraction"] <= 1.0
    # every five-bar joint spans at least a full turn: the limits never bind; collisions only remove points
    assert summary["fraction reached within the joint limits"] == summary["reachable fraction"]
    assert 0.0 <= summary["fraction reached free of self-collision"] <= summary["reachable fraction"]
    scenes = _blocks(result, "scene")
    scene = next(b for caption, b in scenes.items() if caption.startswith("The mechanism at the reference"))
    assert scene.html.lstrip().startswith("<!DOCTYPE html>")
    np.testing.assert_allclose(scene.data["q"], plm_pin.load(fivebar_overview[0]).q_ref)
    assert scene.data["arrows"] and scene.data["scale"] > 0


def test_overview_scene_overlays_the_slice_boundary_and_singular_points(fivebar_overview):
    """The 3D view's dots: the slice's boundary poses (brute-force neighbours) and its singular points."""
    from tests.viz.test_scene_marks import brute_force_boundary

    _, result = fivebar_overview
    figure = next(iter(_blocks(result, "figure").values()))
    data = figure.data["slice"]
    xs, ys = (np.asarray(v) for v in data["values"])
    edge = brute_force_boundary(np.asarray(data["reachable"], dtype=bool))
    scene = next(
        b for caption, b in _blocks(result, "scene").items() if caption.startswith("The mechanism at")
    )
    expected = [(xs[i], ys[j]) for i, j in zip(*np.nonzero(edge), strict=True)]
    np.testing.assert_allclose(scene.data["workspace_boundary"][:, :2], expected, atol=1e-9)
    points = figure.data["singular_points"]
    for kind, drawn in scene.data["singular_points"].items():
        found = [p["x"] for p in points if p["kind"] == kind]
        np.testing.assert_allclose(drawn[:, :2], np.reshape(found, (-1, 2)), atol=1e-7)
    assert sum(len(v) for v in scene.data["singular_points"].values()) == len(points) > 0
    legend = scene.html[scene.html.index('id="plm-pin-legend"') :]
    assert "workspace boundary" in legend and "direct singularity (type 2)" in legend


def test_overview_without_task_skips_the_slice(user_fivebar):
    """Without end effector: mobility, statics and the 3D view still; the slice section says why not."""
    sidecar = user_fivebar.with_name("fivebar.plm.yaml")
    data = yaml.safe_load(sidecar.read_text())
    del data["end_effector"]
    sidecar.write_text(yaml.safe_dump(data, sort_keys=False))
    result = run_study(find_study("overview"), user_fivebar)
    for index, what in ((1, "No workspace slice"), (3, "No decoupling check")):
        (text,) = result.sections[index].blocks
        assert text.text.startswith(f"{what}: it needs a task")
    assert result.block("actuator_forces").rows


def test_overview_of_a_one_dof_mechanism_sweeps_its_task(tmp_path):
    """The four-bar (task rz only) gets a sweep of its manipulability instead of a map."""
    result = run_study(find_study("overview"), "fourbar")
    figures = [b for s in result.sections for b in s.blocks if b.kind == "figure"]
    assert figures[0].data["slice"]["axes"] == ["rz"]


def test_overview_of_a_gripper_finger_reports_its_transmission(tmp_path):
    """A four-bar finger with its output joint as task: the transmission table holds the closed forms."""
    import math

    from tests import textbook as tb

    tb.finger(tmp_path)
    result = run_study(find_study("overview"), tmp_path / "finger.urdf")
    rows = {row[0]: row[2] for row in result.block("transmission").rows}
    ratio = tb.finger_velocity_ratio(tb.FINGER_THETA2)
    assert rows["d finger_pivot / d drive"] == pytest.approx(ratio, rel=1e-9)
    assert rows["finger_pivot force per drive force"] == pytest.approx(1 / ratio, rel=1e-9)
    mu = tb.finger_transmission_angle(tb.FINGER_THETA2)
    assert rows["closure knuckle, motion of finger_pivot"] == pytest.approx(math.sin(mu), abs=1e-10)
    figures = [b for s in result.sections for b in s.blocks if b.kind == "figure"]
    assert figures[0].data["slice"]["axes"] == ["finger_pivot"]


def test_overview_of_a_gripper_finger_lists_its_two_certified_assembly_modes(tmp_path):
    """The report states "all 2 assembly modes (certified": Freudenstein's two branches at the drive angle.

    The output angles of the table (degrees) are the closed form's two roots theta4(+-1): the
    finger's joint sits on the ground line with no offset in its URDF.
    """
    from tests import textbook as tb

    tb.finger(tmp_path)
    result = run_study(find_study("overview"), tmp_path / "finger.urdf")
    table = result.block("assembly-modes")
    assert "all 2 assembly modes (certified" in table.title
    texts = [b.text for s in result.sections for b in s.blocks if b.kind == "text"]
    assert any("all 2 assembly modes (certified" in t for t in texts)
    expected = sorted(
        np.degrees(np.angle(np.exp(1j * tb.finger_freudenstein(tb.FINGER_THETA2, b)[0]))) for b in (-1, 1)
    )
    found = sorted(float(np.degrees(np.angle(np.exp(1j * np.radians(row[1]))))) for row in table.rows)
    np.testing.assert_allclose(found, expected, atol=1e-8)
    assert all(row[-1] == "Krawczyk" for row in table.rows)


@pytest.fixture(scope="module")
def limited_3d4m_overview(tmp_path_factory):
    """The overview of the 3D4M with effort limits of +-1.5 N on every slider, as a user's description."""
    import shutil

    from plm_pin.models import urdf_folder

    folder = tmp_path_factory.mktemp("limited")
    for suffix in (".urdf", ".plm.yaml"):
        shutil.copy(urdf_folder() / f"harada2011_3d4m{suffix}", folder / f"table{suffix}")
    sidecar = folder / "table.plm.yaml"
    data = yaml.safe_load(sidecar.read_text())
    for act in data["actuation"]:
        act["limits"] = [-LIMIT, LIMIT]
    sidecar.write_text(yaml.safe_dump(data, sort_keys=False))
    return run_study(find_study("overview"), folder / "table.urdf")


LIMIT = 1.5
"""Effort limit of the sliders in the limited 3D4M [N]."""


def test_overview_internal_range_is_the_interval_intersection(limited_3d4m_overview):
    """One internal-force direction g: y is admissible iff -L <= f_p,i + g_i y <= L for all i (intervals)."""
    result = limited_3d4m_overview
    f_p = np.array([row[2] for row in result.block("actuator_forces").rows])
    (direction,) = result.block("internal_directions").rows
    g = np.array(direction[1:])
    ends = np.sort(np.stack([(-LIMIT - f_p) / g, (LIMIT - f_p) / g]), axis=0)
    (row,) = result.block("internal_range").rows
    assert row[1] == pytest.approx(np.max(ends[0]), abs=1e-9)
    assert row[3] == pytest.approx(np.min(ends[1]), abs=1e-9)
    assert row[1] < 0.0 < row[3] and row[2] == pytest.approx(0.0, abs=1e-12)  # min norm: y = 0


def test_overview_decoupling_of_the_3d4m_is_harada_s(limited_3d4m_overview):
    """Harada 2011 eq. (26), (M.30): m_xx = 4 m_l + 4 m_m + m_t constant, m_xy = m_xθ = 0, g_x along y."""
    m_l, m_m, m_t, gravity = 0.026, 0.375, 0.132, 9.8  # Table 1 and (M.37)
    rows = {r[0]: r for r in limited_3d4m_overview.block("decoupling").rows}
    assert rows["M_xx"][1] == "constant"
    assert rows["M_xx"][2] == pytest.approx(4 * m_l + 4 * m_m + m_t, rel=1e-9)
    assert (
        rows["M_xy"][1] == rows["M_xrz"][1] == rows["g_x"][1] == rows["g_rz"][1] == rows["h_x"][1] == "zero"
    )
    assert rows["g_y"][1] == "constant" and rows["g_y"][2] == pytest.approx(
        (2 * m_l + m_t) * gravity, rel=1e-9
    )
    assert rows["M_yy"][1] == "varies"
    header = [c.name for c in limited_3d4m_overview.block("decoupling").columns]
    spread, tolerance = header.index("spread (max - min)"), header.index("tolerance")
    for name, row in rows.items():  # 'varies' exactly when the spread exceeds the tolerance stated beside it
        if row[1] in ("constant", "varies"):
            assert (row[1] == "varies") == (row[spread] > row[tolerance]), name
    assert rows["h_y"][1] == "nonzero"  # a velocity term is zero or not; it has no constant value


def test_overview_simulation_conserves_energy_and_closure(limited_3d4m_overview):
    """Released at rest, actuators free: 1 s simulated, loops closed to 1e-10 m, energy drift < 1e-7 J."""
    rows = _rows(limited_3d4m_overview.block("simulation"))
    assert rows["time simulated"] == pytest.approx(1.0)
    assert rows["largest closure residual"] <= 1e-10
    assert rows["energy drift (max |E - E(0)|)"] < 1e-7
    assert rows["largest joint speed"] > 0.1  # it does fall
    scenes = _blocks(limited_3d4m_overview, "scene")
    animation = scenes["The passive simulation: play it in the page."]
    assert len(animation.data["qs"]) == len(animation.data["times"]) > 50


def test_overview_stiffness_drive_share_is_k_j_ce_t_j_ce_and_preload_changes_it(limited_3d4m_overview):
    """Drives share of K_x: k J_ce^T J_ce (eq. (12)); the preload table varies and meets it at y = 0."""
    from analyses import _harada2011_paper as paper
    from plm_pin.models.registry import HARADA2011_DRIVE_STIFFNESS

    result = limited_3d4m_overview
    pose, legs = (0.0, 0.08, np.radians(-20.0)), (1, 2, 3, 4)
    J = paper.J_ce(pose, paper.slider_positions(pose, 0.14, 0.05, legs), 0.14, 0.05, legs)
    share = {r[0]: r[1:] for r in result.block("stiffness_shares").rows}
    np.testing.assert_allclose(share["actuators"], HARADA2011_DRIVE_STIFFNESS * np.diag(J.T @ J), rtol=1e-9)
    rows = _rows(result.block("stiffness"))
    preload = result.block("preload").rows
    at_zero = [r for r in preload if r[0] == 0.0]
    assert at_zero and at_zero[0][1] == pytest.approx(rows["translational eigen-stiffness 1"], rel=1e-12)
    assert max(r[1] for r in preload) - min(r[1] for r in preload) > 1e-3  # the internal force changes K_x
    figures = _blocks(limited_3d4m_overview, "figure")
    caption = next(c for c in figures if c.startswith("Smallest translational eigen-stiffness"))
    assert figures[caption].data["stiffness_map"]["units"]["min_translational_stiffness"] == "N/m"


def test_overview_collision_free_slice_of_the_3d4m_is_the_carriage_gaps(limited_3d4m_overview):
    """A reached pose of the 3D4M's slice is collision-free iff its carriages are 3 cm apart.

    Rods and plate move in layers above the carriages (the preset's ignore list): only carriages
    (3 cm boxes on the stator) collide, decided by the slider positions of eq. (2), (M.5).
    """
    from analyses import _harada2011_paper as paper

    figure = next(b for b in _blocks(limited_3d4m_overview, "figure").values() if "slice" in b.data)
    data = figure.data["slice"]
    legs, free = (1, 2, 3, 4), 0
    for i, a in enumerate(data["values"][0]):
        for j, b in enumerate(data["values"][1]):
            if data["reachable"][i][j]:
                pose = dict(zip(data["dofs"], data["pose"], strict=True)) | {
                    data["axes"][0]: a,
                    data["axes"][1]: b,
                }
                c = paper.slider_positions((pose["x"], pose["y"], pose["rz"]), 0.14, 0.05, legs)
                free += bool(np.min(np.abs(c[:, None] - c[None, :])[np.triu_indices(4, 1)]) >= 0.03)
    summary = _rows(limited_3d4m_overview.block("slice_summary"))
    total = np.size(data["reachable"])
    assert summary["fraction reached free of self-collision"] == pytest.approx(free / total, abs=1e-12)
    assert 0.5 * summary["reachable fraction"] < free / total < summary["reachable fraction"]


def test_overview_of_a_slider_crank_reports_its_transmission_in_metres(tmp_path):
    """A slider-crank with its slider's joint as task: the transmission, and the pose in metres.

    The transmission table holds the closed form dx/dt; the pose table says nothing of degrees.
    """
    from tests import textbook as tb

    with pytest.warns(ReferenceWarning):  # its sidecar gives no reference: moved off the dead centre
        mech = plm_pin.load(tb.slider_crank(tmp_path))
    (t,) = mech.actuator_positions(mech.q_ref)
    result = run_study(find_study("overview"), tmp_path / "slider_crank.urdf")
    rows = {row[0]: row[2] for row in result.block("transmission").rows}
    assert rows["d slider_joint / d crank_joint"] == pytest.approx(tb.slider_crank_ratio(t), rel=1e-9)
    (pose,) = [
        b for s in result.sections for b in s.blocks if b.kind == "table" and "output joints" in b.title
    ]
    assert pose.rows == ((("slider_joint", pytest.approx(tb.slider_crank_position(t), abs=1e-10), "m")),)
    assert "degree" not in pose.note
