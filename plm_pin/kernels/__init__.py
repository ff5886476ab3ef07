"""Compiled kinematics kernels: forward kinematics, closure and task rows and Newton steps in numba.

The same mathematics as :mod:`plm_pin.core.closures`, :mod:`plm_pin.core.task` and
:func:`plm_pin.core.assembly.newton`, read from the Pinocchio model once
(:func:`kernel_of`) and compiled on first use (cached on disk), without a Python call per
joint, frame or iteration. Pinocchio stays the model source and the oracle: the kernels
handle revolute (principal, unaligned and unbounded), prismatic, spherical, free-flyer,
planar and universal joints; for any other joint, without numba, or with
``PLM_PIN_KERNELS=0``, :func:`kernel_of` returns None and the callers take the Pinocchio
path. Importing this package does not import numba.
"""

from .arrays import KernelArrays, unsupported_joints
from .model import SWITCH, Kernel, kernel_of, kernels_enabled

__all__ = ["SWITCH", "Kernel", "KernelArrays", "kernel_of", "kernels_enabled", "unsupported_joints"]
