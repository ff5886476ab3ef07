"""Meshcat inspection (plm_pin/viz/meshcat_view.py, meshcat_server.py) and `plm-pin view`.

Scenes are checked by decoding the drawing commands embedded in meshcat's static HTML and
comparing them with Pinocchio forward kinematics of the frames; servers are real
subprocesses, bound and closed under time-outs. Nothing needs a display or a browser.
"""

from __future__ import annotations

import base64
import importlib.util
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from typer.testing import CliRunner

import plm_pin
from plm_pin.cli import app
from plm_pin.core.mechanism import Mechanism
from plm_pin.exceptions import FrameNotFound, InvalidInput, ViewerError
from plm_pin.viz import MeshcatServer, MeshcatViewer, scene_html, show
from plm_pin.viz.meshcat_server import (
    LOCALHOST,
    PARENT_CHECK_MS,
    ServerWindow,
    check_local_url,
    first_free,
    require_meshcat,
)
from plm_pin.viz.meshcat_view import CLOSED_COLOR, OPEN_COLOR, SINGULAR_COLORS, SKELETON_COLOR, shared_server
from tests.conftest import preset, prrrp_paper_configuration

pytestmark = pytest.mark.skipif(importlib.util.find_spec("meshcat") is None, reason="needs meshcat")

runner = CliRunner()


# ---------------------------------------------------------------- decoding
class Scene:
    """The last object, transform, property and animation of each path in a meshcat static page."""

    def __init__(self, page: str) -> None:
        import umsgpack

        self.objects: dict[str, dict] = {}
        self.transforms: dict[str, np.ndarray] = {}
        self.animations: list = []
        self.properties: dict[tuple[str, str], object] = {}
        for blob in re.findall(r'base64,([A-Za-z0-9+/=]+)"', page):
            cmd = umsgpack.unpackb(base64.b64decode(blob))
            if cmd["type"] == "set_object":
                self.objects[cmd["path"]] = cmd["object"]
            elif cmd["type"] == "set_transform":
                self.transforms[cmd["path"]] = np.array(cmd["matrix"]).reshape(4, 4).T  # column-major
            elif cmd["type"] == "set_property":
                self.properties[(cmd["path"], cmd["property"])] = cmd["value"]
            elif cmd["type"] == "set_animation":
                self.animations = cmd["animations"]

    def under(self, prefix: str) -> list[str]:
        """Paths of the objects below ``prefix``."""
        return sorted(p for p in self.objects if p.startswith(prefix + "/"))

    def color(self, path: str) -> int:
        """The 0xRRGGBB colour of an object's material."""
        return int(self.objects[path]["materials"][0]["color"])

    def geometry(self, path: str) -> dict:
        """An object's geometry description."""
        return self.objects[path]["geometries"][0]


def rgb(color) -> int:
    """0xRRGGBB of an RGBA colour in [0, 1], truncated as meshcat materials store it."""
    return int(color[0] * 255) * 65536 + int(color[1] * 255) * 256 + int(color[2] * 255)


def frame_origins(mech: Mechanism, q: np.ndarray) -> dict[str, np.ndarray]:
    """World position of every frame at ``q`` [m], by Pinocchio forward kinematics."""
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    return {f.name: data.oMf[i].translation.copy() for i, f in enumerate(mech.model.frames)}


def root(mech: Mechanism) -> str:
    return f"/meshcat/plm_pin/{mech.name}"


def listening_addresses(port: int) -> set[str]:
    """Addresses with a TCP socket listening on ``port``, from /proc/net/tcp and tcp6 (Linux)."""
    found = set()
    for table in (Path("/proc/net/tcp"), Path("/proc/net/tcp6")):
        if not table.exists():
            continue
        for line in table.read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, port_hex = local.split(":")
            if state == "0A" and int(port_hex, 16) == port:  # 0A: LISTEN
                raw = bytes.fromhex(address)
                found.add(socket.inet_ntoa(raw[::-1]) if len(raw) == 4 else f"ipv6:{address}")
    return found


