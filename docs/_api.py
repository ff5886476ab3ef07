"""The API reference pages, written by conf.py at every build from the packages' ``__all__``.

One page per public package: ``automodule`` documents its classes and functions (imported
ones included), and each data name of its ``__all__`` gets an ``autodata`` entry (autodoc
does not document imported data by itself), so that every public name has an entry.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import types
from pathlib import Path

from sphinx.pycode import ModuleAnalyzer

PACKAGES = {
    "plm_pin": "The top level: loading and building mechanisms, the `Mechanism` object, the errors.",
    "plm_pin.description": "Reading and writing descriptions: URDF spanning tree plus closure sidecar, MJCF.",
    "plm_pin.core": "The Mechanism and what it is made of: closures, task, legs, idle gauges, assembly, "
    "workspaces.",
    "plm_pin.export": "A Mechanism written as a MuJoCo model (MJCF) that simulates with its loops closed.",
    "plm_pin.models": "The registry of named presets.",
    "plm_pin.kinematics": "Task pose, Jacobians, working modes, inverse and forward kinematics, "
    "singularities, limits, mode graphs and path tracking.",
    "plm_pin.kinematics.homotopy": "Complete forward kinematics: polynomial form of the closures, generic "
    "solve, parameter homotopy, interval certificates.",
    "plm_pin.families": "Mechanism families, one package each, with its builder and its own analyses.",
    "plm_pin.families.classic": "The crank-rocker four-bar and the RRRRR five-bar.",
    "plm_pin.families.prrrp": "The 2-PRRRP (Harada 2011, 2015): builder, layout, assembly and working modes, "
    "mode-change planners, complex singularity.",
    "plm_pin.families.pss": "n-PSS spatial platforms (Zhao 2011's 8-PSS and its 6-PSS counterpart).",
    "plm_pin.families.star_triangle": "The 3-PRP star-triangle (Enferadi 2017).",
    "plm_pin.workspace": "Manipulability, workspace maps, singular loci, orientation range.",
    "plm_pin.statics": "The static balance, actuator-force allocation, reactions, link forces, "
    "force capability.",
    "plm_pin.dynamics": "Trajectories on the closure manifold, inverse dynamics, power and work, task-space "
    "dynamics, decoupling, simulation.",
    "plm_pin.stiffness": "Elastostatics of closed chains: compliant model (virtual joints), Cartesian "
    "stiffness, deflection, natural frequencies, stiffness maps.",
    "plm_pin.sweep": "Design sweeps, local or on Dask, with checkpoints.",
    "plm_pin.viz": "matplotlib figures and meshcat scenes.",
    "plm_pin.report": "Studies and their reports.",
    "plm_pin.schemas": "The JSON Schemas of the sidecar and of the sweep configuration.",
    "plm_pin.warnings": "The warnings plm_pin emits, all subclasses of `PlmWarning`, for filtering.",
    "plm_pin.results": "The result protocol: the base of the result dataclasses, the units of their fields.",
}
"""Public package -> one line saying what it holds."""

SHORT_VALUE = 80
"""Longest value shown in full for a data name [characters]."""


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
    lines = [
        f"# `{package}`",
        "",
        PACKAGES[package],
        "",
        "```{eval-rst}",
        f".. automodule:: {package}",
        "   :members:",
        "   :undoc-members:",
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
    """Write every package's page into ``folder`` (only where its text changed, for Sphinx's cache)."""
    for package in PACKAGES:
        path = folder / f"{page_name(package)}.md"
        text = page(package)
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
