"""Reader for the example-parallel-robots sidecar (``robot.yaml``).

That convention (Gepetto/example-parallel-robots) lists frame pairs in ``closed_loop``,
their constraint ``type`` (``3d``: point, ``6d``: weld) and the actuated joints in
``name_mot``. It carries no actuator limits, no task and no gravity.
"""

from __future__ import annotations

from typing import Any

from .._text import short
from ..exceptions import DescriptionError
from .sidecar import ActuatorSpec, ClosureSpec, Sidecar

EPR_TYPES: dict[str, str] = {"3d": "point", "6d": "weld"}


def parse_epr_sidecar(data: Any, path: str | None = None, name: str | None = None) -> Sidecar:
    """Translate a loaded ``robot.yaml`` into a :class:`Sidecar`.

    Raises:
        DescriptionError: when keys are missing or inconsistent.
    """
    if not isinstance(data, dict):
        raise DescriptionError("robot.yaml must be a YAML mapping", path)
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
        if kind not in EPR_TYPES:
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
    dup = sorted({m for m in motors if motors.count(m) > 1})
    if dup:
        raise DescriptionError(f"name_mot: joint(s) {short(dup)} actuated twice", path)
    return Sidecar(
        closures=tuple(closures),
        actuation=tuple(actuation),
        name=name,
        source="example-parallel-robots (Gepetto, BSD-3)",
    )
