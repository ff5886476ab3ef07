"""Studies: modules that fill a report through a :class:`StudyContext`, and where they are found.

The studies are found in one place, :func:`study_modules`: the library's own (:data:`BUILTIN_STUDIES`:
the generic ``overview`` of any mechanism, which an installed wheel carries), then the paper
studies, the modules of the package :data:`STUDY_PACKAGE` (the ``analyses/`` folder of a source
checkout) when it is importable.

A study is a module (``analyses/<name>.py`` for a paper study) defining:

- ``TITLE``: the report title;
- ``SUMMARY``: one line for the index (optional);
- ``MECHANISM``: the mechanism it studies by default, a preset name or a path (optional:
  only a study that defines it takes ``--mechanism``, e.g. the generic ``overview``);
- ``run(ctx: StudyContext) -> None``: loads its mechanisms with :meth:`StudyContext.load`,
  adds sections with :meth:`StudyContext.section` and reports progress with
  :meth:`StudyContext.step`;
- ``ANIMATIONS``: case name -> function returning an :class:`~plm_pin.report.Animation`
  (optional; played by ``plm-pin view --animate STUDY:CASE``, see
  :mod:`plm_pin.report.animation`);
- ``TAKES_CASE``: True when the study reads :attr:`StudyContext.case` (a load, a pose, a
  working mode, slice ranges: ``plm-pin report --load ...``); optional, default False.

The engine runs it in memory (:func:`run_study`); nothing is written until it has finished
(:mod:`plm_pin.report.writer`). Modules whose names start with ``_`` are helpers, not studies.
"""

from __future__ import annotations

import importlib
import pkgutil
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from types import MappingProxyType, ModuleType

from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput, PlmError
from ..loading import load
from ..models.registry import PRESETS
from ..warnings import PlmWarning
from .animation import Animation
from .content import MechanismInfo, Parameter, Section, StudyResult
from .folders import FOLDER, slug
from .provenance import software_versions

BUILTIN_STUDIES: Mapping[str, str] = MappingProxyType({"overview": "plm_pin.report.overview"})
"""The library's own studies, found with or without a checkout: name -> module."""

STUDY_PACKAGE = "analyses"
"""The package the paper studies are modules of: the ``analyses/`` folder of a source checkout."""

PAPER_STUDIES_HINT = (
    "the paper studies live in the analyses/ folder of the plm_pin source checkout: run plm-pin "
    "from a checkout installed with `pip install -e .`, or put the checkout on PYTHONPATH"
)


@dataclass(frozen=True)
class Study:
    """A study module, checked.

    Attributes:
        name: the study's name (its module's), also the report's folder.
        title: ``TITLE``.
        summary: ``SUMMARY`` (empty when absent).
        mechanism: ``MECHANISM``: the default mechanism, None when the study takes none.
        run: ``run(ctx)``.
        animations: ``ANIMATIONS``: case name -> function computing the motion (empty when absent).
        takes_case: ``TAKES_CASE``: the study reads :attr:`StudyContext.case`.
    """

    name: str
    title: str
    summary: str
    mechanism: str | None
    run: Callable[[StudyContext], None]
    animations: Mapping[str, Callable[..., Animation]] = field(default_factory=dict)
    takes_case: bool = False


@dataclass(frozen=True)
class StudyCase:
    """The case a study is asked to look at (``plm-pin report`` options); empty: the study's own.

    The entries are checked against the mechanism by the study that reads them.

    Attributes:
        load: external load, one value per task coordinate [N, N m]: a wrench on the task
            frame (``fx fy mz`` for an ``x y rz`` task), or a force or torque per output joint
            of a joint task; None: no load.
        pose: task coordinates of the pose to study [m, rad], by name; the others are the
            reference's. Empty: the reference configuration.
        mode: working mode to study, one sign per square leg; None: the reference's.
        ranges: the workspace slice's values per varied task coordinate [m, rad] (one or two
            coordinates); empty: the study's default slice.
    """

    load: tuple[float, ...] | None = None
    pose: Mapping[str, float] = field(default_factory=dict)
    mode: tuple[int, ...] | None = None
    ranges: Mapping[str, tuple[float, ...]] = field(default_factory=dict)

    @property
    def empty(self) -> bool:
        """Whether nothing is asked for."""
        return self.load is None and not self.pose and self.mode is None and not self.ranges


def _study_package() -> ModuleType | None:
    """The package :data:`STUDY_PACKAGE` when importable, else None."""
    try:
        return importlib.import_module(STUDY_PACKAGE)
    except ModuleNotFoundError as exc:
        if exc.name != STUDY_PACKAGE:
            raise
        return None


