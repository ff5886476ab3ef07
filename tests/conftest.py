"""Shared fixtures: cached presets and small inline mechanisms."""

from __future__ import annotations

import functools
import math
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.core.mechanism import Mechanism
from plm_pin.description import Sidecar, write_description
from plm_pin.description import urdf_parts as u
from plm_pin.models import urdf_folder
from plm_pin.report import StudyResult

REPO = Path(__file__).resolve().parents[1]
INTEROP = REPO.parent / "shared" / "interop" / "example-parallel-robots"


def load_corpus(path: Path) -> Mechanism:
    """Load an example-parallel-robots description, its missing meshes, URDF limits and reference not warned.

    Those warnings are tested in tests/description/test_interop.py, tests/kinematics/test_limits.py
    and tests/kinematics/test_reference.py (a sidecar written for a corpus robot has no reference).
    """
    import warnings

    from plm_pin.warnings import MissingLimitsWarning, MissingMeshWarning, ReferenceWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingMeshWarning)
        warnings.simplefilter("ignore", MissingLimitsWarning)
        warnings.simplefilter("ignore", ReferenceWarning)
        return plm_pin.load(path)


@functools.cache
def preset(name: str) -> Mechanism:
    """Load a preset once per test session (Mechanism objects are not mutated by tests)."""
    return plm_pin.load(name)


def fd_jacobian(f, model: pin.Model, q: np.ndarray, eps: float = 1e-6) -> np.ndarray:
    """Central finite differences of ``f`` along the tangent space of ``model`` at ``q``."""
    cols = []
    for k in range(model.nv):
        dv = np.zeros(model.nv)
        dv[k] = eps
        cols.append((f(pin.integrate(model, q, dv)) - f(pin.integrate(model, q, -dv))) / (2 * eps))
    return np.column_stack(cols)


def ball_joint_body(tmp_path: Path, closure: dict) -> Mechanism:
    """A body on a ball joint (three revolutes x, y, z) whose frame is closed on the world.

    The body frame ``body_tip`` sits at the ball centre, so a point closure leaves the three
    rotations free, a revolute closure leaves one and a weld none.
    """
    links = [
        u.link("base"),
        u.link("gimbal1", 1e-3, (1e-6, 1e-6, 1e-6)),
        u.link("gimbal2", 1e-3, (1e-6, 1e-6, 1e-6)),
        u.link("body", 1.0, (0.01, 0.02, 0.03), com=(0.1, 0.0, 0.0)),
        u.link("body_tip"),
        u.link("anchor"),
    ]
    joints = [
        u.joint("rx", "revolute", "base", "gimbal1", xyz=(0.0, 0.0, 0.5), axis=(1, 0, 0)),
        u.joint("ry", "revolute", "gimbal1", "gimbal2", axis=(0, 1, 0)),
        u.joint("rz", "revolute", "gimbal2", "body", axis=(0, 0, 1)),
        u.joint("tip_fixed", "fixed", "body", "body_tip"),
        u.joint("anchor_fixed", "fixed", "base", "anchor", xyz=(0.0, 0.0, 0.5)),
    ]
    import yourdfpy

    from plm_pin.description.sidecar import parse_sidecar

    sidecar = parse_sidecar(
        {
            "format": "plm-pin/1",
            "closures": [{"name": "c", "frames": ["anchor", "body_tip"], **closure}],
            "actuation": [{"joint": "rz"}],
            "reference": {"rx": 0.0, "ry": 0.0, "rz": 0.0},
        }
    )
    assert isinstance(sidecar, Sidecar)
    write_description(yourdfpy.Robot(name="ball", links=links, joints=joints), sidecar, tmp_path, "ball")
    return plm_pin.load(tmp_path / "ball.urdf")


