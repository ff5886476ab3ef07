r"""Every tolerance of plm_pin: one name, one value, one unit and the decision it takes.

A tolerance, a threshold or a margin is a decision, so each one lives here and nowhere else
(``tests/test_tolerances.py`` refuses a tolerance constant defined in another module, and a
literal default of a ``tol`` / ``rtol`` / ``atol`` / ``eps`` argument). Each docstring starts
with the unit in brackets (``[-]`` for a ratio) and says what the value decides. The guide page
``docs/guide/tolerances.md`` lists them, checked against this module by a test.

A description carries its own closure tolerance (:data:`CLOSURE_TOL` by default; the sidecar's
``closure_tolerance``, ``plm_pin.load(..., closure_tol=)`` or ``--closure-tol`` for a CAD export
whose coordinates were rounded): :attr:`plm_pin.Mechanism.closure_tol` is the value assembly,
kinematics, simulation and the checks then use; the constants below that depend on it say so.

This module imports nothing from plm_pin.
"""

__all__ = [
    "ACTUATED_SINGULAR_RTOL",
    "ASSEMBLED_TOL",
    "ASSEMBLY_RCOND",
    "ATTACHMENT_ATOL",
    "AXIS_MIN",
    "BATCH_LOG3_SERIES_ANGLE",
    "BEAM_AXIS_MIN",
    "BEAM_MIN_LENGTH",
    "BRANCH_TOL",
    "CLOSURE_TOL",
    "COMPARISON_RTOL",
    "COMPLIANCE_SYMMETRY_RTOL",
    "CONCURRENT_AXES_TOL",
    "CONSTRAINT_NULL_RTOL",
    "CROSSING_MARGIN",
    "CROSSING_WATCH_RTOL",
    "DEAD_RTOL",
    "DECOUPLING_RTOL",
    "DEFLECTION_CLOSURE_TOL",
    "DEFLECTION_RTOL",
    "DE_TOL",
    "ENERGY_ROUND_OFF_RTOL",
    "ENERGY_RTOL",
    "EQUAL_RODS_TOL",
    "EQUILIBRIUM_RTOL",
    "FACTOR_RCOND",
    "FEASIBILITY_RTOL",
    "FEASIBLE_VELOCITY_RTOL",
    "FK_SAME_MODE_TOL",
    "FOLD_PAIR_TOL",
    "GAUGE_MIN_PIVOT",
    "GAUGE_TIE_RTOL",
    "GRAM_RTOL",
    "HOMOTOPY_CORRECTOR_TOL",
    "HOMOTOPY_DIVERGED_NORM",
    "HOMOTOPY_ENDGAME_MIN_STEP",
    "HOMOTOPY_ENTRY_TOL",
    "HOMOTOPY_INFINITY_RTOL",
    "HOMOTOPY_MAX_BOX_RTOL",
    "HOMOTOPY_MIN_STEP",
    "HOMOTOPY_PREDICTOR_RTOL",
    "HOMOTOPY_REAL_RTOL",
    "HOMOTOPY_ROOT_RTOL",
    "HOMOTOPY_SAME_ROOT_RTOL",
    "HOMOTOPY_SINGULAR_COND",
    "HOMOTOPY_ZERO_ENTRY_RTOL",
    "IDLE_RTOL",
    "ILL_CONDITIONED_MARGIN",
    "INERTIA_RTOL",
    "INSPECT_EDGE_TOL",
    "INTERNAL_TIE_RTOL",
    "INVERSE_RTOL",
    "KNOT_TOL",
    "LAYOUT_TOL",
    "LEG_SINGULAR_RTOL",
    "LIMIT_TOL",
    "LINK_FORCE_RTOL",
    "LOCUS_REFINE_MARGIN",
    "LOCUS_XTOL",
    "LOG3_SERIES_ANGLE",
    "LOOSE_END_RTOL",
    "LOST_ROW_DRIFT_RTOL",
    "MASSLESS_INERTIA_RTOL",
    "MASSLESS_RTOL",
    "MAX_EFFORT",
    "MIN_PRINCIPAL_MOMENT",
    "MODE_CHANGE_DEVIATION_TOL",
    "MODE_CHANGE_RESIDUAL_TOL",
    "MODE_CHANGE_TOL",
    "NOISE",
    "PAIR_DISCRIMINANT_RTOL",
    "PAIR_TOL",
    "PATTERN_ATOL",
    "PATTERN_RTOL",
    "PLANE_NORMAL_TOL",
    "PRRRP_MODE_TOL",
    "QP_EPS",
    "QP_INFEASIBILITY_EPS",
    "RANGE_XTOL",
    "RANK_CEILING_RTOL",
    "RANK_GAP_MIN",
    "RANK_RTOL",
    "RATE_CONSISTENCY_TOL",
    "REFERENCE_MARGIN",
    "REFERENCE_SHIFT_ANGLE",
    "REFERENCE_SHIFT_RTOL",
    "RIGHT_ANGLE_TOL",
    "ROUNDED_DATA_HEADROOM",
    "ROUNDED_DATA_RTOL",
    "ROUND_OFF",
    "SAME_ASSEMBLY_TOL",
    "SAMPLE_COUNT_RTOL",
    "SHEET_GRADIENT_RTOL",
    "SIMULATION_ATOL",
    "SIMULATION_RTOL",
    "SINGULARITY_TOL",
    "STAR_SINGULAR_SIN",
    "STATICS_SINGULAR_RTOL",
    "STEP_DRIFT_TOL",
    "TASK_COMPLIANCE_RTOL",
    "TASK_UNRESISTED_RTOL",
    "TIP_TOL",
    "TRACK_TOL",
    "UNIT_VECTOR_TOL",
    "UNRESISTED_RTOL",
    "VIEW_MIN_LENGTH",
    "VIEW_OPEN_TOL",
    "ZHAO_WORK_TOL",
]

