"""Imports deferred to first use, so that ``import plm_pin`` stays light.

``import plm_pin`` loads numpy, pinocchio and the modules that load a description; everything
else (scipy: 0.25 s, yourdfpy and trimesh: ~1 s, the mechanism families and the analyses) is
imported when it is first used:

- a third-party module that a light module needs in a few functions is a :func:`lazy_module`
  stand-in at module level (``scipy_linalg = lazy_module("scipy.linalg")``), so the module's
  code reads as if it were imported there;
- a package that re-exports names from heavy submodules maps each name to its submodule with
  :func:`lazy_exports` (its ``__getattr__`` and ``__dir__``), and imports them for type checkers only;
- a preset names its builder as a ``"module:function"`` string, resolved by :func:`import_object`.
"""

from __future__ import annotations

import importlib
import sys
import types
from collections.abc import Callable, Mapping
from typing import Any


class LazyModule(types.ModuleType):
    """Stand-in for a module that is imported the first time one of its attributes is read."""

    def __getattr__(self, attr: str) -> Any:
        """Import the module (once: Python caches it), read ``attr`` and keep it for the next reads."""
        value = getattr(importlib.import_module(self.__name__), attr)
        setattr(self, attr, value)  # later reads are plain attribute reads (hot loops use them)
        return value


def lazy_module(name: str) -> Any:
    """A stand-in for module ``name`` that imports it on first use (yourdfpy pulls trimesh: ~1 s)."""
    return LazyModule(name)


def lazy_exports(
    package: str, exports: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """A package's module-level ``__getattr__`` and ``__dir__`` importing each re-exported name on use.

    ``__dir__`` lists the re-exported names too, so that ``dir()``, autodoc and completion see them.

    Args:
        package: the package's ``__name__``.
        exports: re-exported name -> the submodule defining it, relative (``".planners"``).

    Returns:
        ``(__getattr__, __dir__)`` (PEP 562); ``__getattr__`` raises ``AttributeError`` for other names.
    """

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(module, package), name)

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__


def import_object(target: str) -> Any:
    """The object named by ``"package.module:name"`` (``name`` may be dotted), imported now.

    Raises:
        ValueError: when ``target`` is not of the form ``module:name``.
    """
    module, sep, name = target.partition(":")
    if not (sep and module and name):
        raise ValueError(f"expected 'module:name', got {target!r}")
    obj: Any = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj
