"""Meshcat inspection of a mechanism: geometry, frames, closure points, forces, singularities, motions.

A :class:`MeshcatViewer` draws one mechanism under ``/meshcat/plm_pin/<name>`` of a meshcat scene,
with Pinocchio's ``MeshcatVisualizer``:

- its visual geometry, or, when it has none, a skeleton: rods between joint origins and
  from each joint to its frames, balls at the joints, thin dashed lines from the base
  origin to the joints on the base (not links);
- the rail of each prismatic joint (its stroke between its limits, along its axis) and the
  platform as a closed polygon through its attachment points (:mod:`plm_pin.viz.skeleton`);
- triads at the joint frames and the task frame (x red, y green, z blue);
- a ball at both frames of every closure, green when the closure holds at the displayed
  configuration, magenta when its residual exceeds :data:`VIEW_OPEN_TOL`;
- the geometry recoloured when :func:`plm_pin.kinematics.classify` finds the configuration
  singular (one colour per kind, :data:`SINGULAR_COLORS`);
- force arrows of a static case (:meth:`MeshcatViewer.show_forces`);
- motions as meshcat animations (:meth:`MeshcatViewer.animate`);
- overlays: the boundary of a workspace slice (:meth:`MeshcatViewer.show_workspace`) and
  singular points (:meth:`MeshcatViewer.show_singular_points`);
- a legend of these colours and marks over the page (:mod:`plm_pin.viz.legend`).

The camera looks at the centre of the box around the mechanism's frame origins, from the
distance at which the box fills :data:`FILL_FRACTION` of the view's height.

The scene goes to a meshcat server on 127.0.0.1 (see :mod:`plm_pin.viz.meshcat_server`) or,
with ``static=True``, stays in memory; either way :meth:`MeshcatViewer.static_html` returns
it as one self-contained HTML page a reader can rotate without a server. Lengths in [m],
forces in [N], angles in [rad], times in [s].
"""

from __future__ import annotations

import functools
import html
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._io import atomic_write_text
from ..core.mechanism import Mechanism
from ..exceptions import FrameNotFound, InvalidInput
from ..kinematics.singularity import SingularityReport, classify
from ..results import Result, unit
from ..tolerances import PLANE_NORMAL_TOL, VIEW_MIN_LENGTH, VIEW_OPEN_TOL
from ..workspace import SingularPoint, WorkspaceSlice
from .force_figure import ForceArrow
from .legend import (
    CLOSED_COLOR,
    ENTRIES,
    FORCE_COLOR,
    OPEN_COLOR,
    PLATFORM_COLOR,
    RAIL_COLOR,
    SINGULAR_COLORS,
    SKELETON_COLOR,
    VIRTUAL_COLOR,
    WORKSPACE_COLOR,
    with_legend,
)
from .meshcat_server import MeshcatServer, ServerWindow, StaticWindow, require_meshcat
from .skeleton import platform_polygon, prismatic_rails

ANIMATION_FPS = 30
"""Frame rate of meshcat animation clips [1/s] (key times are not rounded to it)."""

# sizes relative to the mechanism's extent (largest side of the box around its frame origins)
_MARKER = 0.02
_ROD = 0.006
_BALL = 0.012
_AXIS = 0.08
_ARROW = 0.006
_DASH = 0.03
_RAIL = 0.01
_EDGE = 0.008
_POINT = 0.03
_MIN_EXTENT = 1e-3  # [m]

_VISUAL = pin.GeometryType.VISUAL


@dataclass(frozen=True)
class SceneStatus(Result):
    """What a displayed configuration shows.

    Attributes:
        closure_errors: largest absolute residual of each closure [m, rad].
        open_closures: the closures whose residual exceeds :data:`VIEW_OPEN_TOL`, marked apart.
        singularity: the classification of the configuration, or None when it was not
            classified (the mechanism has no task, or a closure is open).
    """

    closure_errors: Mapping[str, float] = field(metadata=unit("m, rad"))
    open_closures: tuple[str, ...]
    singularity: SingularityReport | None

    @property
    def singular_kinds(self) -> tuple[str, ...]:
        """The singularity kinds found (empty when regular or not classified)."""
        return self.singularity.kinds if self.singularity is not None else ()


def scene_status(mech: Mechanism, q: ArrayLike) -> SceneStatus:
    """Closure residuals of ``q`` and, when the loops hold and there is a task, its singularity report."""
    errors = mech.closure_errors(q)
    open_closures = tuple(name for name, err in errors.items() if err > VIEW_OPEN_TOL)
    report = None
    if mech.task_compiled is not None and not open_closures:
        report = classify(mech, q)
    return SceneStatus(errors, open_closures, report)


def _segment(name: str) -> str:
    """A name usable as one meshcat path element ('/' separates elements)."""
    return name.replace("/", "_") or "_"


def _frame_box(mech: Mechanism) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners of the box around the frame origins [m], each shape (3,).

    At the reference guess (no assembly needed).
    """
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.reference_guess())
    points = np.array([M.translation for M in data.oMf])  # (n_frames, 3)
    return points.min(axis=0), points.max(axis=0)


CAMERA_DIRECTION = np.array([0.6, 2.0, 1.0]) / np.linalg.norm([0.6, 2.0, 1.0])
"""Where the camera looks from, in meshcat's turned camera frame (y up): world (0.6, -1, 2), normalised."""

FILL_FRACTION = 0.8
"""Share of the view's height the mechanism fills [-]: the sphere around its bounding box is seen
under this share of the half-height (in tangent of the angle from the view's axis)."""

CAMERA_FOV = 75.0
"""Vertical field of view of meshcat's default camera [deg]."""

CAMERA_NEAR = 0.01
"""Near clipping plane of the camera, in camera distances [-]."""

GRID_CELL = 0.25
"""Side of a cell of the ground grid, in mechanism sizes [-] (meshcat's grid: 40 cells of 0.5 m)."""


def camera_distance(lower: ArrayLike, upper: ArrayLike, fill: float = FILL_FRACTION) -> float:
    """Distance [m] from the centre of box ``lower``..``upper`` [m] at which it fills ``fill`` of the view.

    The sphere around the box (radius ``r``, the half-diagonal) is tangent to the cone of
    half-angle ``a = atan(fill tan(fov / 2))`` around the view's axis, with :data:`CAMERA_FOV`:
    ``d = r / sin(a)``, so the whole box is in view whatever the direction. A box smaller than
    1 mm is taken as 1 mm wide.

    Raises:
        InvalidInput: corners that are not 3 finite numbers each, or ``fill`` outside (0, 1].
    """
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if lo.shape != (3,) or hi.shape != (3,) or not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise InvalidInput("lower and upper must be 3 finite numbers each [m]")
    if not (isinstance(fill, numbers.Real) and 0.0 < fill <= 1.0):
        raise InvalidInput(f"fill must be in (0, 1], got {fill!r}")
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 0.5 * _MIN_EXTENT)
    return radius / float(np.sin(np.arctan(float(fill) * np.tan(np.radians(CAMERA_FOV) / 2.0))))


PLANAR_TILT = 0.05
"""Tilt of the camera off a planar mechanism's normal [rad-ish]: keeps the orbit controls off their pole."""

AXES_SCALE = 1.0
"""Length of meshcat's world axes, in mechanism sizes (meshcat draws them 0.5 m long) [-]."""


def plane_normal(mech: Mechanism, tol: float = PLANE_NORMAL_TOL) -> np.ndarray | None:
    """The unit normal of the plane a planar mechanism moves in, None for a spatial one.

    Planar: at the reference guess, every joint turns about one common world axis n (or
    slides), and no frame can move along n. Computed from the world-aligned frame Jacobians.
    """
    model, data = mech.model, mech.model.createData()
    q = mech.reference_guess()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    blocks = [
        pin.getFrameJacobian(model, data, k, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        for k in range(model.nframes)
    ]
    angular = np.hstack([J[3:] for J in blocks])  # (3, nframes * nv)
    _, sv, vt = np.linalg.svd(angular.T, full_matrices=False)
    if sv.size == 0 or sv[0] == 0.0 or (sv.size > 1 and sv[1] > tol * sv[0]):
        return None
    normal = vt[0] / np.linalg.norm(vt[0])
    linear = np.hstack([J[:3] for J in blocks])  # (3, nframes * nv)
    scale = max(float(np.abs(linear).max()), 1e-12)
    if np.abs(normal @ linear).max() > tol * scale:
        return None
    k = int(np.argmax(np.abs(normal)))
    return normal if normal[k] > 0 else -normal  # pointing along +z for a mechanism in the xy plane


def _camera_direction(mech: Mechanism) -> np.ndarray:
    """Where the camera looks from, in meshcat's turned camera frame: near the normal when planar.

    A planar mechanism is seen from its plane's normal, tilted by :data:`PLANAR_TILT` so that
    world +y (or +z for a vertical plane) points up the screen.
    """
    normal = plane_normal(mech)
    if normal is None:
        return CAMERA_DIRECTION
    up = np.array([0.0, 1.0, 0.0]) if abs(normal[1]) < 0.9 else np.array([0.0, 0.0, 1.0])
    up -= (up @ normal) * normal
    eye = normal - PLANAR_TILT * up / np.linalg.norm(up)  # world frame: then +up is up the screen
    eye /= np.linalg.norm(eye)
    return np.array([eye[0], eye[2], -eye[1]])  # world (x, y, z) -> camera frame (x, z, -y)


def _along(offset: np.ndarray) -> pin.SE3:
    """Placement of a z-axis rod (centred at its origin) spanning from 0 to ``offset``."""
    rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), offset).matrix()
    return pin.SE3(rotation, 0.5 * offset)


def _rod(name: str, parent: int, start: np.ndarray, end: np.ndarray, radius: float) -> pin.GeometryObject:
    """A cylinder from ``start`` to ``end`` [m], fixed in joint ``parent``'s frame."""
    import coal

    offset = end - start
    placement = _along(offset)
    placement.translation = placement.translation + start
    return pin.GeometryObject(name, parent, placement, coal.Cylinder(radius, float(np.linalg.norm(offset))))


