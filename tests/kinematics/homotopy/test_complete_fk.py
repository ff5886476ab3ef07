"""Complete forward kinematics by homotopy (plm_pin/kinematics/homotopy), through forward_kinematics.

Oracles: the four-bar's circle intersection (closed form), a univariate search in the
platform angle for a planar 3-RPR (tests/kinematics/homotopy/rpr.py), PHCpack on a 6-6
platform's leg equations written independently (slow, where phcpy is installed), and
multi-start Newton with many starts on the presets.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import brentq

import plm_pin
from plm_pin.kinematics import forward_kinematics, same_assembly
from plm_pin.kinematics.forward import FKModes
from plm_pin.legs import hexapod
from plm_pin.warnings import ReferenceWarning
from tests.conftest import preset

from .rpr import rpr_complex_poses, rpr_files, rpr_poses

HERE = Path(__file__).parent
# A 3-RPR with six real assembly modes (found by the univariate search of rpr.py, the oracle)
RPR_BASE = np.array([[0.0, 0.0], [0.61, -0.47], [-0.43, 0.65]])
RPR_PLATE = np.array([[0.0, 0.0], [0.37, 0.4], [-0.39, 0.15]])
RPR_RHO = np.array([0.54, 0.59, 0.89])


def _fourbar_geometry(mech: plm_pin.Mechanism) -> tuple[np.ndarray, np.ndarray, float, float, float]:
    """Crank pivot O, rocker pivot P, crank, coupler and rocker lengths, read from the reference pose."""
    model, data = mech.model, mech.model.createData()
    pin.framesForwardKinematics(model, data, mech.q_ref)
    o = data.oMi[model.getJointId("crank_pivot")].translation[:2]
    c = data.oMi[model.getJointId("coupler_pivot")].translation[:2]
    p = data.oMi[model.getJointId("rocker_pivot")].translation[:2]
    tip = data.oMf[model.getFrameId("coupler_tip")].translation[:2]
    return o, p, float(np.linalg.norm(c - o)), float(np.linalg.norm(tip - c)), float(np.linalg.norm(tip - p))


def _coupler_tips(o, p, lc, lk, lr, theta):  # type: ignore[no-untyped-def]
    """The two coupler-tip positions at crank angle theta: circles about the crank tip and P."""
    c = o + lc * np.array([math.cos(theta), math.sin(theta)])
    d = p - c
    dist = float(np.linalg.norm(d))
    a = (lk**2 - lr**2 + dist**2) / (2 * dist)
    h = math.sqrt(max(lk**2 - a**2, 0.0))
    n = np.array([-d[1], d[0]]) / dist
    return [c + a * d / dist + s * h * n for s in (1.0, -1.0)]


def _tips(mech: plm_pin.Mechanism, modes: FKModes) -> list[np.ndarray]:
    data = mech.model.createData()
    out = []
    for s in modes:
        pin.framesForwardKinematics(mech.model, data, s.q)
        out.append(data.oMf[mech.model.getFrameId("coupler_tip")].translation[:2].copy())
    return out


def _match(found: list[np.ndarray], expected: list[np.ndarray], tol: float) -> None:
    assert len(found) == len(expected)
    for e in expected:
        assert min(np.abs(f - e).max() for f in found) <= tol


def test_fourbar_two_modes_match_the_circle_intersection():
    """The four-bar's two assembly modes are the two circle intersections; complete, both certified."""
    mech = preset("fourbar")
    geo = _fourbar_geometry(mech)
    for theta in (0.3, 1.0471975511965976, 2.5):
        modes = forward_kinematics(mech, [theta])
        assert modes.method == "homotopy" and modes.complete and modes.generic_count == 2
        assert modes.certified == 2 and not modes.why_incomplete
        _match(_tips(mech, modes), _coupler_tips(*geo, theta), 1e-12)
        assert all(s.residual_norm <= 1e-12 for s in modes)


