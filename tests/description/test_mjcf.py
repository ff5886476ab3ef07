"""MJCF import: hand-written MuJoCo models against the same mechanisms in URDF, and against MuJoCo."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.core.mechanism import Mechanism
from plm_pin.description.mjcf import StateMap, read_mjcf
from plm_pin.exceptions import DescriptionError, FrameNotFound
from plm_pin.warnings import IgnoredElementWarning

mujoco = pytest.importorskip("mujoco")

INERTIA = {  # per link: mass [kg], com [m], full inertia about the com (ixx iyy izz ixy ixz iyz) [kg m^2]
    "crank": (0.2, (0.05, 0.0, 0.0), (2.5e-6, 1.7e-4, 1.7e-4, 1e-6, 0.0, 0.0)),
    "coupler": (0.5, (0.125, 0.01, 0.0), (6e-6, 2.6e-3, 2.6e-3, 0.0, 2e-6, 0.0)),
    "rocker": (0.4, (0.1, 0.0, 0.0), (2e-5, 1.3e-3, 1.31e-3, 0.0, 0.0, 1e-6)),
}


def _mj_inertial(link: str) -> str:
    m, c, i = INERTIA[link]
    return f'<inertial pos="{c[0]} {c[1]} {c[2]}" mass="{m}" fullinertia="{" ".join(map(str, i))}"/>'


def _crank_coupler(crank_joint: str, coupler_joint: str, tip: str) -> str:
    """MJCF bodies of a crank (0.1 m) on the world carrying a coupler that holds ``tip``."""
    return f"""<body name="crank">
      <joint name="{crank_joint}" type="hinge" axis="0 0 1"/>
      {_mj_inertial("crank")}
      <body name="coupler" pos="0.1 0 0">
        <joint name="{coupler_joint}" type="hinge" axis="0 0 1"/>
        {_mj_inertial("coupler")}
        {tip}
      </body>
    </body>"""


PLATE = """<body name="plate" pos="0.25 0 0" quat="0.9238795325112867 0 0 0.3826834323650898">
          <inertial pos="0.02 0 0" mass="0.3" diaginertia="1e-4 2e-4 3e-4"/>
        </body>"""


def _urdf_link(link: str) -> str:
    m, c, i = INERTIA[link]
    return (
        f'<link name="{link}"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}"/><mass value="{m}"/>'
        f'<inertia ixx="{i[0]}" iyy="{i[1]}" izz="{i[2]}" ixy="{i[3]}" ixz="{i[4]}" iyz="{i[5]}"/>'
        "</inertial></link>"
    )


def _urdf_joint(
    name: str, parent: str, child: str, xyz: str = "0 0 0", rpy: str = "0 0 0", kind: str = "revolute"
) -> str:
    limit = '<limit effort="10" velocity="10" lower="-10" upper="10"/>' if kind == "revolute" else ""
    axis = '<axis xyz="0 0 1"/>' if kind == "revolute" else ""
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/>{axis}{limit}</joint>'
    )


# the four-bar: MuJoCo's default degrees, a rotated rocker base (euler), a joint ref, site connect
FOURBAR_MJCF = f"""<mujoco model="fourbar_hand">
  <option gravity="0 -9.81 0"/>
  <worldbody>
    {_crank_coupler("crank_pivot", "coupler_pivot", '<site name="coupler_tip" pos="0.25 0 0"/>')}
    <body name="rocker" pos="0.3 0 0" euler="0 0 90">
      <joint name="rocker_pivot" type="hinge" axis="0 0 1" ref="30"/>
      {_mj_inertial("rocker")}
      <site name="rocker_tip" pos="0.2 0 0"/>
    </body>
  </worldbody>
  <equality><connect name="loop" site1="coupler_tip" site2="rocker_tip"/></equality>
  <actuator><motor name="drive" joint="crank_pivot" gear="2" ctrlrange="-1 1"/></actuator>
</mujoco>
"""

FOURBAR_URDF = f"""<robot name="fourbar_hand">
  <link name="base"/>{_urdf_link("crank")}{_urdf_link("coupler")}{_urdf_link("rocker")}
  <link name="coupler_tip"/><link name="rocker_tip"/>
  {_urdf_joint("crank_pivot", "base", "crank")}
  {_urdf_joint("coupler_pivot", "crank", "coupler", "0.1 0 0")}
  {_urdf_joint("rocker_pivot", "base", "rocker", "0.3 0 0", f"0 0 {math.pi / 2}")}
  {_urdf_joint("coupler_tip_fixed", "coupler", "coupler_tip", "0.25 0 0", kind="fixed")}
  {_urdf_joint("rocker_tip_fixed", "rocker", "rocker_tip", "0.2 0 0", kind="fixed")}