def spatial_6r(tmp_path: Path, closure: dict) -> Mechanism:
    """A spatial 6R chain with skew axes whose tip frame is closed on a world anchor.

    The anchor is placed where the tip is at a generic configuration ``q0``, so the loop
    is assembled at ``q0``; generically a point closure leaves 3 DOF, a revolute 1, a weld 0.
    """
    import yourdfpy

    from plm_pin.description.sidecar import parse_sidecar

    axes = [(0, 0, 1), (0, 1, 0), (1, 0, 1), (0, 1, 1), (1, 1, 0), (1, 0, 0)]
    offsets = [(0, 0, 0.1), (0.2, 0, 0), (0, 0.15, 0.05), (0.1, 0.1, 0), (0, 0, 0.2), (0.12, -0.05, 0)]
    links = [u.link("base")]
    joints = []
    parent = "base"
    for k, (axis, xyz) in enumerate(zip(axes, offsets, strict=True)):
        name = f"l{k + 1}"
        links.append(u.link(name, 0.5, (0.01, 0.012, 0.014), com=(0.05, 0.0, 0.0)))
        norm = np.linalg.norm(axis)
        joints.append(
            u.joint(f"j{k + 1}", "revolute", parent, name, xyz=xyz, axis=tuple(a / norm for a in axis))
        )
        parent = name
    links.append(u.link("tip"))
    joints.append(u.joint("tip_fixed", "fixed", parent, "tip", xyz=(0.1, 0.02, 0.03)))
    q0 = np.array([0.3, -0.4, 0.5, 0.2, -0.6, 0.7])
    tree = yourdfpy.Robot(name="chain6r", links=links, joints=joints)
    from plm_pin.description.writer import urdf_text

    model = pin.buildModelFromXML(urdf_text(tree))
    data = model.createData()
    pin.framesForwardKinematics(model, data, q0)
    oMt = data.oMf[model.getFrameId("tip")]
    rpy = pin.rpy.matrixToRpy(oMt.rotation)
    links.append(u.link("anchor"))
    joints.append(
        u.joint("anchor_fixed", "fixed", "base", "anchor", xyz=tuple(oMt.translation), rpy=tuple(rpy))
    )
    sidecar = parse_sidecar(
        {
            "format": "plm-pin/1",
            "closures": [{"name": "c", "frames": ["anchor", "tip"], **closure}],
            "actuation": [{"joint": "j1"}],
            "reference": {f"j{k + 1}": float(v) for k, v in enumerate(q0)},
        }
    )
    write_description(
        yourdfpy.Robot(name="chain6r", links=links, joints=joints), sidecar, tmp_path, "chain6r"
    )
    return plm_pin.load(tmp_path / "chain6r.urdf")


@dataclass(frozen=True)
class ReportAll:
    """What the one ``plm-pin report all`` of the session left.

    Attributes:
        out: its output folder.
        exit_code: the command's exit code.
        output: what it printed.
        results: the result of each study it wrote, by study name.
    """

    out: Path
    exit_code: int
    output: str
    results: dict[str, StudyResult]

    def study(self, name: str) -> StudyResult:
        """The result of study ``name``; fails with the command's output when the run did not write it."""
        assert self.exit_code == 0 and name in self.results, self.output
        return self.results[name]


@pytest.fixture(scope="session")
def report_all(tmp_path_factory) -> ReportAll:
    """``plm-pin report all`` run once, through the CLI, for the CLI, browser and study tests.

    Every study runs once in the session: the CLI's calls of ``run_study`` are recorded (not
    replaced), so the study tests read the very results whose reports the command wrote. Under
    pytest-xdist the tests reading it share one worker (``pytest_collection_modifyitems``).
    """
    from typer.testing import CliRunner

    from plm_pin import cli

    if os.environ.get("PYTEST_XDIST_WORKER") and "@report_all" not in os.environ["PYTEST_CURRENT_TEST"]:
        pytest.fail(  # each worker would run it: the tests reading it must share one xdist group
            "report_all on an xdist worker outside the report_all group: run with --dist loadgroup "
            "(pyproject's addopts; pytest 9.2 loses the groups, pytest-xdist#1386)"
        )
    out = tmp_path_factory.mktemp("report_all") / "reports"
    results: dict[str, StudyResult] = {}
    run_study = cli.run_study

    def recorded(*args, **kwargs) -> StudyResult:
        result = run_study(*args, **kwargs)
        results[result.study] = result
        return result

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(cli, "run_study", recorded)
        # one process: the recording sees the studies run here (--jobs 2 is checked in test_cli)
        invoked = CliRunner().invoke(cli.app, ["report", "all", "--out", str(out), "--jobs", "1"])
    return ReportAll(out, invoked.exit_code, invoked.output, results)


