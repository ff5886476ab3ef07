"""MJCF export: every preset round-trips; MuJoCo follows plm_pin's simulation to its soft-constraint error."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.description.mjcf import StateMap
from plm_pin.dynamics.simulation import simulate
from plm_pin.exceptions import InvalidInput
from plm_pin.export import REVOLUTE_PAIR_SPACING, mjcf_text
from plm_pin.models.registry import PRESETS
from plm_pin.warnings import SimulationUnstableWarning
from tests.conftest import INTEROP, ball_joint_body, preset

mujoco = pytest.importorskip("mujoco")


def _tangent_map(a, b, mj, q_a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``b``'s configuration matching ``q_a`` of ``a`` through the exported qpos, and T with v_a = T v_b."""
    to_a, to_b = StateMap(a.model, mj), StateMap(b.model, mj)
    q_b = to_b.q(to_a.qpos(q_a))
    return q_b, np.linalg.solve(to_a.velocity_matrix(q_a), to_b.velocity_matrix(q_b))


def _mujoco_equality_jacobian(a, mj, q_a: np.ndarray) -> np.ndarray:
    """MuJoCo's Jacobian of its equality constraints at ``q_a``, on ``a``'s tangent space (rows, a.nv)."""
    to_a = StateMap(a.model, mj)
    mj.opt.jacobian = int(mujoco.mjtJacobian.mjJAC_DENSE)
    data = mujoco.MjData(mj)
    data.qpos[:] = to_a.qpos(q_a)
    mujoco.mj_forward(mj, data)
    rows = np.asarray(data.efc_type) == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    J = np.asarray(data.efc_J).reshape(data.nefc, mj.nv)[rows]
    return J @ to_a.velocity_matrix(q_a)


def _mujoco_mass_matrix(a, mj, q_a: np.ndarray) -> np.ndarray:
    """MuJoCo's mass matrix at ``q_a`` on ``a``'s tangent space: G^T M_mj G with qvel = G v."""
    to_a = StateMap(a.model, mj)
    data = mujoco.MjData(mj)
    data.qpos[:] = to_a.qpos(q_a)
    mujoco.mj_forward(mj, data)
    M = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, data, M)
    G = to_a.velocity_matrix(q_a)
    return G.T @ M @ G


def _rank(J: np.ndarray) -> int:
    """Rank by SVD: singular values above 1e-9 of the largest (exact models: a gap of many decades)."""
    s = np.linalg.svd(J, compute_uv=False)
    return int(np.sum(s > 1e-9 * max(s[0], 1.0))) if s.size else 0


def _limits(mech) -> dict[str, tuple[float, float]]:
    """Finite position limits of the one-coordinate joints, by joint name."""
    out = {}
    for j in range(1, mech.model.njoints):
        joint = mech.model.joints[j]
        lo, hi = mech.model.lowerPositionLimit[joint.idx_q], mech.model.upperPositionLimit[joint.idx_q]
        if joint.nq == 1 and max(abs(lo), abs(hi)) < np.finfo(float).max:
            out[str(mech.model.names[j])] = (float(lo), float(hi))
    return out


def _round_trip(a, path: Path, configurations: list[np.ndarray]):
    """Export ``a`` and load it back: mobility, redundancy, closure rows, visuals, limits, M, J_phi, phi.

    MuJoCo's compiled model is the independent check: its mass matrix is ``a``'s, and the rank of
    its equality Jacobian is the rank of ``a``'s closures (idle gauges, plm_pin's own, left out).
    """
    error = plm_pin.export_mjcf(a, path)
    b = plm_pin.load(path)
    mj = mujoco.MjModel.from_xml_path(str(path))
    assert (b.mobility, b.redundancy, b.n_closure_rows) == (a.mobility, a.redundancy, a.n_closure_rows)
    assert (b.idle_mobility, b.joint_names) == (a.idle_mobility, a.joint_names)
    assert b.visual_model.ngeoms == a.visual_model.ngeoms
    assert b.collision_model.ngeoms == a.collision_model.ngeoms
    own = a.collision_model is not a.visual_model  # collision shapes of its own, written beside the visuals
    assert mj.ngeom == a.visual_model.ngeoms + own * a.collision_model.ngeoms
    assert _limits(b) == _limits(a)
    gauges = {g.closure.name for g in a.idle_gauges}
    own_rows = np.concatenate(
        [np.arange(a.n_closure_rows)[c.rows] for c in a.closures if c.name not in gauges]
        or [np.zeros(0, int)]
    )
    for q_a in configurations:
        q_b, T = _tangent_map(a, b, mj, q_a)
        M_a = pin.crba(a.model, a.data, q_a)
        np.testing.assert_allclose(T.T @ M_a @ T, pin.crba(b.model, b.data, q_b), atol=1e-12)
        np.testing.assert_allclose(_mujoco_mass_matrix(a, mj, q_a), M_a, atol=1e-12)
        np.testing.assert_allclose(a.closure_jacobian(q_a) @ T, b.closure_jacobian(q_b), atol=1e-12)
        np.testing.assert_allclose(a.closure_residual(q_a), b.closure_residual(q_b), atol=1e-12)
        assert _rank(_mujoco_equality_jacobian(a, mj, q_a)) == _rank(a.closure_jacobian(q_a)[own_rows])
    return b, mj, error


