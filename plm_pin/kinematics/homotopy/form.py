"""The polynomial form of a mechanism's closures as data: the arrays the compiled kernels read.

Built by :func:`plm_pin.kinematics.homotopy.polynomial.polynomial_form`, which documents the
unknowns, the equations and their degrees.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

Program = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
r"""A straight-line program of the square system (:mod:`.straight_line`): constants, complex (c,);
instructions, int32 (k, 3): registers a, b, c; coefficients (k, 2): P and S of
:math:`r_t = P\, r_a r_b + S\, r_c`; outputs, int32 (n, 1 + n + n_params): the registers of F and of
each row of :math:`[F_x\ F_p]`; angles, int32: the parameters whose cosine and sine it reads."""

EMPTY_PROGRAM: Program = (
    np.zeros(0, dtype=np.complex128),
    np.zeros((0, 3), dtype=np.int32),
    np.zeros((0, 2)),
    np.zeros((0, 0), dtype=np.int32),
    np.zeros(0, dtype=np.int32),
)
"""No program yet: a form being built, before :func:`.straight_line.straight_line` traces it (the
trackers need the traced program)."""

FIXED, REVOLUTE, PRISMATIC, SPHERICAL, FREE_FLYER, REVOLUTE_PARAM, PRISMATIC_PARAM = range(7)
"""Joint kinds: held fixed, revolute (cos, sin), prismatic, spherical and free-flyer (quaternion)
unknowns, actuated revolute and prismatic parameters."""


@dataclass(frozen=True)
class LegAim:
    """What aims an eliminated leg (a distance closure) at its other closure frame.

    Attributes:
        frame: the closure frame at the leg's end.
        target: the closure's other frame (placed by the form's unknowns).
        carrier: the joint carrying the leg's centre O.
        centre: O's placement in the carrier (homogeneous), shape (4, 4).
        joints: the concurrent joints, the carrier's child first: two revolutes or one spherical.
        axes: each joint's axis in its frame (zero for a spherical joint), shape (len(joints), 3).
        q_index: each joint's first configuration coordinate.
        nq: each joint's number of configuration coordinates.
    """

    frame: int
    target: int
    carrier: int
    centre: np.ndarray
    joints: tuple[int, ...]
    axes: np.ndarray
    q_index: tuple[int, ...]
    nq: tuple[int, ...]


@dataclass(frozen=True)
class PolynomialForm:
    """A mechanism's closures as a square polynomial system (see the module docstring).

    Attributes:
        joints: Pinocchio ids of the joints kept (on a path to a closure frame), ascending.
        parent: index in ``joints`` of each kept joint's parent, -1 for the universe, shape (k,).
        kind: joint kind codes, shape (k,).
        offset: first unknown (or parameter, for actuated joints) of each joint, shape (k,).
        axis: joint axis in its own frame (revolute, prismatic), shape (k, 3).
        placement: joint placement in its parent :math:`M_j`, homogeneous, shape (k, 4, 4).
        fixed: local transform of fixed joints :math:`X_j`, shape (k, 4, 4).
        frame_joint: index in ``joints`` of the joint carrying each closure point (-1: world), shape (f,).
        frame_placement: closure frame placement in its joint, shape (f, 4, 4).
        closure_kind: 0 point, 1 weld, 2 revolute, 3 distance (an eliminated leg), shape (nc,).
        closure_frames: indices of frames A and B per closure, and of the frame L whose distance
            to the world origin is the length of a distance closure on an actuated strut (-1
            otherwise), shape (nc, 3).
        closure_axis: revolute closure axis in B's frame, shape (nc, 3).
        closure_length2: squared length of each distance closure on a rigid strut [m^2], shape (nc,).
        entry_offset: first entry of each closure, shape (nc,).
        n_entries: total closure entries.
        combination: the matrix :math:`C`, a selection of the live entries or random,
            shape (n - n_unit, n_entries).
        n: number of unknowns.
        n_unit: number of unit equations (first in the system).
        unit_offsets: first unknown of each unit block (revolute 2, quaternion 4), shape (n_unit,).
        unit_sizes: 2 or 4 per unit block, shape (n_unit,).
        n_params: number of parameters (actuators).
        parameters: the actuators that are parameters (indices into the mechanism's actuators),
            shape (n_params,): all of them, or as many as the mobility for redundant actuation.
        checked: the other actuators, left unknowns and checked against their values afterwards:
            per actuator its index, its first unknown and 1 for a revolute (c, s) pair, 0 for a
            prismatic displacement, shape (r, 3).
        degrees: degree of each equation of the square system, shape (n,).
        eliminated_v: velocity indices of the joints of the eliminated legs (set by the polish).
        digest: hex digest of all of the above (the cache key of the generic solve).
        legs: per eliminated leg, the frames and joints that aim it again at a platform pose
            (:func:`plm_pin.kinematics.homotopy.polynomial.aim_legs`; not in the digest).
        program: the square system as a straight-line program, traced from the arrays above
            (:mod:`.straight_line`; not in the digest).
    """

    joints: np.ndarray
    parent: np.ndarray
    kind: np.ndarray
    offset: np.ndarray
    axis: np.ndarray
    placement: np.ndarray
    fixed: np.ndarray
    frame_joint: np.ndarray
    frame_placement: np.ndarray
    closure_kind: np.ndarray
    closure_frames: np.ndarray
    closure_axis: np.ndarray
    closure_length2: np.ndarray
    entry_offset: np.ndarray
    n_entries: int
    combination: np.ndarray
    n: int
    n_unit: int
    unit_offsets: np.ndarray
    unit_sizes: np.ndarray
    n_params: int
    parameters: np.ndarray
    checked: np.ndarray
    degrees: np.ndarray
    eliminated_v: np.ndarray
    digest: str
    legs: tuple[LegAim, ...] = ()
    program: Program = EMPTY_PROGRAM

    def kernel_args(self) -> tuple[np.ndarray, ...]:
        """The arrays the generic evaluation's kernels take, in their order."""
        return (
            self.parent,
            self.kind,
            self.offset,
            self.axis,
            self.placement,
            self.fixed,
            self.frame_joint,
            self.frame_placement,
            self.closure_kind,
            self.closure_frames,
            self.closure_axis,
            self.closure_length2,
            self.entry_offset,
            self.combination,
            self.unit_offsets,
            self.unit_sizes,
        )