# ----------------------------------------------------------------- closures and assembly
CLOSURE_TOL = 1e-12
"""[m, rad] Default closure tolerance of a description (:attr:`Mechanism.closure_tol`): the largest
closure residual the assembly, the inverse and forward kinematics, the path tracking floor and the
simulation's projection accept. Exact descriptions close to round-off; 1e-12 is reached from any
guess in a few Newton steps."""

ASSEMBLED_TOL = 1e-8
"""[m, rad] Largest closure residual of a configuration an analysis accepts as assembled (raised to
the mechanism's closure tolerance when that is larger). Every configuration plm_pin computes closes
the loops to the closure tolerance; 1e-8 leaves room for configurations read back from files while
refusing ones whose loops are visibly open (``q_ref + 0.05`` opens them by centimetres)."""

ROUND_OFF = 1e-15
"""[m, rad] Closure residual below which the assembly takes no polishing step (round-off reached)."""

ASSEMBLY_RCOND = 1e-10
"""[-] Singular values of the closure Jacobian below this fraction of the largest take no part in a
Levenberg-Marquardt assembly step (the redundant rows of planar closures)."""

ROUNDED_DATA_RTOL = 1e-4
"""[-] Least-squares closure residual [m, rad], relative to the size of the model (the largest frame
distance from the origin, at least 1 m), up to which loops that do not close to the closure tolerance
are taken for rounded coordinates and loaded with a warning; above it the loops are open and the load
is refused. A CAD export written to 6-8 significant digits closes to 1e-8...1e-5 m (an angle near
pi/2 written to 6 digits is off by up to 5e-6 rad)."""

ROUNDED_DATA_HEADROOM = 10.0
"""[-] Factor between the least-squares residual of a rounded description and the closure tolerance
it is loaded with (then rounded up to a power of ten): other configurations close a little worse."""

SAME_ASSEMBLY_TOL = 1e-7
"""[m] Largest distance between the frame origins of two configurations of one assembly."""

BRANCH_TOL = 1e-11
"""[m, rad] Residual up to which a combination of leg branches is an inverse-kinematics solution when
every working mode is enumerated (or the tolerance asked, when larger)."""

# ----------------------------------------------------------------- rank and idle mobilities
RANK_RTOL = 1e-9
"""[-] Fixed relative tolerance of the rank decisions made at arbitrary configurations (constraint
dynamics, trajectories, mode graphs): singular values at most ``RANK_RTOL * max(s_max, 1)`` are zero.
The closure rank (mobility) is decided at the largest gap instead (:data:`RANK_CEILING_RTOL`)."""

RANK_CEILING_RTOL = 1e-4
"""[-] Closure rank by the largest gap: singular values above this fraction of ``max(s_max, 1)`` are
independent rows, whatever their gap. Between it and the floor ``closure_tol * max(s_max, 1)`` (the
description's closure tolerance) the rank is cut where consecutive singular values have their
largest ratio; below the floor they are zero (see :mod:`plm_pin.core.rank`)."""

