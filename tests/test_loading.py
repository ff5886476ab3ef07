"""Building mechanisms from parametric builders in memory (plm_pin/loading.py: build_mechanism)."""

from __future__ import annotations

import numpy as np
import pytest

import plm_pin
from plm_pin.description import write_description
from plm_pin.families.prrrp import build_2prrrp
from plm_pin.loading import build_mechanism, resolve_builder
from plm_pin.models import PRESETS
from plm_pin.models.registry import builder_parameters
from plm_pin.workspace import manipulability


def test_variant_equals_the_description_written_and_loaded(tmp_path):
    """A preset variant built in memory is the same model as its description written to disk and loaded."""
    params = {**PRESETS["harada2011_3d3m"].parameters, "half_plate": 0.035}
    robot, sidecar = build_2prrrp(name="v", source="Harada 2011 Fig. 6", **params)
    write_description(robot, sidecar, tmp_path, "v")
    on_disk = plm_pin.load(tmp_path / "v.urdf")
    built = build_mechanism("harada2011_3d3m", {"half_plate": 0.035}, name="v")
    assert built.name == "v" and (built.nq, built.nv, built.mobility) == (on_disk.nq, on_disk.nv, 3)
    assert np.array_equal(built.q_ref, on_disk.q_ref)
    assert manipulability(built, built.q_ref).w == manipulability(on_disk, on_disk.q_ref).w
    assert built.sidecar.source == PRESETS["harada2011_3d3m"].source


def test_preset_parameters_are_overridden_and_the_rest_kept():
    """Only the given parameters change: the plate half length moves the right pair, rods keep 0.14 m."""
    default = build_mechanism("harada2011_3d4m")
    wide = build_mechanism("harada2011_3d4m", {"half_plate": 0.07})
    assert default.name == "harada2011_3d4m_variant"
    assert np.array_equal(default.q_ref, plm_pin.load("harada2011_3d4m").q_ref)
    frame = wide.model.getFrameId("plate_right")
    assert wide.model.frames[frame].placement.translation[0] == pytest.approx(0.14)  # 2 r_t


def test_builder_callable_takes_its_parameters_alone():
    """A builder given as a callable gets exactly the parameters passed (no preset defaults)."""
    params = dict(PRESETS["harada2011_3d3m"].parameters)
    mech = build_mechanism(build_2prrrp, params, name="three")
    assert mech.n_actuators == 3 and mech.redundancy == 0
    builder, base, label = resolve_builder(build_2prrrp)
    assert builder is build_2prrrp and base == {} and label == "plm_pin.families.prrrp.builder:build_2prrrp"


def test_unknown_parameter_and_preset_are_refused_with_the_valid_names():
    """Misspelt parameters and presets raise InvalidInput listing what is valid."""
    with pytest.raises(plm_pin.InvalidInput) as err:
        build_mechanism("harada2011_3d3m", {"rod_length": 0.2})
    assert str(err.value) == (
        "unknown parameter(s) ['rod_length'] of harada2011_3d3m; its parameters are "
        f"{list(builder_parameters(build_2prrrp))}"
    )
    assert "'rod_lengths', 'half_plate'" in str(err.value)
    with pytest.raises(plm_pin.InvalidInput, match=r"unknown preset 'harada'; presets are \['delta', 'enf"):
        build_mechanism("harada")
    with pytest.raises(plm_pin.InvalidInput, match="expected a preset name or a builder callable, got 3"):
        build_mechanism(3)  # type: ignore[arg-type]


def test_builder_parameters_leave_out_the_labels():
    """builder_parameters lists the keyword parameters except name and source, in signature order."""
    names = builder_parameters(build_2prrrp)
    assert names[:2] == ("rod_lengths", "half_plate") and "name" not in names and "source" not in names


def test_the_reference_chooser_named_by_the_loader_is_the_kinematic_step():
    """The loader names its one kinematic step by a string (it sits below the kinematics): it resolves."""
    from plm_pin._lazy import import_object
    from plm_pin.kinematics.reference import away_from_singularities
    from plm_pin.loading import REFERENCE_CHOOSER

    assert import_object(REFERENCE_CHOOSER) is away_from_singularities
