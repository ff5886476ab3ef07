"""The Mechanism: a Pinocchio spanning tree, its closures, actuation and task, and what they are made of.

Everything else works on a :class:`Mechanism`: :mod:`plm_pin.kinematics`, :mod:`plm_pin.statics`,
:mod:`plm_pin.dynamics`, :mod:`plm_pin.workspace`, :mod:`plm_pin.stiffness`. The modules here
depend on the description (:mod:`plm_pin.description`) and Pinocchio only: closures (residual
and Jacobian rows), task (the end-effector coordinates), legs (the blocks of the
inverse-kinematics Jacobian), idle gauges, assembly (the closure solver), scratch workspaces
and the rank decisions.
"""

from .assembly import Assembly
from .closures import Closure
from .idle import IdleGauge
from .legs import Leg
from .mechanism import Actuator
from .task import Task

__all__ = [
    "Actuator",
    "Assembly",
    "Closure",
    "IdleGauge",
    "Leg",
    "Task",
]
"""The parts. The Mechanism itself is public as :class:`plm_pin.Mechanism`; task targets in
:mod:`plm_pin.kinematics`."""
