"""The docs site: `make docs` builds with no warning, tutorials executed, every internal link resolving."""

from __future__ import annotations

import html.parser
import subprocess
import sys
import urllib.parse
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"


class _Links(html.parser.HTMLParser):
    """The href and src targets of a page."""

    def __init__(self) -> None:
        super().__init__()
        self.targets: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if name in ("href", "src") and value:
                self.targets.append(value)


def _broken_links(site: Path) -> list[str]:
    """Internal links of the built site whose file (or anchor) does not exist."""
    broken = []
    anchors: dict[Path, str] = {}
    for page in sorted(site.rglob("*.html")):
        parser = _Links()
        parser.feed(page.read_text(encoding="utf-8"))
        for target in parser.targets:
            url = urllib.parse.urlsplit(target)
            if url.scheme or url.netloc or target.startswith(("#", "data:", "mailto:")):
                continue
            path = (page.parent / urllib.parse.unquote(url.path)).resolve()
            if not path.exists():
                broken.append(f"{page.relative_to(site)} -> {target}")
            elif url.fragment and path.suffix == ".html":
                text = anchors.setdefault(path, path.read_text(encoding="utf-8"))
                if f'id="{url.fragment}"' not in text:
                    broken.append(f"{page.relative_to(site)} -> {target} (no such anchor)")
    return broken


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built as `make docs` does (warnings are errors), into a temporary folder."""
    out = tmp_path_factory.mktemp("docs")
    build = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(DOCS), str(out)],
        capture_output=True,
        text=True,
    )
    assert build.returncode == 0, build.stderr[-4000:]
    return out


@pytest.mark.slow
def test_docs_build_without_warnings_and_links_resolve(site):
    """The build passes with -W; every internal href/src of every page points to a file and anchor."""
    assert (site / "index.html").is_file()
    assert _broken_links(site) == []


@pytest.mark.slow
def test_docs_have_the_pages_the_user_needs(site):
    """Getting started, every guide page, the tutorials executed, the studies, the API and the schemas."""
    for page in (
        "getting-started",
        "guide/describing",
        "guide/kinematics",
        "guide/singularities",
        "guide/statics",
        "guide/stiffness",
        "guide/mujoco",
        "guide/any-robot",
        "guide/reliability",
        "guide/dynamics",
        "guide/simulation",
        "guide/sweeps",
        "guide/reports",
        "guide/viewer",
        "guide/presets",
        "studies",
        "api/index",
        "tutorials/first_mechanism",
        "tutorials/redundant_table",
        "tutorials/spatial_platform",
    ):
        assert (site / f"{page}.html").is_file(), page
    first = (site / "tutorials" / "first_mechanism.html").read_text(encoding="utf-8")
    assert "closed-form branch differs by" in first  # executed: its outputs are in the page
    for schema in ("plm-pin-sidecar.schema.json", "plm-pin-sweep.schema.json"):
        assert (site / schema).is_file()


def _documented_modules() -> list[str]:
    """The packages the API pages document (docs/_api.py writes one page each at build time)."""
    sys.path.insert(0, str(DOCS))
    try:
        import _api
    finally:
        sys.path.remove(str(DOCS))
    return list(_api.PACKAGES)


def test_api_pages_cover_every_public_package():
    """Each module with an __all__ has an API page, and only those; every package has one."""
    import importlib
    import pkgutil

    import plm_pin

    walked = list(pkgutil.walk_packages(plm_pin.__path__, "plm_pin."))
    public = {"plm_pin"} | {m.name for m in walked if hasattr(importlib.import_module(m.name), "__all__")}
    packages = {m.name for m in walked if m.ispkg}
    assert sorted(packages - public) == []
    assert sorted(_documented_modules()) == sorted(public)


def _public_names() -> list[tuple[str, str]]:
    import importlib

    return [(m, name) for m in _documented_modules() for name in importlib.import_module(m).__all__]


@pytest.mark.slow
def test_api_reference_lists_every_public_name(site):
    """Every name in the __all__ of plm_pin and its public packages has an entry in the API pages."""
    text = "".join(p.read_text(encoding="utf-8") for p in (site / "api").glob("*.html"))
    missing = [
        f"{m}.{n}"
        for m, n in _public_names()
        if f'id="{m}.{n}"' not in text and f'id="module-{m}.{n}"' not in text  # a name or a package
    ]
    assert missing == []


def test_getting_started_examples_run():
    """The Python blocks of the getting-started page execute as written, in order, in one namespace."""
    import re

    page = DOCS / "getting-started.md"
    blocks = re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S)
    assert blocks
    namespace: dict[str, object] = {}
    for block in blocks:
        exec(compile(block, str(page), "exec"), namespace)


def test_sweep_guide_lists_every_metric_and_option():
    """The sweeps page has a table row for every metric and names every option plm_pin.sweep accepts."""
    from plm_pin.sweep import METRICS, OPTIONS

    page = (DOCS / "guide" / "sweeps.md").read_text(encoding="utf-8")
    assert [m for m in METRICS if f"\n| `{m}` |" not in page] == []
    assert [o for o in OPTIONS if f"`{o}`" not in page] == []
