"""Descriptions rounded as CAD exports are: they load with a warning and every analysis works.

Each case is an exact description made CAD-like (:mod:`tests.cad`: link frames turned at
random, every ``xyz`` / ``rpy`` rounded to 6 significant digits), so that its planar loops,
modelled in 3D, close only to about 1e-7 m. The oracles are independent of the rounded model:

- the mobility from Grübler's planar count, and the exact description's own answers (IK
  configuration, actuator forces) at the same task pose;
- the least-squares closure residual from SciPy's Levenberg-Marquardt on a Pinocchio model
  built from the rounded file alone;
- MuJoCo's compiled model of the same loops (its equality-constraint Jacobian rank).
"""

from __future__ import annotations

import json
import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from scipy.optimize import least_squares

import plm_pin
from plm_pin.core.assembly import rounded_closure
from plm_pin.core.closures import compile_closures
from plm_pin.core.rank import numerical_rank
from plm_pin.exceptions import ClosureNotSatisfied, InvalidInput
from plm_pin.kinematics import inverse_kinematics, task_pose
from plm_pin.statics import static_forces
from plm_pin.tolerances import RANK_GAP_MIN, RANK_RTOL
from plm_pin.warnings import RoundedClosureWarning
from tests.cad import reframed, rounded
from tests.conftest import INTEROP, load_corpus

URDF = Path(__file__).resolve().parents[2] / "urdf"

# preset -> planar Grübler count 3 (n - 1) - 2 j (n links with the ground, j one-DOF joints)
GRUBLER = {"fourbar": 3 * (4 - 1) - 2 * 4, "harada2011_3d4m": 3 * (10 - 1) - 2 * 12}


def _copy(name: str, folder: Path, digits: int | None = 6, sidecar: dict | None = None) -> Path:
    """The preset ``name`` written CAD-like into ``folder`` (exact when ``digits`` is None)."""
    text = reframed((URDF / f"{name}.urdf").read_text(), seed=1)
    (folder / f"{name}.urdf").write_text(text if digits is None else rounded(text, digits))
    side = yaml.safe_load((URDF / f"{name}.plm.yaml").read_text())
    side.pop("self_collision", None)
    side.update(sidecar or {})
    (folder / f"{name}.plm.yaml").write_text(yaml.safe_dump(side))
    return folder / f"{name}.urdf"


def _load(path: Path, **kwargs) -> tuple[plm_pin.Mechanism, list[warnings.WarningMessage]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RoundedClosureWarning)
        mech = plm_pin.load(path, **kwargs)
    return mech, [w for w in caught if issubclass(w.category, RoundedClosureWarning)]


