"""The docs site: `make docs` builds with no warning, tutorials executed, every internal link resolving."""

from __future__ import annotations

import html.parser
import re
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
        "guide/accuracy",
        "guide/mujoco",
        "guide/cad-and-mujoco",
        "guide/any-robot",
        "guide/tolerances",
        "guide/reliability",
        "guide/dynamics",
        "guide/simulation",
        "guide/sweeps",
        "guide/reports",
        "guide/shell",
        "guide/viewer",
        "guide/presets",
        "studies",
        "benchmarks",
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


class _Scripts(html.parser.HTMLParser):
    """The src of every script and the href of every stylesheet or preload of a page."""

    def __init__(self) -> None:
        super().__init__()
        self.sources: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if tag == "script" and values.get("src"):
            self.sources.append(values["src"] or "")
        elif tag == "link" and values.get("rel") in ("stylesheet", "preload") and values.get("href"):
            self.sources.append(values["href"] or "")


@pytest.mark.slow
def test_docs_read_offline_with_mathjax_bundled(site):
    """No page loads a script or stylesheet over the network; MathJax is served from the site's _static."""
    remote = []
    for page in sorted(site.rglob("*.html")):
        parser = _Scripts()
        parser.feed(page.read_text(encoding="utf-8"))
        remote += [f"{page.relative_to(site)}: {s}" for s in parser.sources if s.startswith(("http", "//"))]
    assert remote == []
    assert (site / "_static" / "mathjax" / "tex-chtml.js").is_file()
    top = (site / "api" / "plm_pin.html").read_text(encoding="utf-8")
    assert r"\(\phi(q) = 0\)" in top  # a page with formulas, handed to MathJax as LaTeX ...
    assert 'src="../_static/mathjax/tex-chtml.js"' in top  # ... loads the bundled copy


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


def _object_section(page: str, module: str, name: str) -> str:
    """The HTML of the entry ``module.name`` of an API page, up to the next entry of the module."""
    start = page.index(f'id="{module}.{name}"')
    following = re.finditer(rf'id="{re.escape(module)}\.[^".]+"', page[start + 1 :])
    end = next((start + 1 + m.start() for m in following), len(page))
    return page[start:end]


@pytest.mark.slow
def test_api_reference_documents_each_dataclass_field_once(site):
    """Each public field of each public dataclass is described once: not again as a parameter or member."""
    import dataclasses
    import importlib

    shown = {}
    for module, name in _public_names():
        value = getattr(importlib.import_module(module), name)
        if not (isinstance(value, type) and dataclasses.is_dataclass(value)):
            continue
        page = (site / "api" / f"{module.replace('.', '_')}.html").read_text(encoding="utf-8")
        section = _object_section(page, module, name)
        for field in dataclasses.fields(value):
            if not field.name.startswith("_"):
                count = section.count(f"<strong>{field.name}</strong>")
                count += section.count(f'id="{module}.{name}.{field.name}"')
                shown[f"{module}.{name}.{field.name}"] = count
    assert len(shown) > 100  # the result dataclasses were found
    assert {field: count for field, count in shown.items() if count != 1} == {}


@pytest.mark.slow
def test_api_index_gives_each_package_and_module_its_summary(site):
    """The API index and the package pages show the first docstring line of each public package and module."""
    import html as html_module
    import importlib

    quotes = str.maketrans("\u2018\u2019\u201c\u201d", "''\"\"")  # Sphinx's smart quotes, undone

    def text(path: Path) -> str:
        page = html_module.unescape(re.sub(r"<[^>]+>", "", path.read_text(encoding="utf-8")))
        return " ".join(page.translate(quotes).split())

    def first_words(module: str) -> str:  # the longest plain run of the line, between roles and literals
        line = (importlib.import_module(module).__doc__ or "").strip().splitlines()[0]
        return max((piece.strip() for piece in re.split(r"[`:]", line)), key=len)

    index = text(site / "api" / "index.html")
    missing = [m for m in _documented_modules() if not first_words(m) or first_words(m) not in index]
    pages = {m: text(site / "api" / f"{m.replace('.', '_')}.html") for m in _documented_modules()}
    modules = [(p, f"{p}.{n}") for p in pages for n in _module_names(p)]
    missing += [m for p, m in modules if not first_words(m) or first_words(m) not in pages[p]]
    assert missing == []