</robot>
"""

GUESS = {"crank_pivot": 1.05, "coupler_pivot": -0.58, "rocker_pivot": 1.70 - math.pi / 2}

FOURBAR_SIDECAR = f"format: plm-pin/1\nend_effector: {{frame: rocker_tip, task: [rz]}}\nreference: {GUESS}\n"

URDF_SIDECAR_FOURBAR = (
    "format: plm-pin/1\ngravity: [0, -9.81, 0]\n"
    "closures: [{name: loop, frames: [coupler_tip, rocker_tip], type: point}]\n"
    "actuation: [{joint: crank_pivot, limits: [-2, 2]}]\n" + FOURBAR_SIDECAR.split("\n", 1)[1]
)

# a planar five-bar whose last revolute is a hinge on the right leg, closed by a body weld
FIVEBAR_MJCF = f"""<mujoco model="fivebar_weld">
  <compiler angle="radian"/>
  <option gravity="0 -9.81 0"/>
  <worldbody>
    {_crank_coupler("motor_l", "elbow_l", PLATE)}
    <body name="rocker" pos="0.15 0 0">
      <joint name="motor_r" type="hinge" axis="0 0 1"/>
      {_mj_inertial("rocker")}
      <body name="tip" pos="0.2 0 0">
        <joint name="elbow_r" type="hinge" axis="0 0 1"/>
        <inertial pos="0.1 0 0" mass="0.25" diaginertia="1e-5 8e-4 8e-4"/>
        <body name="hand" pos="0.2 0 0">
          <joint name="wrist_r" type="hinge" axis="0 0 1"/>
          <inertial pos="0 0 0" mass="0.01" diaginertia="1e-6 1e-6 1e-6"/>
        </body>
      </body>
    </body>
  </worldbody>
  <equality><weld name="weld" body1="plate" body2="hand" relpose="0 0 0 1 0 0 0" anchor="0 0 0"/></equality>
  <actuator>
    <motor joint="motor_l" forcerange="-3 3"/>
    <position joint="motor_r" kp="10" forcerange="-4 5"/>
  </actuator>
</mujoco>
"""

FIVEBAR_URDF = f"""<robot name="fivebar_weld">
  <link name="base"/>{_urdf_link("crank")}{_urdf_link("coupler")}{_urdf_link("rocker")}
  <link name="plate"><inertial><origin xyz="0.02 0 0"/><mass value="0.3"/>
    <inertia ixx="1e-4" iyy="2e-4" izz="3e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"><inertial><origin xyz="0.1 0 0"/><mass value="0.25"/>
    <inertia ixx="1e-5" iyy="8e-4" izz="8e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="hand"><inertial><origin xyz="0 0 0"/><mass value="0.01"/>
    <inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial></link>
  {_urdf_joint("motor_l", "base", "crank")}
  {_urdf_joint("elbow_l", "crank", "coupler", "0.1 0 0")}
  {_urdf_joint("plate_fixed", "coupler", "plate", "0.25 0 0", f"0 0 {math.pi / 4}", kind="fixed")}
  {_urdf_joint("motor_r", "base", "rocker", "0.15 0 0")}
  {_urdf_joint("elbow_r", "rocker", "tip", "0.2 0 0")}
  {_urdf_joint("wrist_r", "tip", "hand", "0.2 0 0")}
