"""Private input checks shared by the public API."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .exceptions import ClosureNotSatisfied, DescriptionError, InvalidInput

if TYPE_CHECKING:
    from .mechanism import Mechanism


def as_vector(x: object, size: int, name: str) -> np.ndarray:
    """Return ``x`` as a float array of shape (size,); refuse non-numbers, wrong shapes, non-finite values.

    Raises:
        InvalidInput: naming ``name`` and what is wrong.
    """
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidInput(f"{name} must be {size} numbers: {exc}") from None
    if arr.shape != (size,):
        raise InvalidInput(f"{name} must have shape ({size},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidInput(
            f"{name} has non-finite entries at indices {np.flatnonzero(~np.isfinite(arr)).tolist()}"
        )
    return arr


# ------------------------------------------------------------------ closure manifold

CLOSURE_TOL = 1e-8
"""Largest closure residual [m, rad] of a configuration the analyses accept as assembled.

Every configuration plm_pin computes (assembly, inverse and forward kinematics, trajectories)
closes the loops to about 1e-12; 1e-8 leaves room for configurations read back from files
while refusing ones whose loops are visibly open (``q_ref + 0.05`` opens them by centimetres)."""


def check_assembled(mech: Mechanism, q: object, name: str = "q") -> np.ndarray:
    """Return ``q`` checked (see :meth:`Mechanism.check_q`) and refuse it off the closure manifold.

    One residual evaluation, no Jacobian: cheap enough for the entry of every public analysis.

    Raises:
        InvalidInput: a malformed ``q``.
        ClosureNotSatisfied: a closure is open by more than :data:`CLOSURE_TOL`; the error
            carries the residual, the tolerance and the worst closure. Assemble first:
            ``mech.assemble(q).q``.
    """
    qa = mech.check_q(q, name)
    if not mech.closures:
        return qa
    phi = mech.closure_residual(qa)
    if not np.max(np.abs(phi)) <= CLOSURE_TOL:  # NaN refused too
        errors = {c.name: float(np.max(np.abs(phi[c.rows]))) for c in mech.closures}
        worst = max(errors, key=lambda k: errors[k])
        raise ClosureNotSatisfied(
            f"{mech.name}: {name} is not assembled: closure {worst!r} is open by {errors[worst]:.3g} "
            f"(tolerance {CLOSURE_TOL:.0e} m/rad); assemble it first: mech.assemble({name}).q",
            errors[worst],
            CLOSURE_TOL,
            qa,
            worst,
        )
    return qa


def check_samples_assembled(mech: Mechanism, q: np.ndarray, t: np.ndarray) -> None:
    """Refuse a sampled trajectory with a configuration off the closure manifold.

    Args:
        mech: the mechanism.
        q: configurations, shape (n, nq).
        t: their times [s], shape (n,).

    Raises:
        ClosureNotSatisfied: at the first sample whose residual exceeds :data:`CLOSURE_TOL`,
            naming the sample, its time and the worst closure.
    """
    for k in range(q.shape[0]):
        try:
            check_assembled(mech, q[k], "q")
        except ClosureNotSatisfied as exc:
            raise ClosureNotSatisfied(
                f"sample {k} (t = {float(t[k]):.9g} s) of the trajectory: {exc}",
                exc.residual_norm,
                exc.tolerance,
                exc.q,
                exc.worst_closure,
            ) from None


# ------------------------------------------------------------ tolerances and results


def check_tolerance(value: object, name: str, *, relative: bool = False) -> float:
    """Return a tolerance as a float; refuse non-numbers, NaN, infinities and negative values.

    Args:
        value: the tolerance given.
        name: the argument's name, for the message.
        relative: a relative tolerance, which must also be below 1.

    Raises:
        InvalidInput: naming ``name`` and the valid range.
    """
    valid = "a finite number in [0, 1)" if relative else "a finite number >= 0"
    try:
        tol = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidInput(f"{name} must be {valid}, got {value!r}") from None
    if not (0.0 <= tol < (1.0 if relative else np.inf)):  # NaN fails every comparison
        raise InvalidInput(f"{name} must be {valid}, got {tol!r}")
    return tol


def non_finite_bodies(mech: Mechanism) -> list[str]:
    """Bodies whose spatial inertia is not finite (a mass or a centre of mass that overflows)."""
    return [
        name
        for j, name in enumerate(mech.body_names, start=1)
        if not np.all(np.isfinite(mech.model.inertias[j].matrix()))
    ]


def check_finite_model(mech: Mechanism) -> None:
    """Refuse a model whose bodies' spatial inertias are not finite: every dynamic result would overflow.

    A centre of mass at 1e300 m has a finite lever but an infinite :math:`m c^2`; the forces
    computed from it are NaN, infinite, or 1e300 N that mean nothing.

    Raises:
        DescriptionError: naming the bodies.
    """
    bodies = non_finite_bodies(mech)
    if bodies:
        raise DescriptionError(
            f"{mech.name}: the spatial inertia of bodies {bodies} is not finite (a mass or centre "
            "of mass too large for floating point); fix their <inertial> in the description"
        )


def check_finite_result(mech: Mechanism, what: str, **arrays: np.ndarray) -> None:
    """Final guard where a result is built: refuse NaN or infinite entries instead of returning them.

    Args:
        mech: the mechanism.
        what: the result, completing the message (``"static forces"``).
        arrays: the result's arrays by name.

    Raises:
        DescriptionError: when a body's inertia is not finite (see :func:`check_finite_model`).
        InvalidInput: otherwise, naming the arrays with non-finite entries.
    """
    bad = [name for name, arr in arrays.items() if not np.all(np.isfinite(arr))]
    if not bad:
        return
    check_finite_model(mech)
    raise InvalidInput(
        f"{mech.name}: {what} are not finite ({', '.join(bad)}); an input is too large for floating point"
    )