# ---------------------------------------------------------------- static scenes
@pytest.mark.parametrize("name", ["fivebar", "harada2011_3d4m", "zhao2011_8pss"])
def test_static_scene_has_geometry_frames_and_two_markers_per_closure_at_the_closure_frames(name):
    """Static page: every visual, a triad per joint and the task frame, green balls on both closure frames."""
    mech = preset(name)
    viewer = MeshcatViewer(mech, static=True)
    status = viewer.display()
    scene = Scene(viewer.static_html())
    assert status.open_closures == () and status.singular_kinds == ()
    markers = scene.under(f"{root(mech)}/visuals/closures")
    assert len(markers) == 2 * len(mech.sidecar.closures)
    origins = frame_origins(mech, mech.q_ref)
    for spec in mech.sidecar.closures:
        a, b = (f"{root(mech)}/visuals/closures/{spec.name}/{frame}" for frame in spec.frames)
        for path, frame in zip((a, b), spec.frames, strict=True):
            assert scene.color(path) == rgb(CLOSED_COLOR)
            np.testing.assert_allclose(scene.transforms[path][:3, 3], origins[frame], atol=1e-12)
        np.testing.assert_allclose(scene.transforms[a][:3, 3], scene.transforms[b][:3, 3], atol=1e-9)
    drawn = ("/closures/", "/rails/", "/platform/")  # the viewer's own marks
    robot = [p for p in scene.under(f"{root(mech)}/visuals") if not any(part in p for part in drawn)]
    assert len(robot) == mech.visual_model.ngeoms
    joint_frames = [f.name for f in mech.model.frames if f.type == pin.FrameType.JOINT]
    expected = set(joint_frames) | {mech.task.frame}
    assert {p.rsplit("/", 1)[1] for p in scene.under(f"{root(mech)}/frames")} == expected
    camera = np.array(scene.properties[("/Cameras/default/rotated/<object>", "position")])  # y up
    assert np.linalg.norm(camera) > max(np.linalg.norm(p) for p in origins.values())  # outside, looking in


def test_open_closure_markers_are_magenta_and_apart():
    """A five-bar motor turned off its assembly: the tip closure is open, its markers magenta and apart."""
    mech = preset("fivebar")
    q = mech.q_ref.copy()
    mech.set_joint(q, "left_motor", q[mech.model.joints[mech.model.getJointId("left_motor")].idx_q] + 0.3)
    viewer = MeshcatViewer(mech, static=True)
    status = viewer.display(q)
    assert status.open_closures == ("tip",)
    assert status.closure_errors["tip"] > 1e-3
    assert status.singularity is None  # not classified: the loops are open
    scene = Scene(viewer.static_html())
    a, b = (f"{root(mech)}/visuals/closures/tip/{frame}" for frame in ("left_tip", "right_tip"))
    assert scene.color(a) == scene.color(b) == rgb(OPEN_COLOR)
    origins = frame_origins(mech, q)
    gap = np.linalg.norm(scene.transforms[a][:3, 3] - scene.transforms[b][:3, 3])
    assert gap == pytest.approx(np.linalg.norm(origins["left_tip"] - origins["right_tip"]), abs=1e-12)
    assert gap > 1e-3


def test_singular_configuration_is_drawn_in_the_colour_of_its_kind_and_restored_after():
    """Harada 2015 table, rod 2 vertical (inverse singular, Harada 2011 (9)): body orange, markers green."""
    mech = preset("harada2015_asymmetric")
    rt, lengths, signs = 0.05, (0.24, 0.17, 0.17, 0.24), (-1, 1, -1, 1)
    theta = -0.3
    q = prrrp_paper_configuration(mech, (0.0, 0.17 + rt * np.sin(theta), theta), lengths, rt, signs)
    viewer = MeshcatViewer(mech, static=True)
    status = viewer.display(q)
    assert status.singular_kinds == ("inverse",)
    scene = Scene(viewer.static_html())
    drawn = ("/closures/", "/rails/", "/platform/")  # the viewer's own marks
    robot = [p for p in scene.under(f"{root(mech)}/visuals") if not any(part in p for part in drawn)]
    assert robot and all(scene.color(p) == rgb(SINGULAR_COLORS["inverse"]) for p in robot)
    assert all(scene.color(p) == rgb(CLOSED_COLOR) for p in scene.under(f"{root(mech)}/visuals/closures"))
    viewer.display()  # the reference configuration is regular
    scene = Scene(viewer.static_html())
    own = {rgb(g.meshColor) for g in mech.visual_model.geometryObjects}
    assert {scene.color(p) for p in robot} == own


def test_mechanism_without_visuals_is_drawn_as_rods_between_joint_and_frame_origins():
    """No visuals: a ball at every joint, rods whose two ends are frame origins, one ending at each tip."""
    five = preset("fivebar")
    mech = Mechanism(five.model, five.sidecar, name="bare_fivebar")
    assert mech.visual_model.ngeoms == 0
    viewer = MeshcatViewer(mech, static=True)
    viewer.display()
    scene = Scene(viewer.static_html())
    balls = scene.under(f"{root(mech)}/visuals/joints")
    assert {p.rsplit("/", 1)[1] for p in balls} == set(mech.joint_names)
    origins = np.array(list(frame_origins(mech, mech.q_ref).values()))
    ends = []
    rods = scene.under(f"{root(mech)}/visuals/links")
    assert rods
    for path in rods:
        assert scene.geometry(path)["type"] == "CylinderGeometry"
        assert scene.color(path) == rgb(SKELETON_COLOR)
        T, half = scene.transforms[path], 0.5 * scene.geometry(path)["height"]
        for end in (T[:3, 3] + half * T[:3, 2], T[:3, 3] - half * T[:3, 2]):  # Pinocchio cylinders: along z
            distances = np.linalg.norm(origins - end, axis=1)
            assert distances.min() < 1e-9, f"{path} ends away from every frame origin"
            ends.append(end)
    tips = frame_origins(mech, mech.q_ref)
    for tip in ("left_tip", "right_tip"):
        assert min(np.linalg.norm(e - tips[tip]) for e in ends) < 1e-9