</robot>
"""


def _fivebar_guess() -> dict[str, float]:
    """Elbow-up configuration putting both leg tips at (0.075, 0.3) (two-link inverse kinematics)."""

    def two_link(base_x: float, l1: float, l2: float, sign: float) -> tuple[float, float]:
        dx, dy = 0.075 - base_x, 0.3
        c2 = (dx * dx + dy * dy - l1 * l1 - l2 * l2) / (2 * l1 * l2)
        q2 = sign * math.acos(c2)
        q1 = math.atan2(dy, dx) - math.atan2(l2 * math.sin(q2), l1 + l2 * math.cos(q2))
        return q1, q2

    ml, el = two_link(0.0, 0.1, 0.25, -1.0)
    mr, er = two_link(0.15, 0.2, 0.2, 1.0)
    return {
        "motor_l": ml,
        "elbow_l": el,
        "motor_r": mr,
        "elbow_r": er,
        "wrist_r": ml + el + math.pi / 4 - mr - er,
    }


FIVEBAR_SIDECAR = (
    f"format: plm-pin/1\nend_effector: {{frame: plate, task: [x, y]}}\nreference: {_fivebar_guess()}\n"
)

URDF_SIDECAR_FIVEBAR = (
    "format: plm-pin/1\ngravity: [0, -9.81, 0]\n"
    "closures: [{name: weld, frames: [plate, hand], type: weld}]\n"
    "actuation: [{joint: motor_l, limits: [-3, 3]}, {joint: motor_r, limits: [-4, 5]}]\n"
    + FIVEBAR_SIDECAR.split("\n", 1)[1]
)


def _write(folder: Path, stem: str, files: dict[str, str]) -> Path:
    for suffix, text in files.items():
        (folder / f"{stem}{suffix}").write_text(text)
    return folder / f"{stem}{next(iter(files))}"


def _pair(tmp_path: Path, stem: str, mjcf: str, side: str, urdf: str, urdf_side: str) -> tuple:
    (tmp_path / "mj").mkdir()
    (tmp_path / "ur").mkdir()
    mj = plm_pin.load(_write(tmp_path / "mj", stem, {".xml": mjcf, ".plm.yaml": side}))
    ur = plm_pin.load(_write(tmp_path / "ur", stem, {".urdf": urdf, ".plm.yaml": urdf_side}))
    return mj, ur


@pytest.mark.parametrize(
    ("stem", "mjcf", "side", "urdf", "urdf_side"),
    [
        ("fourbar_hand", FOURBAR_MJCF, FOURBAR_SIDECAR, FOURBAR_URDF, URDF_SIDECAR_FOURBAR),
        ("fivebar_weld", FIVEBAR_MJCF, FIVEBAR_SIDECAR, FIVEBAR_URDF, URDF_SIDECAR_FIVEBAR),
    ],
)
def test_hand_written_mjcf_agrees_with_urdf(tmp_path: Path, stem, mjcf, side, urdf, urdf_side) -> None:
    """A hand-written MJCF and the same mechanism in URDF + sidecar agree to 1e-12 at several states."""
    mj, ur = _pair(tmp_path, stem, mjcf, side, urdf, urdf_side)
    assert mj.joint_names == ur.joint_names
    assert (mj.mobility, mj.redundancy, mj.n_closure_rows) == (ur.mobility, ur.redundancy, ur.n_closure_rows)
    assert [c.spec.type for c in mj.closures] == [c.spec.type for c in ur.closures]
    assert [(a.joint, a.limits) for a in mj.actuators] == [(a.joint, a.limits) for a in ur.actuators]
    assert mj.task == ur.task
    np.testing.assert_allclose(mj.model.gravity.linear, ur.model.gravity.linear, atol=0)
    rng = np.random.default_rng(7)
    states = [(ur.q_ref, np.zeros(ur.nv))] + [
        (rng.uniform(-3, 3, ur.nq), rng.normal(size=ur.nv)) for _ in range(4)
    ]
    for q, v in states:
        np.testing.assert_allclose(pin.crba(mj.model, mj.data, q), pin.crba(ur.model, ur.data, q), atol=1e-12)
        np.testing.assert_allclose(
            pin.nonLinearEffects(mj.model, mj.data, q, v),
            pin.nonLinearEffects(ur.model, ur.data, q, v),
            atol=1e-12,
        )
        np.testing.assert_allclose(mj.closure_residual(q), ur.closure_residual(q), atol=1e-12)
        np.testing.assert_allclose(mj.closure_jacobian(q), ur.closure_jacobian(q), atol=1e-12)
        pin.framesForwardKinematics(mj.model, mj.data, q)
        pin.framesForwardKinematics(ur.model, ur.data, q)
        task = mj.task.frame
        assert mj.data.oMf[mj.model.getFrameId(task)].isApprox(ur.data.oMf[ur.model.getFrameId(task)], 1e-12)


def test_fourbar_reference_and_units(tmp_path: Path) -> None:
    """Degrees and the joint ref are MuJoCo's: the rocker coordinate is qpos - 30 deg, at a 90 deg base."""
    path = _write(tmp_path, "fourbar_hand", {".xml": FOURBAR_MJCF})
    mjcf = read_mjcf(path)
    state = mjcf.state_map()
    q = np.array([0.3, -0.2, 0.4])
    qpos = state.qpos(q)
    np.testing.assert_allclose(qpos, [0.3, -0.2, 0.4 + math.radians(30)], atol=1e-15)
    data = mujoco.MjData(mjcf.mj_model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(mjcf.mj_model, data)
    rocker = mjcf.mj_model.body("rocker").id
    # the rocker's x axis turns by 90 deg + 0.4 rad from the world x axis
    angle = math.atan2(data.xmat[rocker].reshape(3, 3)[1, 0], data.xmat[rocker].reshape(3, 3)[0, 0])
    assert angle == pytest.approx(math.pi / 2 + 0.4, abs=1e-14)
    assert mjcf.reference_origin == "qpos0"
    assert mjcf.sidecar.reference["rocker_pivot"] == (0.0,)  # qpos0 = ref maps to q = 0


def _frames_match(mjcf, q: np.ndarray) -> None:
    """Body and site frames of the Pinocchio model are MuJoCo's body and site poses."""
    model, m = mjcf.model, mjcf.mj_model
    data = mujoco.MjData(m)
    data.qpos[:] = mjcf.state_map().qpos(q)
    mujoco.mj_kinematics(m, data)
    pdata = model.createData()
    pin.framesForwardKinematics(model, pdata, q)
    for b in range(1, m.nbody):
        oMf = pdata.oMf[model.getFrameId(m.body(b).name)]
        np.testing.assert_allclose(oMf.translation, data.xpos[b], atol=1e-12)
        np.testing.assert_allclose(oMf.rotation, data.xmat[b].reshape(3, 3), atol=1e-12)
    for s in range(m.nsite):
        oMf = pdata.oMf[model.getFrameId(m.site(s).name)]
        np.testing.assert_allclose(oMf.translation, data.site_xpos[s], atol=1e-12)
        np.testing.assert_allclose(oMf.rotation, data.site_xmat[s].reshape(3, 3), atol=1e-12)


# every joint type, several joints in one body about offset anchors, skew axes, quat / euler / axisangle
# orientations, inertia from geoms, a body connect (anchor on body2 from qpos0) and a body weld
SPATIAL_MJCF = """<mujoco model="spatial">
  <compiler angle="radian" inertiafromgeom="auto"/>
  <option gravity="0.5 -1 -9.81"/>
  <worldbody>
    <body name="base" pos="0.1 0.2 0.3" euler="0.1 0.2 0.3">
      <joint name="h1" type="hinge" axis="0.3 -0.5 1" pos="0.01 0.02 0.03" ref="0.2"/>
      <joint name="s1" type="slide" axis="1 1 0" pos="0 0.05 0" ref="0.1"/>
      <geom type="box" size="0.1 0.02 0.03" pos="0.1 0 0" density="500"/>
      <site name="base_site" pos="0.2 0 0" axisangle="1 0 0 0.7"/>
      <body name="arm" pos="0.2 0 0" quat="0.9 0.1 0.3 -0.2">
        <joint name="b1" type="ball" pos="0 0 0.01"/>
        <inertial pos="0.05 0.01 0" mass="0.7" fullinertia="3e-3 4e-3 5e-3 1e-4 -2e-4 3e-4"/>
        <body name="hand" pos="0.15 0 0">
          <joint name="h2" type="hinge" axis="0 1 0"/>
          <joint name="h3" type="hinge" axis="1 0 0" pos="0.02 0 0"/>
          <geom type="capsule" size="0.01 0.05" pos="0.05 0 0" euler="0 1.5707963 0"/>
        </body>
      </body>
    </body>
    <body name="float" pos="0.5 0 0.2" quat="0.8 0 0.6 0">
      <freejoint name="free"/>
      <geom type="sphere" size="0.05" mass="1.3"/>
      <site name="float_site" pos="0 0.05 0"/>
    </body>
  </worldbody>
  <equality>
    <connect name="c" body1="hand" body2="float" anchor="0.1 0 0"/>
    <weld name="w" body1="arm" body2="float" anchor="0.01 0 0" relpose="0.3 0.1 0 0.6 0 0.8 0"/>
  </equality>
  <actuator><motor joint="h1"/><motor joint="s1" gear="-3" ctrlrange="-1 2"/></actuator>
</mujoco>
"""


def test_against_mujoco_mass_matrix_bias_and_frames(tmp_path: Path) -> None:
    """M, bias forces, frames and equality errors equal MuJoCo's (mj_fullM, qfrc_bias, efc_pos)."""
    mjcf = read_mjcf(_write(tmp_path, "spatial", {".xml": SPATIAL_MJCF}))
    model, m = mjcf.model, mjcf.mj_model
    assert [model.joints[j].shortname() for j in range(1, model.njoints)] == [
        "JointModelRevoluteUnaligned",
        "JointModelPrismaticUnaligned",
        "JointModelSpherical",
        "JointModelRY",
        "JointModelRX",
        "JointModelFreeFlyer",
    ]
    assert [(a.joint, a.limits) for a in mjcf.sidecar.actuation] == [("h1", None), ("s1", (-6.0, 3.0))]
    state = mjcf.state_map()
    data = mujoco.MjData(m)
    pdata = model.createData()
    rng = np.random.default_rng(3)
    pin.seed(3)  # pin.randomConfiguration's generator
    mech = Mechanism(model, mjcf.sidecar, name="spatial")
    for _ in range(4):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        v = rng.normal(size=model.nv)
        _frames_match(mjcf, q)
        data.qpos[:] = state.qpos(q)
        data.qvel[:] = state.qvel(q, v)
        mujoco.mj_forward(m, data)
        G = state.velocity_matrix(q)
        M_mj = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, data, M_mj)
        np.testing.assert_allclose(pin.crba(model, pdata, q), G.T @ M_mj @ G, atol=1e-12)
        # qvel = G v, so qacc = G a + dG v; dG v = (R (w x v_lin), 0) on the free joint (hand derivation)
        dGv = np.zeros(m.nv)
        w, v_lin = v[-3:], v[-6:-3]
        dGv[-6:-3] = G[-6:-3, -6:-3] @ np.cross(w, v_lin)
        expected = G.T @ (M_mj @ dGv + data.qfrc_bias)
        np.testing.assert_allclose(pin.nonLinearEffects(model, pdata, q, v), expected, atol=1e-12)
        # MuJoCo's equality error: connect pos1 - pos2, weld position rows the same (efc rows in order)
        phi = mech.closure_residual(q)
        eq_rows = np.array(data.efc_pos[:9])
        np.testing.assert_allclose(phi[:3], -eq_rows[:3], atol=1e-12)
        np.testing.assert_allclose(phi[3:6], -eq_rows[3:6], atol=1e-12)
        # rotation rows: MuJoCo gives the axis times sin(angle / 2), ours the rotation vector
        angle = np.linalg.norm(phi[6:9])
        assert np.linalg.norm(eq_rows[6:9]) == pytest.approx(math.sin(angle / 2), abs=1e-12)