RANK_GAP_MIN = 1e3
"""[-] Smallest ratio of the two singular values around the closure rank's cut for the decision to be
clear-cut; below it :class:`plm_pin.warnings.AmbiguousRankWarning` is warned."""

IDLE_RTOL = 1e-8
"""[-] Singular values of the observed rows on the feasible motions (:mod:`plm_pin.core.idle`) at most
this (or the closure tolerance, when larger) times the largest (or 1) are idle motions."""

GAUGE_MIN_PIVOT = 1e-3
"""[-] Smallest share of an idle motion a held joint must carry for it to fix that motion."""

GAUGE_TIE_RTOL = 1e-9
"""[-] Relative difference below which two joints' shares of the idle motions count as equal."""

PATTERN_RTOL = 1e-9
"""[-] Entries of the inverse-kinematics Jacobian below this times the largest entry of their row are
structural zeros when the legs are found."""

PATTERN_ATOL = 1e-12
"""[-] Entries of the leg rows at most this (absolute, unit axes and lever arms [m]) are structural zeros."""

LEG_SINGULAR_RTOL = 1e-9
"""[-] A leg block is singular when its determinant is at most this times Hadamard's bound."""

# ----------------------------------------------------------------- reference, diagnostics, transmission
REFERENCE_MARGIN = 0.05
"""[-] A reference whose smallest singularity margin (constraint, inverse, direct; normalised
singular values, see :class:`~plm_pin.kinematics.SingularityReport`) is below this is flagged
as close to that singularity."""

REFERENCE_SHIFT_ANGLE = 0.1
"""[rad] A revolute joint that the assembly moved farther than this from the sidecar's reference
value flags a reference far from its author's (a mistyped length, a wrong guess)."""

REFERENCE_SHIFT_RTOL = 0.05
"""[-] Likewise for a prismatic joint, as a fraction of the mechanism's size (the largest
distance between two joint origins at the reference)."""

DEAD_RTOL = 1e-12
"""[-] The actuators cannot drive the task (a dead centre) when the smallest singular value of
:math:`C` is at most this fraction of its largest."""

LOOSE_END_RTOL = 0.02
"""[-] A leaf body's frame within this fraction of the mechanism's size (the largest distance
between two joint origins at the reference) of another body's frame is a loose end: a
closure between them may be missing."""

# ----------------------------------------------------------------- descriptions
INERTIA_RTOL = 1e-9
"""[-] Tolerance of the inertia checks (moments >= 0, triangle inequalities), relative to the largest
moment."""

AXIS_MIN = 1e-9
"""[-] Smallest norm of a joint axis or closure axis read from a description (a shorter one is refused)."""

COMPLIANCE_SYMMETRY_RTOL = 1e-9
"""[-] Largest asymmetry of a compliance matrix, relative to its largest entry."""

MIN_PRINCIPAL_MOMENT = 1e-13
"""[kg m^2] Smallest principal moment of inertia written to an MJCF export (MuJoCo refuses zero)."""

LOG3_SERIES_ANGLE = 1e-6
"""[rad] Rotation angle below which a closure's log3 Jacobian uses its Taylor series."""

BATCH_LOG3_SERIES_ANGLE = 1e-4
"""[rad] Rotation angle below which the batched log3 and its Jacobian use their Taylor series
(error < 1e-17)."""

# ----------------------------------------------------------------- kinematics and singularities
SINGULARITY_TOL = 1e-6
"""[-] Default margin at or below which a configuration counts as singular."""

INSPECT_EDGE_TOL = 1e-6
"""[-] Fraction of a move within which the live inspector finds the edge it stops at (workspace, singular)."""

INVERSE_RTOL = 1e-12
r"""[-] :math:`T` is singular (S, J_ce undefined) when :math:`\sigma_{min}(T) \le` INVERSE_RTOL x
:math:`|J_x|`.

Relative to the whole task Jacobian (:math:`|J_x| = \sigma_{max}(J_x)`), not to :math:`T` itself,
whose ratio is 1 for any 1 x 1 :math:`T` (see :mod:`plm_pin.kinematics.singularity`)."""

ACTUATED_SINGULAR_RTOL = 1e-8
r"""[-] The actuators fix the configuration (the accuracy sensitivity exists) unless the smallest
singular value of :math:`[J_\phi; S_a]` is at most this times its largest (a direct, type 2, singularity)."""

LIMIT_TOL = 1e-9
"""[m or rad] A joint within this distance of its range respects it."""