def test_fourbar_modes_1e_3_apart_near_the_folded_singularity_are_both_found():
    """Near the stretched coupler-rocker pair the two modes are 1e-3 apart: both found and certified."""
    params = {"crank": 0.1, "coupler": 0.25, "rocker": 0.2, "ground": 0.4, "crank_angle": 1.0}
    mech = plm_pin.build_mechanism("fourbar", params, name="fourbar_folding")
    o, p, lc, lk, lr = _fourbar_geometry(mech)

    def gap(theta: float) -> float:  # distance between the two modes, minus 1e-3
        a, b = _coupler_tips(o, p, lc, lk, lr, theta)
        return float(np.linalg.norm(a - b)) - 1e-3

    # the crank angle where the crank tip is lk + lr from P (the folded singularity), then 1e-3 apart
    thetas = np.linspace(-math.pi, math.pi, 20001)
    reach = [float(np.linalg.norm(o + lc * np.array([math.cos(t), math.sin(t)]) - p)) for t in thetas]
    i = int(np.argmax(reach))
    assert reach[i] > lk + lr  # the crank can stretch the pair past its length: a singularity exists
    j = i
    while reach[j] > lk + lr:
        j -= 1

    def stretch(t: float) -> float:
        return float(np.linalg.norm(o + lc * np.array([math.cos(t), math.sin(t)]) - p)) - (lk + lr)

    singular = brentq(stretch, thetas[j], thetas[j + 1], xtol=1e-16)
    theta = brentq(gap, singular - 0.2, singular, xtol=1e-16)
    expected = _coupler_tips(o, p, lc, lk, lr, theta)
    assert abs(np.linalg.norm(expected[0] - expected[1]) - 1e-3) < 1e-9
    modes = forward_kinematics(mech, [theta])
    assert modes.complete and modes.certified == 2 and len(modes) == 2
    _match(_tips(mech, modes), expected, 1e-10)


def _load_rpr(folder: Path) -> plm_pin.Mechanism:
    """The test 3-RPR, loaded.

    Its sidecar gives no reference, so the loader moves the one it closes near a singularity (a
    ReferenceWarning): the forward kinematics does not depend on the reference.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ReferenceWarning)
        return plm_pin.load(rpr_files(folder, RPR_BASE, RPR_PLATE))


def _nearest_planar_pose(modes, e: np.ndarray) -> float:
    """Largest difference of the (x, y, angle) pose ``e`` to the nearest mode's, the angle taken mod 2 pi."""
    errs = []
    for s in modes:
        d = s.x - e
        d[2] = (d[2] + math.pi) % (2 * math.pi) - math.pi
        errs.append(np.abs(d).max())
    return min(errs)


def test_3rpr_six_real_modes_match_the_univariate_search(tmp_path):
    """A planar 3-RPR with 6 real modes: all six, complete (generic count 6), equal to the oracle's poses."""
    mech = _load_rpr(tmp_path)
    modes = forward_kinematics(mech, RPR_RHO)
    assert modes.method == "homotopy" and modes.complete
    assert modes.generic_count == 6 and modes.certified == 6 and len(modes) == 6
    assert all(s.certified for s in modes)
    assert not any(s.certified for s in forward_kinematics(mech, RPR_RHO, method="multi-start"))
    expected = rpr_poses(RPR_BASE, RPR_PLATE, RPR_RHO, n_grid=100_000)
    assert len(expected) == 6
    for e in expected:
        assert _nearest_planar_pose(modes, e) <= 1e-12


def test_3rpr_out_of_reach_is_unreachable_with_proof(tmp_path):
    """Legs too short to meet: no real mode, PoseUnreachable says all six roots are complex."""
    mech = _load_rpr(tmp_path)
    with pytest.raises(plm_pin.PoseUnreachable, match=r"none of the 6 complex roots is real"):
        forward_kinematics(mech, [0.01, 0.01, 0.01])