KERNEL_PARTS = (("homotopy",), ("kinematics", "dynamics"))
"""The parts of ``tests/compile_kernels.py``, one process each (on a cold cache: about 75 s and 100 s)."""


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist starts its workers (its hook is trylast)
def pytest_sessionstart(session: pytest.Session) -> None:
    """Under pytest-xdist, compile the numba kernels once into their disk cache before the workers start.

    Otherwise, on a cold cache (a fresh clone, CI), each worker compiles the same kernels. A part
    that fails is said and left to the workers: its kernels compile where the tests call them.
    """
    if os.environ.get("PYTEST_XDIST_WORKER") or not getattr(session.config.option, "numprocesses", None):
        return
    script = Path(__file__).with_name("compile_kernels.py")
    runs = [
        subprocess.Popen(
            [sys.executable, str(script), *parts], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
        )
        for parts in KERNEL_PARTS
    ]
    for parts, run in zip(KERNEL_PARTS, runs, strict=True):
        _, err = run.communicate()
        if run.returncode:
            last = (err.decode(errors="replace").strip().splitlines() or ["no message"])[-1]
            print(f"tests/compile_kernels.py {' '.join(parts)} failed ({last}): the workers compile them")


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the groups
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Work units of pytest-xdist (``make test`` runs on 2 workers, ``--dist loadgroup``), longest first.

    The tests reading the session's ``report_all`` share one unit, so ``report all`` runs once;
    every other test shares one with its module, so a module fixture (the docs build, the wheel's
    venv, an overview run) is built once. That unit comes first, then the modules holding slow
    tests, so the short ones fill the end of both workers. The tests of the installed wheel come
    last: its venv takes the kernels the other tests compiled (``tests/test_package.py``).
    A run without xdist ignores the groups.
    """
    groups = {
        item: "report_all" if "report_all" in item.fixturenames else item.nodeid.split("::")[0]
        for item in items
    }
    slow = {groups[item] for item in items if item.get_closest_marker("slow")}
    wheel = {groups[item] for item in items if "wheel_venv" in item.fixturenames}
    items.sort(
        key=lambda item: (groups[item] in wheel, groups[item] != "report_all", groups[item] not in slow)
    )
    for item in items:
        item.add_marker(pytest.mark.xdist_group(groups[item]))


@pytest.fixture
def fourbar(tmp_path) -> Path:
    """A copy of the fourbar preset (URDF + sidecar) in a temporary folder; returns the URDF."""
    for suffix in (".urdf", ".plm.yaml"):
        shutil.copy(urdf_folder() / f"fourbar{suffix}", tmp_path / f"fourbar{suffix}")
    return tmp_path / "fourbar.urdf"


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded random generator."""
    return np.random.default_rng(1234)


