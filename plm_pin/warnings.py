"""Warnings of plm_pin, all subclasses of :class:`PlmWarning`."""

from __future__ import annotations

__all__ = [
    "AmbiguousRankWarning",
    "CorruptChunkWarning",
    "DescriptionWarning",
    "IgnoredElementWarning",
    "IllConditionedWarning",
    "IncompleteSearchWarning",
    "KernelFallbackWarning",
    "MissingLimitsWarning",
    "MissingMeshWarning",
    "PlmWarning",
    "ReferenceWarning",
    "RoundedClosureWarning",
    "SimulationUnstableWarning",
]


class PlmWarning(UserWarning):
    """Base class of every warning plm_pin emits."""


class MissingMeshWarning(PlmWarning):
    """A visual mesh file named in a URDF is absent; the model loads without that visual."""


class IllConditionedWarning(PlmWarning):
    """A computation is close to singular; its result may be inaccurate."""


class CorruptChunkWarning(PlmWarning):
    """A sweep checkpoint file cannot be read or is not that sweep's; its points are computed again."""


class DescriptionWarning(PlmWarning):
    """A third-party URDF holds a flaw refused in plm_pin descriptions, tolerated there (see ``strict``)."""


class IgnoredElementWarning(PlmWarning):
    """An element of a description (an MJCF joint's damping, say) has no plm_pin counterpart: ignored."""


class SimulationUnstableWarning(PlmWarning):
    """A simulation another engine runs of an exported model (MuJoCo's) diverges."""


class MissingLimitsWarning(PlmWarning):
    """URDF joints carry no position limits (read as [0, 0]); they are treated as unlimited."""


class ReferenceWarning(PlmWarning):
    """A description gives no reference: the loader chose one (said where), or it lies near a singularity."""


class RoundedClosureWarning(PlmWarning):
    """The loops close only to a least-squares residual: the description's coordinates look rounded."""


class AmbiguousRankWarning(PlmWarning):
    """The singular values of the closure Jacobian have no clear-cut gap: the mobility is in doubt."""


class IncompleteSearchWarning(PlmWarning):
    """A search for every solution (every assembly mode) cannot prove it found them all."""


class KernelFallbackWarning(PlmWarning):
    """The compiled kernels cannot serve a mechanism (a joint type, no numba): the Pinocchio path runs."""
