"""Study discovery and running (plm_pin/report/study.py)."""

from __future__ import annotations

import sys
import warnings

import pytest

from plm_pin.exceptions import InvalidInput, PlmError
from plm_pin.models import PRESETS
from plm_pin.report import Study, find_study, run_study, study_modules, study_names
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
    for name in [m for m in sys.modules if m.split(".")[0] == "fake_studies"]:  # another test's package
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setattr(study_module, "STUDY_PACKAGE", "fake_studies")
    return package


def test_shipped_studies_are_found():
    """The library's overview and the paper studies of analyses/ are found, each with a title and run()."""
    modules = study_modules()
    assert modules["overview"] == "plm_pin.report.overview" and modules["harada2015"] == "analyses.harada2015"
    assert study_names() == sorted(modules) == list(modules)
    assert {m for m in modules.values() if not m.startswith("analyses.")} == {"plm_pin.report.overview"}
    overview = find_study("overview")
    assert overview.mechanism in PRESETS and overview.title == "Overview"
    assert find_study("harada2015").mechanism is None


def test_private_modules_are_not_studies_and_non_studies_are_refused(fake_package):
    """_helper is skipped; a module without run() is named as not a study; the library's overview stays."""
    assert study_names() == ["broken", "good", "overview"]
    assert find_study("good").mechanism == "fivebar"
    with pytest.raises(PlmError, match=r"^fake_studies.broken is not a study: it must define TITLE"):
        find_study("broken")


def test_unknown_study_lists_the_studies():
    """An unknown name is InvalidInput naming it and the studies."""
    with pytest.raises(InvalidInput, match=r"unknown study 'nope'; studies are \[.*'harada2015'.*\]"):
        find_study("nope")


def test_without_the_analyses_package_only_the_librarys_studies_are_found(monkeypatch):
    """Without the paper studies' package the overview remains; a missing paper study says where it is."""
    monkeypatch.setattr(study_module, "STUDY_PACKAGE", "no_such_studies_package")
    assert study_names() == ["overview"]
    assert find_study("overview").mechanism == "harada2011_3d4m"
    with pytest.raises(
        InvalidInput, match=r"unknown study 'harada2011'; studies are \['overview'\] \(the paper"
    ):
        find_study("harada2011")


def test_a_paper_study_cannot_take_the_name_of_the_librarys_own(fake_package):
    """A module overview.py among the paper studies is refused, named, rather than hiding the overview."""
    (fake_package / "overview.py").write_text('TITLE = "Mine"\n\ndef run(ctx):\n    pass\n')
    with pytest.raises(PlmError, match=r"^fake_studies.overview takes the name of plm_pin's own study"):
        study_names()


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


def test_case_only_for_studies_that_take_one():
    """A case reaches ctx.case of a study with TAKES_CASE; another study refuses a non-empty one."""
    from plm_pin.report import StudyCase

    seen = []
    case = StudyCase(load=(1.0, 2.0), pose={"x": 0.01}, mode=(1, -1), ranges={"y": (0.1, 0.2)})
    taking = Study("demo", "Demo", "", "fivebar", lambda ctx: seen.append(ctx.case), {}, True)
    run_study(taking, case=case)
    assert seen == [case]
    run_study(make_study(lambda ctx: seen.append(ctx.case)), case=StudyCase())  # empty: accepted
    assert seen[-1].empty
    with pytest.raises(
        InvalidInput, match=r"^study 'demo' takes no load, pose, working mode or slice ranges"
    ):
        run_study(make_study(), case=case)
    assert find_study("overview").takes_case and not find_study("harada2015").takes_case


def test_folder_of_a_mechanism_study_names_the_mechanism(user_fivebar):
    """A study of a chosen mechanism writes to STUDY-<mechanism slug>; its origin is the path."""
    result = run_study(make_study(lambda ctx: ctx.load() and None, mechanism="fourbar"), user_fivebar)
    assert result.folder == "demo-fivebar"
    assert result.mechanisms[0].origin == f"description {user_fivebar}"
    assert result.mechanisms[0].parameters == ()
