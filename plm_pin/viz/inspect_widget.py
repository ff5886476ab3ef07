"""The live inspector in Jupyter: ipywidgets controls and readouts beside the inline meshcat scene.

The same controls as the browser page (:mod:`plm_pin.viz.inspect_server`), each calling
:meth:`Inspector.update <plm_pin.viz.Inspector.update>` (so
:func:`~plm_pin.viz.inspect_state.inspect_update`); ipywidgets is imported only here
(``pip install 'plm-pin[viz]'``).
"""

from __future__ import annotations

import html
import importlib
import math
from collections.abc import Mapping
from typing import Any, Protocol

from ..exceptions import PlmError, ViewerError
from .inspect_state import InspectState
from .meshcat_view import MeshcatViewer


class Driven(Protocol):
    """What the panel drives: an :class:`~plm_pin.viz.Inspector`."""

    state: InspectState
    viewer: MeshcatViewer
    ranges: dict[str, dict[str, tuple[float, float]]]

    def update(self, change: Mapping[str, object]) -> InspectState:
        """Apply a change and redraw; return the new state."""
        ...


SCENE_HEIGHT = 480
"""Height of the inline scene [px]."""


def _widgets() -> Any:
    try:
        return importlib.import_module("ipywidgets")
    except ImportError as exc:
        raise ViewerError(
            f"the inspector's Jupyter panel needs ipywidgets, which cannot be imported ({exc}): "
            "pip install 'plm-pin[viz]'"
        ) from None


