"""Options of the wrong type or range: one InvalidInput (or DescriptionError) naming the option, no traceback.

Classes: solver tolerances and iteration caps not > 0; numbers given as text, lists or None; booleans given
as text or numbers; mappings given as lists; names given as lists; results of the wrong kind; profiles
that are not functions; non-finite entries named by index; loads no machine exerts.
"""

from __future__ import annotations

import contextlib
import functools
import math
import re
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from plm_pin import DescriptionError, InvalidInput, SimulationFailed, build_mechanism, load
from plm_pin.description.interop import parse_epr_sidecar
from plm_pin.description.sidecar import ClosureSpec
from plm_pin.dynamics import (
    adaptive_trapezoid_work,
    decoupling_check,
    differentiated_profile,
    inverse_dynamics,
    simulate,
    task_trajectory,
)
from plm_pin.dynamics.trajectory import sampled_profile
from plm_pin.families import prrrp
from plm_pin.kinematics import (
    classify,
    follow_targets,
    forward_kinematics,
    inverse_kinematics,
    same_assembly,
    task_pose,
    track_actuator_path,
    working_mode,
    working_modes,
)
from plm_pin.statics import internal_force_range, static_balance, static_forces, wrench_polygon
from plm_pin.stiffness import deflection, natural_frequencies, stiffness
from plm_pin.sweep import sweep
from plm_pin.workspace import orientation_range, workspace_map, workspace_sweep
from tests.conftest import preset

LIMITS = [(-100.0, 100.0)] * 4
"""Effort limits of the 3D4M's drives for the capability calls [N]."""


@functools.cache
def trajectory():
    """A short task trajectory of the 3D4M (seven samples from the reference pose)."""
    m = preset("harada2011_3d4m")
    t = np.linspace(0.0, 0.06, 7)
    return task_trajectory(m, sampled_profile(t, task_pose(m, m.q_ref) + np.outer(t, [0.1, 0.0, 0.0])), t)


def calls() -> dict[str, Callable[..., Any]]:
    """Each function under test bound to a valid call, so that only the option given varies."""
    m, fb, asym = preset("harada2011_3d4m"), preset("fourbar"), preset("harada2015_asymmetric")
    x, c = task_pose(m, m.q_ref), m.actuator_positions(m.q_ref)
    t = np.linspace(0.0, 0.06, 7)
    return {
        "assemble": lambda **kw: m.assemble(m.q_ref, **kw),
        "inverse_kinematics": lambda **kw: inverse_kinematics(m, x, **kw),
        "forward_kinematics": lambda **kw: forward_kinematics(m, c, **kw),
        "working_modes": lambda **kw: working_modes(m, x, **kw),
        "working_mode": lambda **kw: working_mode(m, m.q_ref, **kw),
        "same_assembly": lambda **kw: same_assembly(m, m.q_ref, m.q_ref, **kw),
        "classify": lambda **kw: classify(m, m.q_ref, **kw),
        "follow_targets": lambda **kw: follow_targets(m, m.q_ref, **{"fixed": {"slider1": [c[0]]}, **kw}),
        "track_actuator_path": lambda **kw: track_actuator_path(m, [c, c], m.q_ref, **kw),
        "static_balance": lambda **kw: static_balance(m, m.q_ref, **kw),
        "static_forces": lambda **kw: static_forces(m, m.q_ref, **kw),
        "inverse_dynamics": lambda **kw: inverse_dynamics(m, trajectory(), **kw),
        "task_trajectory": lambda **kw: task_trajectory(
            m, kw.pop("profile", sampled_profile(t, x + np.outer(t, [0.1, 0.0, 0.0]))), t, **kw
        ),
        "differentiated_profile": lambda **kw: differentiated_profile(lambda s: x, **kw),
        "adaptive_trapezoid_work": lambda **kw: adaptive_trapezoid_work(
            lambda s: np.ones((len(s), 1)), 0, 1, **kw
        ),
        "decoupling_check": lambda **kw: decoupling_check(m, [(0.0, 0.08, 0.0)], **kw),
        "orientation_range": lambda **kw: orientation_range(m, "rz", [-0.1, 0.0, 0.1], **kw),
        "stiffness": lambda **kw: stiffness(m, m.q_ref, **kw),
        "deflection": lambda **kw: deflection(m, m.q_ref, [1.0, 0.0, 0.0], **kw),
        "natural_frequencies": lambda **kw: natural_frequencies(m, m.q_ref, **kw),
        "simulate": lambda **kw: simulate(fb, fb.q_ref, **{"duration": 0.01, "dt": 0.01, **kw}),
        "load": lambda **kw: load("fourbar", **kw),
        "prrrp_state": lambda **kw: prrrp.prrrp_state(asym, asym.q_ref, **kw),
        "pair_solutions": lambda **kw: prrrp.pair_solutions(
            **{"c1": 0.0, "c2": 0.1, "l1": 0.24, "l2": 0.17, **kw}
        ),
        "assembly_mode_graph": lambda **kw: prrrp.assembly_mode_graph(asym, **kw),
        "plan_working_mode_change": lambda **kw: prrrp.plan_working_mode_change(asym, **kw),
        "workspace_map": lambda **kw: workspace_map(m, ("x", "y"), ([0.0, 0.01], [0.08, 0.09]), **kw),
        "wrench_polygon": lambda **kw: wrench_polygon(
            m, m.q_ref, [1.0, 0, 0], [0, 1.0, 0], limits=LIMITS, **kw
        ),
        "internal_force_range": lambda **kw: internal_force_range(m, m.q_ref, **kw),
        "sweep": lambda **kw: sweep("harada2011_3d4m", {"half_plate": [0.05]}, {"y": [0.08]}, **kw),
        "build_mechanism": lambda **kw: build_mechanism("fourbar", **kw),
    }