def study_modules() -> dict[str, str]:
    """Every study: name -> module, the library's own then the paper studies, sorted by name.

    The paper studies are the modules of :data:`STUDY_PACKAGE` whose names are lower-case
    folder names (modules starting with ``_`` are helpers).

    Raises:
        PlmError: a paper study takes the name of one of the library's own.
    """
    found = dict(BUILTIN_STUDIES)
    package = _study_package()
    if package is not None:
        for m in pkgutil.iter_modules(package.__path__):
            if m.ispkg or m.name.startswith("_") or not FOLDER.fullmatch(m.name):
                continue
            if m.name in found:
                raise PlmError(
                    f"{package.__name__}.{m.name} takes the name of plm_pin's own study {m.name!r}"
                )
            found[m.name] = f"{package.__name__}.{m.name}"
    return dict(sorted(found.items()))


def study_names() -> list[str]:
    """Names of the studies (:func:`study_modules`), sorted."""
    return list(study_modules())


def studies_hint() -> str:
    """Where the paper studies are, when :data:`STUDY_PACKAGE` cannot be imported (else empty)."""
    return f" ({PAPER_STUDIES_HINT})" if _study_package() is None else ""


def find_study(name: str) -> Study:
    """Import and check the study ``name``.

    Raises:
        InvalidInput: no such study (the message lists them).
        PlmError: the module is not a study (no ``TITLE`` or ``run``, or malformed
            ``MECHANISM`` or ``ANIMATIONS``).
    """
    modules = study_modules()
    if name not in modules:
        raise InvalidInput(f"unknown study {name!r}; studies are {list(modules)}{studies_hint()}")
    module = importlib.import_module(modules[name])
    title, run = getattr(module, "TITLE", None), getattr(module, "run", None)
    if not isinstance(title, str) or not callable(run):
        raise PlmError(f"{module.__name__} is not a study: it must define TITLE (a string) and run(ctx)")
    mechanism = getattr(module, "MECHANISM", None)
    if mechanism is not None and not isinstance(mechanism, str):
        raise PlmError(f"{module.__name__}.MECHANISM must be a preset name or a path, got {mechanism!r}")
    animations = getattr(module, "ANIMATIONS", {})
    if not isinstance(animations, Mapping) or not all(
        isinstance(k, str) and callable(f) for k, f in animations.items()
    ):
        raise PlmError(f"{module.__name__}.ANIMATIONS must map case names to functions")
    takes_case = getattr(module, "TAKES_CASE", False)
    if not isinstance(takes_case, bool):
        raise PlmError(f"{module.__name__}.TAKES_CASE must be True or False, got {takes_case!r}")
    summary = str(getattr(module, "SUMMARY", ""))
    return Study(name, title, summary, mechanism, run, dict(animations), takes_case)


def _describe(mech: Mechanism, target: str | Path | Mechanism) -> MechanismInfo:
    if isinstance(target, Mechanism):
        return MechanismInfo(mech.name, "built by the study", mech.summary(), (), ())
    preset = PRESETS.get(str(target))
    if preset is None:
        return MechanismInfo(mech.name, f"description {target}", mech.summary(), (), ())
    parameters = tuple(Parameter(key, value) for key, value in preset.parameters.items())
    return MechanismInfo(mech.name, f"preset {preset.name}", mech.summary(), parameters, preset.notes)