def _text(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else str(value)
    return html.escape(str(value))


def _number(value: float) -> str:
    """A limit as the text of its entry: blank when infinite (no limit)."""
    return f"{value:.9g}" if math.isfinite(value) else ""


def _signs(mode: tuple[int, ...]) -> str:
    return ",".join("+" if s > 0 else "-" if s < 0 else "0" for s in mode)


def readout_html(state: InspectState) -> str:
    """The readouts of ``state`` as an HTML table (margins, manipulability, ellipse, forces, stiffness)."""
    rows = [
        ("stopped", state.stopped or "-"),
        ("closure residual [m, rad]", state.closure_residual),
        *((f"{kind} margin [-]", value) for kind, value in state.margins.items()),
        ("singular", ", ".join(state.singular) or "no"),
        ("manipulability w", state.manipulability),
        ("condition number [-]", state.condition_number),
        ("velocity ellipse radii", ", ".join(f"{r:.6g}" for r in state.ellipse_radii) or "-"),
        ("smallest stiffness [N/m]", state.stiffness),
        *(
            (f"force {name} [N, N m]", float(f))
            for name, f in zip(state.actuator_names, state.forces, strict=True)
        ),
        *(
            (f"internal {k + 1} range", f"{lo:.6g} .. {hi:.6g}")
            for k, (lo, hi) in enumerate(state.internal_range)
        ),
        *(("note", n) for n in state.notes),
    ]
    body = "".join(f"<tr><td>{html.escape(name)}</td><td>{_text(v)}</td></tr>" for name, v in rows)
    return f"<table>{body}</table><pre>{html.escape(state.cli_line)}</pre>"


class InspectorPanel:
    """ipywidgets controls of an :class:`~plm_pin.viz.Inspector` beside its inline scene.

    Attributes:
        inspector: the inspector the controls drive.
        task_sliders: one slider per task coordinate.
        actuator_sliders: one slider per actuator.
        working_mode: the working-mode selector.
        assembly_mode: the assembly-mode selector (filled by the "find modes" button).
        find_modes: the button that searches every working and assembly mode.
        load: one entry per task coordinate [N, N m].
        limits: one (lower, upper) pair of entries per actuator [N, N m], blank for no limit.
        readouts: the readouts (HTML).
        widget: the whole panel (an ``ipywidgets.HBox``).
    """

    def __init__(self, inspector: Driven) -> None:
        """Build the controls of ``inspector``.

        Raises:
            ViewerError: ipywidgets missing.
        """
        w = _widgets()
        self.inspector = inspector
        state = inspector.state
        self._quiet = False  # True while the panel sets its own widgets: no update is sent
        layout = {"width": "360px"}
        self.task_sliders = {
            d: self._slider(w, d, inspector.ranges["task"][d], float(v), "task", layout)
            for d, v in zip(state.dofs, state.x, strict=True)
        }
        self.actuator_sliders = {
            a: self._slider(w, a, inspector.ranges["actuators"][a], float(v), "actuators", layout)
            for a, v in zip(state.actuator_names, state.actuators, strict=True)
        }
        self.working_mode = w.Dropdown(description="working mode", layout=layout)
        self.working_mode.observe(self._on_working_mode, names="value")
        self.assembly_mode = w.Dropdown(description="assembly mode", layout=layout)
        self.assembly_mode.observe(self._on_assembly_mode, names="value")
        self.find_modes = w.Button(description="find modes")
        self.find_modes.on_click(lambda _: self._send({"find_modes": True}))
        self.load = [w.FloatText(value=0.0, description=f"load {d}", layout=layout) for d in state.dofs]
        for box in self.load:
            box.observe(lambda _: self._send({"load": [b.value for b in self.load]}), names="value")
        self.limits = {
            a: tuple(
                w.Text(_number(v), placeholder="none", description=f"{a} {side}", continuous_update=False)
                for side, v in zip(("min", "max"), pair, strict=True)
            )
            for a, pair in zip(state.actuator_names, state.force_limits, strict=True)
        }
        for pair in self.limits.values():
            for box in pair:
                box.observe(lambda _: self._send_limits(), names="value")
        self.readouts = w.HTML()
        self.error = w.HTML()
        controls = w.VBox(
            [
                w.HTML("<b>task coordinates</b>"),
                *self.task_sliders.values(),
                w.HTML("<b>actuators</b>"),
                *self.actuator_sliders.values(),
                self.working_mode,
                w.HBox([self.assembly_mode, self.find_modes]),
                *self.load,
                w.HTML("<b>actuator effort limits [N, N m]</b>"),
                *(w.HBox(list(pair)) for pair in self.limits.values()),
                self.error,
                self.readouts,
            ]
        )
        url = html.escape(inspector.viewer.url or "")
        scene = w.HTML(
            f'<iframe src="{url}" style="width: 100%; height: {SCENE_HEIGHT}px; border: none"></iframe>'
        )
        scene.layout = w.Layout(flex="1")
        self.widget = w.HBox([controls, scene])
        self._show(state)

    def _slider(
        self, w: Any, name: str, span: tuple[float, float], value: float, key: str, layout: dict
    ) -> Any:
        slider = w.FloatSlider(
            value=value,
            min=span[0],
            max=span[1],
            step=(span[1] - span[0]) / 1000.0,
            description=name,
            readout_format=".6g",
            continuous_update=True,
            layout=layout,
        )
        slider.observe(lambda change: self._send({key: {name: change["new"]}}), names="value")
        return slider

    def _on_working_mode(self, change: Mapping[str, Any]) -> None:
        if change["new"] is not None:
            self._send({"working_mode": list(change["new"])})

    def _on_assembly_mode(self, change: Mapping[str, Any]) -> None:
        if change["new"] is not None:
            self._send({"assembly_mode": change["new"]})

    def _send_limits(self) -> None:
        """Send the limits entries; one that is not a number is named in the error line."""
        pairs = []
        for name, boxes in self.limits.items():
            pair = []
            for box in boxes:
                text = box.value.strip()
                try:
                    pair.append(float(text) if text else None)
                except ValueError:
                    self.error.value = (
                        f'<span style="color: #b00">limits of {html.escape(name)}: '
                        f"{html.escape(text)!r} is not a number (blank: no limit)</span>"
                    )
                    return
            pairs.append(pair)
        self._send({"limits": pairs})

    def _send(self, change: Mapping[str, object]) -> None:
        if self._quiet:
            return
        try:
            state = self.inspector.update(change)
        except PlmError as exc:
            self.error.value = f'<span style="color: #b00">{html.escape(str(exc))}</span>'
            return
        self.error.value = ""
        self._show(state)

    def _show(self, state: InspectState) -> None:
        """Set every control to ``state`` (without sending updates) and write the readouts."""
        self._quiet = True
        try:
            for d, v in zip(state.dofs, state.x, strict=True):
                self.task_sliders[d].value = float(v)
            for a, v in zip(state.actuator_names, state.actuators, strict=True):
                self.actuator_sliders[a].value = float(v)
            modes = list(dict.fromkeys([state.working_mode, *state.working_modes]))
            self.working_mode.options = [
                (",".join("+" if s > 0 else "-" if s < 0 else "0" for s in m), m) for m in modes
            ]
            self.working_mode.value = state.working_mode
            count = len(state.assembly_modes)
            self.assembly_mode.options = [(f"mode {i + 1} of {count}", i) for i in range(count)]
            self.assembly_mode.value = state.assembly_index
            self.readouts.value = readout_html(state)
        finally:
            self._quiet = False

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display(self.widget)