def test_state_map_round_trip(tmp_path: Path) -> None:
    """Qpos <-> q and qvel <-> v are inverse maps (quaternion order, joint ref, free-joint velocity frame)."""
    mjcf = read_mjcf(_write(tmp_path, "spatial", {".xml": SPATIAL_MJCF}))
    state = mjcf.state_map()
    pin.seed(4)
    q = pin.randomConfiguration(mjcf.model, -np.ones(mjcf.model.nq), np.ones(mjcf.model.nq))
    v = np.arange(mjcf.model.nv, dtype=float)
    np.testing.assert_allclose(state.q(state.qpos(q)), q, atol=1e-15)
    np.testing.assert_allclose(state.v(q, state.qvel(q, v)), v, atol=1e-13)
    qpos = state.qpos(q)
    np.testing.assert_allclose(qpos[-4:], [q[-1], q[-4], q[-3], q[-2]], atol=1e-15)  # (w, x, y, z)


REFUSED = {
    "tendon": (
        '<tendon><fixed name="t"><joint joint="crank_pivot" coef="1"/></fixed></tendon>',
        "cannot represent: 1 <tendon> ('t'). To read the loops without them, load with ignore=('tendons',)",
    ),
    "joint equality": (
        '<equality><joint name="couple" joint1="crank_pivot" joint2="coupler_pivot" '
        'polycoef="0 2 0 0 0"/></equality>',
        "cannot represent: 1 <equality><joint> ('couple'). To read the loops without them, load with "
        "ignore=('joint_equalities',) (CLI: --ignore joint_equalities)",
    ),
    "contact pair": (
        '<worldbody><geom name="g" type="sphere" size="0.1"/></worldbody>'
        '<contact><pair name="p" geom1="g" geom2="g2"/></contact>',
        "cannot represent: 1 <contact><pair> ('p'). To read the loops without them, load with "
        "ignore=('contacts',) (CLI: --ignore contacts)",
    ),
    "site actuator": (
        '<actuator><general name="push" site="coupler_tip" gear="1 0 0 0 0 0"/></actuator>',
        "cannot represent: 1 <actuator> not on one hinge or slide ('push')",
    ),
    "inactive equality": (
        '<equality><connect name="off" site1="coupler_tip" site2="rocker_tip" active="false"/></equality>',
        """1 <equality active="false"> (plm_pin closures always hold) ('off')""",
    ),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_unrepresentable_elements_refused(tmp_path: Path, case: str) -> None:
    """Tendons, joint couplings, contact pairs, site actuators, inactive equalities: one error naming them."""
    extra, message = REFUSED[case]
    text = FOURBAR_MJCF.replace("</mujoco>", extra + "</mujoco>")
    if case == "contact pair":
        text = text.replace(
            '<site name="rocker_tip"', '<geom name="g2" type="sphere" size="0.01"/><site name="rocker_tip"'
        )
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(_write(tmp_path, "bad", {".xml": text}))
    assert message in str(info.value)


def test_sidecar_beside_mjcf_checked(tmp_path: Path) -> None:
    """A sidecar beside an MJCF may not redefine closures, and its task frame must exist."""
    _write(tmp_path, "fb", {".xml": FOURBAR_MJCF, ".plm.yaml": FOURBAR_SIDECAR + "closures: []\n"})
    with pytest.raises(DescriptionError, match=r"key\(s\) \['closures'\] not allowed beside an MJCF"):
        plm_pin.load(tmp_path / "fb.xml")
    _write(
        tmp_path,
        "fb",
        {".xml": FOURBAR_MJCF, ".plm.yaml": "format: plm-pin/1\nend_effector: {frame: nope, task: [x]}\n"},
    )
    with pytest.raises(FrameNotFound, match="frame 'nope' not found"):
        plm_pin.load(tmp_path / "fb.xml")


def test_unassembled_reference_names_its_origin(tmp_path: Path) -> None:
    """Without a sidecar reference the loops are assembled from qpos0, and the error says so."""
    with pytest.raises(plm_pin.ClosureNotSatisfied, match=r"reference guess \(qpos0\)"):
        text = FOURBAR_MJCF.replace(
            '<site name="rocker_tip" pos="0.2 0 0"/>', '<site name="rocker_tip" pos="2 0 0"/>'
        )
        plm_pin.load(_write(tmp_path, "fb", {".xml": text}))


def test_damping_warned_and_malformed_refused(tmp_path: Path) -> None:
    """Joint damping is ignored with a warning; MuJoCo's compile error is wrapped."""
    text = FOURBAR_MJCF.replace('<joint name="crank_pivot"', '<joint name="crank_pivot" damping="0.1"')
    with pytest.warns(IgnoredElementWarning, match="joint damping is not modelled"):
        _write(tmp_path, "fb", {".xml": text, ".plm.yaml": FOURBAR_SIDECAR})
        plm_pin.load(tmp_path / "fb.xml")
    with pytest.raises(DescriptionError, match="MuJoCo cannot compile this MJCF"):
        plm_pin.load(_write(tmp_path, "broken", {".xml": "<mujoco><worldbody><body></mujoco>"}))


def test_cli_checks_an_mjcf(tmp_path: Path) -> None:
    """``plm-pin check robot.xml`` reads the MJCF and its sidecar."""
    from typer.testing import CliRunner

    from plm_pin.cli import app

    path = _write(tmp_path, "fourbar_hand", {".xml": FOURBAR_MJCF, ".plm.yaml": FOURBAR_SIDECAR})
    result = CliRunner().invoke(app, ["check", str(path)])
    assert result.exit_code == 0, result.output
    assert "ok: fourbar_hand: 1 closures, 1 actuators, mobility 1, redundancy 0" in result.output


def test_visual_geoms_follow_mujoco(tmp_path: Path) -> None:
    """Box, capsule and sphere geoms become visual objects placed where MuJoCo puts the geoms."""
    mjcf = read_mjcf(_write(tmp_path, "spatial", {".xml": SPATIAL_MJCF}))
    visuals = mjcf.visual_model()
    m = mjcf.mj_model
    assert visuals.ngeoms == m.ngeom == 3
    pin.seed(5)
    q = pin.randomConfiguration(mjcf.model, -np.ones(mjcf.model.nq), np.ones(mjcf.model.nq))
    data = mujoco.MjData(m)
    data.qpos[:] = mjcf.state_map().qpos(q)
    mujoco.mj_kinematics(m, data)
    pdata, gdata = mjcf.model.createData(), pin.GeometryData(visuals)
    pin.updateGeometryPlacements(mjcf.model, pdata, visuals, gdata, q)
    for g in range(m.ngeom):
        np.testing.assert_allclose(gdata.oMg[g].translation, data.geom_xpos[g], atol=1e-12)
        np.testing.assert_allclose(gdata.oMg[g].rotation, data.geom_xmat[g].reshape(3, 3), atol=1e-12)
    box = visuals.geometryObjects[0].geometry
    np.testing.assert_allclose(box.halfSide, [0.1, 0.02, 0.03])


def test_names_shared_by_a_joint_and_a_body(tmp_path: Path) -> None:
    """A joint named as its body loads (the name is the body's frame); a site named as a body is refused."""
    text = FOURBAR_MJCF.replace('joint name="crank_pivot"', 'joint name="crank"').replace(
        'joint="crank_pivot"', 'joint="crank"'
    )
    mech = plm_pin.load(
        _write(tmp_path, "fb", {".xml": text, ".plm.yaml": FOURBAR_SIDECAR.replace("crank_pivot", "crank")})
    )
    assert mech.model.frames[mech.model.getFrameId("crank")].type == pin.FrameType.BODY
    assert mech.actuators[0].joint == "crank"
    text = FOURBAR_MJCF.replace('<site name="coupler_tip"', '<site name="rocker"').replace(
        'site1="coupler_tip"', 'site1="rocker"'
    )
    with pytest.raises(
        DescriptionError, match="the site and the body named 'rocker' would give two Pinocchio frames"
    ):
        plm_pin.load(_write(tmp_path, "bad", {".xml": text}))


def test_benchmark_fourbar_mjcf_is_the_preset(tmp_path: Path) -> None:
    """The benchmarks' MuJoCo four-bar (two bodies on the world) loads whole and is the fourbar preset."""
    from benchmarks.harness import fourbar_mjcf
    from tests.conftest import preset

    ref = preset("fourbar")
    side = f"format: plm-pin/1\nreference: {dict(zip(ref.joint_names, ref.q_ref.tolist(), strict=True))}\n"
    mech = plm_pin.load(_write(tmp_path, "fourbar", {".xml": fourbar_mjcf(), ".plm.yaml": side}))
    assert mech.joint_names == ref.joint_names
    assert (mech.mobility, mech.n_closure_rows) == (ref.mobility, ref.n_closure_rows)
    np.testing.assert_allclose(mech.q_ref, ref.q_ref, atol=1e-12)
    q = ref.q_ref
    np.testing.assert_allclose(
        pin.crba(mech.model, mech.data, q), pin.crba(ref.model, ref.data, q), atol=1e-12
    )
    np.testing.assert_allclose(mech.closure_jacobian(q), ref.closure_jacobian(q), atol=1e-12)


def test_enum_values_are_mujocos() -> None:
    """The joint, equality, transmission, object and geom codes the reader uses are MuJoCo's."""
    from plm_pin.description import mjcf

    for name in ("FREE", "BALL", "SLIDE", "HINGE"):
        assert getattr(mjcf, f"_{name}") == int(getattr(mujoco.mjtJoint, f"mjJNT_{name}"))
    assert (mjcf._EQ_CONNECT, mjcf._EQ_WELD) == (int(mujoco.mjtEq.mjEQ_CONNECT), int(mujoco.mjtEq.mjEQ_WELD))
    assert (mjcf._EQ_JOINT, mjcf._EQ_TENDON) == (int(mujoco.mjtEq.mjEQ_JOINT), int(mujoco.mjtEq.mjEQ_TENDON))
    assert mjcf._TRN_TENDON == int(mujoco.mjtTrn.mjTRN_TENDON)
    for code, name in mjcf._EQ_NAMES.items():
        assert int(getattr(mujoco.mjtEq, f"mjEQ_{name.upper()}")) == code
    assert mjcf._TRN_JOINT == int(mujoco.mjtTrn.mjTRN_JOINT) and mjcf._OBJ_SITE == int(
        mujoco.mjtObj.mjOBJ_SITE
    )
    for name in ("PLANE", "HFIELD", "SPHERE", "CAPSULE", "ELLIPSOID", "CYLINDER", "BOX", "MESH"):
        assert getattr(mjcf, f"_GEOM_{name}") == int(getattr(mujoco.mjtGeom, f"mjGEOM_{name}"))


def test_sidecar_path_loads_its_mjcf(tmp_path: Path) -> None:
    """Giving the ``.plm.yaml`` of an MJCF (no URDF beside it) loads the MJCF."""
    _write(tmp_path, "fourbar_hand", {".xml": FOURBAR_MJCF, ".plm.yaml": FOURBAR_SIDECAR})
    mech = plm_pin.load(tmp_path / "fourbar_hand.plm.yaml")
    assert (mech.name, mech.task.frame, mech.source) == (
        "fourbar_hand",
        "rocker_tip",
        "MJCF fourbar_hand.xml",
    )


# a floating four-bar as public collections write one: unnamed <freejoint/> and hinges, a rocker
# whose hinge sits 2 cm from its body origin, a limited hinge; a parallelogram closed at qpos0
FLOATING_MJCF = """<mujoco model="floating">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base" pos="0 0 1">
      <freejoint/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.02 0.03"/>
      <body name="crank">
        <joint type="hinge" axis="0 0 1" range="-1 1.5" limited="true"/>
        <inertial pos="0 0.05 0" mass="0.2" diaginertia="1e-4 1e-5 1e-4"/>
        <body name="coupler" pos="0 0.1 0">
          <joint type="hinge" axis="0 0 1"/>
          <inertial pos="0.15 0 0" mass="0.3" diaginertia="1e-5 1e-3 1e-3"/>
          <site name="coupler_tip" pos="0.3 0 0"/>
        </body>
      </body>
      <body name="rocker" pos="0.3 0 0">
        <joint type="hinge" axis="0 0 1" pos="0 0.02 0"/>
        <joint type="slide" axis="0 1 0"/>
        <inertial pos="0 0.05 0" mass="0.2" diaginertia="1e-4 1e-5 1e-4"/>
        <site name="rocker_tip" pos="0 0.1 0"/>
      </body>
    </body>
  </worldbody>
  <equality><connect site1="coupler_tip" site2="rocker_tip"/></equality>
</mujoco>
"""


def test_unnamed_joints_are_named_after_their_body(tmp_path: Path) -> None:
    """Unnamed joints load as <body>_free and <body>_<kind><i>; the model is MuJoCo's (M, frames)."""
    path = _write(tmp_path, "floating", {".xml": FLOATING_MJCF})
    mech = plm_pin.load(path)
    assert mech.joint_names == (
        "base_free",
        "crank_hinge0",
        "coupler_hinge0",
        "rocker_hinge0",
        "rocker_slide1",
    )
    mjcf = read_mjcf(path)
    m = mjcf.mj_model
    state = mjcf.state_map()
    data = mujoco.MjData(m)
    pin.seed(6)
    for _ in range(3):
        q = pin.randomConfiguration(mjcf.model, -np.ones(mjcf.model.nq), np.ones(mjcf.model.nq))
        _frames_match(mjcf, q)
        data.qpos[:] = state.qpos(q)
        mujoco.mj_forward(m, data)
        M_mj = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, data, M_mj)
        G = state.velocity_matrix(q)
        np.testing.assert_allclose(
            pin.crba(mjcf.model, mjcf.model.createData(), q), G.T @ M_mj @ G, atol=1e-12
        )
    # the limited hinge keeps MuJoCo's range; the others are unlimited
    crank = mech.model.joints[mech.model.getJointId("crank_hinge0")].idx_q
    assert (mech.model.lowerPositionLimit[crank], mech.model.upperPositionLimit[crank]) == (-1.0, 1.5)
    assert mech.model.upperPositionLimit[mech.model.joints[3].idx_q] == np.inf
    # the floating base's 6 DOF, the parallelogram's 1 and the slide's 1 (a point closure of rank 2)
    assert mech.mobility == 8


