"""The square system as a straight-line program (plm_pin/kinematics/homotopy/straight_line.py).

Oracle: the generic evaluation it is traced from (evaluation.generic_system, itself checked
against central differences and the closure residual in test_kernels.py), at random complex
points away from the trace's own inputs.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from plm_pin.kinematics.homotopy import polynomial_form
from plm_pin.kinematics.homotopy.evaluation import evaluate
from plm_pin.kinematics.homotopy.straight_line import TracedBranch, _Tape, system, workspace
from plm_pin.warnings import ReferenceWarning
from tests.conftest import preset

from .rpr import rpr_files
from .test_complete_fk import RPR_BASE, RPR_PLATE, _general_stewart

PRESETS = [
    "fourbar",
    "fivebar",
    "delta",
    "planar_3rpr",
    "stewart_6ups",
    "zhao2011_6pss",
    "zhao2011_8pss",
    "harada2011_3d4m",
    "harada2011_3d3m",
    "harada2015_asymmetric",
    "enferadi2017_star_triangle",
]


def _mechanism(name: str, folder):
    import plm_pin

    if name == "3-RPR":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ReferenceWarning)
            return plm_pin.load(rpr_files(folder, RPR_BASE, RPR_PLATE))
    if name == "general 6-UPS":
        return _general_stewart(folder)
    return preset(name)


@pytest.mark.parametrize("name", [*PRESETS, "3-RPR", "general 6-UPS"])
def test_program_equals_the_generic_evaluation(name, tmp_path):
    """F + b and [F_x F_p] by the program equal the generic evaluation's at random complex points."""
    form = polynomial_form(_mechanism(name, tmp_path))
    program = form.program
    assert program[1].shape[0] > 0
    ws = workspace(form.n, form.n_params, program)
    rng = np.random.default_rng(5)
    for _ in range(5):
        x = rng.normal(size=form.n) + 1j * rng.normal(size=form.n)
        p = rng.normal(size=form.n_params) + 1j * rng.normal(size=form.n_params)
        b = rng.normal(size=form.n) + 1j * rng.normal(size=form.n)
        F, J = system(x, p, b, ws, program)
        F0, Jx, Jp = evaluate(form, x, p, b)
        J0 = np.concatenate([Jx, Jp], axis=1)
        assert np.abs(F - F0).max() <= 1e-13 * np.abs(F0).max()
        assert np.abs(J - J0).max() <= 1e-13 * np.abs(J0).max()
        assert np.array_equal(J == 0, J0 == 0)  # the same structural zeros


@pytest.mark.parametrize("name", PRESETS)
def test_no_instruction_multiplies_by_a_constant_zero_or_one(name):
    """Products by the constants 0 and 1 are folded while tracing: no instruction is left doing one.

    Registers 0 and 1 hold the constants 0 and 1. An instruction r = P a b + S c never reads 0 as a
    factor; a product (S = 0) never reads 1 as one either. A sum reads 1 as ``b`` (its ``a`` times
    one), and an instruction reads 0 as ``c`` only with S = 0.
    """
    constants, instructions, coefficients, _, _ = polynomial_form(preset(name)).program
    assert constants[0] == 0 and constants[1] == 1
    a, b, c = instructions.T
    P, S = coefficients.T
    assert not np.any((a == 0) | (b == 0))
    product = S == 0
    assert not np.any(product & ((a == 1) | (b == 1)))
    assert np.all(S[c == 0] == 0)
    assert set(np.unique(P)) <= {-1.0, 1.0} and set(np.unique(S)) <= {-1.0, 0.0, 1.0}


@pytest.mark.parametrize("name", PRESETS)
def test_the_angles_are_the_revolute_parameters(name):
    """The program takes the cosine and sine of the actuated revolute joints' parameters, no other."""
    from plm_pin.kinematics.homotopy.form import REVOLUTE_PARAM

    form = polynomial_form(preset(name))
    revolute = sorted(int(o) for k, o in zip(form.kind, form.offset, strict=True) if k == REVOLUTE_PARAM)
    assert form.program[4].tolist() == revolute


def test_a_branch_on_a_traced_value_is_refused():
    """The evaluation traced must be straight-line code: comparing a traced value raises TracedBranch."""
    tape = _Tape(2, 1)
    x = tape.input(0)
    with pytest.raises(TracedBranch, match="branches"):
        bool(x * x == 0)
    with pytest.raises(TracedBranch, match="parameters"):
        np.cos(np.array([x], dtype=object))
