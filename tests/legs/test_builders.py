"""The leg-type builders (plm_pin/legs) against closed forms derived here from the geometry alone.

Each mechanism is written into a folder, loaded, its inverse kinematics compared with the
closed form of its legs (never with plm_pin's own formulas), its forward kinematics brought
back to the pose, and its mobility compared with its task dimension.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.kinematics import forward_kinematics, inverse_kinematics
from plm_pin.legs import delta, hexapod, planar, translational


def rot2(phi: float) -> np.ndarray:
    return np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])


def rpy_matrix(rx: float, ry: float, rz: float) -> np.ndarray:
    """R = Rz(rz) Ry(ry) Rx(rx), written out."""
    cx, sx, cy, sy, cz, sz = (
        math.cos(rx),
        math.sin(rx),
        math.cos(ry),
        math.sin(ry),
        math.cos(rz),
        math.sin(rz),
    )
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


# ----------------------------------------------------------------- planar
ANGLES = [math.radians(90 + 120 * i) for i in range(3)]
BASE2 = np.array([[0.3 * math.cos(t), 0.3 * math.sin(t)] for t in ANGLES])
PLAT2 = np.array([[0.08 * math.cos(t), 0.08 * math.sin(t)] for t in ANGLES])
TANGENTS = np.array([[-math.sin(t), math.cos(t)] for t in ANGLES])
RADIALS = np.array([[math.cos(t), math.sin(t)] for t in ANGLES])
PLANAR_OPTIONS = {
    "RPR": {},
    "PRR": {"lengths": 0.25, "directions": TANGENTS},
    "RRR": {"lengths": (0.2, 0.2)},
    "PRP": {"directions": TANGENTS, "slots": RADIALS},
}
PLANAR_POSE = (0.02, -0.01, 0.05)


def planar_points(pose: tuple[float, float, float]) -> np.ndarray:
    """The platform points C_i = p + R(phi) P_i [m], shape (3, 2)."""
    return np.array(pose[:2]) + PLAT2 @ rot2(pose[2]).T


@pytest.fixture(scope="module")
def planar_mechs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("planar")
    return {
        leg: plm_pin.load(
            planar(leg, BASE2, PLAT2, folder=folder, name=leg.lower(), pose=(0.01, 0.02, 0.1), **kw)
        )
        for leg, kw in PLANAR_OPTIONS.items()
    }


@pytest.mark.parametrize("leg", list(PLANAR_OPTIONS))
def test_planar_mobility_and_files(planar_mechs, leg, tmp_path):
    """3 freedoms for the task x, y, rz, non-redundant; both files written, the URDF path returned."""
    mech = planar_mechs[leg]
    assert (mech.mobility, mech.redundancy, len(mech.sidecar.task.dofs)) == (3, 0, 3)
    path = planar(leg, BASE2, PLAT2, folder=tmp_path, name="m", **PLANAR_OPTIONS[leg])
    assert path == tmp_path / "m.urdf" and path.is_file() and (tmp_path / "m.plm.yaml").is_file()


def test_planar_rpr_leg_lengths_are_distances(planar_mechs):
    """3-RPR: each cylinder's length is the distance from its base hinge to its platform point."""
    sol = inverse_kinematics(planar_mechs["RPR"], PLANAR_POSE)
    expected = np.linalg.norm(planar_points(PLANAR_POSE) - BASE2, axis=1)
    np.testing.assert_allclose(sol.actuators, expected, atol=1e-10)


def test_planar_prr_slider_positions(planar_mechs):
    """3-PRR: s_i = d.u + sqrt(l^2 - (d.n)^2) (branch +1), d = C_i - A_i, n normal to the rail."""
    sol = inverse_kinematics(planar_mechs["PRR"], PLANAR_POSE)
    d = planar_points(PLANAR_POSE) - BASE2
    along = np.sum(d * TANGENTS, axis=1)
    across = np.sum(d * RADIALS, axis=1)
    np.testing.assert_allclose(sol.actuators, along + np.sqrt(0.25**2 - across**2), atol=1e-10)