def refused(function: str, option: str, value: Any, message: str, error: type = InvalidInput) -> None:
    """Call ``function`` with ``option=value``: it raises ``error`` whose message starts with ``message``."""
    with pytest.raises(error) as info:
        calls()[function](**{option: value})
    assert re.match(message, str(info.value)), str(info.value)


TOLERANCES = [
    # solver tolerances and iteration caps: > 0 (a tolerance of 0 is never reached), a whole number >= 1
    ("assemble", "tol", -1e-9, r"tol must be a positive finite number \[m, rad\], got -1e-09$"),
    ("assemble", "tol", 0.0, r"tol must be a positive finite number \[m, rad\], got 0.0$"),
    ("assemble", "tol", "1e-9", r"tol must be a positive finite number \[m, rad\], got '1e-9'$"),
    ("assemble", "tol", [1e-9], r"tol must be a positive finite number \[m, rad\], got \[1e-09\]$"),
    ("assemble", "tol", math.nan, r"tol must be a positive finite number"),
    ("assemble", "max_iterations", 0, r"max_iterations must be a whole number >= 1, got 0$"),
    ("assemble", "max_iterations", -3, r"max_iterations must be a whole number >= 1, got -3$"),
    ("assemble", "max_iterations", "100", r"max_iterations must be a whole number >= 1, got '100'$"),
    ("assemble", "max_iterations", 2.5, r"max_iterations must be a whole number >= 1, got 2.5$"),
    ("assemble", "max_iterations", None, r"max_iterations must be a whole number >= 1, got None$"),
    ("inverse_kinematics", "tol", -1.0, r"tol must be a positive finite number"),
    ("forward_kinematics", "tol", 0, r"tol must be a positive finite number"),
    ("working_modes", "starts_per_leg", 0, r"starts_per_leg must be a whole number >= 1, got 0$"),
    ("working_modes", "starts_per_leg", "12", r"starts_per_leg must be a whole number >= 1"),
    ("working_modes", "seed", -1, r"seed must be a whole number >= 0, got -1$"),
    ("working_mode", "rtol", "1e-9", r"rtol must be a finite number in \[0, 1\), got '1e-9'$"),
    ("working_mode", "rtol", 1.5, r"rtol must be a finite number in \[0, 1\), got 1.5$"),
    ("same_assembly", "tol", None, r"tol must be a positive finite number \[m\], got None$"),
    ("classify", "tol", "1e-6", r"tol must be a finite number >= 0, got '1e-6'$"),
    ("follow_targets", "tol", -1.0, r"tol must be a positive finite number"),
    ("track_actuator_path", "closure_tol", 0.0, r"closure_tol must be a positive finite number"),
    ("track_actuator_path", "tol", "a", r"tol must be a finite number >= 0, got 'a'$"),
    ("static_forces", "singular_rtol", "1e-8", r"singular_rtol must be a finite number in \[0, 1\)"),
    ("inverse_dynamics", "singular_rtol", [1e-8], r"singular_rtol must be a finite number in \[0, 1\)"),
    ("task_trajectory", "tol", -1e-12, r"tol must be a positive finite number \[m, rad\]"),
    ("task_trajectory", "singularity_tol", None, r"singularity_tol must be a finite number >= 0, got None$"),
    ("differentiated_profile", "step", "1e-3", r"step must be a positive finite number \[s\], got '1e-3'$"),
    ("adaptive_trapezoid_work", "tol", "0.001", r"tol must be a positive finite number \[J\], got '0.001'$"),
    ("adaptive_trapezoid_work", "n_max", math.inf, r"n_max must be a whole number >= 1, got inf$"),
    ("decoupling_check", "atol", [0.0], r"atol must be a finite number >= 0, got \[0.0\]$"),
    ("decoupling_check", "velocity_scale", -1.0, r"velocity_scale must be a positive finite number"),
    ("orientation_range", "near", "0.01", r"near must be a finite number >= 0, got '0.01'$"),
    ("orientation_range", "ik_tol", 0.0, r"ik_tol must be a positive finite number \[m, rad\], got 0.0$"),
    ("orientation_range", "reference", "0", r"reference must be a finite number \[rad\], got '0'$"),
    ("deflection", "max_iterations", "30", r"max_iterations must be a whole number >= 1, got '30'$"),
    ("deflection", "max_iterations", 0, r"max_iterations must be a whole number >= 1, got 0$"),
    ("natural_frequencies", "count", "2", r"count must be a positive integer or None, got '2'$"),
    ("simulate", "rtol", "1e-10", r"rtol must be a positive finite number, got '1e-10'$"),
]


