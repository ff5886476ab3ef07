"""The live inspector: a meshcat scene and a control page on 127.0.0.1, both driven by :func:`inspect_update`.

:func:`inspect` draws the mechanism in meshcat (:class:`~plm_pin.viz.MeshcatViewer`, coloured
at singularities as every scene is) with the velocity ellipse at the task frame and, when the
description has a compliance section, the axis of the smallest stiffness, and the actuator
forces as arrows along the prismatic actuators (scaled as the page's bars); and serves a small
page (the standard library's :class:`http.server.ThreadingHTTPServer`, bound to 127.0.0.1
only) with sliders for the task coordinates and the actuators, working- and assembly-mode
selectors, the load and the preload, the readouts and force bars, and meshcat's page beside
them. The page talks JSON to two endpoints: ``GET /state`` and ``POST /update`` (a change, as
:func:`~plm_pin.viz.inspect_state.inspect_update` takes it). In Jupyter the inspector shows
an ipywidgets panel beside the inline scene (:mod:`plm_pin.viz.inspect_widget`).
"""

from __future__ import annotations

import functools
import html
import json
import math
import threading
import webbrowser
from collections.abc import Mapping
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any

import numpy as np
import pinocchio as pin

from ..core.mechanism import Mechanism
from ..exceptions import PlmError
from ..results import plain
from .force_figure import actuator_arrows
from .inspect_state import InspectState, inspect_state, inspect_update
from .inspect_widget import InspectorPanel
from .legend import ELLIPSE_COLOR, ELLIPSE_OPACITY, ENTRIES, STIFFNESS_COLOR, legend_html
from .meshcat_server import LOCALHOST, MeshcatServer, ServerWindow, first_free, require_meshcat
from .meshcat_view import MeshcatViewer

PAGE_PORT = 7200
"""First port tried for the control page when none is asked for."""

SLIDER_SPAN = 0.5
"""Half range of a translation or prismatic-actuator slider without limits, in mechanism sizes [-]."""

ELLIPSE_SIZE = 0.3
"""Largest drawn semi-axis of the velocity ellipse, in mechanism sizes [-] (the shape is to scale)."""

FORCE_SIZE = 0.3
"""Length of the longest force arrow, in mechanism sizes [-]: the largest of the forces and finite limits."""

MAX_BODY = 1 << 16
"""Largest request body the page may send [bytes]."""