def test_cli_info_lists_the_joint_names(tmp_path: Path) -> None:
    """``plm-pin info`` shows the joints, named ones and the names given to unnamed ones."""
    from typer.testing import CliRunner

    from plm_pin.cli import app

    path = _write(tmp_path, "floating", {".xml": FLOATING_MJCF})
    result = CliRunner().invoke(app, ["info", str(path), "--json"])
    assert result.exit_code == 0, result.output
    assert '"name": "base_free",\n      "type": "free"' in result.output
    assert '"name": "rocker_slide1",\n      "type": "prismatic"' in result.output


def test_generated_name_taken_by_another_joint_is_refused(tmp_path: Path) -> None:
    """An unnamed joint whose generated name another joint holds: the error names both and the file."""
    text = FLOATING_MJCF.replace('<joint type="slide"', '<joint name="crank_hinge0" type="slide"')
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(_write(tmp_path, "floating", {".xml": text}))
    assert str(info.value) == (
        f"{tmp_path / 'floating.xml'}: an unnamed joint of body 'crank' would be named 'crank_hinge0', "
        "the name of another joint; name it"
    )


# the four-bar with what MuJoCo models for contacts and couplings: two tendons (one driven), a
# tendon equality, a joint coupling and two contact pairs
MANY_EXTRAS = """<tendon>
    <fixed name="t1"><joint joint="crank_pivot" coef="1"/></fixed>
    <fixed name="t2"><joint joint="rocker_pivot" coef="1"/><joint joint="coupler_pivot" coef="0.5"/></fixed>
  </tendon>
  <contact><pair name="p1" geom1="g1" geom2="g2"/><pair geom1="g2" geom2="g1"/></contact>
  <equality>
    <tendon name="te" tendon1="t1" tendon2="t2"/>
    <joint name="couple" joint1="crank_pivot" joint2="coupler_pivot" polycoef="0 2 0 0 0"/>
  </equality>
  <actuator><motor name="pull" tendon="t2"/></actuator>
</mujoco>"""


