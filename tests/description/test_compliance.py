"""The sidecar's compliance section: parsing, errors, YAML round trip, beam compliance."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from plm_pin.description.compliance import BeamSpec
from plm_pin.description.sidecar import parse_sidecar
from plm_pin.exceptions import DescriptionError

BASE = {"format": "plm-pin/1", "actuation": [{"joint": "slider1"}]}


def _with(compliance):
    return parse_sidecar({**BASE, "compliance": compliance})


def test_round_trip_keeps_every_key():
    """A compliance section survives to_yaml and parse_sidecar unchanged."""
    sidecar = _with(
        {
            "source": "assumed",
            "actuators": {"slider1": "2e7"},  # YAML 1.1 reads 2e7 as a string
            "joints": {"rod1_pivot": 5.0},
            "links": [
                {
                    "link": "rod1",
                    "tip": "rod1_tip",
                    "E": 2e11,
                    "G": 8e10,
                    "A": 1e-4,
                    "Iy": 1e-9,
                    "Iz": 2e-9,
                    "J": 3e-9,
                },
                {"link": "rod2", "tip": "rod2_tip", "compliance": np.diag([1.0, 2, 3, 4, 5, 6]).tolist()},
            ],
        }
    )
    assert sidecar.compliance is not None and sidecar.compliance.actuators == {"slider1": 2e7}
    again = parse_sidecar(yaml.safe_load(sidecar.to_yaml()))
    assert again.compliance == sidecar.compliance


def test_beam_compliance_is_the_cantilever_closed_form():
    """Tip compliance of a beam: L/EA, L^3/3EI, L^2/2EI couplings with their signs, L/GJ."""
    E, G, A, Iy, Iz, J, L = 2e11, 8e10, 1e-4, 1e-9, 2e-9, 3e-9, 0.3
    c = BeamSpec("rod", "tip", (E, G, A, Iy, Iz, J)).tip_compliance(L)
    assert c[0, 0] == pytest.approx(L / (E * A))
    assert c[1, 1] == pytest.approx(L**3 / (3 * E * Iz)) and c[1, 5] == pytest.approx(L**2 / (2 * E * Iz))
    assert c[2, 2] == pytest.approx(L**3 / (3 * E * Iy)) and c[2, 4] == pytest.approx(-(L**2) / (2 * E * Iy))
    assert c[3, 3] == pytest.approx(L / (G * J)) and np.allclose(c, c.T)


@pytest.mark.parametrize(
    ("compliance", "message"),
    [
        ({"actuator": {}}, r"unknown key\(s\) \['actuator'\]; valid keys are"),
        ({"actuators": {"slider1": -1.0}}, "compliance.actuators.slider1 must be a positive finite number"),
        ({"links": [{"link": "rod1", "tip": "t", "E": 1.0}]}, r"missing \['G', 'A', 'Iy', 'Iz', 'J'\]"),
        ({"links": [{"link": "rod1", "tip": "t", "compliance": [[1.0]]}]}, "must be a 6x6 list"),
        ({"links": [{"link": "rod1", "tip": "t", "compliance": (-np.eye(6)).tolist()}]}, "positive definite"),
        (
            {"links": [{"tip": "t", "compliance": np.eye(6).tolist()}]},
            r"links\[0\].link must be a non-empty string",
        ),
    ],
)
def test_errors_name_the_key(compliance, message):
    """Each malformed compliance entry is refused with a message naming it."""
    with pytest.raises(DescriptionError, match=message):
        _with(compliance)
