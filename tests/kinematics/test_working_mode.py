"""Working modes at a configuration (plm_pin/kinematics/working_mode.py).

Oracle: Harada 2011 eqs. (2)-(3), configurations of the 3D4M built inline with the square-root
sign sigma_i of each leg (:func:`tests.conftest.prrrp_paper_configuration`): a leg's sign flips
with sigma_i alone, and vanishes with the root (a rod normal to the stator, condition (9)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from plm_pin import InvalidInput
from plm_pin.kinematics import guess_mode, working_mode
from tests.conftest import preset, prrrp_paper_configuration

LENGTHS = (0.140,) * 4
RT = 0.05
REFERENCE = (0.0, 0.08, math.radians(-20.0))  # the preset's reference pose (Harada 2011, (M.38))
PAPER_SIGNS = (-1, 1, -1, 1)  # the preset's working modes, the paper's (M.5)


def test_guess_mode_follows_the_square_root_sign_of_each_leg():
    """Flipping sigma_i of eq. (2) flips leg i's sign and no other; no guess means the reference."""
    mech = preset("harada2011_3d4m")
    q = prrrp_paper_configuration(mech, REFERENCE, LENGTHS, RT, PAPER_SIGNS)
    mode = guess_mode(mech, q)
    assert mode is not None and 0 not in mode and len(mode) == 4
    assert guess_mode(mech) == mode  # the reference configuration is the paper's, in its modes
    for leg in range(4):
        signs = tuple(-s if k == leg else s for k, s in enumerate(PAPER_SIGNS))
        flipped = prrrp_paper_configuration(mech, REFERENCE, LENGTHS, RT, signs)
        assert np.max(np.abs(mech.closure_residual(flipped))) < 1e-15
        assert guess_mode(mech, flipped) == tuple(-m if k == leg else m for k, m in enumerate(mode))


def test_guess_mode_is_none_where_a_leg_is_singular():
    """Rods 1 and 2 normal to the stator (their pair at the rods' height): no working mode to keep."""
    mech = preset("harada2011_3d4m")
    q = prrrp_paper_configuration(mech, (0.0, LENGTHS[0], 0.0), LENGTHS, RT, PAPER_SIGNS)
    assert 0 in working_mode(mech, q)
    assert guess_mode(mech, q) is None


def test_guess_mode_refuses_a_guess_of_the_wrong_size():
    """A guess that is not a configuration is InvalidInput naming the guess."""
    mech = preset("harada2011_3d4m")
    with pytest.raises(InvalidInput, match="guess"):
        guess_mode(mech, [0.0, 1.0])