def _scipy_floor(urdf: Path, frames: list[tuple[str, str]], guess: np.ndarray) -> float:
    """Largest point-closure residual [m] at SciPy's least-squares configuration from ``guess``."""
    model = pin.buildModelFromXML(urdf.read_text())
    data = model.createData()
    pairs = [(model.getFrameId(a), model.getFrameId(b)) for a, b in frames]

    def residual(dq: np.ndarray) -> np.ndarray:
        pin.framesForwardKinematics(model, data, pin.integrate(model, guess, dq))
        return np.concatenate([data.oMf[b].translation - data.oMf[a].translation for a, b in pairs])

    fit = least_squares(residual, np.zeros(model.nv), method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return float(np.abs(fit.fun).max())


@pytest.fixture(scope="module", params=sorted(GRUBLER))
def case(request, tmp_path_factory):
    """(preset name, exact CAD-like mechanism, rounded mechanism, its warnings, rounded file)."""
    name = request.param
    exact, _ = _load(_copy(name, tmp_path_factory.mktemp("exact"), digits=None))
    path = _copy(name, tmp_path_factory.mktemp("rounded"))
    mech, caught = _load(path)
    return name, exact, mech, caught, path


def test_a_rounded_description_loads_with_a_warning_naming_the_tolerance(case):
    """The warning says how far the loops close, why (rounded data) and which tolerance to state."""
    _, exact, mech, caught, _ = case
    assert exact.closure_tol == 1e-12  # the exact CAD-like copy closes: no warning, no tolerance
    assert len(caught) == 1
    text = str(caught[0].message)
    assert "the loops close only to" in text and "coordinates look rounded" in text
    assert (
        f"closure_tolerance: {mech.closure_tol:g}" in text and f"--closure-tol {mech.closure_tol:g}" in text
    )
    assert mech.closure_tol == 1e-5  # 10 x a residual of 1e-7...1e-6, rounded up to a power of ten


def test_the_stated_residual_is_the_least_squares_floor(case):
    """The residual the warning states is SciPy's least-squares residual from the same guess (within 2x)."""
    _, _, mech, caught, path = case
    cut = compile_closures(mech.model, mech.sidecar.closures)
    found = rounded_closure(mech.model, cut, mech.reference_guess(), 1e-12)
    assert found is not None and f"close only to {found.residual:.2g} m/rad" in str(caught[0].message)
    frames = [c.frames for c in mech.sidecar.closures]
    floor = _scipy_floor(path, frames, mech.reference_guess())
    assert 1e-8 < floor <= found.residual <= 2.0 * floor
    assert found.tolerance >= 10.0 * found.residual


def test_the_rounded_mobility_is_gruebler_s_where_a_fixed_tolerance_fails(case):
    """Mobility by the largest singular-value gap equals Grübler's count; a fixed 1e-9 cut would not."""
    name, exact, mech, _, _ = case
    assert mech.mobility == exact.mobility == GRUBLER[name]
    gap = mech.rank_gap
    assert gap.rank == mech.nv - GRUBLER[name] and gap.ratio > RANK_GAP_MIN and 1e-9 < gap.below < 1e-4
    J = mech.closure_jacobian(mech.q_ref)
    assert mech.nv - numerical_rank(J, RANK_RTOL, floor=1.0) < GRUBLER[name]  # the dependent rows counted


def test_assembly_reports_the_tolerance_it_used(case):
    """``assemble`` closes to the mechanism's tolerance by default and reports the one it used."""
    _, _, mech, _, _ = case
    guess = pin.integrate(mech.model, mech.q_ref, np.full(mech.nv, 0.01))
    default = mech.assemble(guess)
    assert default.tolerance == mech.closure_tol and default.residual_norm <= mech.closure_tol
    assert mech.assemble(guess, tol=1e-6).tolerance == 1e-6
    with pytest.raises(ClosureNotSatisfied) as err:
        mech.assemble(guess, tol=1e-12)
    assert err.value.tolerance == 1e-12 and err.value.residual_norm > 1e-9


def test_inverse_kinematics_and_statics_agree_with_the_exact_description(case):
    """IK and actuator forces at the exact model's reference pose match the exact model's to the rounding."""
    _, exact, mech, _, _ = case
    x = task_pose(exact, exact.q_ref)
    sol = inverse_kinematics(mech, x, mech.q_ref)
    assert sol.residual_norm <= mech.closure_tol
    assert np.allclose(mech.actuator_positions(sol.q), exact.actuator_positions(exact.q_ref), atol=1e-5)
    forces = static_forces(mech, sol.q).f_c
    reference = static_forces(exact, exact.q_ref).f_c
    assert np.allclose(forces, reference, rtol=1e-4, atol=1e-6 * np.abs(reference).max())


def test_a_stated_closure_tolerance_loads_without_warning(tmp_path):
    """``closure_tol=`` or the sidecar's ``closure_tolerance`` replaces the guess, with no warning."""
    path = _copy("fourbar", tmp_path)
    mech, caught = _load(path, closure_tol=1e-6)
    assert mech.closure_tol == 1e-6 and not caught and mech.mobility == 1
    side = _copy("fourbar", tmp_path / "..", sidecar={"closure_tolerance": 2e-6})
    mech, caught = _load(side)
    assert mech.closure_tol == 2e-6 and not caught and mech.sidecar.closure_tolerance == 2e-6


def test_a_stated_tolerance_too_small_is_refused_not_rescued(tmp_path):
    """A tolerance below the rounding is the user's statement: the load fails with the residual."""
    with pytest.raises(ClosureNotSatisfied, match="cannot be assembled"):
        _load(_copy("fourbar", tmp_path), closure_tol=1e-9)
    with pytest.raises(InvalidInput, match="closure_tol must be a positive finite number"):
        _load(_copy("fourbar", tmp_path), closure_tol=-1.0)


def test_open_loops_are_still_refused(tmp_path):
    """A rod 1 mm too short is no rounding: the load fails as before, with no warning."""
    path = _copy("fourbar", tmp_path, digits=None)
    text = (
        (URDF / "fourbar.urdf")
        .read_text()
        .replace('<origin xyz="0.125 0.0 0.0"', '<origin xyz="0.124 0.0 0.0"')
    )
    path.write_text(text)
    side = yaml.safe_load(path.with_suffix("").with_suffix(".plm.yaml").read_text())
    side["reference"] = {"crank_pivot": 1.0}
    side["closures"][0]["type"] = "weld"  # a weld cannot absorb the length change by turning
    path.with_suffix("").with_suffix(".plm.yaml").write_text(yaml.safe_dump(side))
    with pytest.raises(ClosureNotSatisfied, match="cannot be assembled"):
        _load(path)


@pytest.mark.skipif(not INTEROP.is_dir(), reason=f"example-parallel-robots corpus absent ({INTEROP})")
@pytest.mark.parametrize(("robot", "mobility", "idle"), [("5bar_linkage", 2, 1), ("robot_delta", 2, 3)])
def test_rounded_corpus_robots_keep_their_mobility(tmp_path, robot, mobility, idle):
    """A corpus robot rounded to 6 digits (weld loops, idle pairs) loads with the exact copy's mobility."""
    folder = tmp_path / robot
    shutil.copytree(INTEROP / robot, folder)
    urdf = folder / "robot.urdf"
    exact = load_corpus(urdf)
    urdf.write_text(rounded(urdf.read_text()))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mech = load_corpus(urdf)
    assert [w for w in caught if issubclass(w.category, RoundedClosureWarning)]
    assert (exact.mobility, exact.idle_mobility) == (mobility, idle)
    assert (mech.mobility, mech.idle_mobility) == (mobility, idle)
    assert mech.rank_gap.clear and mech.closure_tol > 1e-8


def test_the_cli_says_how_far_the_loops_close(tmp_path):
    """`plm-pin check` states the residual and the tolerance to use; `info` shows tolerance and rank gap."""
    from typer.testing import CliRunner

    from plm_pin.cli import app

    path = _copy("harada2011_3d4m", tmp_path)
    checked = CliRunner().invoke(app, ["check", str(path)])
    assert checked.exit_code == 0, checked.output
    text = " ".join(checked.output.split())
    assert "the loops close only to" in text and "closure_tolerance: 1e-05" in text
    assert "mobility 3" in text and "(closure tolerance 1e-05)" in text
    info = CliRunner().invoke(app, ["info", "--json", "--closure-tol", "1e-5", str(path)])
    assert info.exit_code == 0 and "close only to" not in info.output
    summary = json.loads(info.stdout)
    assert summary["closure_tolerance"] == 1e-5 and summary["mobility"] == 3
    assert summary["rank_gap"]["rank"] == 6 and summary["rank_gap"]["ratio"] > RANK_GAP_MIN


def test_an_unvalidated_load_assembles_to_the_tolerance_asked(tmp_path):
    """``validate=False``: ``assemble(tol=1e-5)`` closes from the reference guess and reports 1e-5."""
    mech = plm_pin.load(_copy("fourbar", tmp_path), validate=False)
    assert mech.closure_tol == 1e-12  # nothing was checked, nothing was guessed
    asm = mech.assemble(tol=1e-5)
    assert asm.tolerance == 1e-5 and asm.residual_norm <= 1e-5
    with pytest.raises(ClosureNotSatisfied) as err:
        mech.assemble()
    assert err.value.tolerance == 1e-12


def test_stiffness_and_simulation_agree_with_the_exact_description(case):
    """Task stiffness and a passive fall of the rounded copy match the exact copy's to the rounding."""
    from plm_pin.dynamics.simulation import simulate
    from plm_pin.stiffness import stiffness

    _, exact, mech, _, _ = case
    if mech.sidecar.compliance is not None:
        K, K_exact = stiffness(mech, mech.q_ref).K_x, stiffness(exact, exact.q_ref).K_x
        assert np.abs(K - K_exact).max() <= 1e-5 * np.abs(K_exact).max()
    run = simulate(mech, mech.q_ref, duration=0.2, dt=0.02)
    ref = simulate(exact, exact.q_ref, duration=0.2, dt=0.02)
    assert run.max_residual <= mech.closure_tol
    assert np.abs(mech.actuator_positions(run.q) - exact.actuator_positions(ref.q)).max() < 1e-4


def test_a_rounded_mjcf_loads_and_mujoco_measures_the_same_residual(tmp_path):
    """An MJCF export rounded to 6 digits: warned, mobility kept; MuJoCo's equality residual is ours."""
    mujoco = pytest.importorskip("mujoco")
    from plm_pin.description.mjcf import read_mjcf
    from plm_pin.export import export_mjcf

    exact, _ = _load(_copy("harada2011_3d4m", tmp_path, digits=None))
    export_mjcf(exact, tmp_path / "exact.xml")

    def six(match: re.Match[str]) -> str:
        return f'{match.group(1)}="{" ".join(f"{float(v):.6g}" for v in match.group(2).split())}"'

    text = (tmp_path / "exact.xml").read_text()
    (tmp_path / "rounded.xml").write_text(re.sub(r'\b(pos|quat|axis|euler)="([^"]*)"', six, text))
    mech, caught = _load(tmp_path / "rounded.xml")
    assert caught and mech.mobility == exact.mobility == 3 and mech.closure_tol >= 1e-7
    mjcf = read_mjcf(tmp_path / "rounded.xml")
    found = rounded_closure(
        mech.model, compile_closures(mech.model, mjcf.sidecar.closures), mech.reference_guess(), 1e-12
    )
    assert found is not None and f"close only to {found.residual:.2g} m/rad" in str(caught[0].message)
    data = mujoco.MjData(mjcf.mj_model)
    data.qpos[:] = mjcf.state_map().qpos(found.q)
    mujoco.mj_forward(mjcf.mj_model, data)
    eq = np.array(data.efc_pos[: 3 * len(mjcf.sidecar.closures)])  # the connects' rows, in order
    assert np.abs(eq).max() == pytest.approx(found.residual, rel=1e-9)