def test_force_arrows_start_at_the_point_and_end_at_point_plus_scale_times_force():
    """show_forces: arrows span point -> point + scale f, under forces/<label>; display() removes them."""
    mech = preset("fivebar")
    viewer = MeshcatViewer(mech, static=True)
    arrows = [((0.1, 0.2, 0.0), (3.0, -4.0, 0.0), "load"), ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), "nothing")]
    scale = 0.02  # [m/N]
    viewer.show_forces(mech.q_ref, arrows, np.float32(scale))  # NumPy scalars are accepted too
    viewer.show_forces(mech.q_ref, arrows, scale)
    scene = Scene(viewer.static_html())
    forces = f"{root(mech)}/forces"
    assert scene.under(forces) == [f"{forces}/load/head", f"{forces}/load/shaft"]
    point, tip = np.array([0.1, 0.2, 0.0]), np.array([0.1, 0.2, 0.0]) + scale * np.array([3.0, -4.0, 0.0])
    u = (tip - point) / np.linalg.norm(tip - point)
    for part, far in (("shaft", None), ("head", tip)):
        T, h = scene.transforms[f"{forces}/load/{part}"], scene.geometry(f"{forces}/load/{part}")["height"]
        np.testing.assert_allclose(T[:3, 1], u, atol=1e-12)  # meshcat cylinders: along y
        if far is None:
            np.testing.assert_allclose(T[:3, 3] - 0.5 * h * u, point, atol=1e-12)
        else:
            np.testing.assert_allclose(T[:3, 3] + 0.5 * h * u, far, atol=1e-12)
    viewer.display()
    assert Scene(viewer.static_html()).under(forces) == []


def _tail(scene: Scene, node: str) -> np.ndarray:
    """Where an arrow drawn under ``node`` starts: its shaft's centre minus half its length along y."""
    T, h = scene.transforms[f"{node}/shaft"], scene.geometry(f"{node}/shaft")["height"]
    return T[:3, 3] - 0.5 * h * T[:3, 1]


def test_a_frame_name_as_point_starts_the_arrow_at_that_frame():
    """show_forces: a frame name stands for the frame's origin at q (Pinocchio forward kinematics)."""
    mech = preset("fivebar")
    q = mech.assemble(mech.q_ref, fixed={"left_motor": 1.9}).q
    viewer = MeshcatViewer(mech, static=True)
    viewer.show_forces(q, [("left_tip", (0.0, -5.0, 0.0), "pull")], 0.01)
    scene = Scene(viewer.static_html())
    np.testing.assert_allclose(
        _tail(scene, f"{root(mech)}/forces/pull"), frame_origins(mech, q)["left_tip"], atol=1e-12
    )


def test_force_arrows_are_drawn_as_they_are_returned():
    """show_forces takes force_arrows(...) as is: an arrow per nonzero force at its point, named by kind."""
    from plm_pin.statics import static_forces
    from plm_pin.viz import force_arrows

    mech = preset("harada2011_3d4m")
    arrows = force_arrows(static_forces(mech, mech.q_ref, wrench=(3.0, -2.0, 0.5), gravity=False))
    viewer = MeshcatViewer(mech, static=True)
    viewer.show_forces(mech.q_ref, arrows, 0.01)
    scene = Scene(viewer.static_html())
    drawn = [a for a in arrows if np.linalg.norm(a.force) > 0.0]
    assert len(drawn) >= 4  # four actuator forces at least
    forces = f"{root(mech)}/forces"
    assert {p.rsplit("/", 1)[0] for p in scene.under(forces)} == {
        f"{forces}/{a.kind} {a.name}" for a in drawn
    }
    for a in drawn:
        node = f"{forces}/{a.kind} {a.name}"
        np.testing.assert_allclose(_tail(scene, node), a.point, atol=1e-12)
        T = scene.transforms[f"{node}/shaft"]
        np.testing.assert_allclose(T[:3, 1], a.force / np.linalg.norm(a.force), atol=1e-12)


def test_an_unknown_frame_as_point_is_refused_by_name():
    """show_forces: a point naming no frame raises FrameNotFound listing the frames (no raw ValueError)."""
    mech = preset("fivebar")
    viewer = MeshcatViewer(mech, static=True)
    with pytest.raises(FrameNotFound, match=re.escape("frame 'nowhere' not found; frames are [")):
        viewer.show_forces(mech.q_ref, [("nowhere", (1.0, 0.0, 0.0), "f")], 1.0)


