"""What a meshcat scene draws beside the mechanism: framing, legend, rails, platform, base lines, overlays.

Scenes are decoded from meshcat's static HTML (the ``Scene`` of test_meshcat_view.py) and
compared with Pinocchio forward kinematics, the joint limits, brute-force neighbour counts
and the task poses the workspace functions were asked for.
"""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.core.mechanism import Mechanism
from plm_pin.exceptions import InvalidInput
from plm_pin.kinematics.reference import task_pose
from plm_pin.models import PRESETS
from plm_pin.viz import MeshcatViewer, scene_html
from plm_pin.viz.legend import (
    ELEMENT_ID,
    ENTRIES,
    PLATFORM_COLOR,
    RAIL_COLOR,
    SINGULAR_COLORS,
    SKELETON_COLOR,
    VIRTUAL_COLOR,
    LegendEntry,
    legend_html,
    with_legend,
)
from plm_pin.viz.meshcat_view import FILL_FRACTION, boundary_mask, camera_distance
from plm_pin.workspace import singular_points_along, workspace_map
from tests.conftest import preset
from tests.viz.test_meshcat_view import Scene, frame_origins, rgb, root

pytestmark = pytest.mark.skipif(importlib.util.find_spec("meshcat") is None, reason="needs meshcat")


def rod_ends(scene: Scene, path: str) -> tuple[np.ndarray, np.ndarray]:
    """The two ends of a Pinocchio cylinder (along its local z) drawn at ``path`` [m]."""
    T, half = scene.transforms[path], 0.5 * scene.geometry(path)["height"]
    return T[:3, 3] - half * T[:3, 2], T[:3, 3] + half * T[:3, 2]


def bare(name: str) -> Mechanism:
    """The preset without its visual geometry: drawn as a skeleton."""
    mech = preset(name)
    return Mechanism(mech.model, mech.sidecar, name=f"bare_{name}")


# ---------------------------------------------------------------- framing
def test_camera_distance_of_a_known_box():
    """A 0.3 x 0.4 m box: its 0.25 m sphere is tangent to the cone of tangent FILL tan(37.5 deg)."""
    d = camera_distance([0.0, 0.0, 0.0], [0.3, 0.4, 0.0])
    tangent = FILL_FRACTION * math.tan(math.radians(37.5))
    assert d == pytest.approx(0.25 * math.sqrt(1 + tangent**2) / tangent, rel=1e-12)  # 1/sin(atan t)
    moved = camera_distance([1.0, 1.0, 1.0], [1.3, 1.4, 1.0], fill=1.0)  # same size elsewhere, full view
    assert moved == pytest.approx(0.25 / math.sin(math.radians(37.5)), rel=1e-12)


@pytest.mark.parametrize(("lower", "upper", "fill"), [([0, 0], [1, 1, 1], 0.8), ([0, 0, 0], [1, 1, 1], 0.0)])
def test_camera_distance_refuses_bad_input(lower, upper, fill):
    with pytest.raises(InvalidInput):
        camera_distance(lower, upper, fill)


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_6pss"])
def test_the_mechanism_fills_the_view(name):
    """The camera is at camera_distance of the frames' box (by forward kinematics), every corner in view."""
    mech = preset(name)
    viewer = MeshcatViewer(mech, static=True)
    viewer.display()
    scene = Scene(viewer.static_html())
    points = np.array(list(frame_origins(mech, mech.reference_guess()).values()))
    lower, upper = points.min(axis=0), points.max(axis=0)
    c = np.array(scene.properties[("/Cameras/default/rotated/<object>", "position")])
    eye = np.array([c[0], -c[2], c[1]])  # meshcat's turned camera frame (x, z, -y) back to the world
    assert np.linalg.norm(eye) == pytest.approx(camera_distance(lower, upper), rel=1e-12)
    shift = scene.transforms["/meshcat"][:3, 3]
    np.testing.assert_allclose(shift, -0.5 * (lower + upper), atol=1e-12)  # orbit point at the centre
    corners = np.array([[(lower, upper)[b >> k & 1][k] for k in range(3)] for b in range(8)]) + shift
    half_fov = math.radians(75.0) / 2
    for corner in corners:
        ray = corner - eye
        angle = math.acos(np.dot(ray, -eye) / (np.linalg.norm(ray) * np.linalg.norm(eye)))
        assert angle < half_fov  # in view
    radius = 0.5 * np.linalg.norm(upper - lower)
    assert math.atan(radius / np.linalg.norm(eye)) > 0.5 * math.atan(math.tan(half_fov))  # not a speck


