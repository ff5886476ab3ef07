"""``plm_pin.load``: one entry point for presets, user descriptions and example-robot-data."""

from __future__ import annotations

import dataclasses
import functools
import warnings
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from ._arguments import flag, mapping
from ._lazy import import_object
from ._text import short
from .core.assembly import rounded_closure
from .core.closures import compile_closures
from .core.mechanism import Mechanism
from .description.loader import (
    Description,
    build_collision_model,
    build_model,
    build_visual_model,
    read_description,
)
from .description.mjcf import MJCF_SUFFIX, check_ignore, read_mjcf
from .description.overrides import DescriptionBuilder
from .description.sidecar import FORMAT, ActuatorSpec, Sidecar, TaskSpec
from .description.sidecar import SIDECAR_SUFFIX_DEFAULT as SIDECAR_SUFFIX
from .description.urdf import read_urdf_text
from .description.writer import urdf_text
from .exceptions import ClosureNotSatisfied, DescriptionError, InvalidInput
from .models.registry import PRESETS, Builder, builder_parameters, urdf_folder
from .warnings import RoundedClosureWarning

REFERENCE_CHOOSER = "plm_pin.kinematics.reference:away_from_singularities"
"""Where a description without a ``reference`` gets its reference chosen: named, not imported.

The loader sits below the kinematics; it calls this one kinematic step only for a plm-pin
description that gives no reference (shipped presets and most descriptions give one), so a
load imports no kinematics otherwise. The preset registry names its builders the same way."""

ERD_PREFIX = "erd:"


def mechanism_from_description(
    description: Description,
    name: str,
    *,
    validate: bool = True,
    closure_tol: float | None = None,
    mobility: int | None = None,
) -> Mechanism:
    """Build a :class:`Mechanism` from a description.

    Args:
        description: URDF tree and sidecar.
        name: mechanism name.
        validate: assemble the reference configuration now, so that a description whose
            loops cannot be closed fails here with a clear message (see :func:`load` for
            loops that close only to a rounded description's least-squares residual).
        closure_tol: how far the loops close [m, rad] (default: the sidecar's
            ``closure_tolerance``, else :data:`~plm_pin.tolerances.CLOSURE_TOL`).
        mobility: fixes the mobility instead of deciding the closure rank from the singular
            values (default: the sidecar's ``mobility``).

    Raises:
        DescriptionError: when the model cannot be built or names are wrong.
        ClosureNotSatisfied: when ``validate`` and the loops cannot be closed.
    """
    mech = _mechanism(description, description.sidecar, name, closure_tol, mobility)
    guess = "sidecar reference" if description.sidecar.reference else "neutral configuration"
    mech = _validated(mech, guess, validate, stated=closure_tol is not None)
    if validate and not description.sidecar.reference and description.convention == FORMAT and mech.closures:
        rebuild = functools.partial(_with_reference, description, name, mech.closure_tol, mech.fixed_mobility)
        chooser: Callable[..., Mechanism] = import_object(REFERENCE_CHOOSER)
        return chooser(mech, rebuild, name)
    return mech


def _mechanism(
    description: Description,
    sidecar: Sidecar,
    name: str,
    closure_tol: float | None = None,
    mobility: int | None = None,
) -> Mechanism:
    """The Mechanism of a description's tree with ``sidecar`` (the description's, or one derived from it)."""
    model = build_model(description)  # a fresh tree: the idle gauges add frames to their model
    return Mechanism(
        model,
        sidecar,
        name=name,
        source=sidecar.source or str(description.urdf_path or ""),
        visual_factory=functools.partial(build_visual_model, model, description),  # picklable
        collision_factory=functools.partial(build_collision_model, model, description),
        closure_tol=closure_tol,
        mobility=mobility,
    )


def _with_reference(
    description: Description,
    name: str,
    closure_tol: float | None,
    mobility: int | None,
    reference: dict[str, tuple[float, ...]],
) -> Mechanism:
    """The mechanism of ``description`` with its sidecar's reference replaced by ``reference``."""
    side = dataclasses.replace(description.sidecar, reference=reference)
    return _mechanism(description, side, name, closure_tol, mobility)


