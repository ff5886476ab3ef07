"""Self-collision of a mechanism's links, with Pinocchio's GeometryModel and coal.

The shapes checked are the description's collision geometry
(:attr:`~plm_pin.core.mechanism.Mechanism.collision_model`): a URDF's ``<collision>``
shapes, an MJCF's geoms that take part in contacts, or the visual shapes (boxes,
cylinders, spheres and meshes) of a description that has no collision shapes.

Every pair of shapes on two different bodies is checked, except *adjacent* bodies, which
touch by design: a body and its parent across a joint (through bodies that carry no shape,
such as the cross of a universal joint), and the two bodies a closure joins. More pairs can
be ignored by body name: in the sidecar,

.. code-block:: yaml

    self_collision:
      ignore: [[slider1, slider2]]

or with the ``ignore`` arguments below.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable

import numpy as np
import pinocchio as pin

from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput


class SelfCollision:
    """The collision pairs of a mechanism and a checker of configurations.

    Attributes:
        mech: the mechanism.
        geometry: the shapes (a copy of its collision geometry model) with the pairs checked.
        pairs: the checked pairs, as body names.
    """

    def __init__(self, mech: Mechanism, ignore: Iterable[tuple[str, str]] = ()) -> None:
        """Build the pairs of ``mech``'s shapes, adjacent bodies and ignored pairs left out.

        The ignored pairs are the sidecar's ``self_collision.ignore`` and ``ignore`` (body names).

        Raises:
            InvalidInput: when ``ignore`` names a body the mechanism lacks.
        """
        self.mech = mech
        model = mech.model
        names = ("universe", *mech.body_names)
        ignored = set()
        for pair in (*mech.sidecar.collision_ignore, *ignore):
            first, second = pair
            for n in (first, second):
                if n not in names:
                    raise InvalidInput(
                        f"cannot ignore collisions of {n!r}: no such body; bodies are {list(names)}"
                    )
            ignored.add(frozenset((names.index(first), names.index(second))))
        self.geometry = mech.collision_model.copy()
        shaped = {int(g.parentJoint) for g in self.geometry.geometryObjects}
        adjacent = {frozenset((j, _shaped_ancestor(model, j, shaped))) for j in shaped}
        for c in mech.closures:  # the cut joint's two bodies
            adjacent.add(frozenset(int(model.frames[f].parentJoint) for f in c.frame_ids))
        objects = list(self.geometry.geometryObjects)
        self.pairs: list[tuple[str, str]] = []
        for i in range(len(objects)):
            for k in range(i + 1, len(objects)):
                ja, jb = int(objects[i].parentJoint), int(objects[k].parentJoint)
                key = frozenset((ja, jb))
                if ja == jb or key in adjacent or key in ignored:
                    continue
                self.geometry.addCollisionPair(pin.CollisionPair(i, k))
                self.pairs.append((names[ja], names[jb]))
        self._data = pin.Data(model)
        self._geometry_data = pin.GeometryData(self.geometry)

    def colliding(self, q: np.ndarray) -> list[tuple[str, str]]:
        """The pairs of bodies in contact at ``q`` (body names), in pair order."""
        pin.updateGeometryPlacements(self.mech.model, self._data, self.geometry, self._geometry_data, q)
        pin.computeCollisions(self.geometry, self._geometry_data, False)
        results = self._geometry_data.collisionResults
        return [self.pairs[k] for k in range(len(self.pairs)) if results[k].isCollision()]

    def collision_free(self, q: np.ndarray) -> np.ndarray:
        """Whether configurations (shape (..., nq)) have no colliding pair; False for NaN rows."""
        arr = np.asarray(q, dtype=float)
        flat = arr.reshape(-1, arr.shape[-1])
        out = np.array([bool(np.all(np.isfinite(x))) and not self.colliding(x) for x in flat], dtype=bool)
        return out.reshape(arr.shape[:-1])


def _shaped_ancestor(model: pin.Model, j: int, shaped: set[int]) -> int:
    """The nearest ancestor of joint ``j`` whose body carries a shape (0: the world)."""
    k = int(model.parents[j])
    while k > 0 and k not in shaped:
        k = int(model.parents[k])
    return k


@functools.lru_cache(maxsize=8)
def _checker(mech: Mechanism, ignore: tuple[tuple[str, str], ...]) -> SelfCollision:
    return SelfCollision(mech, ignore)


def self_collisions(
    mech: Mechanism, q: np.ndarray, ignore: Iterable[tuple[str, str]] = ()
) -> list[tuple[str, str]]:
    """The pairs of bodies of ``mech`` in contact at ``q`` (see :class:`SelfCollision`)."""
    return _checker(mech, tuple((a, b) for a, b in ignore)).colliding(mech.check_q(q))


def collision_free(mech: Mechanism, q: np.ndarray, ignore: Iterable[tuple[str, str]] = ()) -> np.ndarray:
    """Whether configurations (shape (..., nq)) are free of self-collision; False for NaN rows."""
    return _checker(mech, tuple((a, b) for a, b in ignore)).collision_free(q)
