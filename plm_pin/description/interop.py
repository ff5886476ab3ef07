"""Reader for the example-parallel-robots sidecar (``robot.yaml``).

That convention (Gepetto/example-parallel-robots) lists frame pairs in ``closed_loop``,
their constraint ``type`` (``3d``: point, ``6d``: weld) and the actuated joints in
``name_mot``. It carries no actuator limits, no task and no gravity.

A task is read from an ``end_effector`` key added to ``robot.yaml``, written as in a
plm-pin sidecar (``{frame: effector, task: [y, z]}``). Without it, the robots of the
example-parallel-robots corpus whose end effector is obvious get the task of
:data:`CORPUS_TASKS` (the planar five-bars and delta: the effector frame's coordinates in
their plane of motion), when their folder keeps its corpus name and the frame exists. Any
other key is refused, so that a misspelt one does not pass silently.
"""

from __future__ import annotations

from typing import Any

from .._arguments import repeated
from .._text import short
from ..exceptions import DescriptionError
from .sidecar import FORMAT, ActuatorSpec, ClosureSpec, Sidecar, TaskSpec, parse_sidecar

EPR_TYPES: dict[str, str] = {"3d": "point", "6d": "weld"}

EPR_KEYS: tuple[str, ...] = ("closed_loop", "type", "name_mot", "end_effector")
"""Keys ``robot.yaml`` may hold: the convention's three and plm-pin's ``end_effector``."""

CORPUS_TASKS: dict[str, TaskSpec] = {
    "5bar_linkage": TaskSpec("effector", ("y", "z")),
    "5bar_linkage_iso3d": TaskSpec("effector", ("x", "z")),
    "5bar_linkage_iso6d": TaskSpec("effector", ("x", "z")),
    "robot_delta": TaskSpec("eff", ("y", "z")),
}
"""Tasks of the corpus robots with an obvious end effector, by folder name (revolute axes
along world x for ``5bar_linkage`` and ``robot_delta``, along y for the iso five-bars)."""


def corpus_task(folder: str, frames: list[str]) -> TaskSpec | None:
    """The :data:`CORPUS_TASKS` entry of a folder name, if its frame is among ``frames``."""
    task = CORPUS_TASKS.get(folder)
    return task if task is not None and task.frame in frames else None


def parse_epr_sidecar(data: Any, path: str | None = None, name: str | None = None) -> Sidecar:
    """Translate a loaded ``robot.yaml`` into a :class:`Sidecar`.

    Raises:
        DescriptionError: when keys are missing or inconsistent.
    """
    if not isinstance(data, dict):
        raise DescriptionError("robot.yaml must be a YAML mapping", path)
    unknown = [k for k in data if k not in EPR_KEYS]
    if unknown:
        raise DescriptionError(f"robot.yaml: unknown key(s) {unknown}; valid keys are {list(EPR_KEYS)}", path)
    for key in ("closed_loop", "type", "name_mot"):
        if key not in data:
            raise DescriptionError(f"robot.yaml lacks {key!r}; it needs closed_loop, type, name_mot", path)
    loops, types, motors = data["closed_loop"], data["type"], data["name_mot"]
    if not isinstance(loops, list) or not isinstance(types, list) or not isinstance(motors, list):
        raise DescriptionError("closed_loop, type and name_mot must be lists", path)
    if len(loops) != len(types):
        raise DescriptionError(f"closed_loop has {len(loops)} pairs but type has {len(types)} entries", path)
    closures = []
    for i, (pair, kind) in enumerate(zip(loops, types, strict=True)):
        if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(f, str) for f in pair)):
            raise DescriptionError(f"closed_loop[{i}] must be a pair of frame names, got {short(pair)}", path)
        if not isinstance(kind, str) or kind not in EPR_TYPES:
            raise DescriptionError(
                f"type[{i}]: invalid constraint type {short(kind)}; valid are {list(EPR_TYPES)}", path
            )
        closures.append(
            ClosureSpec(name=f"loop{i + 1}", frames=(pair[0], pair[1]), type=EPR_TYPES[kind])  # type: ignore[arg-type]
        )
    actuation = []
    for i, motor in enumerate(motors):
        if not isinstance(motor, str):
            raise DescriptionError(f"name_mot[{i}] must be a joint name, got {short(motor)}", path)
        actuation.append(ActuatorSpec(joint=motor))
    dup = repeated(motors)
    if dup:
        raise DescriptionError(f"name_mot: joint(s) {short(dup)} actuated twice", path)
    task = None
    if data.get("end_effector") is not None:  # validated as in a plm-pin sidecar
        task = parse_sidecar({"format": FORMAT, "end_effector": data["end_effector"]}, path).task
    return Sidecar(
        closures=tuple(closures),
        actuation=tuple(actuation),
        task=task,
        name=name,
        source="example-parallel-robots (Gepetto, BSD-3)",
    )