@pytest.mark.parametrize(
    ("arrows", "scale", "message"),
    [
        (
            [((0, 0, 0), (1, 0, 0), "f"), ((0, 0, 0), (0, 1, 0), "f")],
            1.0,
            "arrow labels must be distinct; 'f'",
        ),
        (
            [((0, 0), (1, 0, 0), "f")],
            1.0,
            "arrow 'f': point (or a frame name) and vector must be 3 finite numbers each",
        ),
        (
            [((0, 0, 0), (1, 0, 0))],
            1.0,
            "arrow 0 must be a ForceArrow or (point [m] or frame name, vector [N], label)",
        ),
        ([((0, 0, 0), (1, 0, 0), "f")], 0.0, "scale must be a positive number [m/N], got 0.0"),
        ([((0, 0, 0), (1, 0, 0), "f")], "1", "scale must be a positive number [m/N], got '1'"),
    ],
)
def test_bad_arrows_are_refused_by_text(arrows, scale, message):
    """Malformed arrows, repeated labels and non-positive scales raise InvalidInput saying which."""
    viewer = MeshcatViewer(preset("fivebar"), static=True)
    with pytest.raises(InvalidInput, match=re.escape(message)):
        viewer.show_forces(preset("fivebar").q_ref, arrows, scale)


def test_animation_keys_follow_the_times_and_forward_kinematics():
    """scene_html(qs, times): keys at (t - t0) * fps frames, markers where the frames are at each q."""
    mech = preset("fivebar")
    angles = [1.85, 1.9, 1.95]
    qs = np.array([mech.assemble(mech.q_ref, fixed={"left_motor": a}).q for a in angles])
    times = np.array([2.0, 2.5, 3.25])
    scene = Scene(scene_html(mech, qs=qs, times=times))
    clips = {a["path"]: a["clip"] for a in scene.animations}
    clip = clips[f"{root(mech)}/visuals/closures/tip/left_tip"]
    fps = clip["fps"]
    (position,) = (t for t in clip["tracks"] if t["name"] == ".position")
    assert [k["time"] for k in position["keys"]] == pytest.approx((times - times[0]) * fps)
    for key, q in zip(position["keys"], qs, strict=True):
        np.testing.assert_allclose(key["value"], frame_origins(mech, q)["left_tip"], atol=1e-12)
    assert f"{root(mech)}/frames/left_motor" in clips  # triads move too


def test_display_after_an_animation_stops_it():
    """A configuration shown after a motion replaces the animation by an empty one."""
    mech = preset("fivebar")
    viewer = MeshcatViewer(mech, static=True)
    viewer.animate([mech.q_ref, mech.q_ref], [0.0, 1.0])
    assert Scene(viewer.static_html()).animations
    viewer.display()
    assert Scene(viewer.static_html()).animations == []


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"qs": [[0.0] * 4], "times": [0.0, 1.0]}, "times must have shape (1,) like qs, got (2,)"),
        ({"qs": [[0.0] * 4] * 2, "times": [1.0, 1.0]}, "times must be strictly increasing [s]"),
        ({"qs": [[0.0] * 3], "times": [0.0]}, "qs must have shape (n, 4) with n >= 1, got (1, 3)"),
        ({"q": [0.0] * 4, "qs": [[0.0] * 4], "times": [0.0]}, "give either q, or qs with times"),
        ({"qs": [[0.0] * 4]}, "give either q, or qs with times"),
    ],
)
def test_bad_motions_are_refused_by_text(kwargs, message):
    """scene_html refuses mismatched, non-increasing or ambiguous motions with a message saying which."""
    with pytest.raises(InvalidInput, match=re.escape(message)):
        scene_html(preset("fivebar"), **kwargs)


def test_show_returns_the_viewer_and_renders_inline_in_a_notebook():
    """show(mech, static=True): a viewer without URL whose notebook HTML embeds the escaped static page."""
    viewer = show(preset("fourbar"), static=True)
    assert isinstance(viewer, MeshcatViewer)
    assert viewer.url is None
    assert repr(viewer) == "MeshcatViewer('fourbar', 'static')"
    inline = viewer._repr_html_()
    assert inline.startswith('<iframe srcdoc="') and "<script>" not in inline
    with pytest.raises(ViewerError, match="a static scene has no server page"):
        viewer.open()


def test_one_scene_sink_at_a_time():
    """static, server and zmq_url are exclusive; port only starts the shared server."""
    with pytest.raises(InvalidInput, match="give at most one of static=True, server= and zmq_url="):
        MeshcatViewer(preset("fourbar"), static=True, zmq_url="tcp://127.0.0.1:6000")
    with pytest.raises(InvalidInput, match="port= is for the shared server: not with static=True"):
        MeshcatViewer(preset("fourbar"), static=True, port=7000)


