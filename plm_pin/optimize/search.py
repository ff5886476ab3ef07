""":func:`optimize`: the search over designs, generation by generation, checkpointed and resumable.

Methods:
- ``"de"`` (default, no new dependency): SciPy's :func:`scipy.optimize.differential_evolution`
  minimising the score (:mod:`plm_pin.optimize.evaluate`: the weighted objectives of a feasible
  design, a penalty by level of the constraint hierarchy otherwise), ``updating="deferred"``:
  each generation's population is evaluated at once through its ``workers`` map, which is
  ours (this process, a Dask client's ``map``, or a local Dask cluster of ``workers``
  processes), no polishing (a gradient step through the penalties would be meaningless);
- ``"nsga2"`` (``pip install 'plm-pin[optimize]'``): pymoo's NSGA-II for several objectives,
  the hierarchy as one inequality constraint (0 when feasible, the level and violation
  otherwise), a Pareto front of the feasible designs.

The start design is evaluated first, as generation 0, then each population the method asks
for. Every evaluated generation is written to the store before the search goes on. Both
methods are seeded: the same problem, settings and seed ask for the same populations, so a
search interrupted (killed) and run again with the same store replays the stored designs
(bit for bit, without evaluating them) and continues where it stopped, to the same result.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._text import short
from ..exceptions import InvalidInput
from ..models.registry import Builder
from ..sweep.execution import check_execution, connect, local_cluster
from ..sweep.spec import PosesArg
from ..tolerances import DE_TOL
from .evaluate import DesignEvaluation, evaluate_design
from .problem import Problem, make_problem
from .result import OptimizationResult, check_feasible
from .store import OptimizeStore, from_row, to_row

if TYPE_CHECKING:
    from distributed import Client

METHODS = ("de", "nsga2")
"""Search methods."""

Progress = Callable[[int, int], None]
"""Called with (generation, designs evaluated so far) after each generation is stored."""

Evaluator = Callable[[Problem, list[tuple[float, ...]]], list[DesignEvaluation]]


def _here(problem: Problem, xs: list[tuple[float, ...]]) -> list[DesignEvaluation]:
    return [evaluate_design(problem, x) for x in xs]


def _on_dask(client: Client) -> Evaluator:
    scattered: list[tuple[Problem, Any]] = []  # the problem sent to every worker once, with its future

    def run(problem: Problem, xs: list[tuple[float, ...]]) -> list[DesignEvaluation]:
        if not scattered or scattered[0][0] is not problem:
            scattered[:] = [(problem, client.scatter(problem, broadcast=True, hash=False))]
        shared = scattered[0][1]
        futures = client.map(evaluate_design, [shared] * len(xs), xs, pure=False)
        out: list[DesignEvaluation] = client.gather(futures)
        return out

    return run


@contextmanager
def _evaluator(
    scheduler: str | Client | None, workers: int | None, scratch: Path | None
) -> Iterator[Evaluator]:
    if scheduler is None and (workers is None or workers == 1):
        yield _here
    elif scheduler is None:
        assert workers is not None
        with local_cluster(workers, scratch) as client:
            yield _on_dask(client)
    elif isinstance(scheduler, str):
        client = connect(scheduler)
        try:
            yield _on_dask(client)
        finally:
            client.close()
    else:
        yield _on_dask(scheduler)


class Generations:
    """Evaluates the populations a search asks for, in order: replayed from the store, else computed.

    Attributes:
        evaluations: every generation's evaluated designs, in order (0: the start design).
        computed: designs evaluated in this run (not replayed).
    """

    def __init__(
        self, problem: Problem, evaluate: Evaluator, store: OptimizeStore | None, progress: Progress | None
    ) -> None:
        """Prepare to evaluate ``problem``'s designs with ``evaluate``, replaying ``store``."""
        self.problem = problem
        self.evaluate = evaluate
        self.store = store
        self.progress = progress
        self.stored = {} if store is None else store.load()
        self.evaluations: list[list[DesignEvaluation]] = []
        self.computed = 0

    def __call__(self, population: np.ndarray) -> list[DesignEvaluation]:
        """Evaluate a population (one design per row) as the next generation."""
        g = len(self.evaluations)
        xs = [tuple(float(v) for v in row) for row in np.atleast_2d(population)]
        rows = self.stored.get(g)
        replay = [from_row(self.problem, r) for r in rows] if rows is not None else None
        if replay is not None and [e.x for e in replay] == xs:
            out = replay
        else:
            out = self.evaluate(self.problem, xs)
            self.computed += len(out)
            if self.store is not None:
                self.store.write(g, [to_row(self.problem, g, i, e) for i, e in enumerate(out)])
        self.evaluations.append(out)
        if self.progress is not None:
            self.progress(g, sum(len(e) for e in self.evaluations))
        return out


