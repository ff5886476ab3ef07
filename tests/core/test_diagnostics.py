"""What ``plm-pin check`` finds (plm_pin/core/diagnostics.py): a closure deleted by mistake.

Oracle: the four-bar and the 3D3M presets, whose closure frames coincide at the reference
by construction (their closures hold there), with one closure deleted from the sidecar.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from typer.testing import CliRunner

import plm_pin
from plm_pin.cli import app
from plm_pin.core.diagnostics import findings, loose_ends
from plm_pin.models import urdf_folder


def without_last_closure(name: str, tmp_path: Path) -> Path:
    """A copy of preset ``name`` with its last closure deleted from the sidecar; the sidecar's path."""
    shutil.copy(urdf_folder() / f"{name}.urdf", tmp_path)
    sidecar = yaml.safe_load((urdf_folder() / f"{name}.plm.yaml").read_text())
    sidecar["closures"] = sidecar["closures"][:-1]
    path = tmp_path / f"{name}.plm.yaml"
    path.write_text(yaml.safe_dump(sidecar))
    return path


@pytest.mark.parametrize(
    ("name", "pair"),
    [("fourbar", ("coupler_tip", "rocker_tip")), ("harada2011_3d3m", ("plate_right", "rod4_tip"))],
)
def test_deleted_closure_is_named_as_a_loose_end(name, pair, tmp_path):
    """The deleted closure's frames are the loose end found; `check` names it before the task cause."""
    intact = plm_pin.load(name)
    assert loose_ends(intact) == ()
    cut = intact.sidecar.closures[-1]
    assert set(cut.frames) == set(pair)
    mech = plm_pin.load(without_last_closure(name, tmp_path))
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    gap = np.linalg.norm(
        data.oMf[mech.model.getFrameId(pair[0])].translation
        - data.oMf[mech.model.getFrameId(pair[1])].translation
    )
    ends = loose_ends(mech)
    assert len(ends) == 1
    assert {ends[0].frame, ends[0].near} == set(pair)
    assert ends[0].distance == pytest.approx(gap, abs=1e-15)
    assert gap < 1e-9  # the loops closed at the reference before the deletion
    message = findings(mech)[0].message
    assert findings(mech)[0].severity == "error"
    assert message.index("a closure is missing") < message.index("the task lacks coordinates")
    result = CliRunner().invoke(app, ["check", str(without_last_closure(name, tmp_path))])
    assert result.exit_code == 1
    end = ends[0]
    assert (
        f"either a closure is missing: frame {end.frame!r} of leaf body {end.body!r} lies "
        f"{end.distance:.3g} m from frame {end.near!r} of body {end.near_body!r} with no closure "
        "between them (add it under closures), or the task lacks coordinates (add the "
        "missing coordinates to end_effector.task)"
    ) in result.stderr.replace("\n", " ")