# ---------------------------------------------------------------- servers
def test_server_listens_on_localhost_only_serves_the_scene_and_stops():
    """The shared server binds web and ZeroMQ ports to 127.0.0.1 only, is reused, serves, and is reaped."""
    if not Path("/proc/net/tcp").exists():
        pytest.skip("needs Linux /proc/net/tcp to read the bound addresses")
    mech = preset("fivebar")
    with shared_server() as server:
        assert shared_server() is server and shared_server(server.port) is server  # reused
        assert server.web_url == f"http://{LOCALHOST}:{server.port}/static/"
        assert server.zmq_url.startswith(f"tcp://{LOCALHOST}:")
        zmq_port = int(server.zmq_url.rsplit(":", 1)[1])
        assert listening_addresses(server.port) == {LOCALHOST}
        assert listening_addresses(zmq_port) == {LOCALHOST}
        viewer = show(mech)  # on the shared server
        assert viewer.server is server and viewer.url == server.web_url
        served = Scene(viewer.static_html())  # asked to the server
        import urllib.request

        with urllib.request.urlopen(server.web_url, timeout=10) as reply:  # the page a browser opens
            page = reply.read().decode("utf-8")
        assert 'id="plm-pin-legend"' in page and 'src="main.min.js"' in page  # meshcat's, with legend
        with urllib.request.urlopen(server.web_url + "main.min.js", timeout=10) as reply:
            assert reply.status == 200
        assert len(served.under(f"{root(mech)}/visuals/closures")) == 2
        again = MeshcatViewer(preset("fourbar"), zmq_url=server.zmq_url)  # reuse by address
        assert again.url == server.web_url
        process = server._process
    assert not server.running
    assert process.returncode is not None
    assert listening_addresses(server.port) == set()


def alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie waiting to be reaped does not)."""
    status = Path(f"/proc/{pid}/status")
    try:
        return "\nState:\tZ" not in status.read_text()
    except FileNotFoundError:
        return False


def test_server_stops_when_the_process_that_started_it_is_killed():
    """A parent killed with SIGKILL cannot close its server: the server notices and exits by itself."""
    if not Path("/proc/self/status").exists():
        pytest.skip("needs Linux /proc to see processes")
    code = (
        "import time; from plm_pin.viz import MeshcatServer; s = MeshcatServer(); "
        "print(s._process.pid, flush=True); time.sleep(60)"
    )
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout is not None
        server_pid = int(parent.stdout.readline())  # the parent's own start-up time-out bounds this
        assert alive(server_pid)
    finally:
        parent.kill()
        parent.wait(timeout=10)
    deadline = time.monotonic() + 10 * PARENT_CHECK_MS / 1000
    while alive(server_pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not alive(server_pid)


@pytest.mark.slow
def test_view_server_started_with_sigint_ignored_still_ends_with_ctrl_c():
    """`plm-pin view` from a script's background (SIGINT inherited ignored): Ctrl-C still ends it, exit 0."""
    process = subprocess.Popen(
        [sys.executable, "-m", "plm_pin", "view", "fourbar"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])},
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )
    try:
        assert process.stdout is not None
        line = process.stdout.readline()  # bounded by the server's own start-up time-out
        assert line.startswith("fourbar: http://127.0.0.1:"), line
        process.send_signal(signal.SIGINT)  # while it may still be announcing itself
        assert process.wait(timeout=60) == 0
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def test_server_that_does_not_start_in_time_is_stopped(monkeypatch):
    """A start-up time-out raises ViewerError saying so, and the half-started process is killed and reaped."""
    started: list[subprocess.Popen] = []
    popen = subprocess.Popen

    def recording_popen(*args, **kwargs):
        started.append(popen(*args, **kwargs))
        return started[-1]

    monkeypatch.setattr(subprocess, "Popen", recording_popen)
    with pytest.raises(ViewerError, match=re.escape("the meshcat server did not start within 0 s")):
        MeshcatServer(timeout=0.0)
    (process,) = started
    assert process.returncode is not None


def _listen(port: int) -> socket.socket:
    """A socket listening on 127.0.0.1:``port`` (OSError when it is taken)."""
    sock = socket.socket()
    try:
        sock.bind((LOCALHOST, port))
    except OSError:
        sock.close()
        raise
    sock.listen()
    return sock


def test_first_free_binds_past_a_busy_port():
    """A port someone listens on (127.0.0.1) is skipped by binding the next; a bad port number is refused."""
    with socket.socket() as busy:
        busy.bind((LOCALHOST, 0))
        busy.listen()
        port = busy.getsockname()[1]
        with first_free(port, _listen, attempts=1000) as bound:
            assert bound.getsockname()[1] > port
        with pytest.raises(ViewerError, match=f"ports {port} to {port} on 127.0.0.1 are all busy"):
            first_free(port, _listen, attempts=1)
    with pytest.raises(InvalidInput, match=re.escape("port must be in 1..65535, got 0")):
        first_free(0, _listen)