def _many(tmp_path: Path) -> Path:
    text = FOURBAR_MJCF.replace("</mujoco>", MANY_EXTRAS)
    text = text.replace('<site name="rocker_tip"', '<geom name="g1" size="0.01"/><site name="rocker_tip"')
    text = text.replace('<site name="coupler_tip"', '<geom name="g2" size="0.01"/><site name="coupler_tip"')
    return _write(tmp_path, "many", {".xml": text, ".plm.yaml": FOURBAR_SIDECAR})


def test_every_unsupported_element_in_one_refusal(tmp_path: Path) -> None:
    """One error lists every element plm_pin cannot represent, with counts, and the ignore= dropping them."""
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(_many(tmp_path))
    assert info.value.problem == (
        "the model holds elements plm_pin cannot represent: 2 <contact><pair> ('p1', '#1'); "
        "2 <tendon> ('t1', 't2'); 1 <equality><tendon> ('te'); 1 <equality><joint> ('couple'); "
        "1 <actuator> on a tendon ('pull'). To read the loops without them, load with "
        "ignore=('contacts', 'tendons', 'joint_equalities') (CLI: --ignore contacts,tendons,joint_equalities)"
    )
    with pytest.raises(
        DescriptionError, match=r"cannot represent: 1 <equality><joint> \('couple'\)\. To read"
    ):
        plm_pin.load(tmp_path / "many.xml", ignore=("contacts", "tendons"))