def _random_configurations(a, n: int, seed: int) -> list[np.ndarray]:
    """``n`` configurations around the reference (loops open), joints turned by up to about 0.3 rad."""
    rng = np.random.default_rng(seed)
    return [pin.integrate(a.model, a.q_ref, rng.normal(scale=0.3, size=a.nv)) for _ in range(n)]


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_every_preset_round_trips(tmp_path: Path, name: str) -> None:
    """Export then import keeps mobility, redundancy, mass matrix, closure rows, actuation and task."""
    a = preset(name)
    step = np.random.default_rng(5).normal(scale=0.05, size=a.nv)
    moved = a.assemble(pin.integrate(a.model, a.q_ref, step)).q
    b, mj, error = _round_trip(
        a, tmp_path / f"{name}.xml", [a.q_ref, moved, *_random_configurations(a, 2, 7)]
    )
    assert error.diverged_at is None
    assert (b.name, b.task) == (a.name, a.task)
    assert b.sidecar.actuation == a.sidecar.actuation  # limits, lead, rotor and screw inertia
    assert [c.spec.type for c in b.closures] == [c.spec.type for c in a.closures]
    np.testing.assert_allclose(b.model.gravity.linear, a.model.gravity.linear, atol=0)
    # armature: the reflected rotor and screw inertia (J_r + J_s)(2 pi / lead)^2 of each drive (Zhao 2011)
    for spec in a.sidecar.actuation:
        expected = (
            (spec.rotor_inertia + spec.screw_inertia) * (2 * np.pi / spec.lead) ** 2 if spec.lead else 0.0
        )
        assert mj.dof_armature[mj.joint(spec.joint).dofadr[0]] == pytest.approx(expected, rel=1e-15, abs=0)
    # the re-imported reference is the exported one (keyframe), assembled
    q_b, _ = _tangent_map(a, b, mj, a.q_ref)
    assert np.abs(pin.difference(b.model, b.q_ref, q_b)).max() < 1e-12


ROBOTS_WRITTEN_ELSEWHERE = (
    "5bar_linkage",
    "5bar_linkage_iso3d",
    "5bar_linkage_iso6d",
    "cassie_like",
    "digit_like",
    "disney_like",
    "robot_delta",
    "talos_like",
    "wl16_like",
)
"""Every robot of the example-parallel-robots corpus that loads (kangaroo_like does not assemble)."""


@pytest.mark.filterwarnings("ignore::plm_pin.warnings.PlmWarning")  # missing meshes, a diverging run
@pytest.mark.parametrize("name", ROBOTS_WRITTEN_ELSEWHERE)
def test_example_parallel_robots_round_trip(tmp_path: Path, name: str) -> None:
    """Robots of example-parallel-robots (STL meshes, welds, free-floating bases) export and load back."""
    a = plm_pin.load(INTEROP / name)
    # the re-import holds the same idle joints
    _round_trip(a, tmp_path / f"{name}.xml", [a.q_ref, *_random_configurations(a, 2, 11)])
    assert "idle" not in (tmp_path / f"{name}.xml").read_text()  # gauges are plm_pin's, not MuJoCo's


