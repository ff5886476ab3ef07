"""The API reference pages, written by conf.py at every build from the packages' ``__all__``.

The index lists each public package with the first line of its docstring. One page per public
package: the first line of each of its modules' docstrings, then ``automodule`` documents its
documented classes and functions (imported ones included), and each data name of its
``__all__`` gets a ``py:data`` entry (autodoc does not document imported data by itself), so
that every public name has an entry. Dataclass fields are documented once, by the class's
``Attributes:`` section (napoleon's ``napoleon_use_ivar``), not again as members.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import types
from pathlib import Path

from sphinx.pycode import ModuleAnalyzer

PACKAGES = (
    "plm_pin",
    "plm_pin.description",
    "plm_pin.core",
    "plm_pin.kernels",
    "plm_pin.kinematics",
    "plm_pin.kinematics.homotopy",
    "plm_pin.families",
    "plm_pin.families.classic",
    "plm_pin.families.prrrp",
    "plm_pin.families.pss",
    "plm_pin.families.star_triangle",
    "plm_pin.models",
    "plm_pin.export",
    "plm_pin.legs",
    "plm_pin.workspace",
    "plm_pin.statics",
    "plm_pin.dynamics",
    "plm_pin.stiffness",
    "plm_pin.sweep",
    "plm_pin.optimize",
    "plm_pin.viz",
    "plm_pin.report",
    "plm_pin.schemas",
    "plm_pin.results",
    "plm_pin.tolerances",
    "plm_pin.warnings",
)
"""The public packages (and modules with an ``__all__``), in the order of the API index."""

INDEX_INTRO = """\
# API reference

Generated from the docstrings: every name in the `__all__` of `plm_pin` and of its public
packages (the pages are written from the `__all__` lists at each build, by `docs/_api.py`).
Units are in brackets in each docstring, SI throughout, angles in radians.

These names are the public API: the functions a user calls, the results they receive, the
errors they catch and the constants they pass as choices. Each is public in one package only
(import it from there); the other names of plm_pin's modules are its internals and may change
without notice.
"""

SHORT_VALUE = 80
"""Longest value shown in full for a data name [characters]."""


def summary(module: str) -> str:
    """The first line of a module's docstring, its reST roles and literals rewritten for MyST."""
    doc = importlib.import_module(module).__doc__ or ""
    line = doc.strip().splitlines()[0] if doc.strip() else ""
    line = re.sub(r":(\w+):`", r"{\1}`", line)  # :math:`x` -> {math}`x`
    return re.sub(r"``([^`]+)``", r"`\1`", line).replace("|", "\\|")


def submodules(package: str) -> list[str]:
    """The public modules of a package (not its subpackages, which have their own page), sorted."""
    module = importlib.import_module(package)
    if not hasattr(module, "__path__"):
        return []
    found = pkgutil.iter_modules(module.__path__, package + ".")
    return sorted(m.name for m in found if not m.ispkg and not m.name.rsplit(".", 1)[1].startswith("_"))


def index() -> str:
    """The MyST page of the API index: each package with its one-line summary, and the toctree."""
    rows = [f"| [`{p}`]({page_name(p)}.md) | {summary(p)} |" for p in PACKAGES]
    return "\n".join(
        [
            INDEX_INTRO,
            "| package | what it holds |",
            "|---|---|",
            *rows,
            "",
            "```{toctree}",
            ":hidden:",
            ":maxdepth: 1",
            "",
            *(page_name(p) for p in PACKAGES),
            "```",
            "",
        ]
    )


def page_name(package: str) -> str:
    """File stem of a package's page, e.g. ``plm_pin_statics``."""
    return package.replace(".", "_")


def _is_data(value: object) -> bool:
    return not (inspect.isclass(value) or inspect.isroutine(value) or isinstance(value, types.ModuleType))


def _attribute_doc(package: str, name: str, value: object) -> tuple[str, list[str]]:
    """The module that defines the data ``name`` re-exported by ``package``, and its docstring lines."""
    module = importlib.import_module(package)
    names = [package]
    if hasattr(module, "__path__"):
        walked = pkgutil.walk_packages(module.__path__, package + ".")
        names += [m.name for m in walked if not m.name.endswith("__main__")]
    for modname in names:
        mod = importlib.import_module(modname)
        if vars(mod).get(name) is value:
            docs = ModuleAnalyzer.for_module(modname).find_attr_docs()
            if ("", name) in docs:
                return modname, [line for line in docs[("", name)] if line is not None]
    return package, []


def _defined_in(package: str, name: str) -> bool:
    """Whether ``package``'s own source assigns ``name`` (automodule then documents it, but dunders)."""
    if name.startswith("__"):
        return False
    source = inspect.getsource(importlib.import_module(package))
    return re.search(rf"^{re.escape(name)}\s*[:=]", source, flags=re.M) is not None


def page(package: str) -> str:
    """The MyST page of one package."""
    module = importlib.import_module(package)
    lines = [f"# `{package}`", ""]  # automodule shows the docstring, its first line the index's summary
    if modules := submodules(package):
        lines += ["| module | what it holds |", "|---|---|"]
        lines += [f"| `{m}` | {summary(m)} |" for m in modules]
        lines += [""]
    lines += [
        "```{eval-rst}",
        f".. automodule:: {package}",
        "   :members:",
        "   :imported-members:",
        "",
    ]
    for name in module.__all__:
        value = getattr(module, name)
        if isinstance(value, types.ModuleType):
            lines += [f"``{name}``: the package :mod:`{value.__name__}` (its own page).", ""]
        elif _is_data(value) and not _defined_in(package, name):
            where, doc = _attribute_doc(package, name, value)
            lines += [f".. py:data:: {name}"]  # in the current module, set by automodule
            shown = repr(value)
            if len(shown) <= SHORT_VALUE and "\n" not in shown:
                lines += [f"   :value: {shown}"]
            lines += [
                "",
                *(f"   {line}" if line else "" for line in doc),
                "",
                f"   Defined in :mod:`{where}`.",
                "",
            ]
    lines += ["```", ""]
    return "\n".join(lines)


def write_pages(folder: Path) -> None:
    """Write the index and every package's page into ``folder`` (only where changed, for Sphinx's cache)."""
    folder.mkdir(exist_ok=True)  # the pages are not committed: a fresh clone has no folder
    pages = {"index": index(), **{page_name(p): page(p) for p in PACKAGES}}
    for stem, text in pages.items():
        path = folder / f"{stem}.md"
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