TRACK_TOL = 1e-11
"""[m, rad] Closure tolerance of the path continuations (raised to the mechanism's closure tolerance)."""

LOCUS_XTOL = 1e-12
"""[unit of t] Default tolerance on the path parameter of a located singularity."""

LOCUS_REFINE_MARGIN = 1e-2
"""[-] Default margin below which a local minimum is refined (redundant mechanisms)."""

RANGE_XTOL = 1e-9
"""[rad] Default tolerance on the located ends of an orientation range."""

GRAM_RTOL = 1e-4
r"""[-] Smallest ratio :math:`\lambda_{min} / \lambda_{max}` of a Gram matrix read for singular values.

A backward-stable symmetric eigensolver perturbs each eigenvalue of :math:`G = M^T M` by about
:math:`\epsilon \lambda_{max}`, so a singular value :math:`\sigma_i = \sqrt{\lambda_i}` has a
relative error of about :math:`\epsilon / (2 \lambda_i / \lambda_{max})`: 1e-12 at this ratio.
Below it the batch takes the SVD of :math:`M` itself."""

FACTOR_RCOND = 1e-8
"""[-] Reciprocal condition number below which a batched LU factorisation is taken as singular."""

PAIR_TOL = 1e-12
"""[m] Default distance deciding touching and coincident circles in the PRRRP pair's closed-form direct
kinematics (Harada 2015, eq. (4))."""

PAIR_DISCRIMINANT_RTOL = 1e-15
"""[-] A PRRRP leg reaches its pair when the discriminant :math:`l^2 - L_y^2` is above minus this times
:math:`l^2` (round-off of a pair exactly at the rod's reach)."""

LAYOUT_TOL = 1e-9
"""[m or -] Largest deviation of a 2-PRRRP's sliders from one stator line and plane, of the stator from
the world x axis and of the plate centre from the pairs' midpoint, for the family's closed forms to apply."""

EQUAL_RODS_TOL = 1e-12
"""[m] Two PRRRP rods this close in length are equal (their pair has coincident circles)."""

FOLD_PAIR_TOL = 1e-9
"""[m] Distance deciding touching and coincident circles at a PRRRP complex-singularity fold."""

RIGHT_ANGLE_TOL = 1e-15
"""[rad] A rod angle this close to pi/2 is the perpendicular one (its working-mode sign is 0)."""

KNOT_TOL = 1e-9
"""[unit of the path parameter] Path parameters this close to a mode change's zero crossing are dropped."""

PRRRP_MODE_TOL = 1e-9
"""[m or -] Pair heights [m] and rod cosines :math:`|z_i^T a|` [-] at or below which a PRRRP mode
sign is 0."""

MODE_CHANGE_TOL = 1e-3
"""[-] Direct and constraint margin the mode-change planners require at every sample.

A thousandth of the largest singular value: far above round-off, so that the rank of :math:`C`
(Harada 2015: rank :math:`J_x = 3`) is not in doubt anywhere on the path."""

MODE_CHANGE_RESIDUAL_TOL = 1e-10
"""[m, rad] Largest closure residual along a tracked mode change for the planners to call it clean."""

MODE_CHANGE_DEVIATION_TOL = 1e-7
"""[m, rad] Largest deviation of a tracked mode change from its planned route for the planners."""

STAR_SINGULAR_SIN = 1e-9
"""[-] The absolute sine of phi below which the star-triangle's star lines are parallel to their rails
(actuator singularity)."""

UNIT_VECTOR_TOL = 1e-12
"""[-] Largest deviation from 1 of the norm of an n-PSS guide direction."""

# ----------------------------------------------------------------- statics and allocation
STATICS_SINGULAR_RTOL = 1e-8
r"""[-] A direction counts as unresisted when its singular value is below this times the largest.

Applies to :math:`C` (the actuators do not hold a feasible motion: direct singularity) and to
:math:`J_\phi` (the closures do not hold a motion they should: constraint singularity)."""

EQUILIBRIUM_RTOL = 1e-9
"""[-] Equilibrium residual allowed, relative to the largest generalized force in the balance."""

INTERNAL_TIE_RTOL = 1e-9
"""[-] Actuator shares of the internal forces equal to this relative tolerance count as a tie
(see :func:`plm_pin.statics.balance.oriented_internal_basis`): the first actuator in order is taken."""

ATTACHMENT_ATOL = 1e-9
"""[m] Attachment points closer than this are the same point."""

FEASIBILITY_RTOL = 1e-9
"""[-] A limit or condition is met when exceeded by at most this times the force scale."""