def _dashes(name: str, end: np.ndarray, size: float) -> list[pin.GeometryObject]:
    """A thin dashed line from the base origin to ``end`` [m]: dashes and gaps about ``size * _DASH`` long."""
    length = float(np.linalg.norm(end))
    count = max(1, int(length / (2.0 * size * _DASH)))
    step = end / (2 * count - 1)  # dash, gap, ..., dash
    return [_rod(f"{name}/{k}", 0, 2 * k * step, (2 * k + 1) * step, 0.5 * size * _ROD) for k in range(count)]


def _skeleton(model: pin.Model, size: float) -> list[pin.GeometryObject]:
    """Rods from each joint origin to its child joints and frames, and a ball at each joint.

    A rod is fixed in its parent joint's frame, so it moves (and animates) with it; it is
    named after the first child found at its end. From the base origin, where no link is,
    the lines are thin and dashed (``virtual/<child>``).
    """
    import coal

    ends: dict[tuple[int, tuple[float, ...]], str] = {}
    for j in range(1, model.njoints):
        ends.setdefault((model.parents[j], tuple(model.jointPlacements[j].translation)), model.names[j])
    for frame in model.frames:
        ends.setdefault((frame.parentJoint, tuple(frame.placement.translation)), frame.name)
    objects = [
        pin.GeometryObject(
            f"joints/{_segment(model.names[j])}", j, pin.SE3.Identity(), coal.Sphere(size * _BALL)
        )
        for j in range(1, model.njoints)
    ]
    for ball in objects:
        ball.meshColor = np.array(SKELETON_COLOR)
    names: set[str] = set()
    for (parent, end), child in ends.items():
        offset = np.array(end)
        length = float(np.linalg.norm(offset))
        if length <= VIEW_MIN_LENGTH:
            continue
        name = f"{'virtual' if parent == 0 else 'links'}/{_segment(child)}"
        while name in names:  # a frame may share a joint's name
            name += "_"
        names.add(name)
        if parent == 0:
            for dash in _dashes(name, offset, size):
                dash.meshColor = np.array(VIRTUAL_COLOR)
                objects.append(dash)
            continue
        rod = _rod(name, parent, np.zeros(3), offset, size * _ROD)
        rod.meshColor = np.array(SKELETON_COLOR)
        objects.append(rod)
    return objects


def _guides(mech: Mechanism, size: float) -> list[pin.GeometryObject]:
    """Rails of the prismatic joints (``rails/<joint>``) and the platform's closed polygon (``platform/<k>``).

    A rail is fixed in the prismatic joint's parent frame; the polygon's edge ``k`` runs from
    attachment point ``k`` to the next (the last to the first), fixed in the platform's frame.
    """
    objects = []
    for rail in prismatic_rails(mech.model):
        obj = _rod(f"rails/{_segment(rail.joint)}", rail.parent, rail.start, rail.end, size * _RAIL)
        obj.meshColor = np.array(RAIL_COLOR)
        objects.append(obj)
    platform = platform_polygon(mech)
    if platform is not None:
        ring = platform.points
        for k in range(len(ring)):
            obj = _rod(f"platform/{k}", platform.joint, ring[k], ring[(k + 1) % len(ring)], size * _EDGE)
            obj.meshColor = np.array(PLATFORM_COLOR)
            objects.append(obj)
    return objects


def _closure_markers(mech: Mechanism, size: float) -> dict[str, tuple[str, pin.GeometryObject]]:
    """A ball at each frame of each closure: ``{"closures/<closure>/<frame>": (closure name, ball)}``."""
    import coal

    markers = {}
    for closure in mech.closures:
        for fid in closure.frame_ids:
            frame = mech.model.frames[fid]
            name = f"closures/{_segment(closure.name)}/{_segment(frame.name)}"
            ball = pin.GeometryObject(
                name, frame.parentJoint, fid, frame.placement, coal.Sphere(size * _MARKER)
            )
            ball.meshColor = np.array(CLOSED_COLOR)
            markers[name] = (closure.name, ball)
    return markers


Arrow = ForceArrow | tuple[ArrayLike | str, ArrayLike, str]
"""A force arrow for :meth:`MeshcatViewer.show_forces`: a ``ForceArrow`` or ``(point, vector, label)``."""


