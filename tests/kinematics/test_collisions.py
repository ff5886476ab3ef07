"""Self-collision (plm_pin/kinematics/collisions.py) on a 3-RRR with spheres at its elbows.

Two spheres of radius rho touch when their centres are closer than 2 rho: the elbows
B_i = A_i + l1 (cos t_i, sin t_i) of Gosselin's closed form decide every pose of a map.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from plm_pin import InvalidInput
from plm_pin.kinematics.collisions import SelfCollision, self_collisions
from plm_pin.workspace import workspace_map
from tests import textbook as tb

XS, YS = np.linspace(-0.06, 0.08, 8), np.linspace(-0.07, 0.06, 7)


def _elbows(pose) -> np.ndarray:
    A, _ = tb.rrr_points(pose)
    t = tb.rrr_ik(pose, (1, 1, 1))
    return A + tb.RRR["l1"] * np.column_stack([np.cos(t), np.sin(t)])


def _closest(pose) -> float:
    B = _elbows(pose)
    return min(float(np.linalg.norm(B[i] - B[k])) for i, k in itertools.combinations(range(3), 2))


@pytest.fixture(scope="module")
def rrr(tmp_path_factory):
    """The 3-RRR with elbow spheres of half the median closest elbow distance over the map."""
    rho = 0.5 * float(np.median([_closest((x, y, tb.RRR_POSE[2])) for x in XS for y in YS]))
    return tb.three_rrr(tmp_path_factory.mktemp("rrr"), elbow_spheres=rho), rho


def test_pairs_leave_out_adjacent_bodies(rrr):
    """Only the three elbow pairs of different legs are checked (a sphere's own leg is adjacent)."""
    mech, _ = rrr
    assert sorted(SelfCollision(mech).pairs) == [("prox0", "prox1"), ("prox0", "prox2"), ("prox1", "prox2")]
    assert SelfCollision(mech, ignore=[("prox0", "prox1")]).pairs == [("prox0", "prox2"), ("prox1", "prox2")]
    with pytest.raises(InvalidInput, match=r"^cannot ignore collisions of 'elbow': no such body; bodies are"):
        SelfCollision(mech, ignore=[("elbow", "prox1")])


def test_map_marks_colliding_poses_by_the_closed_form(rrr):
    """collision_free on an x-y map is |B_i - B_k| > 2 rho for every pair of closed-form elbows."""
    mech, rho = rrr
    grid = workspace_map(mech, ("x", "y"), (XS, YS), tb.RRR_POSE)
    free = grid.collision_free(mech)
    checked = 0
    for i, x in enumerate(XS):
        for j, y in enumerate(YS):
            d = _closest((x, y, tb.RRR_POSE[2]))
            if abs(d - 2 * rho) > 1e-6:
                assert free[i, j] == (d > 2 * rho)
                checked += 1
    assert checked > 40 and 0 < free.sum() < free.size
    i, j = np.argwhere(~free)[0]
    B = _elbows((XS[i], YS[j], tb.RRR_POSE[2]))
    touching = [(f"prox{a}", f"prox{b}") for a, b in itertools.combinations(range(3), 2)]
    expected = [
        p
        for p, (a, b) in zip(touching, itertools.combinations(range(3), 2), strict=True)
        if np.linalg.norm(B[a] - B[b]) < 2 * rho
    ]
    assert sorted(self_collisions(mech, grid.q[i, j])) == expected


def test_sidecar_ignores_pairs(rrr, tmp_path):
    """A sidecar's self_collision.ignore leaves its pairs out; a malformed one is refused."""
    import dataclasses

    from plm_pin.description.sidecar import parse_sidecar
    from plm_pin.exceptions import DescriptionError

    mech, _ = rrr
    data = {**mech.sidecar.to_dict(), "self_collision": {"ignore": [["prox1", "prox2"]]}}
    sidecar = parse_sidecar(data)
    assert sidecar.collision_ignore == (("prox1", "prox2"),)
    assert parse_sidecar(sidecar.to_dict()) == sidecar
    other = dataclasses.replace(mech.sidecar, collision_ignore=sidecar.collision_ignore)
    variant = type(mech)(mech.model, other, name="rrr_ignoring", visual_factory=mech.visual_model.copy)
    assert sorted(SelfCollision(variant).pairs) == [("prox0", "prox1"), ("prox0", "prox2")]
    with pytest.raises(
        DescriptionError, match=r"self_collision.ignore must be a list of \[body, body\] name pairs"
    ):
        parse_sidecar({**data, "self_collision": {"ignore": ["prox1"]}})


def test_harada_sliders_passing_on_the_stator_collide():
    """3D4M turning its plate: two carriages (boxes 3 cm long on one stator) collide iff |c_i - c_j| < 3 cm.

    The sliders of Harada 2011 cannot pass each other on their common stator; here that is a
    self-collision check of the preset's carriage boxes, decided by the slider positions alone.
    Rods and plate move in layers of their own (the sidecar's ignore list): no other pair collides.
    """
    from plm_pin.kinematics import inverse_kinematics, task_pose
    from tests.conftest import preset

    mech = preset("harada2011_3d4m")
    x0, q = task_pose(mech, mech.q_ref), mech.q_ref
    seen = set()
    for theta in np.linspace(0.0, 1.2, 13):
        sol = inverse_kinematics(mech, [x0[0], x0[1], theta], q)
        q = sol.q
        carriages = set(self_collisions(mech, q))
        c = sol.actuators
        expected = {
            (f"carriage{i + 1}", f"carriage{k + 1}")
            for i, k in itertools.combinations(range(4), 2)
            if abs(c[i] - c[k]) < 0.03
        }
        assert carriages == expected
        seen.add(bool(expected))
    assert seen == {True, False}


@pytest.mark.parametrize("name", ["harada2011_3d3m", "harada2011_3d4m", "harada2015_asymmetric"])
def test_harada_reference_is_free_and_only_carriages_share_a_layer(name):
    """At the reference the 2-PRRRP tables are collision-free; the pairs checked are the carriages'.

    Besides the carriage pairs, only the stator (world) against rods and plate stays checked,
    which the drawing keeps apart in depth (z).
    """
    from tests.conftest import preset

    mech = preset(name)
    assert self_collisions(mech, mech.q_ref) == []
    carriages = [b for b in mech.body_names if b.startswith("carriage")]
    checked = set(SelfCollision(mech).pairs)
    assert {p for p in checked if "universe" not in p} == set(itertools.combinations(carriages, 2))


def test_collision_shapes_are_used_where_the_description_has_them(rrr, tmp_path):
    """With <collision> spheres and visual boxes that always overlap, the closed form of the spheres decides.

    The visuals become boxes 2 m wide at the elbows (any two legs' boxes overlap at every pose of
    the map); the spheres move to <collision>: collision_free must still be |B_i - B_k| > 2 rho.
    """
    import re

    import plm_pin

    _, rho = rrr
    tb.three_rrr(tmp_path, elbow_spheres=rho)
    path = tmp_path / "rrr3.urdf"
    visual = re.compile(r"<visual>(.*?)</visual>", re.S)
    box = '<geometry><box size="2 2 2"/></geometry><origin xyz="0.3 0 0" rpy="0 0 0"/>'

    def _swap(match: re.Match) -> str:
        sphere = re.sub(r"<material.*?</material>", "", match.group(1), flags=re.S)
        return f"<visual>{box}</visual><collision>{sphere}</collision>"

    text, n = visual.subn(_swap, path.read_text())
    assert n == 3
    path.write_text(text)
    shaped = plm_pin.load(path)
    assert [g.geometry.__class__.__name__ for g in shaped.visual_model.geometryObjects] == ["Box"] * 3
    assert [g.geometry.__class__.__name__ for g in shaped.collision_model.geometryObjects] == ["Sphere"] * 3
    grid = workspace_map(shaped, ("x", "y"), (XS, YS), tb.RRR_POSE)
    free = grid.collision_free(shaped)
    checked = 0
    for i, x in enumerate(XS):
        for j, y in enumerate(YS):
            d = _closest((x, y, tb.RRR_POSE[2]))
            if abs(d - 2 * rho) > 1e-6:
                assert free[i, j] == (d > 2 * rho)
                checked += 1
    assert checked > 40 and 0 < free.sum() < free.size