@pytest.mark.parametrize(("function", "option", "value", "message"), TOLERANCES, ids=lambda v: str(v)[:24])
def test_tolerances_caps_and_numbers_of_the_wrong_kind_are_refused(function, option, value, message):
    """A negative or zero tolerance, a text or list for a number, a fractional count: named and refused."""
    refused(function, option, value, rf"^{message}")


FLAGS = [
    ("inverse_kinematics", "explain"),
    ("inverse_kinematics", "respect_limits"),
    ("forward_kinematics", "all_modes"),
    ("classify", "raise_if_singular"),
    ("static_forces", "gravity"),
    ("static_balance", "gravity"),
    ("inverse_dynamics", "gravity"),
    ("stiffness", "gravity"),
    ("load", "validate"),
    ("build_mechanism", "validate"),
]


@pytest.mark.parametrize(("function", "option"), FLAGS, ids=str)
@pytest.mark.parametrize("value", ["no", "False", 0, 1.0, None, [True]], ids=repr)
def test_a_boolean_option_takes_true_or_false_only(function, option, value):
    """gravity="no" would count as true: every boolean option refuses text, numbers, None and lists."""
    refused(function, option, value, rf"^{option} must be True or False, got {re.escape(repr(value))}$")


KINDS = [
    # mappings given as lists or numbers, names given as lists, results of the wrong kind
    ("static_forces", "link_limits", [("rod1", (0.0, 1.0))], r"link_limits must be a mapping of link names"),
    ("static_forces", "link_limits", {"rod1": 5.0}, r"link_limits\['rod1'\] must be \(lower, upper\)"),
    ("static_forces", "link_limits", {"rod1": "0, 1"}, r"link_limits\['rod1'\] must be real numbers"),
    ("static_forces", "link_limits", {1: (0.0, 1.0)}, r"link_limits must be keyed by link names \(strings\)"),
    ("static_forces", "min_compression", "5", r"min_compression must be a finite number \[N\], got '5'$"),
    (
        "static_forces",
        "min_compression",
        [5.0],
        r"min_compression must be a finite number \[N\], got \[5.0\]$",
    ),
    (
        "static_forces",
        "internal",
        {"rod2": "a"},
        r"internal\['rod2'\] must be a finite number \[N\], got 'a'$",
    ),
    ("static_forces", "objective", ["norm"], r"objective \['norm'\] is not one of \['norm', 'max'\]$"),
    ("inverse_dynamics", "groups", ["rod1"], r"groups must be a mapping of group names to sequences of body"),
    (
        "inverse_dynamics",
        "groups",
        {"g": "rod1"},
        r"groups\['g'\] must be a sequence of body names, got 'rod1'$",
    ),
    ("inverse_dynamics", "link_limits", 3.0, r"link_limits must be a mapping of link names"),
    (
        "assemble",
        "fixed",
        3,
        r"fixed must be joint names or a mapping from joint name to value \[m, rad\], got 3$",
    ),
    ("assemble", "fixed", [1, 2], r"fixed must be joint names or a mapping"),
    ("assemble", "fixed", {1: 0.0}, r"fixed must map joint names to values, got a key 1$"),
    ("follow_targets", "fixed", [("slider1", [0.0])], r"fixed must be a mapping of one-DOF joint names"),
    ("follow_targets", "task_dofs", "x", r"task_dofs must be a sequence of task coordinate names, got 'x'$"),
    ("build_mechanism", "parameters", [("crank", 0.1)], r"parameters must be a mapping of builder parameter"),
    ("stiffness", "forces", {"f_c": [1.0]}, r"forces must be a StaticForces result \(plm_pin.statics"),
    ("stiffness", "compliance", {"actuators": {}}, r"compliance must be a ComplianceSpec"),
    ("natural_frequencies", "result", "K", r"result must be a StiffnessResult"),
    ("natural_frequencies", "model", ["task"], r"model \['task'\] is not one of"),
    ("deflection", "frame", 3, r"frame must be a frame name \(a string\) or None, got 3$"),
    ("decoupling_check", "mode", (1,), r"mode must hold 4 signs \(\+1 or -1\), one per leg; got \(1,\)$"),
    ("task_trajectory", "profile", None, r"profile must be a function t -> \(x, xd, xdd\) or positions"),
    ("task_trajectory", "profile", "line", r"profile must be a function t -> \(x, xd, xdd\) or positions"),
    ("task_trajectory", "mode", "+-", r"mode must be None or a sequence of signs"),
    ("simulate", "method", ["fixed"], r"method \['fixed'\] is not one of"),
    ("workspace_map", "mode", 1, r"mode must be None or a sequence of signs"),
    ("workspace_map", "mode", (1, -1), r"mode must hold 4 signs \(\+1 or -1\), one per leg; got \(1, -1\)$"),
    ("workspace_map", "workers", "2", r"workers must be a whole number >= 1, got '2'$"),
    ("wrench_polygon", "n", "72", r"n must be a whole number >= 8, got '72'$"),
    ("wrench_polygon", "n", 4, r"n must be a whole number >= 8, got 4$"),
    (
        "internal_force_range",
        "limits",
        {"slider1": (-1.0, 1.0)},
        r"limits must be 'description', None or an \(4, 2\)",
    ),
    ("follow_targets", "s", "uniform", r"s must be real numbers \(array-like\), got 'uniform'$"),
    ("sweep", "metrics", 3, r"metrics must be a non-empty list among"),
    ("sweep", "metrics", [["manipulability"]], r"unknown metric \['manipulability'\]"),
    ("sweep", "base", [("legs", (1, 2, 4))], r"base must be a mapping of builder parameter names to values"),
    ("sweep", "options", ["over"], r"options must be a mapping of option names to values"),
    ("sweep", "pose", "0 0.08 0", r"pose must be real numbers \(array-like\), got '0 0.08 0'$"),
    ("sweep", "store", 3, r"store must be a folder path \(a string or a Path\) or None, got 3$"),
    ("sweep", "progress", True, r"progress must be a function \(done, total\) or None, got True$"),
    ("prrrp_state", "layout", {"legs": []}, r"layout must be a PrrrpLayout \(prrrp_layout\(mech\)\) or None"),
    ("prrrp_state", "tol", "1e-9", r"tol must be a finite number >= 0, got '1e-9'$"),
    ("pair_solutions", "l1", -0.24, r"l1 must be a length > 0 \[m\] \(a finite number\), got -0.24$"),
    ("pair_solutions", "c2", "0.1", r"c2 must be a finite number \[m\], got '0.1'$"),
    ("assembly_mode_graph", "walk_samples", "7", r"walk_samples must be a whole number >= 1, got '7'$"),
    ("assembly_mode_graph", "height", "0.02", r"height must be a finite number \[m\], got '0.02'$"),
    ("plan_working_mode_change", "tilt", "0.5", r"tilt must be a finite number \[rad\], got '0.5'$"),
    ("plan_working_mode_change", "samples", 101.0, r"samples must be a whole number >= 5, got 101.0$"),
]