def _check_arrows(
    mech: Mechanism, q: np.ndarray, arrows: Sequence[Arrow]
) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """The arrows as ``(point [m], vector [N], segment name)``, frame names placed at ``q``.

    Raises:
        InvalidInput: a malformed arrow, a repeated label.
        FrameNotFound: a point naming no frame of ``mech`` (the message lists the frames).
    """
    data = None
    out = []
    labels: set[str] = set()
    for k, arrow in enumerate(arrows):
        point: ArrayLike | str
        vector: ArrayLike
        if isinstance(arrow, ForceArrow):
            point, vector, label = arrow.point, arrow.force, f"{arrow.kind} {arrow.name}"
        else:
            try:
                point, vector, label = arrow
            except (TypeError, ValueError):
                raise InvalidInput(
                    f"arrow {k} must be a ForceArrow or (point [m] or frame name, vector [N], label), "
                    f"got {arrow!r}"
                ) from None
        if isinstance(point, str):
            if not mech.model.existFrame(point):
                raise FrameNotFound(point, mech.frame_names)
            if data is None:
                data = mech.model.createData()
                pin.framesForwardKinematics(mech.model, data, q)
            point = data.oMf[mech.model.getFrameId(point)].translation
        try:
            p = np.asarray(point, dtype=float)
            f = np.asarray(vector, dtype=float)
        except (TypeError, ValueError):
            p = f = np.full(0, np.nan)
        if p.shape != (3,) or f.shape != (3,) or not (np.all(np.isfinite(p)) and np.all(np.isfinite(f))):
            raise InvalidInput(
                f"arrow {label!r}: point (or a frame name) and vector must be 3 finite numbers each"
            )
        if not isinstance(label, str) or not label:
            raise InvalidInput(f"arrow {k}: label must be a non-empty string, got {label!r}")
        name = _segment(label)
        if name in labels:
            raise InvalidInput(f"arrow labels must be distinct; {label!r} is repeated")
        labels.add(name)
        out.append((p, f, name))
    return out


def boundary_mask(reachable: ArrayLike) -> np.ndarray:
    """The boundary of a slice's reachable region: reachable points next to an unreachable one or on the edge.

    Neighbours are the points one step away along one axis (4 in a 2-D grid, 2 in a 1-D one).

    Args:
        reachable: whether each grid point was reached, any number of dimensions.

    Returns:
        Boolean array of the same shape.
    """
    inside = np.asarray(reachable, dtype=bool)
    padded = np.pad(inside, 1, constant_values=False)
    interior = padded.copy()
    for axis in range(inside.ndim):
        for step in (1, -1):
            interior &= np.roll(padded, step, axis=axis)
    return inside & ~interior[tuple(slice(1, -1) for _ in range(inside.ndim))]