def test_planar_rrr_crank_angles(planar_mechs):
    """3-RRR: the crank points at C_i turned by the elbow triangle's angle (law of cosines), branch +1."""
    sol = inverse_kinematics(planar_mechs["RRR"], PLANAR_POSE)
    d = planar_points(PLANAR_POSE) - BASE2
    r = np.linalg.norm(d, axis=1)
    expected = np.arctan2(d[:, 1], d[:, 0]) + np.arccos(r / (2 * 0.2))  # l1 = l2: isosceles
    np.testing.assert_allclose(
        np.remainder(sol.actuators - expected + math.pi, 2 * math.pi) - math.pi, 0, atol=1e-10
    )


def test_planar_prp_pivot_on_the_slot_line(planar_mechs):
    """3-PRP: the pivot A_i + s_i u_i lies on the platform line through C_i along R v_i."""
    pose = PLANAR_POSE
    sol = inverse_kinematics(planar_mechs["PRP"], pose)
    C = planar_points(pose)
    for i in range(3):
        pivot = BASE2[i] + sol.actuators[i] * TANGENTS[i]
        w = rot2(pose[2]) @ RADIALS[i]
        gap = pivot - C[i]
        assert abs(gap[0] * w[1] - gap[1] * w[0]) < 1e-10


@pytest.mark.parametrize("leg", list(PLANAR_OPTIONS))
def test_planar_fk_of_ik(planar_mechs, leg):
    """The forward kinematics of the inverse kinematics' actuators gives the pose back."""
    mech = planar_mechs[leg]
    sol = inverse_kinematics(mech, PLANAR_POSE)
    fk = forward_kinematics(mech, sol.actuators, sol.q, all_modes=False)
    np.testing.assert_allclose(fk[0].x, PLANAR_POSE, atol=1e-9)


# ----------------------------------------------------------------- hexapods
BASE_ANGLES = np.radians([-10, 10, 110, 130, 230, 250])
PLAT_ANGLES = np.radians([-50, 50, 70, 170, 190, 290])
BASE6 = 0.5 * np.column_stack([np.cos(BASE_ANGLES), np.sin(BASE_ANGLES), np.zeros(6)])
PLAT6 = 0.3 * np.column_stack([np.cos(PLAT_ANGLES), np.sin(PLAT_ANGLES), np.zeros(6)])
HEX_HOME = (0.0, 0.0, 0.8, 0.0, 0.0, 0.0)
HEX_POSE = (0.01, -0.02, 0.82, 0.03, -0.02, 0.05)
HEX_OPTIONS = {
    "UPS": {},
    "RUS": {"lengths": (0.25, 0.8)},
    "PSS": {"lengths": 0.7, "directions": [(0, 0, 1)] * 6},
}


def hex_points(pose: tuple[float, ...]) -> np.ndarray:
    """The platform points p + R b_i [m], shape (6, 3)."""
    return np.array(pose[:3]) + PLAT6 @ rpy_matrix(*pose[3:]).T


@pytest.fixture(scope="module")
def hex_mechs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hexapod")
    return {
        leg: plm_pin.load(hexapod(leg, BASE6, PLAT6, pose=HEX_HOME, folder=folder, name=leg.lower(), **kw))
        for leg, kw in HEX_OPTIONS.items()
    }


@pytest.mark.parametrize("leg", list(HEX_OPTIONS))
def test_hexapod_mobility_and_fk_of_ik(hex_mechs, leg):
    """Six freedoms for the 6-D task; the forward kinematics of the IK's actuators gives the pose back."""
    mech = hex_mechs[leg]
    assert (mech.mobility, mech.redundancy, len(mech.sidecar.task.dofs)) == (6, 0, 6)
    sol = inverse_kinematics(mech, HEX_POSE)
    fk = forward_kinematics(mech, sol.actuators, sol.q, all_modes=False)
    np.testing.assert_allclose(fk[0].x, HEX_POSE, atol=1e-9)


def test_stewart_leg_lengths(hex_mechs):
    """6-UPS: leg lengths |p + R b_i - a_i|."""
    sol = inverse_kinematics(hex_mechs["UPS"], HEX_POSE)
    np.testing.assert_allclose(
        sol.actuators, np.linalg.norm(hex_points(HEX_POSE) - BASE6, axis=1), atol=1e-10
    )