def prrrp_paper_configuration(
    mech: Mechanism,
    pose: tuple[float, float, float],
    lengths: tuple[float, ...],
    rt: float,
    signs: tuple[int, ...],
) -> np.ndarray:
    """Configuration of a 2-PRRRP preset from Harada 2011 eqs. (2)-(3), written independently of plm_pin.

    c_i = L_ix + s_i sqrt(l_i^2 - L_iy^2) (clipped at 0 under the root, so a rod can be put
    exactly vertical), phi_i = atan2(L_iy, L_ix - c_i), plate pivot theta - phi_1.
    """
    x, y, theta = pose
    q = mech.q_ref.copy()
    for i, sign in zip((1, 2, 3, 4), signs, strict=True):
        if not mech.model.existJointName(f"slider{i}"):
            continue  # the 3D3M has no leg 3
        s = -rt if i in (1, 2) else rt
        Lx, Ly = x + s * math.cos(theta), y + s * math.sin(theta)
        c = Lx + sign * math.sqrt(max(lengths[i - 1] ** 2 - Ly**2, 0.0))
        phi = math.atan2(Ly, Lx - c)
        q[mech.model.joints[mech.model.getJointId(f"slider{i}")].idx_q] = c
        q[mech.model.joints[mech.model.getJointId(f"rod{i}_pivot")].idx_q] = phi
        if i == 1:
            q[mech.model.joints[mech.model.getJointId("plate_pivot")].idx_q] = theta - phi
    return q


STAR_E = np.array([[0.0, -1.0], [1.0, 0.0]])
"""E of Enferadi 2017 eqs. (4)-(5): the rotation by +90 degrees."""


def star_triangle_legs(pose, side: float = 0.5) -> tuple[np.ndarray, list[tuple[np.ndarray, ...]]]:
    """Enferadi 2017's 3-PRP at ``pose = (x, y, phi)``, apart from plm_pin: ``c`` and legs (P_i, a_i, s_i).

    Rails V1 -> V2, V2 -> V3, V3 -> V1 of the equilateral base V1 = (0, 0), V2 = (a/2, a sqrt(3)/2),
    V3 = (a, 0) (``side`` a [m]): P_i the rail's start, a_i its direction; s_i = -u_i with u_i the
    star line from A_i toward C, at psi_i = phi - 2 pi/3, phi + 2 pi/3, phi.
    """
    x, y, phi = pose
    P = [np.zeros(2), np.array([side / 2, side * math.sqrt(3) / 2]), np.array([side, 0.0])]
    a = [np.array([0.5, math.sqrt(3) / 2]), np.array([0.5, -math.sqrt(3) / 2]), np.array([-1.0, 0.0])]
    psi = [phi - 2 * math.pi / 3, phi + 2 * math.pi / 3, phi]
    s = [-np.array([math.cos(p), math.sin(p)]) for p in psi]
    return np.array([x, y]), list(zip(P, a, s, strict=True))


def star_triangle_eq5(pose, side: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Enferadi 2017 eqs. (4)-(5) (corrected (5)): slider positions q_i and arm lengths rho_i.

    rho_i = -a_i^T E (c - P_i) / (a_i^T E s_i), q_i = s_i^T E (c - P_i) / (s_i^T E a_i), with
    the legs of :func:`star_triangle_legs`.
    """
    c, legs = star_triangle_legs(pose, side)
    E = STAR_E
    q = np.array([s @ E @ (c - P) / (s @ E @ a) for P, a, s in legs])
    rho = np.array([-(a @ E @ (c - P)) / (a @ E @ s) for P, a, s in legs])
    return q, rho


def with_rotated_null_basis(mech: Mechanism, jac, rng: np.random.Generator):
    """The same Jacobians with N replaced by N Q, Q a random orthogonal matrix of determinant -1."""
    from plm_pin.kinematics import ClosedChainJacobians

    Q, _ = np.linalg.qr(rng.normal(size=(jac.N.shape[1], jac.N.shape[1])))
    if np.linalg.det(Q) > 0:
        Q[:, 0] *= -1.0
    NQ = jac.N @ Q
    return ClosedChainJacobians(
        jac.J_phi, jac.J_x, NQ, jac.closure_singular_values, jac.J_x @ NQ, NQ[mech.actuated_v_indices]
    )