def task_origins(mech: Mechanism, qs: ArrayLike) -> np.ndarray:
    """World position [m] of the task frame's origin at each configuration, shape (n, 3).

    Raises:
        InvalidInput: ``mech`` has no frame task, or ``qs`` is not of shape (n, nq).
    """
    fid = mech.task_frame_id
    if fid is None:
        raise InvalidInput(f"{mech.name} has no task frame to place overlay points at")
    arr = np.asarray(qs, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != mech.nq:
        raise InvalidInput(f"configurations must have shape (n, {mech.nq}), got {arr.shape}")
    data = mech.model.createData()
    out = np.empty((arr.shape[0], 3))
    for k, q in enumerate(arr):
        pin.framesForwardKinematics(mech.model, data, q)
        out[k] = data.oMf[fid].translation
    return out


@functools.cache
def _batched_frame_class() -> type:
    """The animation frame of meshcat, its rotations turned to quaternions afterwards, all at once.

    :meth:`set_transform` records the position as meshcat does, and for the quaternion a list
    that :func:`_fill_quaternions` fills in place: the animation is the one meshcat builds,
    its tracks and keys in the same order, without one 4 x 4 eigenproblem call per node and frame.
    """
    base = require_meshcat().animation.AnimationFrameVisualizer

    class BatchedFrame(base):  # type: ignore[misc, valid-type]
        __slots__ = ("pending",)

        def __init__(self, animation: Any, path: Any, current_frame: float, pending: list[Any]) -> None:
            super().__init__(animation, path, current_frame)
            self.pending = pending

        def __getitem__(self, path: str) -> BatchedFrame:
            return BatchedFrame(self.animation, self.path.append(path), self.current_frame, self.pending)

        def set_transform(self, matrix: np.ndarray) -> None:
            clip = self.get_clip()
            clip.set_property(self.current_frame, "position", "vector3", list(matrix[:3, 3]))
            quaternion: list[Any] = []
            clip.set_property(self.current_frame, "quaternion", "quaternion", quaternion)
            self.pending.append((quaternion, np.array(matrix, dtype=np.float64)[:4, :4]))

    return BatchedFrame


def _fill_quaternions(pending: list[tuple[list[Any], np.ndarray]]) -> None:
    """Fill each recorded quaternion list with meshcat's ``js_quaternion`` of its matrix.

    The arithmetic of ``meshcat.transformations.quaternion_from_matrix`` (its general branch),
    on all the matrices at once: the same symmetric matrix K, the same LAPACK eigensolver
    (a stack is solved matrix by matrix), so the same numbers.
    """
    if not pending:
        return
    M = np.stack([m for _, m in pending])  # (n, 4, 4)
    m00, m01, m02 = M[:, 0, 0], M[:, 0, 1], M[:, 0, 2]
    m10, m11, m12 = M[:, 1, 0], M[:, 1, 1], M[:, 1, 2]
    m20, m21, m22 = M[:, 2, 0], M[:, 2, 1], M[:, 2, 2]
    zero = np.zeros(len(pending))
    K = np.stack(
        [
            np.stack([m00 - m11 - m22, zero, zero, zero], axis=-1),
            np.stack([m01 + m10, m11 - m00 - m22, zero, zero], axis=-1),
            np.stack([m02 + m20, m12 + m21, m22 - m00 - m11, zero], axis=-1),
            np.stack([m21 - m12, m02 - m20, m10 - m01, m00 + m11 + m22], axis=-1),
        ],
        axis=1,
    )  # (n, 4, 4)
    K /= 3.0
    w, V = np.linalg.eigh(K)
    for (quaternion, _), wk, Vk in zip(pending, w, V, strict=True):
        q = Vk[[3, 0, 1, 2], np.argmax(wk)]
        if q[0] < 0.0:
            np.negative(q, q)
        quaternion[:] = [q[1], q[2], q[3], q[0]]


def _check_motion(mech: Mechanism, qs: ArrayLike, times: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    q_arr = np.asarray(qs, dtype=float)
    t_arr = np.asarray(times, dtype=float)
    if q_arr.ndim != 2 or q_arr.shape[1] != mech.nq or q_arr.shape[0] == 0:
        raise InvalidInput(f"qs must have shape (n, {mech.nq}) with n >= 1, got {q_arr.shape}")
    if t_arr.shape != (q_arr.shape[0],):
        raise InvalidInput(f"times must have shape ({q_arr.shape[0]},) like qs, got {t_arr.shape}")
    if not (np.all(np.isfinite(q_arr)) and np.all(np.isfinite(t_arr))):
        raise InvalidInput("qs and times must be finite")
    if np.any(np.diff(t_arr) <= 0.0):
        raise InvalidInput("times must be strictly increasing [s]")
    return q_arr, t_arr


class MeshcatViewer:
    """One mechanism in a meshcat scene, on a local server or in memory.

    Attributes:
        mech: the mechanism shown.
        server: the server the scene is on, when this process started it.
        root: path of the mechanism in the scene, ``plm_pin/<name>`` (under meshcat's ``/meshcat``).
        size: extent of the mechanism, the scale of markers, rods and triads [m].
    """

    def __init__(
        self,
        mech: Mechanism,
        *,
        static: bool = False,
        server: MeshcatServer | None = None,
        zmq_url: str | None = None,
        port: int | None = None,
        frames: bool = True,
    ) -> None:
        """Draw ``mech`` in a scene (not yet placed: call :meth:`display`).

        Args:
            mech: the mechanism.
            static: keep the scene in memory (no server): for :meth:`static_html`.
            server: a server to draw in (default: this process's shared server, started
                on first use on ``port``).
            zmq_url: draw in a server started elsewhere (``meshcat-server``, ``plm-pin view``),
                given by its ``tcp://127.0.0.1:PORT`` address.
            port: web port of the shared server when it must be started (default: the
                first free port from 7000); a busy port is replaced by the next free one.
            frames: draw triads at the joint frames and the task frame.

        Raises:
            ViewerError: meshcat missing, or the server cannot be started or reached.
            InvalidInput: more than one of ``static``, ``server``, ``zmq_url``; ``port`` with
                one of them; or a ``zmq_url`` that is not on this machine.
        """
        meshcat = require_meshcat()
        if sum((static, server is not None, zmq_url is not None)) > 1:
            raise InvalidInput("give at most one of static=True, server= and zmq_url=")
        if port is not None and (static or server is not None or zmq_url is not None):
            raise InvalidInput("port= is for the shared server: not with static=True, server= or zmq_url=")
        self.mech = mech
        self.server: MeshcatServer | None = None
        window: StaticWindow | ServerWindow
        if static:
            window = StaticWindow()
        elif zmq_url is not None:
            window = ServerWindow(zmq_url)
        else:
            self.server = server if server is not None else shared_server(port)
            window = ServerWindow(self.server.zmq_url, self.server.web_url)
        self._window = window
        self._vis = meshcat.Visualizer(window=window)
        self.root = f"plm_pin/{_segment(mech.name)}"
        lower, upper = _frame_box(mech)
        self.size = max(float(np.max(upper - lower)), _MIN_EXTENT)
        # meshcat's camera orbits the world origin from (3, 0, 1) m: too far for a 0.3 m table and
        # off-centre for a mechanism away from the origin. Shift the scene (and the grid and world
        # axes with it) so that the mechanism's centre is at the orbit point, scale the world axes
        # and the grid's cells to the mechanism, and look from the distance at which it fills the
        # view: from above and in front, or, for a planar mechanism, from its plane's normal.
        shift = np.eye(4)
        shift[:3, 3] = -0.5 * (lower + upper)
        self._vis["/meshcat"].set_transform(shift)
        for path, scale in (("/Grid", GRID_CELL * self.size / 0.5), ("/Axes", AXES_SCALE * self.size / 0.5)):
            scaled = shift.copy()
            scaled[:3, :3] *= scale
            self._vis[path].set_transform(scaled)
        self.camera_distance = camera_distance(lower, upper)
        camera = self._vis["/Cameras/default/rotated/<object>"]
        camera.set_property("position", (self.camera_distance * _camera_direction(mech)).tolist())
        camera.set_property("near", CAMERA_NEAR * self.camera_distance)  # meshcat's 0.01 m cuts a small part
        self._animated = False
        self._overlays: set[str] = set()
        self._build(frames)

    def _build(self, frames: bool) -> None:
        from pinocchio.visualize import MeshcatVisualizer  # imports meshcat

        mech, size = self.mech, self.size
        geometry = mech.visual_model.copy()
        for obj in geometry.geometryObjects:
            obj.name = _segment(obj.name)
        skeleton = geometry.ngeoms == 0
        for obj in (*(_skeleton(mech.model, size) if skeleton else ()), *_guides(mech, size)):
            geometry.addGeometryObject(obj)
        markers = _closure_markers(mech, size)
        for _, ball in markers.values():
            geometry.addGeometryObject(ball)
        self._marked = {name: closure for name, (closure, _) in markers.items()}  # marker -> closure
        self._geometry = geometry
        self._vis[self.root].delete()
        viz = MeshcatVisualizer(mech.model, None, geometry)
        viz.initViewer(viewer=self._vis)
        viz.loadViewerModel(rootNodeName=self.root)
        if frames:
            ids = [i for i, f in enumerate(mech.model.frames) if f.type == pin.FrameType.JOINT]
            if mech.task_frame_id is not None and mech.task_frame_id not in ids:
                ids.append(mech.task_frame_id)
            viz.displayFrames(True, frame_ids=ids, axis_length=size * _AXIS, axis_width=2)
        self._viz = viz
        self._colors = {  # own colours, as loaded
            obj.name: CLOSED_COLOR if obj.name in self._marked else tuple(obj.meshColor)
            for obj in geometry.geometryObjects
        }
        self._shown = dict(self._colors)  # colours on screen
        drawn = {name.split("/", 1)[0] for name in self._colors}
        self._marks = [  # the legend's keys for what is drawn, in the legend's order
            key
            for key, shown in (
                ("link", skeleton),
                ("virtual", "virtual" in drawn),
                ("rail", "rails" in drawn),
                ("platform", "platform" in drawn),
                ("closed", bool(markers)),
                ("open", bool(markers)),
            )
            if shown
        ]

    # ---------------------------------------------------------------- scene
    @property
    def url(self) -> str | None:
        """Address of the page showing the scene (None for a static scene)."""
        return self._window.web_url

    def open(self) -> MeshcatViewer:
        """Open the page in a web browser (not for a static scene); returns the viewer."""
        self._window.open()
        return self

    def close(self) -> None:
        """Close the connection to the server (idempotent); the server and its page keep running.

        A ``with MeshcatViewer(...) as viewer:`` block closes it at its end.
        """
        self._window.close()

    def __enter__(self) -> MeshcatViewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def legend(self) -> list[str]:
        """Keys of :data:`plm_pin.viz.legend.ENTRIES` of what the scene draws, in the legend's order.

        The singularity kinds are listed when the mechanism has a task; forces and overlays
        once shown.
        """
        kinds = list(SINGULAR_COLORS) if self.mech.task_compiled is not None else []
        keys = [*self._marks, *sorted(self._overlays & {"force", "workspace"}), *kinds]
        return [key for key in ENTRIES if key in keys]

    def static_html(self) -> str:
        """The scene as one self-contained HTML page (what was shown last), with its legend."""
        return with_legend(str(self._vis.static_html()), [ENTRIES[key] for key in self.legend])

    def write_html(self, path: str | Path) -> Path:
        """Write :meth:`static_html` to ``path`` atomically (its folder must exist); returns the path."""
        out = Path(path)
        atomic_write_text(out, self.static_html())
        return out

    # ------------------------------------------------------------ drawing
    def display(self, q: ArrayLike | None = None) -> SceneStatus:
        """Place the mechanism at ``q`` (default: the reference configuration) and mark its state.

        Closure markers turn magenta where a closure is open; the geometry takes the colour of
        the singularity found (:data:`SINGULAR_COLORS`). Force arrows and animations shown
        before are removed.

        Args:
            q: configuration, shape (nq,); need not be assembled.

        Returns:
            The closure residuals and singularity classification shown.
        """
        qa = np.array(self.mech.q_ref if q is None else self.mech.check_q(q))
        status = scene_status(self.mech, qa)
        self._recolor(status)
        if self._animated:
            self._vis.set_animation(require_meshcat().animation.Animation(), play=False)
            self._animated = False
        self._vis[f"{self.root}/forces"].delete()
        self._overlays.discard("force")
        self._viz.display(qa)
        return status

    def _recolor(self, status: SceneStatus) -> None:
        """Reload the geometry whose colour changes: closure markers by state, the rest if singular."""
        kinds = status.singular_kinds
        for obj in self._geometry.geometryObjects:
            closure = self._marked.get(obj.name)
            if closure is not None:
                color = OPEN_COLOR if closure in status.open_closures else CLOSED_COLOR
            else:
                fixed = obj.name.startswith(("rails/", "virtual/"))  # the base keeps its colours
                color = SINGULAR_COLORS[kinds[0]] if kinds and not fixed else self._colors[obj.name]
            if color != self._shown[obj.name]:
                self._viz.loadViewerGeometryObject(obj, _VISUAL, np.array(color))
                self._shown[obj.name] = color

    def show_forces(self, q: ArrayLike, arrows: Sequence[Arrow], scale: float) -> SceneStatus:
        """Display ``q`` with force arrows, e.g. the loads and actuator forces of a static case.

        Each arrow starts at its point and is ``scale * |vector|`` long; it is drawn under
        ``<root>/forces/<label>`` so the labels show in meshcat's scene tree. Zero vectors
        draw nothing.

        Args:
            q: configuration, shape (nq,).
            arrows: the :class:`~plm_pin.viz.ForceArrow` objects that
                :func:`~plm_pin.viz.force_arrows` returns (labelled ``"<kind> <name>"``), or
                ``(point, vector [N], label)`` triples: the point in the world frame [m] or the
                name of a frame (its origin at ``q``), the vector in the world frame; labels distinct.
            scale: arrow length per force [m/N], positive.

        Returns:
            The status of the configuration (see :meth:`display`).

        Raises:
            InvalidInput: malformed arrows, repeated labels or a scale that is not positive.
            FrameNotFound: a point naming no frame (the message lists the frames).
        """
        if not (isinstance(scale, numbers.Real) and np.isfinite(scale) and scale > 0.0):
            raise InvalidInput(f"scale must be a positive number [m/N], got {scale!r}")
        scale = float(scale)  # meshcat's messages take Python numbers only
        qa = self.mech.check_q(q)
        checked = _check_arrows(self.mech, qa, arrows)
        status = self.display(qa)
        mg = require_meshcat().geometry
        material = mg.MeshLambertMaterial(color=FORCE_COLOR)
        radius = self.size * _ARROW
        for point, vector, name in checked:
            length = scale * float(np.linalg.norm(vector))
            if length == 0.0:
                continue
            u = vector / np.linalg.norm(vector)
            head = min(0.3 * length, 6.0 * radius)
            rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 1.0, 0.0]), u).matrix()
            node = self._vis[f"{self.root}/forces/{name}"]
            for part, height, top, bottom, centre in (
                ("shaft", length - head, radius, radius, 0.5 * (length - head)),
                ("head", head, 0.0, 2.5 * radius, length - 0.5 * head),
            ):
                node[part].set_object(mg.Cylinder(height, radiusTop=top, radiusBottom=bottom), material)
                node[part].set_transform(pin.SE3(rotation, point + centre * u).homogeneous)
            self._overlays.add("force")
        return status

    # ------------------------------------------------------------ overlays
    def _points(self, path: str, points: np.ndarray, color: tuple[float, ...]) -> None:
        """Draw ``points`` [m], shape (n, 3), as dots under ``<root>/overlays/<path>`` (none: delete it)."""
        node = self._vis[f"{self.root}/overlays/{path}"]
        if points.size == 0:
            node.delete()
            return
        mg = require_meshcat().geometry
        colors = np.tile(np.array(color[:3], dtype=np.float32)[:, None], (1, len(points)))  # one per point
        geometry = mg.PointsGeometry(points.T.astype(np.float32), color=colors)
        node.set_object(mg.Points(geometry, mg.PointsMaterial(size=self.size * _POINT)))

    def show_workspace(self, grid: WorkspaceSlice) -> np.ndarray:
        """Overlay the boundary of a workspace slice: the task frame's origin at its boundary poses.

        The boundary poses are the reachable grid points next to an unreachable one or on the
        grid's edge (:func:`boundary_mask`); they stay shown (over later configurations and
        motions) until :meth:`clear_overlays` or another slice.

        Args:
            grid: a slice of this mechanism (:func:`plm_pin.workspace.workspace_map` or
                :func:`~plm_pin.workspace.workspace_sweep`).

        Returns:
            The points drawn [m], shape (n, 3), in the world frame.

        Raises:
            InvalidInput: a slice whose configurations do not fit this mechanism.
        """
        points = task_origins(self.mech, grid.q[boundary_mask(grid.reachable)])
        self._points("workspace", points, WORKSPACE_COLOR)
        self._overlays.add("workspace")
        return points

    def show_singular_points(self, points: Sequence[SingularPoint]) -> dict[str, np.ndarray]:
        """Overlay singular points (e.g. :func:`plm_pin.workspace.singular_loci`), coloured by kind.

        Each point is the task frame's origin at its configuration, in the colour of its kind
        (:data:`SINGULAR_COLORS`); they stay shown until :meth:`clear_overlays` or other points.

        Args:
            points: the singular points of this mechanism.

        Returns:
            The points drawn per kind [m], shape (n, 3) each, in the world frame.

        Raises:
            InvalidInput: a point whose configuration does not fit this mechanism.
        """
        out = {}
        for kind, color in SINGULAR_COLORS.items():
            qs = [p.q for p in points if p.kind == kind]
            out[kind] = task_origins(self.mech, np.array(qs).reshape(len(qs), self.mech.nq))
            self._points(f"singular/{kind}", out[kind], color)
        return out

    def clear_overlays(self) -> None:
        """Remove the workspace boundary and the singular points."""
        self._vis[f"{self.root}/overlays"].delete()
        self._overlays.discard("workspace")

    def animate(
        self, qs: ArrayLike, times: ArrayLike, *, play: bool = True, repetitions: int = 1
    ) -> SceneStatus:
        """Show a motion (simulated or planned) as a meshcat animation, starting at ``times[0]``.

        Colours (closures, singularity) are those of the first configuration.

        Args:
            qs: configurations, shape (n, nq).
            times: their times [s], shape (n,), strictly increasing.
            play: start playing at once.
            repetitions: times the clip is played.

        Returns:
            The status of the first configuration.

        Raises:
            InvalidInput: malformed ``qs`` or ``times``.
        """
        q_arr, t_arr = _check_motion(self.mech, qs, times)
        status = self.display(q_arr[0])
        animation = require_meshcat().animation.Animation(default_framerate=ANIMATION_FPS)
        frame_class = _batched_frame_class()
        pending: list[tuple[list[Any], np.ndarray]] = []
        try:
            for q, t in zip(q_arr, t_arr, strict=True):
                frame = frame_class(animation, self._vis.path, (t - t_arr[0]) * ANIMATION_FPS, pending)
                self._viz.viewer = frame  # Pinocchio places the nodes through its viewer
                self._viz.display(q)
        finally:
            self._viz.viewer = self._vis
        _fill_quaternions(pending)
        self._vis.set_animation(animation, play=play, repetitions=repetitions)
        self._animated = True
        return status

    # ------------------------------------------------------------ notebook
    def _repr_html_(self) -> str:
        """The scene inline in a notebook: the live page, or the static page for a static scene."""
        style = 'style="width: 100%; height: 400px; border: none"'
        if self.url is None:
            return f'<iframe srcdoc="{html.escape(self.static_html())}" {style}></iframe>'
        return f'<iframe src="{html.escape(self.url)}" {style}></iframe>'

    def __repr__(self) -> str:
        where = "static" if self.url is None else self.url
        return f"MeshcatViewer({self.mech.name!r}, {where!r})"