# ---------------------------------------------------------------- legend
def test_legend_html_lists_labels_and_swatch_colours():
    entries = [ENTRIES["direct"], LegendEntry("a <b>", (0.0, 0.5, 1.0, 1.0), "dot")]
    text = legend_html(entries)
    assert text.startswith(f'<ul id="{ELEMENT_ID}"') and "direct singularity (type 2)" in text
    assert "a &lt;b&gt;" in text and "rgba(0,128,255,1)" in text
    page = with_legend("<html><body><p>x</p></body></html>", entries)
    assert page.index(ELEMENT_ID) > page.index("<p>x</p>") and page.endswith("</body></html>")
    with pytest.raises(InvalidInput, match="mark 'star' is not one of"):
        legend_html([LegendEntry("x", (0, 0, 0, 1), "star")])
    with pytest.raises(InvalidInput, match="no </body>"):
        with_legend("<p>", entries)


def test_static_page_and_report_scene_carry_the_legend_of_what_is_drawn():
    """The bare five-bar: links, base lines, closure and singularity colours; no rails, no platform."""
    mech = bare("fivebar")
    viewer = MeshcatViewer(mech, static=True)
    viewer.display()
    assert viewer.legend == ["direct", "inverse", "constraint", "closed", "open", "link", "virtual"]
    for page in (viewer.static_html(), scene_html(mech)):
        assert page.count(f'id="{ELEMENT_ID}"') == 1
        legend = page[page.index(ELEMENT_ID) :]
        for key in viewer.legend:
            assert ENTRIES[key].label in legend
        assert ENTRIES["rail"].label not in legend and ENTRIES["force"].label not in legend
    viewer.show_forces(mech.q_ref, [("left_tip", [1.0, 0.0, 0.0], "load")], 0.01)
    assert "force" in viewer.legend
    viewer.display()
    assert "force" not in viewer.legend


# ---------------------------------------------------------------- rails, platform, base lines
def test_rails_span_each_prismatic_stroke_along_its_axis():
    """3D4M: a rail per slider, its stroke long, from the slider's origin at its lower to its upper limit."""
    mech = preset("harada2011_3d4m")
    viewer = MeshcatViewer(mech, static=True)
    viewer.display()
    scene = Scene(viewer.static_html())
    rails = scene.under(f"{root(mech)}/visuals/rails")
    sliders = [a.joint for a in mech.actuators]
    assert sorted(p.rsplit("/", 1)[1] for p in rails) == sorted(sliders)
    model, data = mech.model, mech.model.createData()
    for name in sliders:
        path = f"{root(mech)}/visuals/rails/{name}"
        assert scene.color(path) == rgb(RAIL_COLOR)
        j = model.getJointId(name)
        k = model.joints[j].idx_q
        lower, upper = model.lowerPositionLimit[k], model.upperPositionLimit[k]
        assert scene.geometry(path)["height"] == pytest.approx(upper - lower, abs=1e-12)
        ends = []
        for limit in (lower, upper):
            q = np.array(mech.q_ref)
            q[k] = limit
            pin.forwardKinematics(model, data, q)
            ends.append(data.oMi[j].translation.copy())
        drawn = rod_ends(scene, path)
        assert (
            min(
                np.linalg.norm(drawn[0] - ends[0]) + np.linalg.norm(drawn[1] - ends[1]),
                np.linalg.norm(drawn[0] - ends[1]) + np.linalg.norm(drawn[1] - ends[0]),
            )
            < 1e-9
        )