def mechanism_from_mjcf(
    path: str | Path,
    *,
    validate: bool = True,
    ignore: str | Iterable[str] = (),
    closure_tol: float | None = None,
    mobility: int | None = None,
) -> Mechanism:
    """Build a :class:`Mechanism` from a MuJoCo model (see :mod:`plm_pin.description.mjcf`).

    Args:
        path: the ``.xml`` file (a ``.plm.yaml`` sidecar beside it is read when present).
        validate: assemble the reference configuration now.
        ignore: kinds of MJCF elements to drop rather than refuse (see
            :data:`~plm_pin.description.mjcf.IGNORABLE`), with a warning listing them.
        closure_tol: how far the loops close [m, rad] (see :func:`mechanism_from_description`).
        mobility: fixes the mobility (see :func:`mechanism_from_description`).

    Raises:
        DescriptionError: when MuJoCo is missing or rejects the file, or an element cannot be
            represented.
        ClosureNotSatisfied: when ``validate`` and the loops cannot be closed.
        InvalidInput: when ``ignore`` names an unknown kind.
    """
    mjcf = read_mjcf(path, ignore)
    name = mjcf.sidecar.name or Path(path).name.split(".")[0]
    mech = Mechanism(
        mjcf.model,
        mjcf.sidecar,
        name=name,
        source=mjcf.sidecar.source or "",
        visual_factory=mjcf.visual_model,
        collision_factory=mjcf.collision_model,
        closure_tol=closure_tol,
        mobility=mobility,
    )
    return _validated(mech, mjcf.reference_origin, validate, stated=closure_tol is not None)