def test_pss_slider_positions(hex_mechs):
    """6-PSS on vertical guides: q_i = d_z - sqrt(l^2 - d_x^2 - d_y^2) (branch -1, slider below)."""
    sol = inverse_kinematics(hex_mechs["PSS"], HEX_POSE)
    d = hex_points(HEX_POSE) - BASE6
    np.testing.assert_allclose(
        sol.actuators, d[:, 2] - np.sqrt(0.7**2 - d[:, 0] ** 2 - d[:, 1] ** 2), atol=1e-10
    )


def test_rus_crank_tip_geometry(hex_mechs):
    """6-RUS: the crank tip at the angle found (from the outward radial, towards -z) is l2 from C_i.

    The tip is l1 from the pivot in the plane normal to the tangent axis, by construction here.
    """
    sol = inverse_kinematics(hex_mechs["RUS"], HEX_POSE)
    C = hex_points(HEX_POSE)
    for i in range(6):
        out = BASE6[i] / np.linalg.norm(BASE6[i])
        axis = np.cross([0.0, 0.0, 1.0], out)
        second = np.cross(axis, out)  # -z
        t = sol.actuators[i]
        tip = BASE6[i] + 0.25 * (math.cos(t) * out + math.sin(t) * second)
        assert abs(np.linalg.norm(tip - C[i]) - 0.8) < 1e-10


def test_hexapod_refuses_upu(tmp_path):
    """A UPU hexapod is refused, with the reason and where to go instead."""
    with pytest.raises(plm_pin.InvalidInput, match=r"5 freedoms.*translational"):
        hexapod("UPU", BASE6, PLAT6, pose=HEX_HOME, folder=tmp_path)


# ----------------------------------------------------------------- 3-UPU and Delta
TRI = [2 * math.pi * i / 3 for i in range(3)]
BASE3 = np.array([[0.3 * math.cos(t), 0.3 * math.sin(t), 0.0] for t in TRI])
PLAT3 = np.array([[0.1 * math.cos(t), 0.1 * math.sin(t), 0.0] for t in TRI])


def test_translational_upu(tmp_path):
    """3-UPU: mobility 3, leg lengths |p + b_i - a_i|, the platform level at the IK and after the FK."""
    mech = plm_pin.load(translational("UPU", BASE3, PLAT3, pose=(0.0, 0.0, 0.4), folder=tmp_path))
    assert (mech.mobility, mech.redundancy, len(mech.sidecar.task.dofs)) == (3, 0, 3)
    x = np.array([0.02, -0.03, 0.42])
    sol = inverse_kinematics(mech, x)
    np.testing.assert_allclose(sol.actuators, np.linalg.norm(x + PLAT3 - BASE3, axis=1), atol=1e-10)
    fk = forward_kinematics(mech, sol.actuators, sol.q, all_modes=False)
    np.testing.assert_allclose(fk[0].x, x, atol=1e-9)
    frame = mech.model.getFrameId("platform_center", pin.FrameType.BODY)
    for q in (sol.q, fk[0].q):
        pin.framesForwardKinematics(mech.model, mech.data, q)
        np.testing.assert_allclose(mech.data.oMf[frame].rotation, np.eye(3), atol=1e-9)


DELTA_BASE = np.array([[0.2 * math.cos(t), 0.2 * math.sin(t), 0.0] for t in TRI])
DELTA_PLAT = np.array([[0.05 * math.cos(t), 0.05 * math.sin(t), 0.0] for t in TRI])


def clavel_ik(point: np.ndarray, La: float, Lb: float) -> np.ndarray:
    """Clavel's closed form: in arm i's plane, a cos t + b sin t = c, the elbow-out root [rad]."""
    R = 0.2 - 0.05
    out = []
    for ph in TRI:
        x = math.cos(ph) * point[0] + math.sin(ph) * point[1]
        y = -math.sin(ph) * point[0] + math.cos(ph) * point[1]
        z = point[2]
        a, b = -2 * La * (x - R), 2 * La * z
        c = Lb * Lb - La * La - (x - R) ** 2 - y * y - z * z
        out.append(math.atan2(b, a) + math.acos(c / math.hypot(a, b)))
    return np.array(out)