def test_comment_solver_settings_and_timestep(tmp_path: Path) -> None:
    """The XML states its measured closure error; solref is twice the timestep; RK4, no contacts."""
    text, error = mjcf_text(preset("fourbar"), timestep=5e-4)
    assert f"{error.position:.2g} m" in text
    assert re.search(r"closure error measured by MuJoCo over 1 s passive under gravity", text)
    assert 'solref="0.001 1.0"' in text
    assert 'integrator="RK4"' in text and 'contact="disable"' in text
    assert 0.0 < error.position < 1e-5
    assert error.to_dict() == {
        "position": error.position,
        "rotation": error.rotation,
        "duration": 1.0,
        "timestep": 5e-4,
        "diverged_at": None,
    }
    with pytest.raises(InvalidInput, match="unknown integrator 'euler'; valid are"):
        mjcf_text(preset("fourbar"), integrator="euler")
    with pytest.raises(InvalidInput, match=r"must end in \.xml"):
        plm_pin.export_mjcf(preset("fourbar"), tmp_path / "fourbar.urdf")


def test_revolute_closure_exports_as_a_connect_pair(tmp_path: Path) -> None:
    """A revolute closure becomes two connects along its axis: the same mobility and closure rank, 6 rows."""
    a = ball_joint_body(tmp_path, {"type": "revolute", "axis": [0.0, 0.0, 1.0]})
    path = tmp_path / "out" / "ball.xml"
    plm_pin.export_mjcf(a, path)
    text = path.read_text()
    assert text.count("<connect ") == 2
    mj = mujoco.MjModel.from_xml_path(str(path))
    for end, frame in (("a", "anchor"), ("b", "body_tip")):
        spacing = np.linalg.norm(mj.site(f"c_axis_{end}").pos - mj.site(frame).pos)
        assert spacing == pytest.approx(REVOLUTE_PAIR_SPACING, abs=1e-15)
    b = plm_pin.load(path)
    assert (b.mobility, b.n_closure_rows, a.mobility) == (1, 6, 1)
    q_b, _ = _tangent_map(a, b, mj, a.q_ref)
    assert b.closure_rank(q_b) == a.closure_rank(a.q_ref) == a.nv - a.mobility


SIMULATED = ("fourbar", "harada2011_3d4m", "zhao2011_8pss")


def _deviation(mech, timestep: float, run) -> tuple[float, float]:
    """Largest joint-space gap between MuJoCo's run of the export and plm_pin's; MuJoCo's closure error."""
    text, _ = mjcf_text(mech, timestep=timestep)
    mj = mujoco.MjModel.from_xml_string(text)
    data = mujoco.MjData(mj)
    mujoco.mj_resetDataKeyframe(mj, data, 0)
    state = StateMap(mech.model, mj)
    per = round((run.t[1] - run.t[0]) / timestep)
    deviation = gap = 0.0
    for q in run.q[1:]:
        mujoco.mj_step(mj, data, per)
        q_mj = state.q(data.qpos)
        deviation = max(deviation, float(np.abs(pin.difference(mech.model, q, q_mj)).max()))
        gap = max(gap, float(np.abs(mech.closure_residual(q_mj)).max()))
    return deviation, gap


@pytest.mark.parametrize("name", SIMULATED)
def test_mujoco_follows_plm_pin_to_the_soft_constraint_error(name: str) -> None:
    """0.5 s passive from the reference at rest: MuJoCo's run converges to plm_pin's as its closures stiffen.

    The equalities' time constant is twice the step, so halving the step stiffens them; a deviation due
    to the soft closures then falls faster than first order (measured: by 3.2 to 4.1, the closure error
    with it), while a modelling difference (mass, frames, gravity) would not fall at all.
    """
    mech = preset(name)
    run = simulate(mech, mech.q_ref, duration=0.5, dt=0.01)
    coarse, gap_coarse = _deviation(mech, 1e-3, run)
    fine, gap_fine = _deviation(mech, 5e-4, run)
    assert fine < coarse / 2.5
    assert gap_fine < gap_coarse / 2.5
    # the run starts as the export's measuring run: its closure error stays under the XML comment's
    _, measured = mjcf_text(mech)
    assert gap_coarse <= measured.position + 1e-15