QP_EPS = 1e-11
"""[N or N m] Absolute accuracy asked of ProxSuite's allocation QP (``eps_abs``)."""

QP_INFEASIBILITY_EPS = 1e-12
"""[-] ProxSuite's primal and dual infeasibility thresholds of the allocation QP."""

LINK_FORCE_RTOL = 1e-9
"""[-] Internal forces load the named links independently when the smallest singular value of their
link-force matrix is above this times the largest."""

# ----------------------------------------------------------------- dynamics
MAX_EFFORT = 1e12
"""[N or N m] Largest force or torque a simulation accepts: a thousand times the largest presses'
(about 1e9 N); far beyond it a step's accelerations and energies overflow or lose every digit."""

CROSSING_MARGIN = 1e-3
"""[-] A crossing predicted within this fraction of a bridge step is taken to be at its start (left as is)."""

LOST_ROW_DRIFT_RTOL = 1e-6
"""[-] Largest drift in a lost closure row at a constraint singularity, relative to the drift's norm.

Decides whether the acceleration constraint stays consistent (finite closure forces) where
the closure Jacobian loses a rank; above it the motion is not defined there.
"""

SHEET_GRADIENT_RTOL = 1e-6
"""[-] Smallest gradient of the lost row's second-order form Q(v), relative to its scale.

Decides at a constraint singularity whether the velocity lies on one sheet of the closure
manifold (a regular point of the tangent cone Q = 0: the motion continues on it) or where
sheets meet (Q's gradient vanishes, as at rest: the continuation is not determined).
"""

CROSSING_WATCH_RTOL = 0.1
"""[-] Closure singular values below this fraction of the largest are watched for a crossing."""

SIMULATION_RTOL = 1e-10
"""[-] Default relative error per step of the adaptive (DOP853) simulation."""

SIMULATION_ATOL = 1e-12
"""[m, rad, m/s, rad/s] Default absolute error per step of the adaptive (DOP853) simulation."""

STEP_DRIFT_TOL = 1e-6
"""[m, rad] Largest closure distance one fixed simulation step may open before its projection;
larger: halve it."""

ENERGY_RTOL = 1e-3
"""[-] Energy change allowed in a passive run, relative to the largest kinetic energy reached."""

ENERGY_ROUND_OFF_RTOL = 1e-12
"""[-] Round-off allowance of the energy check of a passive run, relative to max(1 J, the initial energy)."""

SAMPLE_COUNT_RTOL = 1e-9
"""[-] A duration within this many steps of a whole number of output steps has that number of steps."""

FEASIBLE_VELOCITY_RTOL = 1e-9
r"""[-] Largest :math:`|J_\phi v|` of a velocity accepted as feasible, relative to :math:`\max(1, |v|)`
(an initial velocity of a simulation, the velocity of task-space dynamics)."""

ILL_CONDITIONED_MARGIN = 1e-3
"""[-] Inverse margin (:func:`plm_pin.kinematics.classify`) below which task-space dynamics warns.

:math:`S = N T^{-1}` grows as the inverse of that margin and :math:`M_x` as its square, so below
1e-3 the task inertia is amplified more than a million times over the joint-space one."""

RATE_CONSISTENCY_TOL = 1e-6
"""[m/s or rad/s] Default tolerance on the disagreement of redundant actuator rates of a trajectory."""

DECOUPLING_RTOL = 1e-9
"""[-] Default cancellation ratio below which an entry counts as zero or constant."""

ZHAO_WORK_TOL = 1e-3
"""[J] Zhao 2011's convergence tolerance e of eq. (34) (adaptive trapezoid of the work)."""

# ----------------------------------------------------------------- stiffness
TIP_TOL = 1e-9
"""[m] A child joint or frame belongs to a beam's tip when its origin is this close to the tip."""

MASSLESS_RTOL = 1e-12
r"""[-] Vibration modes whose :math:`1/\omega^2` is below this fraction of the largest are massless
(left out)."""

MASSLESS_INERTIA_RTOL = 1e-12
"""[-] A compliant beam segment whose mass is below this times its largest dynamic parameter is massless."""

BEAM_MIN_LENGTH = 1e-6
"""[m] Shortest beam of a compliance description."""

BEAM_AXIS_MIN = 1e-6
"""[-] Smallest component of a beam's y_axis normal to the beam (a y_axis along the beam is refused)."""

