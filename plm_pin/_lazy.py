"""Modules imported on first attribute access, so that ``import plm_pin`` stays light."""

from __future__ import annotations

import importlib
import types
from typing import Any


class LazyModule(types.ModuleType):
    """Stand-in for a module that is imported the first time one of its attributes is read."""

    def __getattr__(self, attr: str) -> Any:
        """Import the module (once: Python caches it) and read ``attr`` from it."""
        return getattr(importlib.import_module(self.__name__), attr)


def lazy_module(name: str) -> Any:
    """A stand-in for module ``name`` that imports it on first use (yourdfpy pulls trimesh: ~1 s)."""
    return LazyModule(name)
