"""Writing reports and the index: atomic swaps, paths kept inside the output folder (report/writer.py)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from plm_pin.exceptions import InvalidInput, PlmError
from plm_pin.report import run_study, write_index, write_report
from plm_pin.report import writer as writer_module
from tests.report.conftest import make_study
from tests.report.numbers import unlisted_numbers


@pytest.fixture
def demo_report(tmp_path) -> Path:
    """The demo study written into tmp_path/out; returns the output folder."""
    out = tmp_path / "out"
    write_report(run_study(make_study(), command="plm-pin report demo --out out"), out)
    return out


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_report_files_and_permissions(demo_report):
    """report.html and results.json in <out>/<study>/, readable by all, nothing else left behind."""
    folder = demo_report / "demo"
    assert sorted(p.name for p in demo_report.iterdir()) == ["demo"]
    assert sorted(p.name for p in folder.iterdir()) == ["report.html", "results.json"]
    assert oct(folder.stat().st_mode & 0o777) == "0o755"
    for f in folder.iterdir():
        assert oct(f.stat().st_mode & 0o777) == "0o644"
    data = json.loads((folder / "results.json").read_text())
    assert data["format"] == "plm-pin-report/1" and data["study"] == "demo"
    assert data["agreement"] == {"rows": 3, "agree": 2, "paper_inconsistent": 0}


def test_every_number_in_a_table_is_in_results_json(demo_report):
    """Each table cell of numbers, parsed back from the HTML, is in results.json (to its rounding)."""
    shown, missing = unlisted_numbers(demo_report / "demo")
    assert shown >= 12 and missing == []


def test_a_study_failing_midway_leaves_the_old_report(demo_report):
    """A study that raises after adding sections writes nothing; the previous report stays byte-identical."""
    before = _snapshot(demo_report)

    def run(ctx):
        ctx.section("half").text("written")
        raise PlmError("boom")

    with pytest.raises(PlmError, match="study 'demo' failed: boom"):
        write_report(run_study(make_study(run)), demo_report)
    assert _snapshot(demo_report) == before


def test_a_write_failing_midway_leaves_the_old_report(demo_report, monkeypatch):
    """A failure (or Ctrl-C) while writing the files or swapping folders leaves the old report, no debris."""
    before = _snapshot(demo_report)
    result = run_study(make_study(lambda ctx: ctx.section("new").text("new")))
    real_write, real_rename = Path.write_text, os.rename

    def failing_write(self, *args, **kwargs):
        if self.name == "report.html":
            raise KeyboardInterrupt
        return real_write(self, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", failing_write)
    with pytest.raises(KeyboardInterrupt):
        write_report(result, demo_report)
    monkeypatch.setattr(Path, "write_text", real_write)
    assert _snapshot(demo_report) == before
    assert sorted(p.name for p in demo_report.iterdir()) == ["demo"]

    calls = []
    monkeypatch.setattr(writer_module, "_exchange", lambda a, b: False)  # the two-rename fallback

    def failing_rename(src, dst):
        calls.append((src, dst))
        if len(calls) == 2:  # the new folder into place, after the old one was moved aside
            raise OSError("disk gone")
        return real_rename(src, dst)

    monkeypatch.setattr(writer_module.os, "rename", failing_rename)
    with pytest.raises(OSError, match="disk gone"):
        write_report(result, demo_report)
    assert _snapshot(demo_report) == before
    assert sorted(p.name for p in demo_report.iterdir()) == ["demo"]


def test_a_new_report_replaces_the_old_one_whole(demo_report):
    """Writing again swaps the folder: the new content, no leftovers."""
    write_report(run_study(make_study(lambda ctx: ctx.section("second run").text("new"))), demo_report)
    assert sorted(p.name for p in demo_report.iterdir()) == ["demo"]
    assert "second run" in (demo_report / "demo" / "report.html").read_text()


@pytest.mark.parametrize("folder", ["../x", "..", ".hidden", "a/b", "/tmp/x", "-rf", ""])
def test_report_folders_outside_or_odd_are_refused(tmp_path, folder):
    """A folder name that is not a plain name is refused before anything is written."""
    result = run_study(make_study(lambda ctx: None))
    out = tmp_path / "out"
    odd = type(result)(**{**result.__dict__, "folder": folder})
    with pytest.raises(InvalidInput, match=r"is not a plain name .* nothing is written outside"):
        write_report(odd, out)
    assert list(tmp_path.rglob("*")) == [out]


def test_a_link_in_place_of_a_report_folder_is_not_followed(tmp_path):
    """out/<study> as a symbolic link to elsewhere is refused; its target is untouched."""
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (elsewhere / "keep.txt").write_text("keep")
    (out / "demo").symlink_to(elsewhere)
    with pytest.raises(InvalidInput, match=r"is a link or lies outside"):
        write_report(run_study(make_study(lambda ctx: None)), out)
    assert [p.name for p in elsewhere.iterdir()] == ["keep.txt"]


def test_out_must_be_a_folder(tmp_path):
    """An output path that is a file is refused."""
    path = tmp_path / "file"
    path.write_text("x")
    with pytest.raises(InvalidInput, match=r"is not a folder"):
        write_report(run_study(make_study(lambda ctx: None)), path)


def test_index_links_reports_and_ignores_other_folders(demo_report):
    """The index lists report folders (escaped titles, agreement counts), not foreign or hidden ones."""
    (demo_report / "notes").mkdir()
    (demo_report / "notes" / "results.json").write_text('{"format": "something else"}')
    (demo_report / "broken").mkdir()
    (demo_report / "broken" / "results.json").write_text("{not json")
    (demo_report / ".demo.x.tmp").mkdir()
    page = write_index(demo_report).read_text()
    assert page.count('href="demo/report.html"') == 1
    assert "notes/" not in page and "broken/" not in page and ".tmp" not in page
    assert "Demo &lt;title&gt;" in page and "<title>Demo" not in page
    assert "2 of 3 agree" in page and "1 differ, each explained in the report" in page


def test_scenes_are_pages_beside_the_report_sharing_one_meshcat_bundle(tmp_path):
    """Two reports with two scenes each: one bundle in out/, scene pages load it, none inlines it."""
    from plm_pin.viz import scene_html
    from plm_pin.viz.meshcat_view import meshcat_bundle

    def run(ctx):
        mech = ctx.load("fourbar")
        section = ctx.section("Scenes")
        for k in range(2):
            section.scene(scene_html(mech), f"scene {k}", {"q": mech.q_ref})

    out = tmp_path / "out"
    for name in ("one", "two"):
        write_report(run_study(make_study(run, name=name)), out)
    bundle = meshcat_bundle()
    assert (out / "meshcat.min.js").read_text() == bundle
    assert sorted(p.name for p in out.iterdir()) == ["meshcat.min.js", "one", "two"]
    for name in ("one", "two"):
        folder = out / name
        assert sorted(p.name for p in folder.iterdir()) == [
            "report.html",
            "results.json",
            "scene-1.html",
            "scene-2.html",
        ]
        page = (folder / "report.html").read_text()
        assert page.count('loading="lazy"') == 2 and 'src="scene-1.html"' in page and "srcdoc" not in page
        for scene in ("scene-1.html", "scene-2.html"):
            text = (folder / scene).read_text()
            assert '<script src="../meshcat.min.js"></script>' in text
            assert bundle[:2000] not in text and len(text) < len(bundle) / 10
    assert oct((out / "meshcat.min.js").stat().st_mode & 0o777) == "0o644"


def test_a_page_without_the_bundle_is_kept_whole():
    """share_bundle leaves a page that does not inline meshcat's bundle as it is."""
    from plm_pin.viz.meshcat_view import share_bundle

    page = "<html><script>var x = 1;</script></html>"
    assert share_bundle(page, "../meshcat.min.js") == page