@pytest.mark.parametrize(("function", "option", "value", "message"), KINDS, ids=lambda v: str(v)[:24])
def test_mappings_names_and_results_of_the_wrong_kind_are_refused(function, option, value, message):
    """A list for a mapping, a list for a name, a dict for a result: named, with the valid form."""
    refused(function, option, value, rf"^{message}")


NONFINITE = [
    ("static_forces", "internal", [math.nan], r"internal has non-finite entries at indices \[0\]$"),
    (
        "static_forces",
        "weights",
        [1.0, math.nan, 1.0, math.inf],
        r"weights has non-finite entries at indices \[1, 3\]$",
    ),
    (
        "static_forces",
        "weights",
        np.where(np.eye(4) > 0, 1.0, np.nan),
        r"weights has non-finite entries at indices \[\(0, 1\), \(0, 2\)",
    ),
    ("inverse_dynamics", "internal", [math.inf], r"internal has non-finite entries at indices \[0\]$"),
    ("stiffness", "internal", [math.nan], r"internal has non-finite entries at indices \[0\]$"),
]


@pytest.mark.parametrize(("function", "option", "value", "message"), NONFINITE, ids=lambda v: str(v)[:24])
def test_non_finite_entries_are_named_by_their_indices_not_by_a_shape(function, option, value, message):
    """NaN in internal or weights: the message says which entries, not 'got shape (1,)'."""
    refused(function, option, value, rf"^{message}")


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("actuator_forces", [1e300], r"actuator_forces reaches 1e\+300 N \(N m\), beyond 1e\+12"),
        ("actuator_forces", [-2e12], r"actuator_forces reaches 2e\+12 N \(N m\), beyond 1e\+12"),
        ("wrench", [1e300, 0.0, 0.0, 0.0, 0.0, 0.0], r"wrench reaches 1e\+300 N \(N m\)"),
    ],
)
def test_simulate_refuses_a_load_no_machine_exerts(option, value, message):
    """1e300 N ended in 'LinAlgError: SVD did not converge'; now refused at the entry as not physical."""
    refused("simulate", option, value, rf"^{message}")