def _de(problem: Problem, generations: Generations, settings: Mapping[str, Any]) -> None:
    from scipy.optimize import differential_evolution

    def mapper(_func: Any, population: Any) -> list[float]:
        return [e.score(problem) for e in generations(np.array(list(population)))]

    start = np.array(problem.start)
    inside = all(v.lower <= s <= v.upper for v, s in zip(problem.variables, start, strict=True))
    differential_evolution(
        lambda x: 0.0,  # never called: every population goes through mapper
        problem.bounds,
        maxiter=settings["generations"],
        popsize=settings["population"],
        tol=settings["tol"],
        rng=settings["seed"],
        polish=False,
        updating="deferred",
        workers=mapper,
        x0=start if inside else None,
    )


def _nsga2(problem: Problem, generations: Generations, settings: Mapping[str, Any]) -> None:
    try:
        from pymoo.algorithms.moo.nsga2 import NSGA2
        from pymoo.core.problem import Problem as PymooProblem
        from pymoo.optimize import minimize
    except ImportError as exc:
        raise ImportError(
            "method 'nsga2' needs pymoo, which is not installed: pip install 'plm-pin[optimize]'"
        ) from exc

    class Pareto(PymooProblem):
        def __init__(self) -> None:
            lower, upper = np.array(problem.bounds).T
            super().__init__(
                n_var=len(lower), n_obj=len(problem.objectives), n_ieq_constr=1, xl=lower, xu=upper
            )

        def _evaluate(self, x: np.ndarray, out: dict[str, Any], *args: Any, **kwargs: Any) -> None:
            evaluated = generations(x)
            out["F"] = np.array([e.signed(problem) for e in evaluated])
            out["G"] = np.array([[e.constraint_violation(problem)] for e in evaluated])

    size = settings["population"] * len(problem.variables)
    minimize(Pareto(), NSGA2(pop_size=size), ("n_gen", settings["generations"]), seed=settings["seed"])


