r"""The generic solve: every solution at one random complex parameter, by monodromy, cached on disk.

Why monodromy: a total-degree start system tracks :math:`\prod_i \deg F_i` paths
(:math:`2^{10}` for a planar 3-RPR in (cos, sin) unknowns, millions for a 6-6 platform)
whose vast majority go to infinity; a multi-homogeneous count is smaller but needs a
variable grouping per family. Monodromy needs neither: it seeds the family
:math:`F(x; p) + b = 0` (offsets :math:`b` added to every equation) with a random complex
:math:`x_0`, :math:`p_0` and :math:`b_0 = -F(x_0; p_0)`, then moves the parameters
:math:`(p, b)` around random triangles back to :math:`(p_0, b_0)`: the paths permute the
solutions, and new ones appear until none is left to find. The loops stop after
:data:`STALE_LOOPS` loops in a row without a new solution. Tracking every solution from
:math:`(p_0, b_0)` to :math:`(p_0, 0)` then gives the solutions of the closures at the generic
parameter :math:`p_0` (paths to infinity or to singular ends dropped), and
:data:`CHECK_LOOPS` loops in a row in :math:`p` alone at :math:`b = 0`, each bringing every path back,
must find nothing new (they find the roots the offset family missed).

The reference assembly as a seed: the random start of the offset family can fail on every loop
(its paths lost, or all of them going to infinity as :math:`b \to 0`), as for a planar
delta whose weld closures tie coaxial half-joints. So a known real solution (the mechanism's
reference configuration at its actuator values) is also tracked to :math:`p_0` at
:math:`b = 0`; when that adds a root the offset stage missed, the loops in :math:`p` alone go
on until :data:`STALE_LOOPS` loops in a row find nothing new.

Quaternion signs: the system is even in each quaternion block (:math:`R(-e) = R(e)`), so
the roots come in orbits of :math:`2^k` (:math:`k` quaternions); only one root per orbit is
kept, tracked and counted (signed by its quaternions' leading components, :func:`canonical`):
the counts are of assemblies, not of signed quaternions.

The start of every call's paths: any generic parameter will do (the parameter continuation
theorem holds for each), but how many steps the paths take depends on it several-fold (on the
test 3-RPR, 464 to 1,109 steps over 12 targets). So :data:`START_CANDIDATES` random parameters
are tried besides :math:`p_0`, each with the solutions carried to it by parameter homotopy (kept
only when every path arrives at its own regular root), and the one whose paths to
:data:`START_TARGETS` actuator vectors about the reference end cleanly most often, then take the
fewest steps, is stored.

What it proves: the count is a *lower bound* on the generic number of solutions (monodromy
cannot show that nothing is left); the stale loops make a miss unlikely, not impossible.

The result depends only on the polynomial form (:attr:`PolynomialForm.digest`) and is stored
in ``$PLM_PIN_CACHE/homotopy/<digest>.v<version>.npz`` (a failed solve leaves its reason
beside it, so it is not run again) (default ``~/.cache/plm_pin``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...tolerances import HOMOTOPY_SAME_ROOT_RTOL
from .form import PolynomialForm
from .polynomial import SEED, NotPolynomial

STALE_LOOPS = 20
"""Monodromy loops in a row without a new solution before the generic solve stops."""
CHECK_LOOPS = 10
"""Loops in a row in the actuator parameters alone (offsets zero), each bringing every path back,
that must find no new solution before the generic solve ends."""
OFFSET_STEP = 0.1
"""Size of the random offsets of the seeded loops, as a move of the unknowns (unit rows of the Jacobian)."""
MAX_SOLUTIONS = 200
"""Generic counts above this are not solved (the mechanism falls back to multi-start)."""
START_CANDIDATES = 8
"""Random generic parameters tried besides the monodromy's as the start of every call's paths."""
START_TARGETS = 6
"""Actuator vectors about the reference to which the candidate starts' paths are counted."""
START_SPREAD = 0.1
"""How far those vectors lie from the reference: each actuator within this fraction of its
magnitude plus the mean magnitude."""
CACHE_VERSION = 5
"""Version of the stored generic solves (part of the file name: a new algorithm starts afresh)."""


