"""Closed-chain kinematics: closures, assembly, task, Jacobians, legs, IK, FK, singularities."""

from .assembly import Assembly, assemble
from .closures import Closure, compile_closures
from .forward import FKSolution, forward_kinematics, same_assembly, task_pose
from .inverse import IKSolution, inverse_kinematics, working_modes
from .jacobians import ClosedChainJacobians, closed_chain_jacobians
from .legs import Leg, find_legs, working_mode
from .singularity import SingularityReport, classify
from .task import Task, TaskTarget, compile_task

__all__ = [
    "Assembly",
    "ClosedChainJacobians",
    "Closure",
    "FKSolution",
    "IKSolution",
    "Leg",
    "SingularityReport",
    "Task",
    "TaskTarget",
    "assemble",
    "classify",
    "closed_chain_jacobians",
    "compile_closures",
    "compile_task",
    "find_legs",
    "forward_kinematics",
    "inverse_kinematics",
    "same_assembly",
    "task_pose",
    "working_mode",
    "working_modes",
]
