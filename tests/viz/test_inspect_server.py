"""The live inspector's page server: 127.0.0.1 only, the state function behind its JSON, stopped by Ctrl-C.

The server and the CLI run for real (meshcat subprocesses, sockets); the browser drives the
page in tests/report/test_browser.py.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from plm_pin.viz import Inspector, inspect, inspect_update
from plm_pin.viz.legend import ENTRIES
from plm_pin.viz.meshcat_server import LOCALHOST
from tests.conftest import preset
from tests.viz.test_meshcat_view import listening_addresses

REPO = Path(__file__).resolve().parents[2]
TIMEOUT = 60.0
"""Longest wait for a request or a process [s]."""


def _get(url: str) -> dict:
    with urllib.request.urlopen(url, timeout=TIMEOUT) as reply:
        return json.loads(reply.read())


def _post(url: str, change: object) -> tuple[int, dict]:
    request = urllib.request.Request(url, data=json.dumps(change).encode(), method="POST")
    try:
        with urllib.request.urlopen(request, timeout=TIMEOUT) as reply:
            return reply.status, json.loads(reply.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


@pytest.fixture(scope="module")
def inspector():
    running = inspect(preset("fourbar"))
    yield running
    running.close()


def test_page_listens_on_localhost_only_and_serves_the_page(inspector):
    """The control page binds 127.0.0.1 alone and serves its HTML with the scene's address in the state."""
    host, port = inspector.address
    assert host == LOCALHOST
    if Path("/proc/net/tcp").exists():
        assert listening_addresses(port) == {LOCALHOST}
    with urllib.request.urlopen(inspector.url, timeout=TIMEOUT) as reply:
        assert b'id="scene"' in reply.read()
    state = _get(inspector.url + "state")
    assert state["scene"] == inspector.viewer.url
    assert state["dofs"] == ["rz"]
    assert inspector.legend == [k for k in ENTRIES if k in {*inspector.viewer.legend}]  # no ellipse: rz only
    for key in inspector.legend:
        assert ENTRIES[key].label in state["legend"]


def test_update_endpoint_answers_what_inspect_update_gives(inspector):
    """A posted change returns the state the state function computes from the same state and change."""
    before = inspector.state
    goal = float(before.x[0]) + 0.05
    status, data = _post(inspector.url + "update", {"task": {"rz": goal}})
    assert status == 200
    expected = inspect_update(before, {"task": {"rz": goal}})
    np.testing.assert_allclose(data["q"], expected.q, atol=1e-12)
    assert data["manipulability"] == pytest.approx(expected.manipulability)
    assert inspector.state.x[0] == pytest.approx(goal)


@pytest.mark.parametrize(
    "path, body, code, words",
    [
        ("update", {"task": {"x": 1.0}}, 400, "is not one of"),
        ("update", [1, 2], 400, "mapping"),
        ("nowhere", {}, 404, "no such endpoint"),
    ],
)
def test_bad_requests_answer_the_reason(inspector, path, body, code, words):
    """A malformed change answers 400 with the state function's message; an unknown path 404."""
    status, data = _post(inspector.url + path, body)
    assert status == code and words in data["error"]


@pytest.mark.parametrize("headers", [{"Origin": "http://example.com"}, {"Host": "evil.example:80"}])
def test_requests_from_other_origins_or_hosts_are_refused(inspector, headers):
    """A post from another site's page, or naming another host (DNS rebinding): 403, nothing changed."""
    before = inspector.state
    body = json.dumps({"task": {"rz": 2.0}}).encode()
    request = urllib.request.Request(inspector.url + "update", data=body, method="POST", headers=headers)
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(request, timeout=TIMEOUT)
    assert refused.value.code == 403
    assert inspector.state is before