def _preset_rpr_triangles() -> tuple[np.ndarray, np.ndarray]:
    """Base hinges and platform hinges (platform frame) of the preset planar_3rpr, from its registry entry."""
    from plm_pin.models.registry import PRESETS

    params = PRESETS["planar_3rpr"].parameters
    return np.array(params["base"], dtype=float), np.array(params["platform"], dtype=float)


@pytest.mark.parametrize("offset", [(1e-3, 1e-3, 1e-3), (0.02, -0.01, 0.0)], ids=["equal_legs", "unequal"])
def test_planar_3rpr_similar_triangles_match_the_elimination(offset):
    """planar_3rpr (similar triangles): 4 generic roots, complete, the real modes are the elimination's.

    With similar base and platform triangles two of the 3-RPR's six roots lie at infinity for
    every leg length, and with equal legs two more go there: the paths to them diverge, and
    the roots reached are the elimination's finite roots.
    """
    from plm_pin.kinematics.homotopy import solve_homotopy

    mech = preset("planar_3rpr")
    base, plate = _preset_rpr_triangles()
    rng = np.random.default_rng(3)
    generic = rpr_complex_poses(base, plate, rng.normal(size=3) + 1j * rng.normal(size=3))
    c = mech.actuator_positions(mech.q_ref) + np.array(offset)
    finite = rpr_complex_poses(base, plate, c)
    real = [e.real for e in finite if np.abs(e.imag).max() <= 1e-9]
    modes = forward_kinematics(mech, c)
    assert modes.method == "homotopy" and modes.complete and not modes.why_incomplete
    assert modes.generic_count == len(generic) == 4
    assert modes.certified == len(modes) == len(real) >= 2
    res = solve_homotopy(mech, c)
    assert res.roots == len(finite) and res.roots + res.diverged == 4
    for e in real:
        assert _nearest_planar_pose(modes, e) <= 1e-9


def _stewart_geometry(mech: plm_pin.Mechanism) -> dict[str, list]:
    """Base points (U centres), platform points and strut lengths of the 6-PUS at its reference pose."""
    model, data = mech.model, mech.model.createData()
    pin.framesForwardKinematics(model, data, mech.q_ref)
    plat = data.oMi[model.getJointId("platform_floating")]
    A, B, L = [], [], []
    for c in mech.closures:
        fa, fb = c.frame_ids
        u = model.getJointId(model.names[model.frames[fa].parentJoint][:-1] + "a")
        a = data.oMi[u].translation
        A.append(a.tolist())
        B.append(plat.actInv(data.oMf[fb].translation).tolist())
        L.append(float(np.linalg.norm(data.oMf[fa].translation - a)))
    return {"A": A, "B": B, "L": L}


def _platform_poses(mech: plm_pin.Mechanism, modes: FKModes) -> list[np.ndarray]:
    """The platform joint's world pose of each mode: position and rotation matrix, shape (12,)."""
    model, data = mech.model, mech.model.createData()
    j = model.getJointId("platform_floating")
    out = []
    for s in modes:
        pin.forwardKinematics(model, data, s.q)
        out.append(np.concatenate([data.oMi[j].translation, data.oMi[j].rotation.ravel()]))
    return out


def test_stewart_platform_has_40_roots_and_every_real_mode_closes():
    """The 6-PUS (a 6-6 platform once its sliders are fixed): 40 generic roots, complete, modes closed."""
    mech = preset("zhao2011_6pss")
    modes = forward_kinematics(mech, mech.actuator_positions(mech.q_ref))
    assert modes.method == "homotopy" and modes.complete and modes.generic_count == 40
    assert modes.certified == len(modes) >= 2
    assert any(same_assembly(mech, s.q, mech.q_ref) for s in modes)
    for i, s in enumerate(modes):
        assert s.residual_norm <= 1e-12
        assert not any(same_assembly(mech, s.q, t.q) for t in modes[:i])