def test_ignore_drops_and_warns_and_keeps_the_linkage(tmp_path: Path) -> None:
    """ignore= drops what it names with one warning; the loops are MuJoCo's (equality Jacobian rank)."""
    with pytest.warns(IgnoredElementWarning) as caught:
        mech = plm_pin.load(_many(tmp_path), ignore="contacts,tendons,joint_equalities")
    (message,) = [str(w.message) for w in caught if "dropped" in str(w.message)]
    assert message == (
        f"{tmp_path / 'many.xml'}: dropped as asked by ignore: 2 <contact><pair> ('p1', '#1'); 2 <tendon> "
        "('t1', 't2'); 1 <equality><tendon> ('te'); 1 <equality><joint> ('couple'); 1 <actuator> on a "
        "tendon ('pull'). Contacts, tendons and inactive equalities do not change a linkage's kinematics. "
        "Without the joint_equalities, the joints they coupled or drove move freely: mobility and "
        "actuation change"
    )
    assert [c.name for c in mech.closures] == ["loop"] and [a.joint for a in mech.actuators] == [
        "crank_pivot"
    ]
    # MuJoCo's own model with the coupling switched off: its connect's Jacobian has the closure's rank
    m = mujoco.MjModel.from_xml_path(str(tmp_path / "many.xml"))
    m.eq_active0[:] = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, i) == "loop" for i in range(m.neq)]
    m.opt.jacobian = int(mujoco.mjtJacobian.mjJAC_DENSE)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    data = mujoco.MjData(m)
    state = StateMap(mech.model, m)
    data.qpos[:] = state.qpos(mech.q_ref)
    mujoco.mj_forward(m, data)
    J = np.asarray(data.efc_J).reshape(data.nefc, m.nv) @ state.velocity_matrix(mech.q_ref)
    assert data.nefc == 3
    assert np.linalg.matrix_rank(J) == mech.closure_rank(mech.q_ref) == mech.nv - mech.mobility == 2