def test_platform_is_a_closed_polygon_through_its_attachment_points():
    """6-PSS: the edges chain end to start, back to the first, through the six platform closure frames."""
    mech = preset("zhao2011_6pss")
    viewer = MeshcatViewer(mech, static=True)
    viewer.display()
    scene = Scene(viewer.static_html())
    edges = sorted(scene.under(f"{root(mech)}/visuals/platform"), key=lambda p: int(p.rsplit("/", 1)[1]))
    assert len(edges) == 6
    origins = frame_origins(mech, mech.q_ref)
    attachments = np.array([origins[f"platform_p{k}"] for k in range(2, 8)])
    segments = [rod_ends(scene, p) for p in edges]
    for path in edges:
        assert scene.color(path) == rgb(PLATFORM_COLOR)
    vertices = np.array([s[0] for s in segments] + [s[1] for s in segments])
    for a in attachments:
        assert np.min(np.linalg.norm(vertices - a, axis=1)) < 1e-9
    for v in vertices:
        assert np.min(np.linalg.norm(attachments - v, axis=1)) < 1e-9
    index = [[int(np.argmin(np.linalg.norm(attachments - end, axis=1))) for end in seg] for seg in segments]
    neighbours: dict[int, list[int]] = {k: [] for k in range(len(attachments))}
    for a, b in index:
        neighbours[a].append(b)
        neighbours[b].append(a)
    assert all(len(v) == 2 for v in neighbours.values())  # every point ends two edges
    ring, previous = [0], None
    while len(ring) <= len(attachments):  # walk the ring: one cycle through all six, back to the start
        step = next(n for n in neighbours[ring[-1]] if n != previous)
        previous = ring[-1]
        ring.append(step)
    assert ring[-1] == 0 and sorted(ring[:-1]) == list(range(len(attachments)))


def test_base_to_joint_lines_are_thin_dashes_on_the_segment_not_rods():
    """Bare five-bar: dashes from the world origin to each motor, thinner than links, in their own colour."""
    mech = bare("fivebar")
    viewer = MeshcatViewer(mech, static=True)
    viewer.display()
    scene = Scene(viewer.static_html())
    origins = frame_origins(mech, mech.q_ref)
    links = scene.under(f"{root(mech)}/visuals/links")
    rod_radius = scene.geometry(links[0])["radiusTop"]
    for motor in ("left_motor", "right_motor"):
        dashes = scene.under(f"{root(mech)}/visuals/virtual/{motor}")
        assert len(dashes) >= 2
        target = origins[motor]
        covered = 0.0
        for path in dashes:
            assert scene.color(path) == rgb(VIRTUAL_COLOR)
            assert scene.geometry(path)["radiusTop"] < rod_radius
            for end in rod_ends(scene, path):  # on the segment from the origin to the motor
                assert (
                    np.linalg.norm(np.cross(end, target)) < 1e-9
                    and -1e-9 <= end @ target <= target @ target + 1e-9
                )
            covered += scene.geometry(path)["height"]
        assert 0.4 * np.linalg.norm(target) < covered < 0.8 * np.linalg.norm(target)  # gaps between dashes
    for path in links:  # no link starts at the world origin any more
        assert all(np.linalg.norm(end) > 1e-9 for end in rod_ends(scene, path))
        assert scene.color(path) == rgb(SKELETON_COLOR)


# ---------------------------------------------------------------- overlays
def brute_force_boundary(reachable: np.ndarray) -> np.ndarray:
    out = np.zeros_like(reachable)
    n, m = reachable.shape
    for i in range(n):
        for j in range(m):
            if not reachable[i, j]:
                continue
            neighbours = [(i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)]
            out[i, j] = any(not (0 <= a < n and 0 <= b < m) or not reachable[a, b] for a, b in neighbours)
    return out


def test_boundary_mask_matches_a_brute_force_count():
    rng = np.random.default_rng(3)
    for _ in range(20):
        grid = rng.random((7, 9)) < 0.6
        np.testing.assert_array_equal(boundary_mask(grid), brute_force_boundary(grid))
    np.testing.assert_array_equal(boundary_mask([0, 1, 1, 1, 0, 1]), [0, 1, 0, 1, 0, 1])