def _module_names(package: str) -> list[str]:
    """The public (not underscored) modules directly inside a package."""
    import importlib
    import pkgutil

    module = importlib.import_module(package)
    found = pkgutil.iter_modules(getattr(module, "__path__", []))
    return [m.name for m in found if not m.ispkg and not m.name.startswith("_")]


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


MONTH = r"(?:Jan|Feb|Mar|Apr|May|Jun|Jul|Aug|Sep|Oct|Nov|Dec)[a-z]*\.?"
WORK_NOTES = re.compile(
    r"(?i:\bissue\s*#?\d+|\bsessions?\b|\bcProfile\b)"  # any case
    rf"|\b\d{{1,2}} {MONTH} |\b\d{{1,2}} {MONTH}$|\b{MONTH} \d{{1,2}}(?:st|nd|rd|th)?,? \d{{4}}\b"
    rf"|\b{MONTH} \d{{4}}\b|\b20\d\d-\d\d-\d\d\b",
    flags=re.M,
)
"""Development notes a user page must not hold: issue numbers, sessions, profiles, dates of work."""

DATED_PAGES = ("benchmarks.md", "_generated/benchmarks.md")
"""The pages that state when their numbers were measured (the benchmark page and its generated tables)."""


def test_work_notes_pattern_finds_dates_and_issues():
    """The pattern catches issue numbers, sessions and dates, and passes a paper's year or a unit."""
    for note in (
        "issue 12",
        "Issue #18",
        "this session",
        "on 2 Dec",
        "1 December 2026",
        "Dec 2026",
        "2026-12-02",
    ):
        assert WORK_NOTES.search(note), note
    for text in ("Harada 2011", "Zhao 2011, eq. (35)", "2 decoupled axes", "a 12 mm rod", "Fig. 6"):
        assert not WORK_NOTES.search(text), text


def test_user_pages_name_no_issues_sessions_or_dates_of_work():
    """The guide, the front pages, the tutorials and the README name no issue number, session or work date."""
    pages = [p for p in sorted(DOCS.rglob("*.md")) + sorted(DOCS.rglob("*.ipynb")) if "_build" not in p.parts]
    pages = [p for p in pages if p.relative_to(DOCS).as_posix() not in DATED_PAGES and p.name != "README.md"]
    pages.append(DOCS.parent / "README.md")  # the front page of the repository speaks to users too
    assert len(pages) > 20
    found = {
        str(p.relative_to(DOCS.parent)): [
            m.group(0) for m in WORK_NOTES.finditer(p.read_text(encoding="utf-8"))
        ]
        for p in pages
    }
    assert {page: notes for page, notes in found.items() if notes} == {}


def test_benchmark_page_states_the_date_and_machine_of_its_numbers():
    """The benchmark page includes the tables `make bench` wrote, which state the date and the machine."""
    from benchmarks.harness import GENERATED

    page = (DOCS / "benchmarks.md").read_text(encoding="utf-8")
    assert "```{include} _generated/benchmarks.md" in page
    table = (DOCS / "_generated" / "benchmarks.md").read_text(encoding="utf-8")
    assert table.startswith(GENERATED)
    assert re.search(r"^Measured on 20\d\d-\d\d-\d\d on .+ \(\d+ cores", table, flags=re.M)
    assert "| mechanism | case | time per call | floor | ratio |" in table


def test_getting_started_examples_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """The Python blocks of the getting-started page execute as written, in order, in one namespace."""
    monkeypatch.chdir(tmp_path)  # what the examples write stays out of the checkout
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
