"""Closed-chain kinematics of a Mechanism: IK, FK, Jacobians, accuracy, modes, singularities, limits, paths.

Generic: any mechanism with a sidecar; the Mechanism and what it is made of (closures, task,
legs, assembly) are in :mod:`plm_pin.core`. Family-specific modes and planners (the 2-PRRRP's) are in
:mod:`plm_pin.families`.
"""

from ..core.task import TaskTarget
from .accuracy import ErrorBound, ErrorModel, Sensitivity, error_bound, error_model, sensitivity
from .forward import FKSolution, forward_kinematics, same_assembly, task_pose
from .inverse import IKSolution, inverse_kinematics, working_modes
from .jacobians import ClosedChainJacobians, closed_chain_jacobians
from .mode_graph import ModeEdge, ModeGraph, ModeNode
from .paths import TrackedPath, follow_targets, redundancy_margin, track_actuator_path
from .reference import ReferenceReport, choose_reference, reference_report
from .singularity import SingularityReport, classify
from .working_mode import guess_mode, working_mode

__all__ = [
    "ClosedChainJacobians",
    "ErrorBound",
    "ErrorModel",
    "FKSolution",
    "IKSolution",
    "ModeEdge",
    "ModeGraph",
    "ModeNode",
    "ReferenceReport",
    "Sensitivity",
    "SingularityReport",
    "TaskTarget",
    "TrackedPath",
    "choose_reference",
    "classify",
    "closed_chain_jacobians",
    "error_bound",
    "error_model",
    "follow_targets",
    "forward_kinematics",
    "guess_mode",
    "inverse_kinematics",
    "redundancy_margin",
    "reference_report",
    "same_assembly",
    "sensitivity",
    "task_pose",
    "track_actuator_path",
    "working_mode",
    "working_modes",
]
