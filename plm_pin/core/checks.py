"""Checks of inputs against a Mechanism: assembled configurations, finite models and results."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..exceptions import ClosureNotSatisfied, DescriptionError, InvalidInput
from .mechanism import Mechanism, body_name


def check_assembled(mech: Mechanism, q: ArrayLike, name: str = "q") -> np.ndarray:
    """Return ``q`` checked (see :meth:`Mechanism.check_q`) and refuse it off the closure manifold.

    One residual evaluation, no Jacobian: cheap enough for the entry of every public analysis.

    Raises:
        InvalidInput: a malformed ``q``.
        ClosureNotSatisfied: a closure is open by more than ``mech.assembled_tol`` (see :func:`check_closed`).
    """
    qa = mech.check_q(q, name)
    if mech.closures:
        check_closed(mech, qa, mech.closure_residual(qa), name)
    return qa


def check_closed(mech: Mechanism, qa: np.ndarray, phi: np.ndarray, name: str = "q") -> None:
    """Refuse a checked ``qa`` whose closure residual ``phi`` [m, rad] is above ``mech.assembled_tol``.

    For callers that have the residual already, from the frame placements of their own
    Pinocchio pass (the check then costs no second pass).

    Raises:
        ClosureNotSatisfied: a closure is open by more than :attr:`Mechanism.assembled_tol`; the error
            carries the residual, the tolerance and the worst closure. Assemble first:
            ``mech.assemble(q).q``.
    """
    tol = mech.assembled_tol
    if phi.size and not np.abs(phi).max() <= tol:  # NaN refused too
        errors = {c.name: float(np.max(np.abs(phi[c.rows]))) for c in mech.closures}
        worst = max(errors, key=lambda k: errors[k])
        raise ClosureNotSatisfied(
            f"{mech.name}: {name} is not assembled: closure {worst!r} is open by {errors[worst]:.3g} "
            f"(tolerance {tol:.0e} m/rad); assemble it first: mech.assemble({name}).q",
            errors[worst],
            tol,
            qa,
            worst,
        )


def check_samples_assembled(mech: Mechanism, q: np.ndarray, t: np.ndarray) -> None:
    """Refuse a sampled trajectory with a configuration off the closure manifold.

    Args:
        mech: the mechanism.
        q: configurations, shape (n, nq).
        t: their times [s], shape (n,).

    Raises:
        ClosureNotSatisfied: at the first sample whose residual exceeds :attr:`Mechanism.assembled_tol`,
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


def non_finite_bodies(mech: Mechanism) -> list[str]:
    """Bodies whose spatial inertia is not finite (a mass or a centre of mass that overflows)."""
    model = mech.model
    finite = np.isfinite(np.array([inertia.matrix() for inertia in model.inertias])).all(axis=(1, 2))
    # names only when needed: each costs a scan of the frames
    return [body_name(model, int(j)) for j in np.flatnonzero(~finite[1:]) + 1]


def check_finite_model(mech: Mechanism) -> None:
    """Refuse a model whose bodies' spatial inertias are not finite: every dynamic result would overflow.

    A centre of mass at 1e300 m has a finite lever but an infinite :math:`m c^2`; the forces
    computed from it are NaN, infinite, or 1e300 N that mean nothing.

    The verdict is kept, with a copy of the model it was given for, in the calling thread's
    scratch of ``mech`` (not pickled): a later call costs one comparison of the models in
    Pinocchio, and an edit of ``mech.model`` after the check (an inertia changed in place)
    makes them differ, so the model is scanned again.

    Raises:
        DescriptionError: naming the bodies.
    """
    model = mech.model
    checked = getattr(mech._local, "finite_model", None)
    if checked is not None and checked == model:  # a model with a NaN never equals its copy
        return
    bodies = non_finite_bodies(mech)
    if bodies:
        raise DescriptionError(
            f"{mech.name}: the spatial inertia of bodies {bodies} is not finite (a mass or centre "
            "of mass too large for floating point); fix their <inertial> in the description"
        )
    mech._local.finite_model = pin.Model(model)


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
    bad = [name for name, arr in arrays.items() if not np.isfinite(arr).all()]  # the method: no wrapper
    if not bad:
        return
    check_finite_model(mech)
    raise InvalidInput(
        f"{mech.name}: {what} are not finite ({', '.join(bad)}); an input is too large for floating point"
    )