class Inspector:
    """A mechanism in the live inspector: its state, its meshcat scene and its control page.

    Attributes:
        state: the current :class:`~plm_pin.viz.inspect_state.InspectState`.
        viewer: the meshcat scene.
        url: address of the control page (``http://127.0.0.1:PORT/``).
        ranges: slider ranges, ``{"task": {dof: (lo, hi)}, "actuators": {name: (lo, hi)}}``.
    """

    def __init__(
        self,
        mech: Mechanism,
        *,
        port: int | None = None,
        server: MeshcatServer | None = None,
        source: str | None = None,
        page: bool = True,
    ) -> None:
        """Start the inspector of ``mech`` at its reference configuration.

        Args:
            mech: the mechanism (its task needs as many coordinates as DOF).
            port: port of the control page (default: the first free from 7200).
            server: a meshcat server to draw in (default: this process's shared one).
            source: the name or path ``mech`` was loaded from, for the "copy pose" texts.
            page: serve the control page (False in Jupyter, where widgets replace it).

        Raises:
            ViewerError: meshcat missing, a server that cannot be started or no free port.
            InvalidInput: a mechanism without a square task.
        """
        self._lock = threading.Lock()
        self.state = inspect_state(mech, source=source)
        self.viewer = MeshcatViewer(mech, server=server)
        assert self.viewer.server is not None
        self._window = ServerWindow(self.viewer.server.zmq_url, self.viewer.server.web_url)
        self._vis = require_meshcat().Visualizer(window=self._window)
        self.ranges = _ranges(self.state, self.viewer.size)
        self._drawn: set[str] = set()  # the inspector's own marks on screen (legend keys)
        self._draw()
        self._http: ThreadingHTTPServer | None = None
        self.url = ""
        if page:
            self._http = first_free(
                PAGE_PORT if port is None else port, lambda p: ThreadingHTTPServer((LOCALHOST, p), _Page)
            )
            self._http.inspector = self  # type: ignore[attr-defined]
            self.url = f"http://{LOCALHOST}:{self._http.server_address[1]}/"
            threading.Thread(target=self._http.serve_forever, daemon=True).start()

    @property
    def address(self) -> tuple[str, int] | None:
        """The (host, port) the control page listens on, None without a page."""
        if self._http is None:
            return None
        host, port = self._http.server_address[:2]
        return str(host), int(port)

    def update(self, change: Mapping[str, object]) -> InspectState:
        """Apply ``change`` (see :func:`~plm_pin.viz.inspect_state.inspect_update`), redraw, return the state.

        Raises:
            InvalidInput: a malformed change (the state is unchanged).
        """
        with self._lock:
            self.state = inspect_update(self.state, change)
            self._draw()
            return self.state

    def to_dict(self) -> dict[str, Any]:
        """The state as JSON data, with the slider ranges and the scene's address."""
        return {
            **self.state.to_dict(),
            "ranges": plain(self.ranges),
            "scene": self.viewer.url,
            "mechanism": self.state.mech.name,
            "legend": legend_html([ENTRIES[key] for key in self.legend]),
        }

    @property
    def legend(self) -> list[str]:
        """Keys of :data:`plm_pin.viz.legend.ENTRIES` of what the scene shows now, in the legend's order."""
        keys = {*self.viewer.legend, *self._drawn}
        return [key for key in ENTRIES if key in keys]

    def open(self) -> Inspector:
        """Open the control page in a web browser; returns the inspector."""
        webbrowser.open(self.url, new=2)
        return self

    def close(self) -> None:
        """Stop serving the page and close the drawing connections (idempotent).

        The meshcat server is this process's shared one: it stops with the process.
        """
        self._window.close()
        self.viewer.close()
        if self._http is not None:
            self._http.shutdown()
            self._http.server_close()
            self._http = None

    def __enter__(self) -> Inspector:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _draw(self) -> None:
        """Place the mechanism, the ellipse and the stiffness axis at the state."""
        state, mech = self.state, self.state.mech
        arrows = actuator_arrows(mech, state.q, state.forces) if np.all(np.isfinite(state.forces)) else []
        if any(np.any(a.force != 0.0) for a in arrows):
            self.viewer.show_forces(state.q, arrows, force_scale(state, self.viewer.size))
        else:
            self.viewer.display(state.q)
        mg = require_meshcat().geometry
        node = self._vis[f"{self.viewer.root}/inspect"]
        data = mech.model.createData()
        pin.framesForwardKinematics(mech.model, data, state.q)
        origin = data.oMf[mech.task_frame_id].translation if mech.task_frame_id is not None else np.zeros(3)
        radii = state.ellipse_radii
        if radii.size and np.all(np.isfinite(radii)) and radii[0] > 0.0:
            scale = ELLIPSE_SIZE * self.viewer.size / float(radii[0])
            axes = list(state.ellipse_axes)
            drawn = [float(r) * scale for r in radii] + [0.02 * self.viewer.size] * (3 - len(radii))
            while len(axes) < 3:  # complete a planar ellipse's frame with its normal
                axes.append(np.cross(axes[0], axes[1]) if len(axes) == 2 else _normal(axes[0]))
            frame = np.eye(4)
            frame[:3, :3] = np.column_stack(axes)
            if np.linalg.det(frame[:3, :3]) < 0.0:
                frame[:3, 2] *= -1.0
            frame[:3, 3] = origin
            node["ellipse"].set_object(
                mg.Ellipsoid(drawn),
                mg.MeshLambertMaterial(color=ELLIPSE_COLOR, opacity=ELLIPSE_OPACITY, transparent=True),
            )
            node["ellipse"].set_transform(frame)
            self._drawn.add("ellipse")
        else:
            node["ellipse"].delete()
            self._drawn.discard("ellipse")
        if math.isfinite(state.stiffness):
            half = 0.5 * ELLIPSE_SIZE * self.viewer.size * state.stiffness_axis
            points = np.column_stack([origin - half, origin + half])
            node["stiffness"].set_object(
                mg.Line(mg.PointsGeometry(points), mg.LineBasicMaterial(color=STIFFNESS_COLOR, linewidth=4))
            )
            self._drawn.add("stiffness")
        else:
            node["stiffness"].delete()
            self._drawn.discard("stiffness")

    def panel(self) -> InspectorPanel:
        """The Jupyter panel: ipywidgets controls and readouts beside the inline scene.

        Raises:
            ViewerError: ipywidgets missing.
        """
        return InspectorPanel(self)

    def _ipython_display_(self) -> None:
        """In a notebook the inspector shows as its panel."""
        self.panel()._ipython_display_()

    def _repr_html_(self) -> str:
        return f'<a href="{html.escape(self.url)}">{html.escape(self.state.mech.name)} inspector</a>'

    def __repr__(self) -> str:
        return f"Inspector({self.state.mech.name!r}, {self.url or self.viewer.url!r})"


def force_scale(state: InspectState, size: float) -> float:
    """Arrow length per force [m/N]: the largest force or finite limit is :data:`FORCE_SIZE` sizes long.

    As the page's bars, which are scaled to the same largest value.
    """
    values = np.abs(np.concatenate([state.forces, state.force_limits.ravel()]))
    largest = float(np.max(values[np.isfinite(values)], initial=0.0))
    return FORCE_SIZE * size / largest if largest > 0.0 else 1.0


def _normal(axis: np.ndarray) -> np.ndarray:
    """A unit vector normal to ``axis``."""
    other = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    n = np.cross(axis, other)
    return n / np.linalg.norm(n)