class StudyContext:
    """What a study writes its report with: mechanisms, sections, progress.

    Attributes:
        study: the study being run.
        target: the mechanism it was asked to study (``--mechanism``, else its ``MECHANISM``),
            None for a study that takes none.
        case: the load, pose, working mode and slice asked for (empty: the study's own).
    """

    def __init__(
        self,
        study: Study,
        target: str | Path | None,
        observer: Callable[[str], None] | None = None,
        case: StudyCase | None = None,
        loaded: Mechanism | None = None,
    ) -> None:
        """Start an empty report for ``study`` on ``target`` and ``case``; ``observer`` receives the steps.

        ``loaded`` is ``target`` already loaded (by the caller): :meth:`load` returns it.
        """
        self.study = study
        self.target = target
        self._loaded = loaded
        self.case = StudyCase() if case is None else case
        self._observer = observer
        self._sections: list[Section] = []
        self._mechanisms: dict[str, MechanismInfo] = {}

    def load(self, target: str | Path | Mechanism | None = None) -> Mechanism:
        """Load a mechanism (default: :attr:`target`) and describe it in the report.

        A preset's parameters and notes (its assumptions) are listed; a mechanism the study
        built itself (e.g. a variant) is passed as the object.

        Raises:
            InvalidInput: no target given and the study has none.
            PlmError: the description cannot be loaded (the loader's message).
        """
        chosen = self.target if target is None else target
        if chosen is None:
            raise InvalidInput(f"study {self.study.name!r} takes no mechanism; give one to ctx.load")
        if isinstance(chosen, Mechanism):
            mech = chosen
        elif target is None and self._loaded is not None:
            mech = self._loaded
        else:
            mech = load(chosen)
        mech.summary()  # mobility now, inside the study's error handling
        self._mechanisms.setdefault(mech.name, _describe(mech, chosen))
        return mech

    def step(self, description: str) -> None:
        """Say what is being computed now (shown by the progress bar)."""
        if self._observer is not None:
            self._observer(description)

    def section(self, title: str) -> Section:
        """Start a new section, after the ones already added; returns it to fill."""
        section = Section(title)
        self._sections.append(section)
        return section

    @property
    def mechanisms(self) -> tuple[MechanismInfo, ...]:
        """The mechanisms loaded so far, in order."""
        return tuple(self._mechanisms.values())

    @property
    def sections(self) -> tuple[Section, ...]:
        """The sections added so far, in order."""
        return tuple(self._sections)


def report_folder(study: Study, mechanisms: tuple[MechanismInfo, ...]) -> str:
    """Folder name of a report: the study name, and for a study of a chosen mechanism its name too."""
    if study.mechanism is None or not mechanisms:
        return study.name
    return f"{study.name}-{slug(mechanisms[0].name)}"


def run_study(
    study: Study,
    mechanism: str | Path | None = None,
    *,
    command: str = "",
    observer: Callable[[str], None] | None = None,
    case: StudyCase | None = None,
    loaded: Mechanism | None = None,
) -> StudyResult:
    """Run a study in memory and return its report (nothing is written).

    Warnings plm_pin emits meanwhile are listed in the report; other warnings pass through.

    Args:
        study: the study.
        mechanism: the mechanism to study instead of its ``MECHANISM`` (preset name or path).
        command: the shell command that writes this report, shown in it.
        observer: called with each step's description (for a progress display).
        case: the load, pose, working mode and slice to study (a study with ``TAKES_CASE``).
        loaded: ``mechanism`` already loaded by the caller (e.g. to check ``case`` first), used
            instead of loading it again.

    Raises:
        InvalidInput: a mechanism given to a study that takes none, a case to a study that
            takes none.
        PlmError: the study failed; the message names it and says why.
    """
    if mechanism is not None and study.mechanism is None:
        raise InvalidInput(f"study {study.name!r} takes no mechanism")
    if case is not None and not case.empty and not study.takes_case:
        raise InvalidInput(
            f"study {study.name!r} takes no load, pose, working mode or slice ranges; the overview does"
        )
    ctx = StudyContext(study, study.mechanism if mechanism is None else mechanism, observer, case, loaded)
    start = time.perf_counter()
    generated = datetime.now(timezone.utc).isoformat(timespec="seconds")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlmWarning)
        try:
            study.run(ctx)
        except PlmError as exc:
            raise PlmError(f"study {study.name!r} failed: {exc}") from exc
    for w in caught:
        if not issubclass(w.category, PlmWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return StudyResult(
        study=study.name,
        title=study.title,
        summary=study.summary,
        folder=report_folder(study, ctx.mechanisms),
        mechanisms=ctx.mechanisms,
        sections=ctx.sections,
        warnings=tuple(dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, PlmWarning))),
        command=command,
        versions=software_versions(),
        generated=generated,
        elapsed=time.perf_counter() - start,
    )


def compute_animation(study: Study, case: str, mechanism: str | None = None) -> Animation:
    """Compute the animation ``case`` of ``study``.

    Args:
        study: the study.
        case: one of its ``ANIMATIONS``.
        mechanism: for a study that takes a mechanism, the one to move (default: its own).

    Raises:
        InvalidInput: an unknown case (the message lists them), or a mechanism given to a
            study that studies fixed mechanisms.
        PlmError: the motion cannot be computed (the library's message).
    """
    if case not in study.animations:
        known = sorted(study.animations)
        raise InvalidInput(
            f"study {study.name!r} has no animation {case!r}; "
            + (f"its animations are {known}" if known else "it defines no animations")
        )
    make = study.animations[case]
    if study.mechanism is None:
        if mechanism is not None:
            raise InvalidInput(f"study {study.name!r} animates its own mechanisms: give no mechanism")
        return make()
    return make(study.mechanism if mechanism is None else mechanism)