def test_simulate_still_runs_a_large_but_physical_load():
    """1e3 N m on the four-bar's crank is a load: the run goes (or stops with SimulationFailed), unrefused."""
    fb = preset("fourbar")
    with contextlib.suppress(SimulationFailed):
        simulate(fb, fb.q_ref, duration=0.01, dt=0.01, actuator_forces=[1e3])


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"type": ["point"]}, r"closure 'c': invalid closure type \['point'\]; valid types are"),
        ({"type": "ball"}, r"closure 'c': invalid closure type 'ball'"),
        ({"frames": ("a",)}, r"closure 'c': frames must be a pair of frame names, got \('a',\)$"),
        ({"frames": ("a", 2)}, r"closure 'c': frames must be a pair of frame names"),
        ({"name": 3}, r"closure 3: the name must be a string$"),
        ({"type": "revolute", "axis": (0.0, math.nan, 1.0)}, r"closure 'c': axis must be 3 finite numbers"),
        ({"type": "revolute", "axis": "001"}, r"closure 'c': axis must be 3 finite numbers"),
    ],
)
def test_a_closure_built_in_python_checks_its_types(changes, message):
    """A ClosureSpec built in Python with a closure type given as a list: DescriptionError, not KeyError."""
    given = {"name": "c", "frames": ("a", "b"), "type": "point", **changes}
    with pytest.raises(DescriptionError, match=rf"^{message}"):
        ClosureSpec(**given)


