"""Closed-chain kinematics: closure residuals and Jacobians, loop assembly."""

from .assembly import Assembly, assemble
from .closures import Closure, compile_closures

__all__ = ["Assembly", "Closure", "assemble", "compile_closures"]