def _validated(mech: Mechanism, guess: str, validate: bool, *, stated: bool) -> Mechanism:
    """``mech`` once its reference is assembled (when ``validate``) from ``guess`` (named in messages).

    When no closure tolerance was stated (``stated`` or the sidecar's ``closure_tolerance``)
    and the loops close only to a least-squares residual small against the model (rounded
    coordinates), the mechanism takes a tolerance above that residual, with a warning
    (:func:`~plm_pin.core.assembly.rounded_closure`).
    """
    name = mech.name
    if validate and mech.sidecar.closures and not stated and mech.sidecar.closure_tolerance is None:
        rounded = rounded_closure(
            mech.model,
            compile_closures(mech.model, mech.sidecar.closures),
            mech.reference_guess(),
            mech.closure_tol,
        )
        if rounded is not None:
            warnings.warn(
                f"{name}: the loops close only to {rounded.residual:.2g} m/rad at best (least squares "
                f"from the {guess}; worst closure {rounded.worst!r}): its coordinates look rounded (a CAD "
                f"export written to a few significant digits). Loaded with closure tolerance "
                f"{rounded.tolerance:g} m/rad; state it (sidecar 'closure_tolerance: {rounded.tolerance:g}', "
                f"plm_pin.load(..., closure_tol={rounded.tolerance:g}) or --closure-tol "
                f"{rounded.tolerance:g}) to load without this warning",
                RoundedClosureWarning,
                stacklevel=3,
            )
            mech.closure_tol = rounded.tolerance
    if validate and mech.closures:
        try:
            mech.q_ref  # noqa: B018 - assembles and caches
        except ClosureNotSatisfied as exc:
            raise ClosureNotSatisfied(
                f"{name}: the closures cannot be assembled from the reference guess "
                f"({guess}): "
                f"residual {exc.residual_norm:.3g} m/rad above the closure tolerance {mech.closure_tol:.3g}, "
                f"worst closure {exc.worst_closure!r}. Give a "
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
    from importlib import metadata  # 20 ms (email, socket): only for example-robot-data

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
    6-D pose of the last frame of the model. Inertias breaking a triangle inequality and
    mimics naming no joint, found in these CAD exports, are warned about rather than refused.
    """
    root = _erd_root()
    files = {p.stem: p for p in sorted(root.glob("robots/*/urdf/*.urdf"), reverse=True)}
    path = files.get(name) or files.get(f"{name}_robot")  # a name, never a pattern
    if path is None:
        raise DescriptionError(f"unknown example-robot-data robot {short(name)}; available are {erd_names()}")
    source = read_urdf_text(path.read_bytes(), root.parent, str(path), strict=False)
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


def load(
    name_or_path: str | Path,
    *,
    validate: bool = True,
    ignore: str | Iterable[str] = (),
    closure_tol: float | None = None,
    mobility: int | None = None,
) -> Mechanism:
    """Load a mechanism.

    Args:
        name_or_path: a preset name (see ``plm-pin list``), ``erd:<robot>`` for an
            example-robot-data robot, a ``.urdf`` with its ``.plm.yaml`` sidecar beside it,
            a ``.plm.yaml``, an example-parallel-robots folder, or a MuJoCo ``.xml`` (MJCF, with
            an optional ``.plm.yaml`` beside it; needs ``plm-pin[mjcf]``).
        validate: assemble the reference configuration at once (see
            :func:`mechanism_from_description`). Loops that close only to a least-squares
            residual small against the model (a CAD export rounded to a few significant
            digits) then load with a :class:`~plm_pin.warnings.RoundedClosureWarning` and a
            closure tolerance above that residual, unless ``closure_tol`` (or the sidecar's
            ``closure_tolerance``) states one.
        ignore: for a MuJoCo model, kinds of elements plm_pin cannot represent to drop
            rather than refuse (``"contacts"``, ``"tendons"``, ... see
            :data:`~plm_pin.description.mjcf.IGNORABLE`), as names or one comma-separated
            string; a warning lists what was dropped.
        closure_tol: how far the description's loops close [m, rad]: the tolerance of the
            assembly, the kinematics and the simulation (default: the sidecar's
            ``closure_tolerance``, else :data:`~plm_pin.tolerances.CLOSURE_TOL`).
        mobility: the mobility (idle mobilities not counted), fixing the closure rank instead
            of deciding it at the largest gap of the singular values (default: the sidecar's
            ``mobility``).

    Returns:
        The mechanism.

    Raises:
        DescriptionError: unknown name, missing or malformed files, unsafe content.
        ClosureNotSatisfied: when the loops cannot be closed from the reference guess.
        InvalidInput: ``ignore`` names an unknown kind, or is given for a model that is not an
            MJCF; a ``closure_tol`` or ``mobility`` out of range.
    """
    flag(validate, "validate")
    extra: dict[str, Any] = {"validate": validate, "closure_tol": closure_tol, "mobility": mobility}
    text = str(name_or_path)
    if check_ignore(ignore) and not _is_mjcf(Path(text)):
        raise InvalidInput(f"ignore={ignore!r} applies to MuJoCo models (.xml) only; {text!r} is not one")
    if text in PRESETS:
        return mechanism_from_description(read_description(urdf_folder() / f"{text}.urdf"), text, **extra)
    if text.startswith(ERD_PREFIX):
        return load_erd(text[len(ERD_PREFIX) :])
    path = Path(text)
    if not path.exists():
        raise DescriptionError(
            f"{text!r} is neither a preset nor an existing path; presets are {sorted(PRESETS)}; "
            f"example-robot-data robots load as 'erd:<name>'"
        )
    if _is_mjcf(path):
        mjcf = path if path.suffix == MJCF_SUFFIX else _mjcf_of_sidecar(path)
        return mechanism_from_mjcf(mjcf, ignore=ignore, **extra)
    description = read_description(path)
    stem = path.name if path.is_dir() else path.name.split(".")[0]
    if stem == "robot":  # the example-parallel-robots file name: name the mechanism after its folder
        stem = path.resolve().parent.name
    name = description.sidecar.name or stem
    return mechanism_from_description(description, name, **extra)


def _mjcf_of_sidecar(path: Path) -> Path:
    """The MJCF a ``.plm.yaml`` sits beside (same stem)."""
    return path.with_name(path.name.removesuffix(SIDECAR_SUFFIX) + MJCF_SUFFIX)


def _is_mjcf(path: Path) -> bool:
    """Whether ``path`` names an MJCF: a ``.xml``, or the sidecar of one with no URDF beside it."""
    if path.suffix == MJCF_SUFFIX:
        return True
    mjcf = _mjcf_of_sidecar(path)
    return path.name.endswith(SIDECAR_SUFFIX) and mjcf.is_file() and not mjcf.with_suffix(".urdf").is_file()


def resolve_builder(target: str | Builder) -> tuple[Builder, dict[str, Any], str]:
    """The builder of a preset name (with the preset's parameters), of a description path, or a callable.

    A path (a ``.urdf``, ``.plm.yaml`` or folder) gives a
    :class:`~plm_pin.description.overrides.DescriptionBuilder`: joint origins, lengths and
    masses by name.

    Returns:
        ``(builder, base parameters, label)``; the label is the preset name or the builder's
        ``module:qualname``.

    Raises:
        InvalidInput: an unknown preset name (the message lists them) or a non-callable target.
    """
    if isinstance(target, str):
        preset = PRESETS.get(target)
        if preset is None and Path(target).exists():
            return DescriptionBuilder(target), {}, target
        if preset is None:
            raise InvalidInput(
                f"unknown preset {target!r}; presets are {sorted(PRESETS)}, or give the path of a description"
            )
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
            ``parameters``) or a builder such as :func:`plm_pin.families.prrrp.build_2prrrp`, called
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
    flag(validate, "validate")
    builder, base, label = resolve_builder(target)
    given = dict(mapping(parameters or {}, "parameters", "builder parameter names to values [SI units]"))
    valid = builder_parameters(builder)
    unknown = [key for key in given if key not in valid]
    if unknown:
        raise InvalidInput(f"unknown parameter(s) {unknown} of {label}; its parameters are {list(valid)}")
    stem = getattr(builder, "__name__", "mechanism") if target not in PRESETS else target
    label_name = name or f"{stem}_variant"
    source = PRESETS[target].source if isinstance(target, str) and target in PRESETS else label
    robot, sidecar = builder(name=label_name, source=source, **{**base, **given})
    description = Description(read_urdf_text(urdf_text(robot), None, f"<{label_name}>"), sidecar)
    return mechanism_from_description(description, label_name, validate=validate)