@pytest.mark.slow
def test_stewart_real_modes_equal_phcpack():
    """PHCpack's real solutions of the independently written leg equations are exactly our modes."""
    mech = preset("zhao2011_6pss")
    geometry = _stewart_geometry(mech)
    (phc,) = _phcpack(geometry["A"], geometry["B"], [geometry["L"]])
    assert phc["total"] == 80  # 40 poses, each with its quaternion and its opposite
    modes = forward_kinematics(mech, mech.actuator_positions(mech.q_ref))
    _match(_platform_poses(mech, modes), _phc_poses(phc), 1e-8)


# A general (non-symmetric, non-planar) 6-6 Gough-Stewart platform: irregular points
_SG_RNG = np.random.default_rng(7)
_SG_ANGLES = np.sort(_SG_RNG.uniform(0, 2 * np.pi, (2, 6)), axis=1)
SG_BASE = np.c_[
    0.5 * np.cos(_SG_ANGLES[0]) * _SG_RNG.uniform(0.8, 1.2, 6),
    0.5 * np.sin(_SG_ANGLES[0]) * _SG_RNG.uniform(0.8, 1.2, 6),
    _SG_RNG.uniform(-0.05, 0.05, 6),
]
SG_PLATFORM = np.c_[
    0.3 * np.cos(_SG_ANGLES[1]) * _SG_RNG.uniform(0.8, 1.2, 6),
    0.3 * np.sin(_SG_ANGLES[1]) * _SG_RNG.uniform(0.8, 1.2, 6),
    _SG_RNG.uniform(-0.05, 0.05, 6),
]
SG_POSE = (0.02, -0.03, 0.8, 0.05, -0.04, 0.1)


def _general_stewart(folder: Path) -> plm_pin.Mechanism:
    return plm_pin.load(hexapod("UPS", SG_BASE.tolist(), SG_PLATFORM.tolist(), folder=folder, pose=SG_POSE))


def _leg_lengths(mech: plm_pin.Mechanism, q: np.ndarray) -> np.ndarray:
    """|p + R b_i - a_i| from the platform pose at ``q`` alone (the closed form of a UPS leg's length)."""
    model, data = mech.model, mech.model.createData()
    pin.forwardKinematics(model, data, q)
    M = data.oMi[model.getJointId("platform_floating")]
    b = np.array(
        [model.frames[model.getFrameId(f"platform_p{i}")].placement.translation for i in range(1, 7)]
    )
    return np.linalg.norm(M.translation + b @ M.rotation.T - SG_BASE, axis=1)


def test_general_stewart_ups_legs_reduce_to_distances_40_roots(tmp_path):
    """A 6-UPS with irregular points: 40 generic roots, complete, every mode certified, at its leg lengths."""
    mech = _general_stewart(tmp_path)
    form, _ = plm_pin.kinematics.homotopy.prepared(mech)
    assert form.n == 7 and list(form.closure_kind) == [3] * 6  # the platform pose alone; six distances
    c = mech.actuator_positions(mech.q_ref)
    modes = forward_kinematics(mech, c)
    assert modes.method == "homotopy" and modes.complete and modes.generic_count == 40
    assert modes.certified == len(modes) >= 2
    assert any(same_assembly(mech, s.q, mech.q_ref) for s in modes)
    for i, s in enumerate(modes):
        np.testing.assert_allclose(_leg_lengths(mech, s.q), c, rtol=0, atol=1e-10)
        assert not any(same_assembly(mech, s.q, t.q) for t in modes[:i])


def _phcpack(base: list, platform: list, lengths: list[list[float]]) -> list[dict[str, list]]:
    """PHCpack's solutions of the 6-6 leg equations at each set of ``lengths`` (phc_stewart.py).

    PHCpack runs in Debian's python3-phcpy (``make test`` installs it): skipped where it is
    missing, except on CI, where the oracle must run.
    """
    probe = None
    if shutil.which("/usr/bin/python3") is not None:
        probe = subprocess.run(["/usr/bin/python3", "-c", "import phcpy"], capture_output=True, check=False)
    if probe is None or probe.returncode:
        why = "phcpy is not installed for the system python (make test, or apt-get install python3-phcpy)"
        if os.environ.get("CI"):
            pytest.fail(why)
        pytest.skip(why)
    run = subprocess.run(
        ["/usr/bin/python3", str(HERE / "phc_stewart.py")],
        input=json.dumps({"A": base, "B": platform, "L": lengths}),
        capture_output=True,
        text=True,
        check=True,
        timeout=1800,
    )
    return json.loads(run.stdout.strip().splitlines()[-1])