def test_delta(tmp_path):
    """Delta with parallelograms: 6 rods, mobility 3, Clavel's angles, FK of IK, the platform level."""
    path = delta(
        DELTA_BASE, DELTA_PLAT, arm=0.3, forearm=0.6, width=0.08, pose=(0.0, 0.0, -0.5), folder=tmp_path
    )
    mech = plm_pin.load(path)
    assert (mech.mobility, mech.redundancy, len(mech.sidecar.task.dofs)) == (3, 0, 3)
    assert sum(1 for f in mech.model.frames if f.name.startswith("rod") and f.name.endswith("_tip")) == 6
    x = np.array([0.01, -0.02, -0.55])
    sol = inverse_kinematics(mech, x)
    np.testing.assert_allclose(sol.actuators, clavel_ik(x, 0.3, 0.6), atol=1e-10)
    fk = forward_kinematics(mech, sol.actuators, sol.q, all_modes=False)
    np.testing.assert_allclose(fk[0].x, x, atol=1e-9)
    frame = mech.model.getFrameId("platform_center", pin.FrameType.BODY)
    pin.framesForwardKinematics(mech.model, mech.data, fk[0].q)
    np.testing.assert_allclose(mech.data.oMf[frame].rotation, np.eye(3), atol=1e-9)


# ----------------------------------------------------------------- bad inputs
@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda f: planar("RXR", BASE2, PLAT2, folder=f),
            r"leg must be one of \['RPR', 'PRR', 'RRR', 'PRP'\]",
        ),
        (lambda f: planar("RPR", BASE2[:2], PLAT2, folder=f), r"base must be 3 points"),
        (lambda f: planar("RRR", BASE2, PLAT2, folder=f, lengths=(0.2, -0.1)), r"lengths must be .*> 0"),
        (lambda f: planar("RRR", BASE2, PLAT2, folder=f), r"RRR legs need lengths"),
        (lambda f: planar("RPR", BASE2, PLAT2, folder=f, lengths=0.2), r"RPR legs take no lengths"),
        (lambda f: planar("PRR", BASE2, PLAT2, folder=f, lengths=0.05, directions=TANGENTS), r"leg 1's rod"),
        (lambda f: planar("RPR", BASE2, PLAT2, folder=f, stroke=(0.0, 1.0)), r"stroke .*0 < lower < upper"),
        (lambda f: planar("RPR", BASE2, PLAT2, folder=f, colour="red"), r"unknown option\(s\) \['colour'\]"),
        (lambda f: hexapod("UPS", BASE6, PLAT6[:5], pose=HEX_HOME, folder=f), r"platform must be 6 points"),
        (
            lambda f: hexapod("RUS", BASE6, PLAT6, pose=HEX_HOME, folder=f, lengths=(0.1, 0.2)),
            r"leg 1's crank",
        ),
        (
            lambda f: translational("UPS", BASE3, PLAT3, pose=(0, 0, 0.4), folder=f),
            r"leg must be one of \['UPU'\]",
        ),
        (
            lambda f: delta(DELTA_BASE, DELTA_PLAT, arm=0.0, forearm=0.6, pose=(0, 0, -0.5), folder=f),
            r"arm must be",
        ),
        (
            lambda f: delta(DELTA_BASE, DELTA_PLAT, arm=0.3, forearm=0.6, pose=(0, 0, -2.0), folder=f),
            r"arm 1",
        ),
    ],
)
def test_bad_parameters(tmp_path, call, match):
    """One typed error naming the argument (and the valid choices) for each bad parameter."""
    with pytest.raises(plm_pin.InvalidInput, match=match):
        call(tmp_path)


def test_flat_points_build_the_same_description():
    """Points given flat (n * dim numbers, the form a sweep varies) write the same URDF and sidecar."""
    from plm_pin.description.writer import urdf_text
    from plm_pin.legs import build_hexapod, build_planar

    nested = build_planar(leg="RPR", base=BASE2, platform=PLAT2)
    flat = build_planar(leg="RPR", base=tuple(BASE2.ravel()), platform=tuple(PLAT2.ravel()))
    assert urdf_text(flat[0]) == urdf_text(nested[0]) and flat[1] == nested[1]
    nested = build_hexapod(leg="UPS", base=BASE6, platform=PLAT6, pose=HEX_HOME)
    flat = build_hexapod(
        leg="UPS", base=BASE6.ravel().tolist(), platform=PLAT6.ravel().tolist(), pose=HEX_HOME
    )
    assert urdf_text(flat[0]) == urdf_text(nested[0]) and flat[1] == nested[1]
