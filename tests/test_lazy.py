"""Deferred imports (plm_pin/_lazy.py)."""

from __future__ import annotations

import importlib
import re

import pytest

from plm_pin._lazy import import_object, lazy_exports, lazy_module


def test_lazy_module_reads_the_real_module_and_keeps_what_it_read():
    """A lazy stand-in gives the module's attribute and keeps it for the next reads."""
    stand_in = lazy_module("json.decoder")
    assert stand_in.JSONDecodeError is importlib.import_module("json.decoder").JSONDecodeError
    assert "JSONDecodeError" in vars(stand_in)


def test_lazy_exports_import_the_named_submodule_and_refuse_other_names():
    """A lazy package __getattr__ imports a mapped name from its submodule, refuses other names."""
    getattr_, dir_ = lazy_exports("json", {"JSONDecodeError": ".decoder"})
    assert getattr_("JSONDecodeError") is importlib.import_module("json.decoder").JSONDecodeError
    with pytest.raises(AttributeError, match="module 'json' has no attribute 'nothing'"):
        getattr_("nothing")
    assert "JSONDecodeError" in dir_() and "dumps" in dir_()


def test_a_lazy_family_lists_its_names_before_importing_them():
    """dir() of the 2-PRRRP package lists every name of its __all__, and each resolves to its module's."""
    import plm_pin.families.prrrp as prrrp
    from plm_pin.families.prrrp import planners

    assert set(prrrp.__all__) <= set(dir(prrrp))
    assert prrrp.plan_working_mode_change is planners.plan_working_mode_change


def test_import_object_reads_module_colon_name():
    """'module:dotted.name' gives the object; a target without a colon is refused with its text."""
    assert import_object("json.decoder:JSONDecodeError.__name__") == "JSONDecodeError"
    with pytest.raises(ValueError, match=re.escape("expected 'module:name', got 'json.decoder'")):
        import_object("json.decoder")