def test_server_started_on_a_busy_port_serves_on_the_next():
    """The server binds past a port taken after any check could be made: the port is found by binding it."""
    with socket.socket() as busy:
        busy.bind((LOCALHOST, 0))
        busy.listen()
        port = busy.getsockname()[1]
        with MeshcatServer(port) as server:
            assert server.port > port and server.moved
            assert server.web_url == f"http://{LOCALHOST}:{server.port}/static/"
            assert listening_addresses(server.port) <= {LOCALHOST}


def test_silent_server_times_out_with_a_clear_error():
    """A zmq_url nobody answers raises ViewerError after the time-out instead of hanging."""
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind((LOCALHOST, 0))
        url = f"tcp://{LOCALHOST}:{probe.getsockname()[1]}"
    with pytest.raises(
        ViewerError, match=re.escape(f"the meshcat server at {url} did not answer within 0.2 s")
    ):
        ServerWindow(url, timeout=0.2)


@pytest.mark.parametrize(
    "url", ["tcp://192.168.1.5:6000", "tcp://example.org:6000", "ipc:///tmp/x", "tcp://[::1]"]
)
def test_zmq_url_must_be_on_this_machine(url):
    """Only tcp:// loopback addresses with a port are accepted."""
    with pytest.raises(
        InvalidInput,
        match=re.escape(f"zmq_url must be tcp://127.0.0.1:PORT (a server on this machine), got {url!r}"),
    ):
        check_local_url(url)
    assert check_local_url("tcp://127.0.0.1:6000") == "tcp://127.0.0.1:6000"


def test_missing_meshcat_names_the_extra(monkeypatch, tmp_path):
    """Without meshcat: ViewerError naming `pip install 'plm-pin[viz]'`; `view` exits 1 with that one line."""
    monkeypatch.setitem(sys.modules, "meshcat", None)
    with pytest.raises(ViewerError, match=re.escape("pip install 'plm-pin[viz]'")):
        require_meshcat()
    with pytest.raises(ViewerError, match="the meshcat viewer needs meshcat"):
        show(preset("fourbar"), static=True)
    result = runner.invoke(app, ["view", "fourbar", "--html", str(tmp_path / "scene.html")])
    assert result.exit_code == 1
    assert result.stderr.startswith("error: the meshcat viewer needs meshcat")
    assert result.stderr.count("\n") == 1 and "pip install 'plm-pin[viz]'" in result.stderr
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------- CLI
def test_view_html_writes_only_the_given_file(tmp_path):
    """`view --html OUT` writes OUT (creating its folder) and nothing else; the page holds the scene."""
    out = tmp_path / "pages" / "fivebar.html"
    result = runner.invoke(app, ["view", "fivebar", "--html", str(out)])
    assert result.exit_code == 0, result.output
    assert result.stdout == f"wrote {out}\n"
    assert sorted(tmp_path.rglob("*")) == [out.parent, out]
    scene = Scene(out.read_text())
    assert len(scene.under("/meshcat/plm_pin/fivebar/visuals/closures")) == 2


def test_view_pose_sets_joints_or_the_task_pose(tmp_path):
    """--pose x=..: the task frame is there (IK); --pose JOINT=..: the joint has that value (assembly)."""
    mech = preset("fivebar")
    out = tmp_path / "scene.html"
    result = runner.invoke(
        app, ["view", "fivebar", "--html", str(out), "--pose", "x=0.02", "--pose", "y=0.22"]
    )
    assert result.exit_code == 0, result.output
    tip = Scene(out.read_text()).transforms["/meshcat/plm_pin/fivebar/visuals/closures/tip/left_tip"][:3, 3]
    np.testing.assert_allclose(tip[:2], [0.02, 0.22], atol=1e-9)
    result = runner.invoke(app, ["view", "fivebar", "--html", str(out), "--pose", "0.03,0.21"])
    assert result.exit_code == 0, result.output
    tip = Scene(out.read_text()).transforms["/meshcat/plm_pin/fivebar/visuals/closures/tip/left_tip"][:3, 3]
    np.testing.assert_allclose(tip[:2], [0.03, 0.21], atol=1e-9)
    result = runner.invoke(app, ["view", "fivebar", "--html", str(out), "--pose", "left_motor=1.95"])
    assert result.exit_code == 0, result.output
    motor = Scene(out.read_text()).transforms["/meshcat/plm_pin/fivebar/frames/left_motor"]
    data = mech.model.createData()
    q = mech.q_ref.copy()
    mech.set_joint(q, "left_motor", 1.95)
    pin.framesForwardKinematics(mech.model, data, q)
    np.testing.assert_allclose(
        motor[:3, :3], data.oMf[mech.model.getFrameId("left_motor")].rotation, atol=1e-12
    )


