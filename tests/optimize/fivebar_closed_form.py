"""The five-bar's conditioning in closed form, plain numpy, nothing from plm_pin: the tests' oracle.

Motors at ``(-b/2, 0)`` and ``(b/2, 0)``, driven links ``p``, distal links ``d``, elbows outward
(left elbow left of the tip's circle intersection, right elbow right), as ``build_fivebar``'s
reference configuration. With elbow ``B_i = A_i + p (cos t_i, sin t_i)`` and ``|P - B_i| = d``,
differentiating gives ``(P - B_i) . P' = p t_i' (P - B_i) . (-sin t_i, cos t_i)``: the
actuator-from-tip Jacobian's rows are ``(P - B_i)^T`` divided by that factor.
"""

from __future__ import annotations

import numpy as np


def condition_numbers(b: float, p: float, d: float, x: np.ndarray, y: np.ndarray) -> np.ndarray | None:
    """sigma_max / sigma_min of the Jacobian at the tips ``(x, y)``; None if a tip is out of reach."""
    tips = np.stack([x, y], -1)
    rows = []
    for x0, side in ((-b / 2, -1.0), (b / 2, 1.0)):
        a0 = np.array([x0, 0.0])
        v = tips - a0
        r = np.linalg.norm(v, axis=-1)
        along = (p**2 - d**2 + r**2) / (2 * r)
        h2 = p**2 - along**2
        if np.any(h2 <= 0.0):
            return None
        u = v / r[..., None]
        n = np.stack([-u[..., 1], u[..., 0]], -1)
        c1 = a0 + along[..., None] * u + np.sqrt(h2)[..., None] * n
        c2 = a0 + along[..., None] * u - np.sqrt(h2)[..., None] * n
        first = (side * (c1[..., 0] - c2[..., 0]) > 0)[..., None]
        elbow = np.where(first, c1, c2)
        t = np.arctan2(elbow[..., 1], elbow[..., 0] - x0)
        w = tips - elbow
        rows.append(w / (p * (-w[..., 0] * np.sin(t) + w[..., 1] * np.cos(t)))[..., None])
    s = np.linalg.svd(np.stack(rows, -2), compute_uv=False)
    with np.errstate(divide="ignore"):
        return s[..., 0] / s[..., -1]


def best_gci(
    b: float, ps: np.ndarray, ds: np.ndarray, x: np.ndarray, y: np.ndarray
) -> tuple[float, float, float]:
    """Brute force over the grid ``ps x ds``: (p, d, largest mean of 1 / condition number)."""
    best = (np.nan, np.nan, -np.inf)
    for p in ps:
        for d in ds:
            c = condition_numbers(b, p, d, x, y)
            if c is not None and np.mean(1.0 / c) > best[2]:
                best = (float(p), float(d), float(np.mean(1.0 / c)))
    return best
