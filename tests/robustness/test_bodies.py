"""Non-physical bodies are refused naming the link: negative masses, inertias no rigid body has."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from plm_pin import build_mechanism, load
from plm_pin.description.urdf import read_urdf_text
from plm_pin.exceptions import DescriptionError, InvalidInput
from plm_pin.models.registry import PRESETS
from plm_pin.warnings import DescriptionWarning
from tests.robustness.conftest import budget, fourbar_files, fourbar_urdf

CRANK_INERTIA = re.compile(r'(<link name="crank">\s*<inertial>.*?)<inertia [^>]*/>', re.S)


def rotation(angles: tuple[float, float, float]) -> np.ndarray:
    """A rotation matrix from three angles [rad] (z-y-x), to turn principal axes anywhere."""
    a, b, c = angles
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rx = np.array([[1, 0, 0], [0, np.cos(c), -np.sin(c)], [0, np.sin(c), np.cos(c)]])
    return rz @ ry @ rx


def with_crank_inertia(tensor: np.ndarray, mass: float = 0.2) -> str:
    """The four-bar URDF with the crank's inertia (and mass) replaced."""
    t = [[float(v) for v in row] for row in tensor]
    element = (
        f'<inertia ixx="{t[0][0]!r}" ixy="{t[0][1]!r}" ixz="{t[0][2]!r}" iyy="{t[1][1]!r}" '
        f'iyz="{t[1][2]!r}" izz="{t[2][2]!r}"/>'
    )
    text, n = CRANK_INERTIA.subn(lambda m: m.group(1) + element, fourbar_urdf(), count=1)
    assert n == 1
    return text.replace('<mass value="0.2"/>', f'<mass value="{float(mass)!r}"/>', 1)


angles = st.tuples(*[st.floats(-np.pi, np.pi)] * 3)
point_masses = st.lists(
    st.tuples(st.floats(0.01, 1.0), st.tuples(*[st.floats(-0.2, 0.2)] * 3)), min_size=1, max_size=6
)


@budget
@given(cloud=point_masses, turn=angles)
def test_the_inertia_of_any_cloud_of_point_masses_loads(tmp_path_factory, cloud, turn):
    """A tensor summed from point masses (a real body, by construction) is accepted in any orientation."""
    tensor = sum(m * (np.dot(r, r) * np.eye(3) - np.outer(r, r)) for m, r in cloud)
    R = rotation(turn)
    mass = sum(m for m, _ in cloud)
    urdf = fourbar_files(tmp_path_factory.mktemp("b"), urdf=with_crank_inertia(R @ tensor @ R.T, mass))
    load(urdf, validate=False)


def tensor_of(
    kind: str, moments: tuple[float, float], size: float, turn: tuple[float, float, float]
) -> np.ndarray:
    """A tensor no rigid body has, by construction: principal moments (a, b) and a third made bad by ``size``.

    ``negative``: the third is -size times the largest; ``triangle``: it is (a + b)(1 + size).
    """
    a, b = moments
    third = -size * max(a, b) if kind == "negative" else (a + b) * (1.0 + size)
    R = rotation(turn)
    return R @ np.diag([third, a, b]) @ R.T


NOT_A_BODY = {
    "negative": r"link 'crank': the inertia is not positive semi-definite \(",
    "triangle": r"link 'crank': the principal moments of inertia .* break the triangle inequality",
}


@budget
@given(
    kind=st.sampled_from(sorted(NOT_A_BODY)),
    moments=st.tuples(st.floats(1e-6, 1.0), st.floats(1e-6, 1.0)),
    size=st.floats(1e-6, 10.0),
    turn=angles,
)
def test_an_inertia_no_rigid_body_has_is_refused(tmp_path_factory, kind, moments, size, turn):
    """A negative principal moment, or one above the sum of the others (1e-6 relative or more): refused."""
    urdf = fourbar_files(
        tmp_path_factory.mktemp("b"), urdf=with_crank_inertia(tensor_of(kind, moments, size, turn))
    )
    with pytest.raises(DescriptionError, match=NOT_A_BODY[kind]):
        load(urdf, validate=False)


def test_a_third_party_urdf_with_a_broken_triangle_inequality_only_warns():
    """Outside plm-pin descriptions (strict=False, as for erd: robots) the same tensor is a warning."""
    text = with_crank_inertia(np.diag([0.001, 0.001, 0.01]))
    with pytest.warns(DescriptionWarning, match=r"link 'crank': the principal moments of inertia"):
        read_urdf_text(text, None, "third.urdf", strict=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DescriptionWarning)
        negative = with_crank_inertia(np.diag([-0.001, 0.001, 0.001]))
        with pytest.raises(DescriptionError, match="not positive semi-definite"):
            read_urdf_text(negative, None, "third.urdf", strict=False)


@pytest.mark.parametrize("mass", ["-1", "-1e-12", "-inf", "nan", "1e400", "abc", ""])
def test_a_urdf_mass_that_is_negative_or_not_a_number_is_refused(tmp_path, mass):
    """Negative, infinite, NaN or malformed masses are refused naming the link."""
    text = fourbar_urdf().replace('<mass value="0.2"/>', f'<mass value="{mass}"/>', 1)
    urdf = fourbar_files(tmp_path, urdf=text)
    with pytest.raises(
        DescriptionError, match=r"link 'crank': (negative mass|<mass value=.* must hold 1 finite)"
    ):
        load(urdf, validate=False)


MASS_PARAMETERS = sorted(
    (name, key)
    for name, preset in PRESETS.items()
    for key in preset.parameters
    if any(word in key for word in ("mass", "density", "inertia"))
)
"""Every (preset, parameter) that sets a mass, a density or an inertia."""


@pytest.mark.parametrize(("preset", "parameter"), MASS_PARAMETERS)
@pytest.mark.parametrize("value", [-1.0, -1e-9])
def test_a_builder_refuses_a_negative_mass_or_inertia(preset, parameter, value):
    """No builder drops a body's inertial silently: a negative mass or inertia is refused, naming it."""
    default = PRESETS[preset].parameters[parameter]
    # two entries, so that an axisymmetric strut (equal transverse moments, checked first) stays so
    bad = [value, value, *default[2:]] if isinstance(default, (list, tuple)) else value
    with pytest.raises(InvalidInput, match=rf"^{parameter} must be (a finite number|\d+ \w+) >= 0 \[k?g"):
        build_mechanism(preset, {parameter: bad})


def test_the_issue_plate_mass_case():
    """The issue's case: a negative plate mass of the 3D4M is refused naming the parameter and its range."""
    with pytest.raises(InvalidInput, match=r"^plate_mass must be a finite number >= 0 \[kg\], got -1$"):
        build_mechanism("harada2011_3d4m", {"plate_mass": -1})
