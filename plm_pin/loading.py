"""``plm_pin.load``: one entry point for presets, user descriptions and example-robot-data."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

from .description.loader import Description, build_model, build_visual_model, read_description
from .description.sidecar import ActuatorSpec, Sidecar, TaskSpec
from .description.urdf import read_urdf_text
from .description.writer import urdf_text
from .exceptions import ClosureNotSatisfied, DescriptionError, InvalidInput
from .mechanism import Mechanism
from .models.registry import PRESETS, Builder, builder_parameters, urdf_folder

ERD_PREFIX = "erd:"


def mechanism_from_description(description: Description, name: str, *, validate: bool = True) -> Mechanism:
    """Build a :class:`Mechanism` from a description.

    Args:
        description: URDF tree and sidecar.
        name: mechanism name.
        validate: assemble the reference configuration now, so that a description whose
            loops cannot be closed fails here with a clear message.

    Raises:
        DescriptionError: when the model cannot be built or names are wrong.
        ClosureNotSatisfied: when ``validate`` and the loops cannot be closed.
    """
    model = build_model(description)
    mech = Mechanism(
        model,
        description.sidecar,
        name=name,
        source=description.sidecar.source or str(description.urdf_path or ""),
        visual_factory=functools.partial(build_visual_model, model, description),  # picklable
    )
    if validate and mech.closures:
        try:
            mech.q_ref  # noqa: B018 - assembles and caches
        except ClosureNotSatisfied as exc:
            raise ClosureNotSatisfied(
                f"{name}: the closures cannot be assembled from the reference guess "
                f"({'sidecar reference' if description.sidecar.reference else 'neutral configuration'}): "
                f"residual {exc.residual_norm:.3g} m/rad, worst closure {exc.worst_closure!r}. Give a "
                "configuration close to an assembled one in the sidecar's 'reference', or check "
                "that the closure frames can meet.",
                exc.residual_norm,
                exc.tolerance,
                exc.q,
                exc.worst_closure,
            ) from None
    return mech


@functools.cache
def _erd_root() -> Path:
    try:
        files = metadata.files("example-robot-data") or []
    except metadata.PackageNotFoundError:
        raise DescriptionError(
            "example-robot-data is not installed (pip install example-robot-data)"
        ) from None
    for f in files:
        parts = Path(str(f)).parts
        if "robots" in parts and parts[-1].endswith(".urdf"):
            located = Path(str(f.locate()))
            return located.parents[len(parts) - parts.index("robots") - 1]
    raise DescriptionError("example-robot-data holds no URDF files")


def erd_names() -> list[str]:
    """Names accepted after ``erd:`` (URDF stems in example-robot-data, ``_robot`` dropped)."""
    root = _erd_root()
    return sorted({p.stem.removesuffix("_robot") for p in root.glob("robots/*/urdf/*.urdf")})


def load_erd(name: str) -> Mechanism:
    """Load an example-robot-data robot as a mechanism with no closures.

    Every one-DOF joint is actuated (limits from the URDF efforts); the task is the full
    6-D pose of the last frame of the model.
    """
    root = _erd_root()
    matches = sorted(root.glob(f"robots/*/urdf/{name}.urdf")) + sorted(
        root.glob(f"robots/*/urdf/{name}_robot.urdf")
    )
    if not matches:
        raise DescriptionError(f"unknown example-robot-data robot {name!r}; available are {erd_names()}")
    path = matches[0]
    source = read_urdf_text(path.read_bytes(), root.parent, str(path))
    bare = Description(source, Sidecar(), path, None, "example-robot-data")
    model = build_model(bare)
    actuation = []
    for jid in range(1, model.njoints):
        joint = model.joints[jid]
        if joint.nv == 1:
            effort = float(model.effortLimit[joint.idx_v])
            limits = (-effort, effort) if 0.0 < effort < 1e10 else None
            actuation.append(ActuatorSpec(model.names[jid], limits))
    sidecar = Sidecar(
        actuation=tuple(actuation),
        task=TaskSpec(model.frames[len(model.frames) - 1].name, ("x", "y", "z", "rx", "ry", "rz")),
        name=name,
        source=f"example-robot-data: {path.relative_to(root)}",
    )
    return mechanism_from_description(Description(source, sidecar, path, None, "example-robot-data"), name)


def load(name_or_path: str | Path, *, validate: bool = True) -> Mechanism:
    """Load a mechanism.

    Args:
        name_or_path: a preset name (see ``plm-pin list``), ``erd:<robot>`` for an
            example-robot-data robot, a ``.urdf`` with its ``.plm.yaml`` sidecar beside it,
            a ``.plm.yaml``, or an example-parallel-robots folder.
        validate: assemble the reference configuration at once (see
            :func:`mechanism_from_description`).

    Returns:
        The mechanism.

    Raises:
        DescriptionError: unknown name, missing or malformed files, unsafe content.
        ClosureNotSatisfied: when the loops cannot be closed from the reference guess.
    """
    text = str(name_or_path)
    if text in PRESETS:
        return mechanism_from_description(
            read_description(urdf_folder() / f"{text}.urdf"), text, validate=validate
        )
    if text.startswith(ERD_PREFIX):
        return load_erd(text[len(ERD_PREFIX) :])
    path = Path(text)
    if not path.exists():
        raise DescriptionError(
            f"{text!r} is neither a preset nor an existing path; presets are {sorted(PRESETS)}; "
            f"example-robot-data robots load as 'erd:<name>'"
        )
    description = read_description(path)
    name = description.sidecar.name or (path.name if path.is_dir() else path.name.split(".")[0])
    return mechanism_from_description(description, name, validate=validate)


def resolve_builder(target: str | Builder) -> tuple[Builder, dict[str, Any], str]:
    """The builder of a preset name (with the preset's parameters) or a builder callable (with none).

    Returns:
        ``(builder, base parameters, label)``; the label is the preset name or the builder's
        ``module:qualname``.

    Raises:
        InvalidInput: an unknown preset name (the message lists them) or a non-callable target.
    """
    if isinstance(target, str):
        preset = PRESETS.get(target)
        if preset is None:
            raise InvalidInput(f"unknown preset {target!r}; presets are {sorted(PRESETS)}")
        return preset.builder, dict(preset.parameters), target
    if not callable(target):
        raise InvalidInput(f"expected a preset name or a builder callable, got {target!r}")
    return target, {}, f"{getattr(target, '__module__', '?')}:{getattr(target, '__qualname__', repr(target))}"


def build_mechanism(
    target: str | Builder,
    parameters: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    validate: bool = True,
) -> Mechanism:
    """Build a mechanism from a parametric builder in memory, without writing its description.

    Args:
        target: a preset name (its builder, with the preset's parameters overridden by
            ``parameters``) or a builder such as :func:`plm_pin.models.build_2prrrp`, called
            with ``parameters`` alone.
        parameters: builder keyword arguments [SI units]; ``name`` and ``source`` are set here.
        name: the mechanism's name (default: the preset's or builder's name with ``_variant``).
        validate: assemble the reference configuration at once (see
            :func:`mechanism_from_description`).

    Returns:
        The mechanism, as :func:`load` would return it after writing the description to disk.

    Raises:
        InvalidInput: an unknown preset or parameter name (the message lists the valid ones).
        DescriptionError: the builder's output is not a valid description.
        ClosureNotSatisfied: when ``validate`` and the loops cannot be closed.
    """
    builder, base, label = resolve_builder(target)
    given = dict(parameters or {})
    valid = builder_parameters(builder)
    unknown = [key for key in given if key not in valid]
    if unknown:
        raise InvalidInput(f"unknown parameter(s) {unknown} of {label}; its parameters are {list(valid)}")
    stem = target if isinstance(target, str) else getattr(target, "__name__", "mechanism")
    label_name = name or f"{stem}_variant"
    source = PRESETS[target].source if isinstance(target, str) else label
    robot, sidecar = builder(name=label_name, source=source, **{**base, **given})
    description = Description(read_urdf_text(urdf_text(robot), None, f"<{label_name}>"), sidecar)
    return mechanism_from_description(description, label_name, validate=validate)