def test_ignore_values_checked(tmp_path: Path) -> None:
    """An unknown kind lists the valid ones; ignore= on a model that is not an MJCF is refused."""
    with pytest.raises(plm_pin.InvalidInput) as info:
        plm_pin.load(_many(tmp_path), ignore=("contact",))
    assert str(info.value) == (
        "ignore: unknown element kind(s) ['contact']; valid are ['contacts', 'tendons', 'joint_equalities', "
        "'inactive_equalities', 'actuators']"
    )
    with pytest.raises(plm_pin.InvalidInput, match=r"ignore=\('contacts',\) applies to MuJoCo models"):
        plm_pin.load("fourbar", ignore=("contacts",))


def test_cli_ignore_option(tmp_path: Path) -> None:
    """``plm-pin check robot.xml --ignore ...`` loads the loops and prints the warning."""
    from typer.testing import CliRunner

    from plm_pin.cli import app

    path = _many(tmp_path)
    refused = CliRunner().invoke(app, ["check", str(path)])
    assert refused.exit_code == 1 and "--ignore contacts,tendons,joint_equalities" in refused.output
    result = CliRunner().invoke(app, ["check", str(path), "--ignore", "contacts,tendons,joint_equalities"])
    assert result.exit_code == 0, result.output
    assert "ok: many: 1 closures, 1 actuators, mobility 1" in result.output
    assert "dropped as asked by ignore" in result.output


def test_collision_geoms_apart_from_visual_geoms(tmp_path: Path) -> None:
    """Geoms without contacts (contype = conaffinity = 0) are the visuals, the others the collision shapes."""
    text = FLOATING_MJCF.replace(
        '<site name="coupler_tip"',
        '<geom name="look" type="box" size="0.15 0.01 0.01" pos="0.15 0 0" contype="0" conaffinity="0" '
        'group="2"/><geom name="touch" type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" group="3"/>'
        '<site name="coupler_tip"',
    )
    mech = plm_pin.load(_write(tmp_path, "floating", {".xml": text}))
    assert [g.name for g in mech.visual_model.geometryObjects] == ["look"]
    assert [g.name for g in mech.collision_model.geometryObjects] == ["touch"]
    # without visual-only geoms every geom is drawn, and the colliding ones are the collision shapes
    text = text.replace(' contype="0" conaffinity="0"', "")
    mech = plm_pin.load(_write(tmp_path, "floating", {".xml": text}))
    assert [g.name for g in mech.visual_model.geometryObjects] == ["look", "touch"]
    assert [g.name for g in mech.collision_model.geometryObjects] == ["look", "touch"]
