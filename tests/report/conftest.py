"""Fixtures of the report tests: small studies built inline, and a user's description on disk."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml

from plm_pin.models import urdf_folder
from plm_pin.report import Column, Comparison, Parameter, Study, StudyContext


def demo_run(ctx: StudyContext) -> None:
    """A study with one of each block and a few numbers, on the five-bar."""
    mech = ctx.load("fivebar")
    section = ctx.section("Numbers <b>bold</b>")
    section.text("Some *prose* with <script>alert('text')</script>.")
    section.table(
        "A table",
        ["name", Column("length", "m", ".3f"), Column("count"), "flag", "missing"],
        [("a", 0.1234567, 3, True, None), ("b <i>", 2.5e-9, 7, False, float("nan"))],
    )
    section.comparison(
        "Paper vs plm_pin",
        [
            Comparison("mobility", 2, mech.mobility),
            Comparison("a length", 0.25, 0.2501, "m"),
            Comparison("a drift", 1.0, 1.5, "m", explanation="the paper rounds"),
        ],
    )
    section.parameters("Inputs", [Parameter("rod lengths", (0.240, 0.170), "m", "Fig. 2")])
    section.assumptions("Assumptions", ["<i>gravity</i> along -y"])
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0.0, 1.0], [0.0, 2.0])
    section.figure(fig, "A line.", {"x": [0.0, 1.0], "y": [0.0, 2.0]})


def make_study(
    run: Callable[[StudyContext], None] = demo_run, *, name: str = "demo", mechanism: str | None = None
) -> Study:
    """A study object without a module in analyses/."""
    return Study(name, "Demo <title>", "A demo study.", mechanism, run)


@pytest.fixture
def user_fivebar(tmp_path) -> Path:
    """A copy of the five-bar description in a temporary folder, as a user would have it; the URDF path."""
    folder = tmp_path / "user"
    folder.mkdir()
    for suffix in (".urdf", ".plm.yaml"):
        shutil.copy(urdf_folder() / f"fivebar{suffix}", folder / f"fivebar{suffix}")
    return folder / "fivebar.urdf"


def rename(urdf: Path, name: str) -> None:
    """Set the mechanism name in the sidecar beside ``urdf``."""
    sidecar = urdf.with_name(urdf.stem + ".plm.yaml")
    data = yaml.safe_load(sidecar.read_text())
    data["name"] = name
    sidecar.write_text(yaml.safe_dump(data, sort_keys=False))