def _phc_poses(phc: dict[str, list]) -> list[np.ndarray]:
    expected: list[np.ndarray] = []
    for x, y, z, w, qx, qy, qz in phc["real"]:
        R = pin.Quaternion(w, qx, qy, qz).normalized().toRotationMatrix()
        pose = np.concatenate([[x, y, z], R.ravel()])
        if not any(np.abs(pose - e).max() < 1e-6 for e in expected):
            expected.append(pose)
    return expected


@pytest.mark.slow
def test_general_stewart_ups_real_modes_equal_phcpack(tmp_path):
    """PHCpack at three sets of leg lengths: 80 signed-quaternion solutions each, its real ones our modes.

    PHCpack solves the first set by its black-box solver and the other two by its own tracker
    from the first set's 80 solutions (phc_stewart.py); each set's count is checked to be 80.
    """
    mech = _general_stewart(tmp_path)
    shifts = [0.0, 0.01, 0.03]
    lengths = [
        mech.actuator_positions(mech.q_ref) + shift * np.array([1.0, -1.0, 0.5, 0.0, -0.5, 1.0])
        for shift in shifts
    ]
    results = _phcpack(SG_BASE.tolist(), SG_PLATFORM.tolist(), [c.tolist() for c in lengths])
    assert [phc["total"] for phc in results] == [80] * len(shifts)
    for c, phc in zip(lengths, results, strict=True):
        expected = _phc_poses(phc)
        if not expected:  # no real assembly: proven by the homotopy too
            with pytest.raises(plm_pin.PoseUnreachable, match="none of the 40 complex roots is real"):
                forward_kinematics(mech, c)
            continue
        modes = forward_kinematics(mech, c)
        assert modes.complete and modes.generic_count == 40
        _match(_platform_poses(mech, modes), expected, 1e-8)


@pytest.mark.parametrize(
    "name",
    [
        "fourbar",
        "fivebar",
        "harada2011_3d3m",
        "harada2011_3d4m",
        "harada2015_asymmetric",
        "enferadi2017_star_triangle",
        "zhao2011_6pss",
        "stewart_6ups",
    ],
)
def test_presets_modes_contain_every_multistart_mode(name):
    """Every mode 200-start multi-start Newton finds is among the homotopy's, and the homotopy is complete."""
    mech = preset(name)
    c = mech.actuator_positions(mech.q_ref)
    modes = forward_kinematics(mech, c)
    assert modes.method == "homotopy" and modes.complete
    multi = forward_kinematics(mech, c, all_modes=False)  # the reference mode
    rng = np.random.default_rng(3)
    from plm_pin.kinematics.forward import _close, _with_actuators
    from plm_pin.kinematics.starts import random_starts

    found = list(multi)
    for start in random_starts(mech, rng, mech.q_ref, mech.passive_v_indices, 200):
        try:
            q = _close(mech, _with_actuators(mech, start, c), mech.passive_v_indices, 1e-12)[0]
        except plm_pin.exceptions.ClosureNotSatisfied:
            continue
        if not any(same_assembly(mech, q, s.q if hasattr(s, "q") else s) for s in found):
            found.append(q)
    for q in [s.q if hasattr(s, "q") else s for s in found]:
        assert any(same_assembly(mech, q, s.q) for s in modes)