def search_settings(
    method: str = "de", generations: int = 50, population: int = 10, seed: int = 0, tol: float = DE_TOL
) -> dict[str, Any]:
    """The search settings checked, defaults filled in (the arguments of :func:`run_problem`).

    Raises:
        InvalidInput: an unknown method, a count below 1, a seed that is no integer, a negative tol.
    """
    if method not in METHODS:
        raise InvalidInput(f"unknown method {short(method)}; methods are {list(METHODS)}")
    for name, value in (("generations", generations), ("population", population)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise InvalidInput(f"{name} must be a positive integer, got {short(value)}")
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise InvalidInput(f"seed must be an integer, got {short(seed)}")
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol >= 0.0:
        raise InvalidInput(f"tol must be a non-negative number, got {short(tol)}")
    return {"method": method, "generations": generations, "population": population, "seed": seed, "tol": tol}


def run_problem(
    problem: Problem,
    *,
    method: str = "de",
    generations: int = 50,
    population: int = 10,
    seed: int = 0,
    tol: float = DE_TOL,
    store: str | Path | None = None,
    scheduler: str | Client | None = None,
    workers: int | None = None,
    progress: Progress | None = None,
) -> OptimizationResult:
    """Search a checked problem (see :func:`plm_pin.optimize.optimize` for the arguments)."""
    began = time.perf_counter()
    settings = search_settings(method, generations, population, seed, tol)
    check_execution(scheduler, workers)
    if progress is not None and not callable(progress):
        raise InvalidInput(
            f"progress must be a function (generation, designs) or None, got {short(progress)}"
        )
    checkpoints = None
    if store is not None:
        checkpoints = OptimizeStore(store, problem, settings)
    try:
        scratch = None if checkpoints is None else checkpoints.root
        with _evaluator(scheduler, workers, scratch) as evaluate:
            gens = Generations(problem, evaluate, checkpoints, progress)
            gens(np.array([problem.start]))
            (_de if method == "de" else _nsga2)(problem, gens, settings)
    finally:
        if checkpoints is not None:
            checkpoints.close()
    result = OptimizationResult(
        problem,
        settings,
        gens.evaluations,
        gens.computed,
        time.perf_counter() - began,
        None if store is None else Path(store),
    )
    check_feasible(result)
    return result


def optimize(
    mechanism: str | Builder,
    variables: Mapping[str, Any],
    poses: PosesArg,
    objectives: Sequence[Any] = ("gci",),
    *,
    constraints: Mapping[str, float] | None = None,
    base: Mapping[str, Any] | None = None,
    pose: Sequence[float] | None = None,
    options: Mapping[str, Any] | None = None,
    method: str = "de",
    generations: int = 50,
    population: int = 10,
    seed: int = 0,
    tol: float = DE_TOL,
    store: str | Path | None = None,
    scheduler: str | Client | None = None,
    workers: int | None = None,
    progress: Progress | None = None,
) -> OptimizationResult:
    """Choose builder parameters that meet the constraints over a task region and optimise the objectives.

    Args:
        mechanism: a preset name, a builder callable or a description path (as
            :func:`plm_pin.sweep.sweep` takes them).
        variables: design variables: builder parameter -> ``[lower, upper]`` (SI units), or
            ``{"bounds": [lower, upper], "repeat": n}`` for a list parameter of n equal entries.
        poses: the task region: ``{task coordinate: values}`` [m, rad], a grid (a trajectory's
            poses: one axis, or the grid of its coordinates).
        objectives: names among :data:`~plm_pin.optimize.OBJECTIVES`, or
            ``{"metric": <sweep variable>, "reduce": ..., "sense": "min" | "max"}``, each with an
            optional ``weight`` (single-objective methods minimise the weighted sum).
        constraints: constraint -> limit (:data:`~plm_pin.optimize.CONSTRAINTS`; ``reach`` is
            1.0, the whole region, unless given).
        base: fixed builder parameters (over the preset's); a variable given here sets the start design.
        pose: task pose giving the coordinates ``poses`` does not vary [m, rad].
        options: sweep metric options, e.g. ``{"wrenches": [[0, -10, 0]]}`` for ``max_force``.
        method: ``"de"`` (differential evolution) or ``"nsga2"`` (pymoo, several objectives).
        generations: most generations after the start design.
        population: population per design variable.
        seed: seed of the search: equal seeds, equal results.
        tol: relative spread of the population's scores at which DE stops.
        store: checkpoint folder; a re-run with the same arguments resumes from it.
        scheduler: None (here, or a local Dask cluster of ``workers`` processes), a Dask
            scheduler address, or a :class:`distributed.Client`.
        workers: processes of the local cluster (default: this process only).
        progress: called with (generation, designs so far) after each generation.

    Returns:
        Every evaluated design, the best (``result.best``), the Pareto front (``result.pareto()``).

    Raises:
        InvalidInput: an unknown parameter, constraint, objective, metric, option or method.
        NoFeasibleDesign: no evaluated design met every constraint; names the furthest level
            any design got to (``partial`` holds the designs).
        StoreMismatch: ``store`` holds another optimisation.
    """
    problem = make_problem(
        mechanism,
        variables,
        poses,
        objectives,
        constraints=constraints,
        base=base,
        pose=pose,
        options=options,
    )
    return run_problem(
        problem,
        method=method,
        generations=generations,
        population=population,
        seed=seed,
        tol=tol,
        store=store,
        scheduler=scheduler,
        workers=workers,
        progress=progress,
    )