_shared: dict[str, MeshcatServer] = {}


def shared_server(port: int | None = None) -> MeshcatServer:
    """This process's meshcat server: the running one, or a new one on ``port``.

    The running server is reused when ``port`` is None or the port it was asked for or
    serves; otherwise a new server on ``port`` replaces it as the shared one.

    Raises:
        ViewerError: meshcat missing, or the server cannot be started.
    """
    current = _shared.get("server")
    if current is not None and current.running and port in (None, current.port, current.requested_port):
        return current
    _shared["server"] = server = MeshcatServer(port)
    return server


def show(mech: Mechanism, q: ArrayLike | None = None, **kwargs: Any) -> MeshcatViewer:
    """Display ``mech`` at ``q`` (default: its reference configuration) in a meshcat viewer.

    Args:
        mech: the mechanism.
        q: configuration, shape (nq,).
        **kwargs: options of :class:`MeshcatViewer` (``static``, ``server``, ``zmq_url``,
            ``port``, ``frames``).

    Returns:
        The viewer: its :attr:`~MeshcatViewer.url` is the page to open; in a notebook it
        shows inline.
    """
    viewer = MeshcatViewer(mech, **kwargs)
    viewer.display(q)
    return viewer


def scene_html(
    mech: Mechanism,
    q: ArrayLike | None = None,
    *,
    qs: ArrayLike | None = None,
    times: ArrayLike | None = None,
) -> str:
    """A self-contained HTML page of ``mech`` at ``q``, or of the motion ``qs`` at ``times``, no server.

    For reports: the reader rotates the mechanism (and plays the motion) in the page.

    Args:
        mech: the mechanism.
        q: configuration, shape (nq,) (default: the reference configuration).
        qs: configurations of a motion, shape (n, nq); with ``times`` [s], shape (n,).
        times: times of ``qs`` [s].

    Raises:
        InvalidInput: both ``q`` and ``qs`` given, ``qs`` without ``times``, or malformed arrays.
    """
    viewer = MeshcatViewer(mech, static=True)
    if qs is None and times is None:
        viewer.display(q)
    elif q is not None or qs is None or times is None:
        raise InvalidInput("give either q, or qs with times")
    else:
        viewer.animate(qs, times)
    return viewer.static_html()


@functools.cache
def meshcat_bundle() -> str:
    """Meshcat's JavaScript bundle (about 0.85 MB), the script every static page inlines.

    Raises:
        ViewerError: meshcat missing.
    """
    meshcat = require_meshcat()
    dist = Path(str(meshcat.__file__)).parent / "viewer" / "dist"
    return (dist / "main.min.js").read_text(encoding="utf-8")


def share_bundle(page: str, src: str) -> str:
    """``page`` (a static meshcat page) with its inlined bundle replaced by ``<script src=src>``.

    Reports write the bundle once (:data:`plm_pin.report.writer.BUNDLE`), so that every scene
    loads the same file instead of carrying its own copy. A page that does not inline this
    meshcat's bundle is returned unchanged.
    """
    bundle = meshcat_bundle()
    start = page.find(bundle)
    if start < 0:
        return page
    opening = page.rfind("<script>", 0, start)
    closing = page.find("</script>", start + len(bundle))
    between = (page[opening + len("<script>") : start], page[start + len(bundle) : closing])
    if opening < 0 or closing < 0 or any(part.strip() for part in between):
        return page
    tag = f'<script src="{html.escape(src, quote=True)}"></script>'
    return page[:opening] + tag + page[closing + len("</script>") :]