def _ranges(state: InspectState, size: float) -> dict[str, dict[str, tuple[float, float]]]:
    """Slider ranges: joint limits where finite, else :data:`SLIDER_SPAN` sizes or a half-turn around."""
    mech = state.mech

    def around(value: float, rotational: bool) -> tuple[float, float]:
        span = math.pi if rotational else SLIDER_SPAN * size
        return float(value - span), float(value + span)

    task = {d: around(float(v), d.startswith("r")) for d, v in zip(state.dofs, state.x, strict=True)}
    actuators = {}
    for a, value in zip(mech.actuators, state.actuators, strict=True):
        j = mech.model.joints[mech.model.getJointId(a.joint)]
        lo, hi = mech.model.lowerPositionLimit[j.idx_q], mech.model.upperPositionLimit[j.idx_q]
        finite = j.nq == 1 and math.isfinite(lo) and math.isfinite(hi) and hi - lo < 1e3
        actuators[a.joint] = (float(lo), float(hi)) if finite else around(float(value), a.kind != "prismatic")
    return {"task": task, "actuators": actuators}


@functools.cache
def page_html() -> str:
    """The control page (HTML, CSS and JavaScript in one file)."""
    return resources.files(__package__).joinpath("inspect_page.html").read_text(encoding="utf-8")


class _Page(BaseHTTPRequestHandler):
    """``GET /`` the page, ``GET /state`` the state, ``POST /update`` a change; to its own pages only."""

    server_version = "plm-pin-inspect"

    def log_message(self, format: str, *args: Any) -> None:
        """Keep the terminal quiet (a slider sends many requests)."""

    def _send(self, status: int, body: bytes, kind: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def _json(self, status: int, data: object) -> None:
        self._send(status, json.dumps(data, allow_nan=False).encode("utf-8"), "application/json")

    def _foreign(self) -> bool:
        """Refuse (403) a request naming another host, or posted by a page of another origin.

        The page is on 127.0.0.1, but any web page the user opens could post to it, and a
        name resolving to 127.0.0.1 could reach it: only its own host and origin are answered.
        """
        port = self.server.server_port  # type: ignore[attr-defined]
        hosts = {f"{LOCALHOST}:{port}", f"localhost:{port}"}
        origin = self.headers.get("Origin")
        if self.headers.get("Host") in hosts and (origin is None or origin.removeprefix("http://") in hosts):
            return False
        self._json(HTTPStatus.FORBIDDEN, {"error": f"only pages of http://{LOCALHOST}:{port} are answered"})
        return True

    def do_GET(self) -> None:
        """The page or the state."""
        inspector: Inspector = self.server.inspector  # type: ignore[attr-defined]
        if self._foreign():
            return
        if self.path == "/":
            self._send(HTTPStatus.OK, page_html().encode("utf-8"), "text/html; charset=utf-8")
        elif self.path == "/state":
            with inspector._lock:
                self._json(HTTPStatus.OK, inspector.to_dict())
        else:
            self._json(HTTPStatus.NOT_FOUND, {"error": f"no such page {self.path!r}; the page is /"})

    def do_POST(self) -> None:
        """Apply a change; a malformed one answers 400 with the message."""
        inspector: Inspector = self.server.inspector  # type: ignore[attr-defined]
        if self._foreign():
            return
        if self.path != "/update":
            self._json(HTTPStatus.NOT_FOUND, {"error": f"no such endpoint {self.path!r}; post to /update"})
            return
        length = int(self.headers.get("Content-Length") or 0)
        if not 0 < length <= MAX_BODY:
            self._json(HTTPStatus.BAD_REQUEST, {"error": f"the body must hold 1 to {MAX_BODY} bytes of JSON"})
            return
        try:
            change = json.loads(self.rfile.read(length))
            inspector.update(change)
        except (ValueError, PlmError) as exc:
            self._json(HTTPStatus.BAD_REQUEST, {"error": str(exc)})
            return
        with inspector._lock:
            self._json(HTTPStatus.OK, inspector.to_dict())


def inspect(mech: Mechanism, *, port: int | None = None, source: str | None = None) -> Inspector:
    """Inspect ``mech`` live: drag it by its task coordinates or actuators and read it as it moves.

    It serves a control page on 127.0.0.1 (open :attr:`Inspector.url`); in a notebook,
    displaying the result shows its ipywidgets panel beside the inline scene
    (:meth:`Inspector.panel`).

    Args:
        mech: the mechanism (its task needs as many coordinates as DOF).
        port: port of the control page (default: the first free from 7200).
        source: the name or path ``mech`` was loaded from, for the "copy pose" texts.

    Returns:
        The running inspector; :meth:`Inspector.close` (or a ``with`` block) stops its page
        and closes its connections.

    Raises:
        ViewerError: meshcat missing, or no server or port.
        InvalidInput: a mechanism without a square task.
    """
    return Inspector(mech, port=port, source=source)