@dataclass(frozen=True)
class GenericSolution:
    """Every solution of the closures at one generic complex parameter.

    Attributes:
        p: the generic actuator parameters (complex), shape (n_params,).
        x: one solution per quaternion-sign orbit, shape (N / symmetry, n).
        loops: monodromy loops run.
        symmetry: roots per orbit (2 to the number of quaternions).
    """

    p: np.ndarray
    x: np.ndarray
    loops: int
    symmetry: int = 1

    @property
    def count(self) -> int:
        """Generic number of complex solutions found, one per quaternion-sign orbit (a lower bound)."""
        return int(self.x.shape[0])


def cache_folder() -> Path:
    """Folder of the stored generic solves: ``$PLM_PIN_CACHE/homotopy`` (default ``~/.cache/plm_pin``)."""
    root = os.environ.get("PLM_PIN_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "plm_pin")
    return Path(root) / "homotopy"


def _regular(
    form: PolynomialForm, X: np.ndarray, codes: np.ndarray, p: np.ndarray, b: np.ndarray
) -> np.ndarray:
    """Rows of ``X`` that ended at t = 1 on a finite, non-singular root (:func:`~.tracking.clean_ends`)."""
    from .tracking import clean_ends

    return X[clean_ends(X, codes, p, b, form.program)].reshape(-1, form.n)


def canonical(form: PolynomialForm, X: np.ndarray) -> np.ndarray:
    """Each row of ``X`` (n,) or (N, n) with every quaternion q signed by its leading component.

    q and -q are one rotation: of the pair, the one whose first component of modulus at least half
    the largest (the lead) has a positive real part, or a positive imaginary part when that is the
    larger. The lead is never near zero, so rounding cannot sign two copies of a root apart (as w
    would at a half turn, where it is zero).
    """
    X = np.array(X, dtype=np.complex128)
    for o, size in zip(form.unit_offsets, form.unit_sizes, strict=True):
        if size == 4:
            q = X[..., o : o + 4]
            size_of = np.abs(q)
            lead = np.argmax(size_of >= 0.5 * size_of.max(axis=-1, keepdims=True, initial=0.0), axis=-1)
            z = np.take_along_axis(q, lead[..., None], axis=-1)[..., 0]
            flip = np.where(np.abs(z.real) >= np.abs(z.imag), z.real, z.imag) < 0
            X[..., o : o + 4] = np.where(flip[..., None], -q, q)
    return X


def _merge(known: np.ndarray, new: np.ndarray) -> np.ndarray:
    rows = list(known)
    for x in new:
        if not any(np.abs(x - y).max() <= HOMOTOPY_SAME_ROOT_RTOL * (1.0 + np.abs(y).max()) for y in rows):
            rows.append(x)
    return np.array(rows).reshape(-1, known.shape[1])


def _loop(  # type: ignore[no-untyped-def]
    form: PolynomialForm, X: np.ndarray, p0, b0, rng: np.random.Generator, vary_b: bool, b_scale: float = 1.0
) -> np.ndarray:
    from .threads import over_threads
    from .tracking import track_all

    program = form.program

    def rand(k: int) -> np.ndarray:
        return rng.normal(size=k) + 1j * rng.normal(size=k)

    p1, p2 = p0 + rand(form.n_params), p0 + rand(form.n_params)
    b1, b2 = (b0 + b_scale * rand(form.n), b0 + b_scale * rand(form.n)) if vary_b else (b0, b0)
    for (pa, ba), (pb, bb) in (((p0, b0), (p1, b1)), ((p1, b1), (p2, b2)), ((p2, b2), (p0, b0))):
        X, codes, *_ = over_threads(track_all, (X,), pa, ba, pb, bb, program)
        X = _regular(form, X, codes, pb, bb)
        if not len(X):
            break
    return X


def _seeded(form: PolynomialForm, seed: tuple[np.ndarray, np.ndarray] | None, p0: np.ndarray) -> np.ndarray:
    """The known solution ``seed = (x, p)`` tracked to ``p0`` at b = 0: zero or one row of shape (n,)."""
    from .tracking import track_all

    if seed is None:
        return np.zeros((0, form.n), dtype=np.complex128)
    x, p = (np.asarray(a, dtype=np.complex128) for a in seed)
    zero = np.zeros(form.n, dtype=np.complex128)
    X, codes, *_ = track_all(x.reshape(1, -1), p, zero, p0, zero, form.program)
    return canonical(form, _regular(form, X, codes, p0, zero))


def solve_generic(form: PolynomialForm, seed: tuple[np.ndarray, np.ndarray] | None = None) -> GenericSolution:
    """Every solution at a generic complex parameter, by monodromy (no cache).

    Args:
        form: the polynomial form.
        seed: a known solution ``(x, p)`` of the closures (unknowns, shape (n,); actuator values,
            shape (n_params,)), e.g. the reference assembly, or None.

    Raises:
        NotPolynomial: more than :data:`MAX_SOLUTIONS` solutions, or none.
    """
    from .evaluation import evaluate
    from .threads import over_threads
    from .tracking import track_all

    rng = np.random.default_rng(SEED + 2)
    p0 = rng.normal(size=form.n_params) + 1j * rng.normal(size=form.n_params)
    x0 = rng.normal(size=form.n) + 1j * rng.normal(size=form.n)
    b0 = -evaluate(form, x0, p0)[0]
    known = canonical(form, x0.reshape(1, -1))
    stale, loops = 0, 0
    while stale < STALE_LOOPS:
        loops += 1
        found = _merge(known, canonical(form, _loop(form, known, p0, b0, rng, vary_b=True)))
        stale = stale + 1 if len(found) == len(known) else 0
        known = found
        if len(known) * 2 ** int(np.sum(form.unit_sizes == 4)) > MAX_SOLUTIONS:
            raise NotPolynomial(f"more than {MAX_SOLUTIONS} generic solutions")
    zero = np.zeros(form.n, dtype=np.complex128)
    X, codes, *_ = over_threads(track_all, (known,), p0, b0, p0, zero, form.program)
    roots = _merge(
        np.zeros((0, form.n), dtype=np.complex128), canonical(form, _regular(form, X, codes, p0, zero))
    )
    offset_roots = len(roots)
    roots = _merge(roots, _seeded(form, seed, p0))
    if not len(roots):
        raise NotPolynomial("no isolated solution at a generic parameter")
    # offsets that move the seeded roots by about OFFSET_STEP (relative), not off to infinity
    b_scale = OFFSET_STEP * float(np.median(np.linalg.norm(evaluate(form, roots[0], p0)[1], axis=1)))
    stale = lost = 0
    while len(roots) > offset_roots and stale < STALE_LOOPS:  # the seed added a root: loops in (p, b)
        loops += 1
        back = canonical(form, _loop(form, roots, p0, zero, rng, vary_b=True, b_scale=b_scale))
        lost += not len(back)
        if lost > STALE_LOOPS or loops > 20 * STALE_LOOPS:
            raise NotPolynomial("the monodromy loops from the reference assembly lose their paths")
        more = _merge(roots, back)
        if len(more) > len(roots):
            stale = 0
        elif len(back) == len(roots):  # only a loop that brought every path back counts as stale
            stale += 1
        roots = more
    stale = tries = 0
    while stale < CHECK_LOOPS and tries < 20 * CHECK_LOOPS:  # loops in p alone, at b = 0
        loops += 1
        tries += 1
        back = canonical(form, _loop(form, roots, p0, zero, rng, vary_b=False))
        more = _merge(roots, back)
        if len(more) > len(roots):
            stale = 0
        elif len(back) == len(roots):  # only a loop that brought every path back counts as stale
            stale += 1
        roots = more
    symmetry = 2 ** int(np.sum(form.unit_sizes == 4))
    if seed is not None:
        roots, p0 = _cheapest_start(form, roots, p0, np.real(np.asarray(seed[1])), rng)
    return GenericSolution(p=p0, x=roots, loops=loops, symmetry=symmetry)


def _cheapest_start(
    form: PolynomialForm, X: np.ndarray, p0: np.ndarray, reference: np.ndarray, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """The solutions ``X`` at ``p0``, or carried to another generic parameter whose paths are shorter.

    Of ``p0`` and :data:`START_CANDIDATES` random parameters, the one whose paths to
    :data:`START_TARGETS` actuator vectors about ``reference`` end cleanly most often (a path lost
    near a singular point stops early: it must not look cheap), then take the fewest steps in all
    (counts, so the choice does not depend on the machine). A candidate counts only when every
    path to it arrives at its own regular root.
    """
    from .threads import over_threads
    from .tracking import HANDOFF_GROWTH, clean_ends, track_all

    zero = np.zeros(form.n, dtype=np.complex128)
    spread = START_SPREAD * (np.abs(reference) + np.abs(reference).mean())
    targets = [
        (reference + spread * rng.uniform(-1, 1, reference.shape)).astype(np.complex128)
        for _ in range(START_TARGETS)
    ]

    def cost(Y: np.ndarray, p: np.ndarray) -> tuple[int, int]:
        unclean = steps = 0
        for t in targets:
            ends, codes, path_steps, _ = over_threads(
                track_all, (Y,), p, zero, t, zero, form.program, HANDOFF_GROWTH
            )
            unclean += int(np.count_nonzero(~clean_ends(ends, codes, t, zero, form.program)))
            steps += int(path_steps.sum())
        return unclean, steps

    best, least = (X, p0), cost(X, p0)
    for _ in range(START_CANDIDATES):
        p = rng.normal(size=form.n_params) + 1j * rng.normal(size=form.n_params)
        Y, codes, *_ = over_threads(track_all, (X,), p0, zero, p, zero, form.program)
        Y = canonical(form, _regular(form, Y, codes, p, zero))
        Y = _merge(np.zeros((0, form.n), dtype=np.complex128), Y)
        if len(Y) == len(X) and (c := cost(Y, p)) < least:
            best, least = (Y, p), c
    return best


def generic_solution(
    form: PolynomialForm, *, seed: tuple[np.ndarray, np.ndarray] | None = None, use_cache: bool = True
) -> GenericSolution:
    """The generic solve of ``form``, read from the disk cache or computed and stored there.

    ``seed`` is a known solution ``(x, p)`` (see :func:`solve_generic`).
    """
    path = cache_folder() / f"{form.digest}.v{CACHE_VERSION}.npz"
    refused = path.with_suffix(".refused.txt")  # a generic solve that failed: its reason, not retried
    if use_cache and path.exists():
        with np.load(path) as z:
            return GenericSolution(p=z["p"], x=z["x"], loops=int(z["loops"]), symmetry=int(z["symmetry"]))
    if use_cache and refused.exists():
        raise NotPolynomial(refused.read_text(encoding="utf-8"))
    try:
        sol = solve_generic(form, seed)
    except NotPolynomial as exc:
        if use_cache:
            refused.parent.mkdir(parents=True, exist_ok=True)
            refused.write_text(str(exc), encoding="utf-8")
        raise
    if use_cache:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
        np.savez(tmp, p=sol.p, x=sol.x, loops=sol.loops, symmetry=sol.symmetry)
        os.replace(tmp, path)
    return sol
