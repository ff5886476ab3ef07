"""Study discovery and running (plm_pin/report/study.py)."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest

from plm_pin.exceptions import InvalidInput, PlmError
from plm_pin.models import PRESETS
from plm_pin.report import find_study, run_study, study_names
from plm_pin.report import study as study_module
from plm_pin.warnings import IllConditionedWarning
from tests.report.conftest import make_study


@pytest.fixture
def fake_package(tmp_path, monkeypatch):
    """A studies package ``fake_studies`` with a good study, a non-study and a private helper."""
    package = tmp_path / "fake_studies"
    package.mkdir()
    (package / "__init__.py").write_text('"""Fake studies."""\n')
    (package / "good.py").write_text(
        'TITLE = "Good"\nMECHANISM = "fivebar"\n\ndef run(ctx):\n    ctx.load()\n'
    )
    (package / "broken.py").write_text('TITLE = "No run here"\n')
    (package / "_helper.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(study_module, "STUDY_PACKAGE", "fake_studies")
    return package


def test_shipped_studies_are_found():
    """The analyses package holds the overview and Harada 2015 studies, each with a title and run()."""
    names = study_names()
    assert {"harada2015", "overview"} <= set(names) and names == sorted(names)
    overview = find_study("overview")
    assert overview.mechanism in PRESETS and overview.title == "Overview"
    assert find_study("harada2015").mechanism is None


def test_private_modules_are_not_studies_and_non_studies_are_refused(fake_package):
    """_helper is skipped; a module without run() is named as not a study."""
    assert study_names() == ["broken", "good"]
    assert find_study("good").mechanism == "fivebar"
    with pytest.raises(PlmError, match=r"^fake_studies.broken is not a study: it must define TITLE"):
        find_study("broken")


def test_unknown_study_lists_the_studies():
    """An unknown name is InvalidInput naming it and the studies."""
    with pytest.raises(InvalidInput, match=r"unknown study 'nope'; studies are \[.*'harada2015'.*\]"):
        find_study("nope")


def test_without_the_analyses_package_the_wheel_studies_are_used(monkeypatch, tmp_path):
    """Without ``analyses`` the studies come from plm_pin.studies; a missing paper study says where it is."""
    package = tmp_path / "builtin_studies"
    package.mkdir()
    (package / "__init__.py").write_text("")
    shutil.copy(Path(__file__).resolve().parents[2] / "analyses" / "overview.py", package / "overview.py")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(study_module, "STUDY_PACKAGE", "no_such_studies_package")
    monkeypatch.setattr(study_module, "BUILTIN_STUDIES", "builtin_studies")
    assert study_names() == ["overview"]
    assert find_study("overview").mechanism == "harada2011_3d4m"
    with pytest.raises(
        InvalidInput, match=r"unknown study 'harada2011'; studies are \['overview'\] \(the paper"
    ):
        find_study("harada2011")


def test_run_study_records_mechanisms_sections_and_plm_warnings():
    """The result holds the preset's parameters and notes, the sections, and the PlmWarnings raised."""

    def run(ctx):
        ctx.load("harada2011_3d4m")
        ctx.section("one").text("x")
        warnings.warn(IllConditionedWarning("nearly singular here"), stacklevel=1)

    result = run_study(make_study(run), command="plm-pin report demo --out r")
    (info,) = result.mechanisms
    assert info.origin == "preset harada2011_3d4m"
    assert [p.name for p in info.parameters] == list(PRESETS["harada2011_3d4m"].parameters)
    assert info.assumptions == PRESETS["harada2011_3d4m"].notes
    assert [s.title for s in result.sections] == ["one"]
    assert result.warnings == ("nearly singular here",)
    assert result.command == "plm-pin report demo --out r"
    assert set(result.versions) >= {"plm_pin", "pinocchio", "proxsuite", "highspy", "numpy", "python"}
    assert result.folder == "demo"


def test_a_failing_study_names_itself():
    """A PlmError inside run() becomes 'study NAME failed: ...'."""

    def run(ctx):
        ctx.load("no-such-preset")

    with pytest.raises(PlmError, match=r"^study 'demo' failed: 'no-such-preset' is neither a preset"):
        run_study(make_study(run))


def test_mechanism_only_for_studies_that_take_one():
    """A study without MECHANISM refuses one; ctx.load() without a target says so."""
    with pytest.raises(InvalidInput, match=r"study 'demo' takes no mechanism"):
        run_study(make_study(), "fivebar")
    with pytest.raises(PlmError, match=r"study 'demo' takes no mechanism; give one to ctx.load"):
        run_study(make_study(lambda ctx: ctx.load()))


def test_folder_of_a_mechanism_study_names_the_mechanism(user_fivebar):
    """A study of a chosen mechanism writes to STUDY-<mechanism slug>; its origin is the path."""
    result = run_study(make_study(lambda ctx: ctx.load() and None, mechanism="fourbar"), user_fivebar)
    assert result.folder == "demo-fivebar"
    assert result.mechanisms[0].origin == f"description {user_fivebar}"
    assert result.mechanisms[0].parameters == ()