def test_view_pose_that_cannot_close_shows_the_open_loop(tmp_path):
    """Motors the loop cannot close on: warnings on stderr, the page written with magenta markers."""
    out = tmp_path / "scene.html"
    result = runner.invoke(
        app, ["view", "fivebar", "--html", str(out), "--pose", "left_motor=3", "--pose", "right_motor=0"]
    )
    assert result.exit_code == 0, result.output
    assert "cannot close the loops" in result.stderr
    assert "closure 'tip' is open" in result.stderr
    scene = Scene(out.read_text())
    assert scene.color("/meshcat/plm_pin/fivebar/visuals/closures/tip/left_tip") == rgb(OPEN_COLOR)


def test_view_animate_writes_the_studys_motion(tmp_path):
    """--animate harada2015:working: the page animates the planned path of the mode change, key by key."""
    from analyses.harada2015 import WORKING_DURATION
    from plm_pin.families.prrrp import plan_working_mode_change

    out = tmp_path / "flip.html"
    result = runner.invoke(app, ["view", "--animate", "harada2015:working", "--html", str(out)])
    assert result.exit_code == 0, result.output
    assert result.stdout.endswith(f"wrote {out}\n")
    mech = preset("harada2015_asymmetric")
    path = plan_working_mode_change(mech, leg=3).path  # computed again here, independently of the CLI
    scene = Scene(out.read_text())
    clip = {a["path"]: a["clip"] for a in scene.animations}[
        f"{root(mech)}/visuals/closures/rod4_plate_right/rod4_tip"
    ]
    (position,) = (t for t in clip["tracks"] if t["name"] == ".position")
    assert len(position["keys"]) == path.n_samples
    assert position["keys"][-1]["time"] == pytest.approx(WORKING_DURATION * clip["fps"])
    for key, q in zip(position["keys"][:: path.n_samples // 5], path.q[:: path.n_samples // 5], strict=True):
        np.testing.assert_allclose(key["value"], frame_origins(mech, q)["rod4_tip"], atol=1e-12)


def test_view_animate_moves_a_users_mechanism_in_the_overview(tmp_path):
    """overview:simulation takes the mechanism given: the five-bar falls under gravity in the page."""
    out = tmp_path / "fall.html"
    result = runner.invoke(app, ["view", "fivebar", "--animate", "overview:simulation", "--html", str(out)])
    assert result.exit_code == 0, result.output
    assert "fivebar released at rest under gravity" in result.stdout
    assert Scene(out.read_text()).animations


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nonsense"], "'nonsense' is neither a preset nor an existing path"),
        ([], "give a mechanism (preset, erd:<robot>, .urdf, folder) or --animate"),
        (["--animate", "harada2015"], "--animate 'harada2015': give STUDY:CASE, e.g. harada2015:assembly"),
        (
            ["--animate", "nostudy:x"],
            "unknown study 'nostudy'; studies are ['delta_optimize', 'enferadi2017'",
        ),
        (
            ["--animate", "harada2015:flip"],
            "study 'harada2015' has no animation 'flip'; its animations are ['assembly', 'working']",
        ),
        (
            ["fourbar", "--animate", "harada2015:working"],
            "--animate harada2015:working moves harada2015_asymmetric, not 'fourbar'",
        ),
        (
            ["--animate", "overview:simulation", "--pose", "x=0"],
            "--animate plays a motion: it takes no --pose",
        ),
        (
            ["fivebar", "--pose", "x=0.1", "--pose", "left_motor=1"],
            "--pose mixes joints and task coordinates",
        ),
        (
            ["fivebar", "--pose", "foo=1"],
            "--pose 'foo=1': 'foo' is not a joint or task coordinate of fivebar, one",
        ),
        (
            ["fivebar", "--pose", "x=abc"],
            "--pose 'x=abc': 'abc' is not a finite number or finite numbers, comma",
        ),
        (["fivebar", "--pose", "x=1,2"], "--pose 'x=1,2': the task coordinate 'x' takes one number"),
        (["fivebar", "--pose", "x=1", "--pose", "x=2"], "--pose 'x=2': 'x' is given twice"),
        (["fivebar", "--html", "{tmp}", "--port", "7000"], "--html writes a page that needs no server"),
        (["fivebar", "--html", "{tmp}"], "is a folder; give a file name"),
        (["fivebar", "--zmq-url", "tcp://10.0.0.1:6000"], "zmq_url must be tcp://127.0.0.1:PORT"),
    ],
)
def test_view_bad_input_is_one_error_line(tmp_path, args, message):
    """Unknown mechanism, bad poses, conflicting options: exit 1, one 'error:' line, nothing written."""
    result = runner.invoke(app, ["view", *[a.replace("{tmp}", str(tmp_path)) for a in args]])
    assert result.exit_code == 1, result.output
    assert result.stdout == ""
    assert result.stderr.startswith("error: ") and result.stderr.count("\n") == 1
    assert message in result.stderr
    assert "Traceback" not in result.output
    assert list(tmp_path.iterdir()) == []


