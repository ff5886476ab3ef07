"""Closed-chain kinematics: closures, assembly, task, Jacobians, legs, IK, FK, singularities, paths, modes.

Generic: any mechanism with a sidecar. Family-specific modes and planners (the 2-PRRRP's) are in
:mod:`plm_pin.families`.
"""

from .assembly import Assembly, assemble
from .closures import Closure, compile_closures
from .forward import FKSolution, forward_kinematics, same_assembly, task_pose
from .inverse import IKSolution, inverse_kinematics, working_modes
from .jacobians import ClosedChainJacobians, closed_chain_jacobians
from .legs import Leg, find_legs, working_mode
from .mode_graph import ModeEdge, ModeGraph, ModeNode, compress_modes
from .paths import TrackedPath, follow_targets, redundancy_margin, track_actuator_path
from .singularity import SINGULARITY_TOL, SingularityReport, classify
from .task import Task, TaskTarget, compile_task

__all__ = [
    "SINGULARITY_TOL",
    "Assembly",
    "ClosedChainJacobians",
    "Closure",
    "FKSolution",
    "IKSolution",
    "Leg",
    "ModeEdge",
    "ModeGraph",
    "ModeNode",
    "SingularityReport",
    "Task",
    "TaskTarget",
    "TrackedPath",
    "assemble",
    "classify",
    "closed_chain_jacobians",
    "compile_closures",
    "compile_task",
    "compress_modes",
    "find_legs",
    "follow_targets",
    "forward_kinematics",
    "inverse_kinematics",
    "redundancy_margin",
    "same_assembly",
    "task_pose",
    "track_actuator_path",
    "working_mode",
    "working_modes",
]