def test_close_stops_the_page():
    """After close() nothing listens on the page's port."""
    running = Inspector(preset("fourbar"))
    port = running.address[1]
    running.close()
    running.close()
    with pytest.raises(OSError):
        urllib.request.urlopen(f"http://{LOCALHOST}:{port}/state", timeout=TIMEOUT)


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.slow
@pytest.mark.parametrize("started", ["from a terminal", "in a script's background (SIGINT ignored)"])
def test_cli_serves_on_localhost_and_ends_with_ctrl_c(started):
    """`plm-pin inspect` prints its page, answers on 127.0.0.1 only, exits 0 on SIGINT, frees the port.

    A process started in the background of a non-interactive shell inherits SIGINT ignored
    (Python keeps it so); the command restores it, so Ctrl-C or ``kill -INT`` stops it either way.
    """
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    process = subprocess.Popen(
        [sys.executable, "-m", "plm_pin", "inspect", "fourbar"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        preexec_fn=_ignore_sigint if "background" in started else None,
    )
    try:
        assert process.stdout is not None
        line = process.stdout.readline()  # bounded by the inspector's own start-up time-outs
        assert line.startswith("fourbar: http://127.0.0.1:"), line + (
            process.stderr.read() if process.stderr else ""
        )
        url = line.split(": ", 1)[1].strip()
        port = int(url.rsplit(":", 1)[1].strip("/"))
        assert _get(url + "state")["source"] == "fourbar"
        if Path("/proc/net/tcp").exists():
            assert listening_addresses(port) == {LOCALHOST}
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=TIMEOUT) == 0
        if Path("/proc/net/tcp").exists():
            assert listening_addresses(port) == set()
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def test_actuator_forces_are_drawn_as_arrows_along_the_prismatic_axes():
    """Under a load, one arrow per prismatic actuator: at its joint, along its axis, as long as its force."""
    import pinocchio as pin

    from plm_pin.statics import static_forces
    from plm_pin.viz.inspect_server import FORCE_SIZE
    from tests.viz.test_meshcat_view import Scene

    mech = preset("harada2011_3d4m")
    running = Inspector(mech, page=False)
    try:
        state = running.update({"load": [3.0, -2.0, 0.5]})
        scene = Scene(running._window.get_scene())
    finally:
        running.close()
    forces = static_forces(mech, state.q, (3.0, -2.0, 0.5), limits=None).f_c
    data = mech.model.createData()
    pin.computeJointJacobians(mech.model, data, state.q)
    lengths = {}
    for act, f in zip(mech.actuators, forces, strict=True):
        assert act.kind == "prismatic"
        node = f"/meshcat/plm_pin/{mech.name}/forces/f_c {act.joint}"
        shaft, head = scene.transforms[f"{node}/shaft"], scene.transforms[f"{node}/head"]
        h_shaft, h_head = (scene.geometry(f"{node}/{p}")["height"] for p in ("shaft", "head"))
        np.testing.assert_allclose(
            shaft[:3, 3] - 0.5 * h_shaft * shaft[:3, 1], data.oMi[act.joint_id].translation, atol=1e-12
        )
        J = pin.getJointJacobian(mech.model, data, act.joint_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        axis = J[:3, mech.model.joints[act.joint_id].idx_v]
        np.testing.assert_allclose(shaft[:3, 1], np.sign(f) * axis / np.linalg.norm(axis), atol=1e-9)
        np.testing.assert_allclose(head[:3, 1], shaft[:3, 1], atol=1e-12)
        lengths[act.joint] = (h_shaft + h_head, abs(f))
    longest = max(length for length, _ in lengths.values())
    assert longest <= FORCE_SIZE * running.viewer.size * (1 + 1e-9)
    ratios = [length / f for length, f in lengths.values()]
    np.testing.assert_allclose(ratios, ratios[0], rtol=1e-9)  # one scale for every arrow
    assert "force" in running.legend


def test_closed_inspector_leaves_no_socket_open_at_exit():
    """A closed inspector (its page, its connections and its viewer's) leaves no unclosed socket at exit."""
    code = (
        "from plm_pin.viz import inspect\nfrom tests.conftest import preset\n"
        "with inspect(preset('fourbar')) as running:\n"
        "    running.update({'task': {'rz': float(running.state.x[0]) + 0.01}})\n"
    )
    done = subprocess.run(
        [sys.executable, "-X", "dev", "-W", "always::ResourceWarning", "-c", code],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
        cwd=REPO,
        env={**os.environ, "PYTHONPATH": str(REPO)},
    )
    assert done.returncode == 0, done.stderr
    assert "ResourceWarning" not in done.stderr