def test_view_on_a_busy_port_serves_on_the_next_and_stops_on_ctrl_c(monkeypatch):
    """`view --port BUSY` says which port it serves instead, prints the 127.0.0.1 URL; Ctrl-C closes it."""
    started: list[MeshcatServer] = []

    def ctrl_c(self: MeshcatServer) -> int:
        started.append(self)
        raise KeyboardInterrupt

    monkeypatch.setattr(MeshcatServer, "wait", ctrl_c)
    with socket.socket() as busy:
        busy.bind((LOCALHOST, 0))
        busy.listen()
        port = busy.getsockname()[1]
        result = runner.invoke(app, ["view", "fourbar", "--port", str(port)])
    assert result.exit_code == 0, result.output
    (server,) = started
    assert server.port != port
    assert result.stderr == f"warning: port {port} is busy; serving on {server.port} instead\n"
    assert f"fourbar: http://127.0.0.1:{server.port}/static/" in result.stdout
    assert f"--zmq-url {server.zmq_url}" in result.stdout
    assert not server.running


@pytest.mark.parametrize("name", ["fourbar", "fivebar", "harada2011_3d4m", "enferadi2017_star_triangle"])
def test_planar_mechanisms_are_seen_from_their_plane_normal(name):
    """Every joint of these presets turns about z and nothing moves along z: the camera looks down z."""
    from plm_pin.viz.meshcat_view import PLANAR_TILT, _camera_direction, plane_normal

    mech = plm_pin.load(name)
    np.testing.assert_allclose(plane_normal(mech), [0.0, 0.0, 1.0], atol=1e-12)
    eye = _camera_direction(mech)  # meshcat's camera frame: world z is its y, world y its -z
    assert np.degrees(np.arccos(eye[1])) == pytest.approx(np.degrees(np.arctan(PLANAR_TILT)), rel=1e-9)
    assert eye[2] > 0.0  # tilted towards world -y: world +y points up the screen


def test_a_spatial_mechanism_has_no_plane_normal():
    """The 8-PSS moves in 3-D: no plane normal, the default oblique camera."""
    from plm_pin.viz.meshcat_view import CAMERA_DIRECTION, _camera_direction, plane_normal

    mech = plm_pin.load("zhao2011_8pss")
    assert plane_normal(mech) is None
    np.testing.assert_array_equal(_camera_direction(mech), CAMERA_DIRECTION)


def test_static_scene_packer_writes_the_bytes_of_meshcats_own_umsgpack():
    """The compiled packer of static scenes gives umsgpack's bytes for meshes, transforms and animations."""
    umsgpack = pytest.importorskip("umsgpack")
    from plm_pin.viz import meshcat_server

    commands = []
    send = meshcat_server.StaticWindow.send

    def record(window, command):
        commands.append(command.lower())
        send(window, command)

    mech = preset("harada2011_3d4m")
    qs = np.array([mech.q_ref, mech.q_ref])
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(meshcat_server.StaticWindow, "send", record)
        scene_html(mech, qs=qs, times=[0.0, 0.5])
    assert any(c["type"] == "set_object" for c in commands)
    assert any(c["type"] == "set_animation" for c in commands)
    packb = meshcat_server.packer()
    assert [packb(c) for c in commands] == [umsgpack.packb(c) for c in commands]


def test_animation_keys_are_those_of_meshcats_own_frames_and_quaternions():
    """The batched quaternions give the animation meshcat's at_frame and js_quaternion give, key for key."""
    meshcat = pytest.importorskip("meshcat")
    mech = preset("harada2011_3d4m")
    rng = np.random.default_rng(3)
    qs = [mech.q_ref]
    for _ in range(12):
        qs.append(mech.assemble(qs[-1] + 0.02 * rng.normal(size=mech.nq)).q)
    times = np.linspace(0.0, 1.2, len(qs))
    viewer = MeshcatViewer(mech, static=True)
    viewer.animate(qs, times)
    animation = meshcat.animation.Animation(default_framerate=30)
    from plm_pin.viz.meshcat_view import ANIMATION_FPS

    animation.default_framerate = ANIMATION_FPS
    try:
        for q, t in zip(qs, times, strict=True):
            with animation.at_frame(viewer._vis, (t - times[0]) * ANIMATION_FPS) as frame:
                viewer._viz.viewer = frame
                viewer._viz.display(q)
    finally:
        viewer._viz.viewer = viewer._vis
    expected = animation.lower()
    sent = []
    send = type(viewer._vis.window).send

    def record(window, command):
        sent.append(command.lower())
        send(window, command)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(type(viewer._vis.window), "send", record)
        viewer.animate(qs, times)
    lowered = [c for c in sent if c["type"] == "set_animation"][-1]["animations"]
    assert any(track["name"] == ".quaternion" for a in expected for track in a["clip"]["tracks"])
    assert lowered == expected