def test_an_example_parallel_robots_closure_type_given_as_a_list_is_refused():
    """robot.yaml's type: [[3d]] was 'TypeError: unhashable type: list'; now the entry is named."""
    data = {"closed_loop": [["a", "b"]], "type": [["3d"]], "name_mot": ["m"]}
    with pytest.raises(
        DescriptionError,
        match=r"^robot.yaml: type\[0\]: invalid constraint type \[\['3d'\]\]|"
        r"type\[0\]: invalid constraint type",
    ):
        parse_epr_sidecar(data, "robot.yaml")


@functools.cache
def _drawables() -> dict[str, Any]:
    """A map, a sweep and a static solution of the 3D4M to draw."""
    m = preset("harada2011_3d4m")
    return {
        "grid": workspace_map(m, ("x", "y"), ([0.0, 0.01], [0.08, 0.09])),
        "line": workspace_sweep(m, "x", [0.0, 0.01]),
        "forces": static_forces(m, m.q_ref),
    }


VIZ = [
    ("plot_map", "ax", "left", r"ax must be matplotlib Axes or None, got 'left'$"),
    ("plot_map", "loci", [1, 2], r"loci must be a sequence of SingularPoint"),
    ("plot_map", "metric", ["manipulability"], r"unknown metric \['manipulability'\]"),
    ("plot_sweep", "singular", 0.1, r"singular must be a sequence of SingularPoint"),
    ("plot_sweep", "label", ["w"], r"label must be a string or None, got \['w'\]$"),
    ("plot_static_forces", "overlay", {"f_c": 1.0}, r"overlay must be a StaticForces result or None"),
    ("plot_static_forces", "scale", -1.0, r"scale must be a positive finite number \[m/N\], got -1.0$"),
    ("panel_grid", "width", "4", r"width must be a positive finite number \[in\], got '4'$"),
    ("plot_panels", "labels", "ab", r"labels must be a sequence of legend texts \(strings\), got 'ab'$"),
    ("plot_panels", "noise", "1e-9", r"noise must be a finite number >= 0, got '1e-9'$"),
]


@pytest.mark.parametrize(("function", "option", "value", "message"), VIZ, ids=lambda v: str(v)[:24])
def test_figure_options_of_the_wrong_kind_are_refused(function, option, value, message):
    """Axes, marked points, labels, scales and sizes of the figures: named, with their valid form."""
    pytest.importorskip("matplotlib")
    from plm_pin import viz

    d = _drawables()
    call = {
        "plot_map": lambda **kw: viz.plot_map(d["grid"], **kw),
        "plot_sweep": lambda **kw: viz.plot_sweep(d["line"], **kw),
        "plot_static_forces": lambda **kw: viz.plot_static_forces(d["forces"], **kw),
        "panel_grid": lambda **kw: viz.panel_grid(2, **kw),
        "plot_panels": lambda **kw: viz.plot_panels([0.0, 1.0], {"a [m]": [0.0, 1.0]}, xlabel="t [s]", **kw),
    }[function]
    with pytest.raises(InvalidInput, match=rf"^{message}"):
        call(**{option: value})
