r"""Every assembly mode at given actuator values: parameter homotopy from the generic solve.

Each of the :math:`N` generic solutions (:mod:`.generic`) is tracked from the generic complex
parameters to the actuator values (:mod:`.tracking`). By the parameter continuation theorem
(Morgan & Sommese 1989; Sommese & Wampler 2005, thm. 7.1.1) every isolated solution at the
target is the end of one of these paths, and no parameter has more than :math:`N`
non-singular isolated solutions. So when every path ends at its own non-singular root or at
infinity, those roots are all the roots: the result is *complete*. Otherwise (a path ended
singular, failed, or two paths met) it is not, and says how many and why.

Paths to infinity: at a non-generic target some roots of the generic parameter are at infinity
(a Delta with its three arms at one angle: base and platform hexagons are then similar, and 12
of its 40 roots leave), and near it they are finite but large. A path the affine tracker cannot
follow to a clean end is tracked again in projective coordinates (:mod:`.projective`), where
both stay bounded: it ends at a root at infinity (dropped; it is no assembly) or at a finite one.

Real roots are refined by Newton on the real system, kept when every closure entry vanishes
(not only the random combination), and certified by a Krawczyk test (:mod:`.certify`).
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from ...core.mechanism import Mechanism
from ...tolerances import (
    HOMOTOPY_ENTRY_TOL,
    HOMOTOPY_REAL_RTOL,
    HOMOTOPY_SAME_ROOT_RTOL,
)
from .form import PolynomialForm
from .generic import GenericSolution, canonical, generic_solution
from .polynomial import NotPolynomial, from_configuration, polynomial_form


@dataclass(frozen=True)
class RealRoot:
    """A certified real root of the polynomial form.

    Attributes:
        x: the unknowns, shape (n,).
        box_radius: relative half-width of the Krawczyk box proven to hold it alone (times 1 + abs(x)).
    """

    x: np.ndarray
    box_radius: float


@dataclass(frozen=True)
class HomotopySolve:
    """Outcome of the homotopy at one actuator vector.

    Attributes:
        generic_count: number of complex solutions at a generic parameter (monodromy: a lower bound),
            one per quaternion-sign orbit.
        roots: distinct non-singular complex roots reached (one per orbit).
        real: certified real roots that solve the full closure system (one per quaternion-sign orbit).
        uncertified: real roots of the full system whose Krawczyk test failed (kept, not proven).
        spurious: real roots of the square system only (the random combination's).
        elsewhere: real assemblies at other values of the actuators left unknowns (redundant
            actuation, :attr:`PolynomialForm.checked`).
        diverged: paths that went to infinity (ended there in projective coordinates).
        singular: paths that ended at a singular root.
        failed: paths the tracker lost.
        collided: paths that ended on a root another path had reached.
    """

    generic_count: int
    roots: int
    real: tuple[RealRoot, ...]
    uncertified: tuple[np.ndarray, ...]
    spurious: int
    elsewhere: int
    diverged: int
    singular: int
    failed: int
    collided: int

    @property
    def complete(self) -> bool:
        """Whether every generic path ended at its own non-singular root or at infinity (all roots found)."""
        return self.roots + self.diverged == self.generic_count and not self.uncertified

    def why_incomplete(self) -> str:
        """What kept the solve from being complete ('' when complete)."""
        if self.complete:
            return ""
        parts = [
            f"{k} {what}"
            for k, what in (
                (self.diverged, "paths went to infinity"),
                (self.singular, "paths ended singular"),
                (self.failed, "paths were lost by the tracker"),
                (self.collided, "paths met another"),
                (len(self.uncertified), "real roots failed the interval test"),
            )
            if k
        ]
        return f"{self.roots} of {self.generic_count} roots reached: " + ", ".join(parts)


_Prepared = tuple[PolynomialForm, GenericSolution]
_FORMS: weakref.WeakKeyDictionary[Mechanism, _Prepared] = weakref.WeakKeyDictionary()


def prepared(mech: Mechanism) -> tuple[PolynomialForm, GenericSolution]:
    """The polynomial form and generic solve of ``mech`` (built once per mechanism, solve cached on disk).

    Raises:
        NotPolynomial: the mechanism has no polynomial form.
    """
    hit = _FORMS.get(mech)
    if hit is None:
        subset = parameter_actuators(mech)
        if subset is not None:  # redundant actuation: as many parameters as the mobility
            try:
                hit = _prepare(mech, subset)
            except NotPolynomial:
                hit = None
        hit = hit or _prepare(mech, None)
        _FORMS[mech] = hit
    return hit


def _prepare(mech: Mechanism, subset: tuple[int, ...] | None) -> _Prepared:
    form = polynomial_form(mech, subset)
    c = mech.actuator_positions(mech.q_ref)[form.parameters]
    return form, generic_solution(form, seed=(from_configuration(form, mech, mech.q_ref), c))


def parameter_actuators(mech: Mechanism) -> tuple[int, ...] | None:
    """For redundant actuation, the actuators (as many as the mobility) taken as parameters, else None.

    Of the subsets of that size, the one whose values best fix the configuration at the reference
    pose: the largest smallest singular value of the closure null space's actuator rows. The
    other actuators stay unknowns, so the system has fewer spurious roots (half the paths on the
    Harada 3D4M), and are checked against their values afterwards.
    """
    import itertools

    k = mech.mobility
    if mech.n_actuators <= k or k <= 0:
        return None
    vt = np.linalg.svd(mech.closure_jacobian(mech.q_ref))[2]
    null = vt[vt.shape[0] - k :].T  # (nv, k): the closed chain's velocities at the reference
    rows = null[mech.actuated_v_indices]
    best = max(
        itertools.combinations(range(mech.n_actuators), k),
        key=lambda sub: float(np.linalg.svd(rows[list(sub)], compute_uv=False)[-1]),
    )
    return tuple(int(a) for a in best)


def _off_actuators(form: PolynomialForm, X: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Per real root (row of ``X``), whether it puts an actuator left unknown off its value ``values[a]``."""
    scale = HOMOTOPY_ENTRY_TOL * (1.0 + np.abs(X).max(axis=1))
    off = np.zeros(len(X), dtype=bool)
    for a, o, revolute in form.checked:
        if revolute:
            cos, sin = np.abs(X[:, o] - np.cos(values[a])), np.abs(X[:, o + 1] - np.sin(values[a]))
            off |= np.where(sin > cos, sin, cos) > scale
        else:
            off |= np.abs(X[:, o] - values[a]) > scale
    return off


def _distinct(X: np.ndarray) -> np.ndarray:
    """Mask of the rows of ``X`` (N, n) kept as distinct roots, in order: the first of each root.

    A row is kept unless a row kept before it lies within :data:`~plm_pin.tolerances.HOMOTOPY_SAME_ROOT_RTOL`
    times 1 + its own largest entry (in every coordinate).
    """
    scale = 1.0 + np.abs(X).max(axis=1)
    near = np.abs(X[:, None] - X[None]).max(axis=2) <= HOMOTOPY_SAME_ROOT_RTOL * scale[:, None]
    order = np.arange(len(X))
    near &= order[:, None] > order  # row k against the rows before it
    kept = np.ones(len(X), dtype=bool)
    for k in np.flatnonzero(near.any(axis=1)).tolist():  # in order: the rows before k are settled
        kept[k] = not (near[k, :k] & kept[:k]).any()
    return kept


def _projective(
    form: PolynomialForm,
    gen: GenericSolution,
    X: np.ndarray,
    codes: np.ndarray,
    ends: np.ndarray,
    unclean: np.ndarray,
    p1: np.ndarray,
) -> tuple[np.ndarray, int, int, int]:
    """The paths the affine tracker did not end cleanly (``unclean``), in projective coordinates.

    A path off to infinity, lost, or at a large root the affine test cannot judge: a path at
    infinity ends there, a large root is reached. A path given up before t = 1 goes on from where
    it stopped; one that reached t = 1 is tracked again from its start. Returns the finite roots
    reached, and the paths that went to infinity, ended singular, and failed.
    """
    from .projective import projective_ends
    from .tracking import GROWING

    resume = ends < 1.0
    starts = np.where(resume[:, None], X, gen.x)[unclean]
    t0 = np.where(resume, ends, 0.0)[unclean]
    far, diverged, singular, lost = projective_ends(form, starts, t0, gen.p, p1)
    # a path lost in projective coordinates too (a singular end at infinity, as the isotropic points
    # of revolute (cos, sin) pairs) whose affine norm grew like a power of 1/(1 - t) went to infinity
    growing = codes[unclean] == GROWING
    diverged += int(np.count_nonzero(lost & growing))
    return far, diverged, singular, int(np.count_nonzero(lost & ~growing))


def solve_homotopy(mech: Mechanism, actuators: np.ndarray) -> HomotopySolve:
    """Track every generic solution of ``mech`` to ``actuators`` and certify the real ends.

    Raises:
        NotPolynomial: the mechanism has no polynomial form.
    """
    from .certify import certify, parameter_intervals
    from .evaluation import entries_at
    from .threads import over_threads
    from .tracking import HANDOFF_GROWTH, clean_ends, real_newton, track_all

    form, gen = prepared(mech)
    values = np.asarray(actuators, dtype=float)
    p1 = values[form.parameters].astype(np.complex128)
    zero = np.zeros(form.n, dtype=np.complex128)
    X, codes, _, ends = over_threads(track_all, (gen.x,), gen.p, zero, p1, zero, form.program, HANDOFF_GROWTH)
    clean = clean_ends(X, codes, p1, zero, form.program)
    far, diverged, singular, failed = (
        (X[:0], 0, 0, 0) if clean.all() else _projective(form, gen, X, codes, ends, ~clean, p1)
    )
    X = canonical(form, np.concatenate([X[clean], far]))
    roots = X[_distinct(X)]
    # the real roots: refined on the real system, kept when every closure entry vanishes and the
    # actuators left unknown are at their values, then certified
    is_real = ~(np.abs(roots.imag).max(axis=1) > HOMOTOPY_REAL_RTOL * (1.0 + np.abs(roots).max(axis=1)))
    pr = np.ascontiguousarray(np.real(p1))
    Xr = real_newton(roots[is_real], pr, form.program)
    entries = entries_at(Xr.astype(np.complex128), p1, form.kernel_args())
    closes = ~(np.abs(entries).max(axis=1) > HOMOTOPY_ENTRY_TOL * (1.0 + np.abs(Xr).max(axis=1)))
    here = ~_off_actuators(form, Xr, values)
    kept = Xr[closes & here]
    radii = certify(form, kept, pr, parameter_intervals(form, pr))
    return HomotopySolve(
        generic_count=gen.count,
        roots=len(roots),
        real=tuple(RealRoot(x, r) for x, r in zip(kept, radii.tolist(), strict=True) if not math.isnan(r)),
        uncertified=tuple(kept[np.isnan(radii)]),
        spurious=int(np.count_nonzero(~closes)),
        elsewhere=int(np.count_nonzero(closes & ~here)),
        diverged=diverged,
        singular=singular,
        failed=failed,
        collided=len(X) - len(roots),
    )