def _clavel_level_poses(theta: np.ndarray) -> list[np.ndarray]:
    """The Delta preset's two level platform positions at crank angles ``theta``: three spheres meet.

    Clavel's closed form (plm_pin/legs/delta.py): elbow E_i = a_i + l_a (cos t_i e_i - sin t_i z),
    and a level platform puts p + b_i at l_b from E_i; the registry's dimensions, written again.
    """
    la, lb = 0.30, 0.60
    centres = []
    for t, phi in zip(theta, np.radians([0.0, 120.0, 240.0]), strict=True):
        e = np.array([math.cos(phi), math.sin(phi), 0.0])
        centres.append(0.20 * e + la * (math.cos(t) * e - math.sin(t) * np.array([0.0, 0.0, 1.0])) - 0.05 * e)
    c1, c2, c3 = centres
    ex = (c2 - c1) / np.linalg.norm(c2 - c1)
    i = float(ex @ (c3 - c1))
    ey = (c3 - c1 - i * ex) / np.linalg.norm(c3 - c1 - i * ex)
    ez = np.cross(ex, ey)
    d, j = float(np.linalg.norm(c2 - c1)), float(ey @ (c3 - c1))
    x = d / 2  # equal radii
    y = (i * i + j * j - 2 * i * x) / (2 * j)
    h = math.sqrt(lb * lb - x * x - y * y)
    return [c1 + x * ex + y * ey + s * h * ez for s in (1.0, -1.0)]


@pytest.mark.parametrize("shift", [(1e-3, 1e-3, 1e-3), (0.02, -0.03, 0.05)])
def test_delta_complete_with_clavel_level_poses_and_every_multistart_mode(shift):
    """The Delta: complete (arms at one angle: 12 of 40 roots at infinity), Clavel's two level poses found.

    Every mode of 300-start multi-start Newton is among the homotopy's, and every mode closes.
    """
    mech = preset("delta")
    c = mech.actuator_positions(mech.q_ref) + np.array(shift)
    modes = forward_kinematics(mech, c)
    assert modes.method == "homotopy" and modes.complete and modes.generic_count == 40
    assert modes.certified == len(modes) >= 2
    for pose in _clavel_level_poses(c):
        assert sum(np.abs(s.x - pose).max() <= 1e-9 for s in modes) == 1
    for s in modes:
        assert s.residual_norm <= 1e-12
    multi = forward_kinematics(mech, c, method="multi-start", starts=300, seed=5)
    for s in multi:
        assert any(same_assembly(mech, s.q, t.q) for t in modes)


def test_redundant_actuators_that_disagree_have_no_mode():
    """The 3D4M's fourth actuator moved off the value its three others imply: no assembly (proven)."""
    mech = preset("harada2011_3d4m")
    c = mech.actuator_positions(mech.q_ref)
    modes = forward_kinematics(mech, c)
    assert modes.complete and len(modes) >= 1
    form, _ = plm_pin.kinematics.homotopy.prepared(mech)
    ((a, _, _),) = form.checked
    c[a] += 0.05
    with pytest.raises(plm_pin.PoseUnreachable, match="complex roots is real"):
        forward_kinematics(mech, c)


def test_without_polynomial_form_multistart_is_used_and_said_once(monkeypatch):
    """A mechanism the homotopy refuses falls back to multi-start: warned once, not complete, modes found."""
    import plm_pin.kinematics.forward as forward
    from plm_pin.kinematics import homotopy
    from plm_pin.warnings import IncompleteSearchWarning

    def refuse(mech):  # type: ignore[no-untyped-def]
        raise homotopy.NotPolynomial("a joint kind it does not cover")

    monkeypatch.setattr(homotopy, "prepared", refuse)
    monkeypatch.setattr(forward, "_FALLBACK_WARNED", set())
    mech = preset("fourbar")
    with pytest.warns(
        IncompleteSearchWarning, match=r"^fourbar: no polynomial form of the closures \(a joint"
    ):
        modes = forward_kinematics(mech, [0.3])
    assert modes.method == "multi-start" and not modes.complete and modes.generic_count is None
    _match(_tips(mech, modes), _coupler_tips(*_fourbar_geometry(mech), 0.3), 1e-12)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        forward_kinematics(mech, [0.3])  # said once
