"""The preset registry and the committed descriptions (plm_pin/models/registry.py)."""

from __future__ import annotations

import pytest

from plm_pin.description.writer import urdf_text
from plm_pin.models import PRESETS, preset_names, urdf_folder

ISSUE_PRESETS = {
    "harada2011_3d4m",
    "harada2011_3d3m",
    "harada2015_asymmetric",
    "enferadi2017_star_triangle",
    "zhao2011_8pss",
    "zhao2011_6pss",
    "fourbar",
    "fivebar",
    "planar_3rpr",
    "stewart_6ups",
    "delta",
}


def test_registry_is_sorted_and_consistent():
    """Registry keys are sorted, match preset names, and every preset names its source."""
    assert list(PRESETS) == sorted(PRESETS)
    for name, p in PRESETS.items():
        assert p.name == name
        assert p.source
        assert p.redundancy == p.actuators - p.dof


def test_every_planned_preset_is_registered():
    """The registry holds exactly the presets the foundation issue lists."""
    assert set(preset_names()) == ISSUE_PRESETS


@pytest.mark.parametrize("name", preset_names())
def test_committed_files_equal_the_builders_output(name):
    """urdf/<name>.urdf and .plm.yaml are exactly what the builder writes (run `make urdf`)."""
    robot, sidecar = PRESETS[name].build()
    folder = urdf_folder()
    assert (folder / f"{name}.urdf").read_text() == urdf_text(robot)
    assert (folder / f"{name}.plm.yaml").read_text() == sidecar.to_yaml()


def test_parameters_are_read_only():
    """Preset parameters cannot be changed in place."""
    with pytest.raises(TypeError):
        PRESETS["fourbar"].parameters["crank"] = 1.0  # type: ignore[index]


def test_every_builder_path_names_a_family_or_leg_builder():
    """Each preset's builder_path 'module:function' imports that function from a family's or a leg builder."""
    for p in PRESETS.values():
        module, _, function = p.builder_path.partition(":")
        family = module.startswith("plm_pin.families.") and module.endswith(".builder")
        assert family or (module.startswith("plm_pin.legs.") and function.startswith("build_"))
        assert p.builder.__module__ == module and p.builder.__name__ == function