DEFLECTION_CLOSURE_TOL = 1e-13
"""[m, rad] Largest closure and lock residual of a converged deflection (or the mechanism's closure
tolerance, when larger)."""

TASK_UNRESISTED_RTOL = 1e-8
"""[-] A stiffness mode no spring resists moves the task when its task motion is above this times
:math:`|T|`."""

TASK_COMPLIANCE_RTOL = 1e-12
"""[-] The task compliance is singular when its smallest singular value is at most this times the largest."""

DEFLECTION_RTOL = 1e-10
"""[-] Largest residual of a deflection Newton step accepted, relative to the largest generalized force."""

CONSTRAINT_NULL_RTOL = 1e-10
"""[-] Singular values of the stiffness constraint rows below this fraction of the largest count as zero."""

UNRESISTED_RTOL = 1e-9
"""[-] Eigenvalues of the projected stiffness below this fraction of the largest are motions no
spring resists."""

# ----------------------------------------------------------------- display
COMPARISON_RTOL = 1e-3
"""[-] Default relative difference up to which a study's number agrees with the paper's in a report."""

PLANE_NORMAL_TOL = 1e-9
"""[-] Largest ratio of a second rotation axis, and of a frame velocity along the normal, to the largest,
for a mechanism to count as planar in the viewer."""

VIEW_OPEN_TOL = 1e-6
"""[m, rad] Closure residual above which the viewer's markers show a closure open."""

VIEW_MIN_LENGTH = 1e-9
"""[m] Link segments shorter than this are not drawn in the viewer."""

NOISE = 1e-9
"""[-] Variation, relative to the quantity's scale, below which a panel is round-off and not drawn.

Far above double-precision round-off (1e-16) and the integrators' and solvers' tolerances (1e-10
relative and tighter in the studies), far below anything a figure could show (a pixel is 1e-3 of
a panel's height)."""


# ----------------------------------------------------------------- complete forward kinematics
HOMOTOPY_REAL_RTOL = 1e-7
"""[-] Relative imaginary part under which a homotopy root counts as real."""

HOMOTOPY_ROOT_RTOL = 1e-8
"""[-] Relative residual of the square system under which a path end is a root."""

HOMOTOPY_ENTRY_TOL = 1e-9
"""[m, -] Largest closure entry of a real root of the square system that solves the full system."""

HOMOTOPY_ZERO_ENTRY_RTOL = 1e-9
"""[-] Relative size below which a closure entry counts as identically zero at random complex points."""

CONCURRENT_AXES_TOL = 1e-9
"""[m] Distance under which joint axes count as meeting at one point (a leg reduces to a distance)."""

HOMOTOPY_SAME_ROOT_RTOL = 1e-6
"""[-] Relative distance under which two generic solutions are the same root."""

HOMOTOPY_SINGULAR_COND = 1e10
"""[-] 1-norm condition number of the square system's Jacobian above which a path end counts as singular."""

HOMOTOPY_DIVERGED_NORM = 1e8
"""[-] Norm of the unknowns above which a homotopy path goes to infinity."""

HOMOTOPY_INFINITY_RTOL = 1e-6
"""[-] Homogenising coordinate, relative to the projective point, at or below which a path is at infinity.

An affine norm above 1e6: no real assembly of a mechanism whose lengths are metres or less is
that far, and a singular root at infinity stops the tracker before a tighter bound is met."""

HOMOTOPY_CORRECTOR_TOL = 1e-9
"""[-] Relative Newton correction at which a homotopy corrector step is accepted."""

HOMOTOPY_MIN_STEP = 1e-9
"""[-] Smallest step in the path parameter t before a homotopy path is declared failed."""

HOMOTOPY_PREDICTOR_RTOL = 1e-3
"""[-] Predictor error (first correction, relative to 1 + the path's norm) a homotopy step is sized for."""

HOMOTOPY_ENDGAME_MIN_STEP = 1e-2
"""[-] Smallest step past t = 0.99, as a fraction of 1 - t, before a projective homotopy path is given up."""

HOMOTOPY_MAX_BOX_RTOL = 1e-6
"""[-] Largest relative half-width of a Krawczyk box (a root certified farther out is not certified)."""

FK_SAME_MODE_TOL = 1e-7
"""[m, rad] Largest task-coordinate difference of two forward-kinematics solutions of one assembly mode."""

DE_TOL = 0.01
"""[-] Relative spread of a differential-evolution population's scores at which the search stops
(SciPy's ``tol``: std <= DE_TOL * abs(mean))."""