def test_workspace_overlay_points_are_the_boundary_poses_of_the_map():
    """Five-bar x-y map: one point per boundary pose, at that pose's (x, y) and the task frame's plane."""
    mech = preset("fivebar")
    x0 = task_pose(mech, mech.q_ref)
    xs, ys = np.linspace(x0[0] - 0.3, x0[0] + 0.3, 9), np.linspace(x0[1] - 0.3, x0[1] + 0.3, 9)
    grid = workspace_map(mech, ("x", "y"), (xs, ys))
    viewer = MeshcatViewer(mech, static=True)
    viewer.display()
    points = viewer.show_workspace(grid)
    edge = brute_force_boundary(grid.reachable)
    assert 0 < edge.sum() < grid.reachable.sum()
    expected = np.array([(xs[i], ys[j]) for i, j in zip(*np.nonzero(edge), strict=True)])
    np.testing.assert_allclose(points[:, :2], expected, atol=1e-9)
    z = frame_origins(mech, mech.q_ref)[mech.task.frame][2]
    np.testing.assert_allclose(points[:, 2], z, atol=1e-12)
    page = viewer.static_html()
    assert f"{root(mech)}/overlays/workspace" in Scene(page).objects
    assert ENTRIES["workspace"].label in page[page.index(ELEMENT_ID) :]
    viewer.display(mech.q_ref)  # overlays stay over later configurations
    assert f"{root(mech)}/overlays/workspace" in Scene(viewer.static_html()).objects
    viewer.clear_overlays()
    assert not Scene(viewer.static_html()).under(f"{root(mech)}/overlays")


def test_singular_point_overlay_sits_at_each_points_task_pose():
    """Five-bar along x: the fold points drawn at their (x, y), in the colour of their kind."""
    mech = preset("fivebar")
    x0 = task_pose(mech, mech.q_ref)
    found = singular_points_along(mech, "x", np.linspace(x0[0] - 0.4, x0[0] + 0.4, 21), x0)
    assert found
    viewer = MeshcatViewer(mech, static=True)
    viewer.display()
    drawn = viewer.show_singular_points(found)
    for kind, points in drawn.items():
        expected = np.array([p.x for p in found if p.kind == kind]).reshape(-1, 2)
        np.testing.assert_allclose(points[:, :2], expected, atol=1e-7)
    scene = Scene(viewer.static_html())
    for kind in {p.kind for p in found}:
        attributes = scene.objects[f"{root(mech)}/overlays/singular/{kind}"]["geometries"][0]["data"][
            "attributes"
        ]
        positions, colors = (points_attribute(attributes, name) for name in ("position", "color"))
        np.testing.assert_allclose(positions, drawn[kind], atol=1e-6)  # float32 in the page
        np.testing.assert_allclose(colors, np.tile(SINGULAR_COLORS[kind][:3], (len(positions), 1)), atol=1e-7)


def points_attribute(attributes: dict, name: str) -> np.ndarray:
    """A meshcat point-cloud attribute (an ``Ext`` of float32 data, one row of 3 per point)."""
    return np.frombuffer(attributes[name]["array"].data, dtype=np.float32).reshape(-1, 3)


CLASH_DISTANCE = 0.3
"""Least RGB distance of a preset's visual colour to a singularity colour [-] (the old orange rods: 0.22)."""


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_preset_colours_are_not_singularity_colours(name):
    """No visual of a preset has a colour near yellow, orange or red: a regular pose never looks singular."""
    mech = preset(name)
    colours = {tuple(np.round(obj.meshColor[:3], 6)) for obj in mech.visual_model.geometryObjects}
    assert colours
    for colour in colours:
        for kind, singular in SINGULAR_COLORS.items():
            assert np.linalg.norm(np.subtract(colour, singular[:3])) > CLASH_DISTANCE, (colour, kind)