def test_cli_exports_a_preset(tmp_path: Path) -> None:
    """``plm-pin export NAME --mjcf out.xml`` writes the model and its sidecar, which load back."""
    from typer.testing import CliRunner

    from plm_pin.cli import app

    out = tmp_path / "fivebar.xml"
    result = CliRunner().invoke(app, ["export", "fivebar", "--mjcf", str(out)])
    assert result.exit_code == 0, result.output
    assert f"wrote {out}: closure error measured by MuJoCo" in result.output
    assert (tmp_path / "fivebar.plm.yaml").is_file()
    assert plm_pin.load(out).mobility == 2
    result = CliRunner().invoke(app, ["export", "fivebar"])
    assert result.exit_code == 1 and "give a format to export to: --mjcf OUT.xml" in result.output


def test_divergence_is_reported(tmp_path: Path) -> None:
    """A step too long for the stiff closures: the comment and a warning say MuJoCo's run diverges."""
    with pytest.warns(SimulationUnstableWarning, match=r"DIVERGES at t = .* with 100 ms steps"):
        error = plm_pin.export_mjcf(preset("fourbar"), tmp_path / "fourbar.xml", timestep=0.1)
    assert error.diverged_at is not None and 0.0 < error.diverged_at < error.duration
    assert "DIVERGES" in (tmp_path / "fourbar.xml").read_text()


def test_mesh_read_from_mjcf_exports_inline(tmp_path: Path) -> None:
    """A mesh geom of an MJCF is written back as an inline mesh whose vertices land where MuJoCo put them."""
    from tests.description.test_mjcf import FOURBAR_MJCF, FOURBAR_SIDECAR

    tetra = '<asset><mesh name="tetra" vertex="0 0 0  0.05 0 0  0 0.03 0  0 0 0.02"/></asset>'
    text = FOURBAR_MJCF.replace("<worldbody>", tetra + "<worldbody>").replace(
        '<site name="coupler_tip"',
        '<geom type="mesh" mesh="tetra" pos="0.1 0 0" euler="10 20 30"/><site name="coupler_tip"',
    )
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "fb.xml").write_text(text)
    (tmp_path / "in" / "fb.plm.yaml").write_text(FOURBAR_SIDECAR)
    a = plm_pin.load(tmp_path / "in" / "fb.xml")
    b, _, _ = _round_trip(a, tmp_path / "out" / "fb.xml", [a.q_ref])

    def world_vertices(mech) -> np.ndarray:
        obj = mech.visual_model.geometryObjects[0]
        pin.forwardKinematics(mech.model, mech.data, mech.q_ref)
        oMg = mech.data.oMi[obj.parentJoint] * obj.placement
        points = np.asarray(obj.geometry.vertices()) @ oMg.rotation.T + oMg.translation
        return points[np.lexsort(points.T)]

    # MuJoCo stores mesh vertices in single precision: 2^-24 relative on coordinates below 0.25 m
    np.testing.assert_allclose(world_vertices(b), world_vertices(a), atol=0.25 * 2.0**-24)


def test_mjcf_with_anchors_off_body_origins_round_trips(tmp_path: Path) -> None:
    """An MJCF with unnamed joints, a hinge 2 cm from its body origin and a range exports and loads back.

    The re-import keeps every frame where it was (bodies where the MJCF put them, sites by name)
    and the hinge's range, beside the checks of :func:`_round_trip`.
    """
    from tests.description.test_mjcf import FLOATING_MJCF

    (tmp_path / "floating.xml").write_text(FLOATING_MJCF)
    a = plm_pin.load(tmp_path / "floating.xml")
    b, mj, _ = _round_trip(a, tmp_path / "out" / "floating.xml", [a.q_ref, *_random_configurations(a, 3, 2)])
    assert b.frame_names == a.frame_names
    q_b, _ = _tangent_map(a, b, mj, a.q_ref)
    da, db = a.model.createData(), b.model.createData()
    pin.framesForwardKinematics(a.model, da, a.q_ref)
    pin.framesForwardKinematics(b.model, db, q_b)
    for name in a.frame_names:
        fa, fb = a.model.getFrameId(name), b.model.getFrameId(name)
        np.testing.assert_allclose(db.oMf[fb].homogeneous, da.oMf[fa].homogeneous, atol=1e-12)
    assert 'range="-1.0 1.5"' in (tmp_path / "out" / "floating.xml").read_text()
