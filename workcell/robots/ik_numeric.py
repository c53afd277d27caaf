"""Numerical inverse kinematics (thesis §4.3): mink differential IK and the thesis's Newton-Gauss.

:func:`solve` is what :meth:`Robot.ik <workcell.robots.robot.Robot.ik>` calls. It never
returns a silently wrong q: a result has ``success=True`` only when ``robot.fk(q)`` (the
DH forward kinematics, not the solver's own model) is within ``tol_position`` (m) and
``tol_orientation`` (rad) of the target, q lies within the joint limits and, when
``config`` is given, q has that configuration (OPW and UR robots). Otherwise ``success=False`` with the
closest pose reached (q of the best attempt, always finite and within the limits), its
errors and a ``reason``.

Two methods:

- ``"mink"``: mink 1.3 differential IK on :func:`~workcell.robots.mjcf.kinematic_model`,
  one ``FrameTask`` on the ``"tool"`` site (position and orientation cost 1,
  ``lm_damping``), the daqp QP backend, a prebuilt ``ConfigurationLimit`` (exact limits),
  tiny global damping; a redundant arm (more than 6 joints) adds a posture task towards
  ``q0`` (cost 1e-2) until the pose is within 1e-3 m and rad, or until the attempt
  stalls with it, then converges without it: of the self-motion's solutions it prefers
  the one nearest ``q0`` (mink's notes: a posture cost above 1e-4 would cost precision
  if kept to the end).
  Attempts, in order: ``q0``; for OPW and UR robots the closed-form solutions nearest to
  ``q0`` (``workcell.robots.ik_closed.ik_all``), filtered by
  ``config``; then seeded random in-limit configurations. An attempt ends when converged,
  when the error stops improving over a window of iterations, or when the step vanishes.
- ``"newton-gauss"``: the thesis's solver. Seven equations in n unknowns: position (3), the
  vector invariant of the rotation error ``E = R_target R^T`` (3,
  ``vect(E) = 1/2 (e32 - e23, e13 - e31, e21 - e12) = sin(theta) k``) and its trace (1,
  ``(trace(E) - 3) / 2 = cos(theta) - 1``), solved in the least-squares sense with the
  analytic 7xn Jacobian, Levenberg-Marquardt damped. Robustness as in the thesis: start
  from the configuration whose Jacobian condition number is smallest (one per
  configuration, or a spread of well-conditioned samples for other robots), follow a
  continuation path from that start's pose to the target (linear position, SLERP
  orientation) solving each step from the previous one, then polish. Joint limits: each
  step is clipped to the limits, and joints at a limit that the step pushes outward are
  held while the others are re-solved (one active-set pass). Failed paths restart from
  the next candidate start (starts of the requested configuration, or of q0's, first).

Unreachable targets (farther than :func:`max_reach`, or with no closed-form solution) get
a reduced restart budget; the attempts are then polished to the closest tool position
(exact-Hessian projected Newton on ``1/2 |p(q) - p_target|^2``), so ``position_error``
is the distance from the target to the reachable workspace (a local minimum in
principle; the global one on every case tested). Stalled attempts (limits, branches)
that are not provably unreachable keep the attempt of least ``position + length *
orientation`` error (``length`` = half the reach bound, m/rad).

Errors: position error in m (Euclidean distance of the tool points), orientation error
in rad (angle of ``R_current^T R_target``). The caches (mink model, configuration, tasks,
limits; Newton-Gauss start candidates) are built once per robot object and reused.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from workcell.errors import GeometryError, KinematicsError
from workcell.robots.ik_common import (
    DEFAULT_MAX_ITERATIONS,
    DEFAULT_RESTARTS,
    Method,
    _check_config,
    _start,
)
from workcell.robots.ik_mink import (
    _solve_mink,
)
from workcell.robots.ik_newton import (
    _solve_newton_gauss,
)
from workcell.robots.robot import IKSolution, Robot
from workcell.spatial import as_transform

__all__ = ["solve"]

# --------------------------------------------------------------------------------- entry
_VALID_OPTIONS = ("tol_position", "tol_orientation", "max_iterations", "restarts", "seed")


def solve(
    robot: Robot,
    T: ArrayLike,
    q0: ArrayLike | None = None,
    *,
    config: str | None = None,
    method: Method = "mink",
    tol_position: float = 1e-6,
    tol_orientation: float = 1e-6,
    max_iterations: int | None = None,
    restarts: int | None = None,
    seed: int = 0,
    **unknown: object,
) -> IKSolution:
    """Numerical IK: joint values placing ``robot``'s tool at pose ``T`` (4x4, base frame, m).

    ``q0`` (rad/m): for mink the first start (default: the robot's ``"home"`` pose, else
    mid-range); for Newton-Gauss, which starts where the Jacobian is best conditioned, the
    starts in q0's configuration go first and q0 itself follows the listed starts;
    ``config`` restricts an OPW or UR solution to a configuration such as ``"lun"``; ``method``
    ``"mink"`` or ``"newton-gauss"``; tolerances in m (``tol_position``, tool-point
    distance) and rad (``tol_orientation``, angle of ``R^T R_target``);
    ``max_iterations`` per attempt (per final polish for Newton-Gauss); ``restarts`` the
    number of extra starts (random seeds for mink, after ``q0`` and the closed-form
    seeds; further candidate starts for Newton-Gauss); ``seed`` for the random starts.

    Returns an :class:`IKSolution` whose ``success`` is verified against ``robot.fk``;
    on failure ``q`` is the closest pose reached (within the limits) and ``reason`` says
    why. Raises KinematicsError for bad input (unknown option or method, bad config
    letters, a non-rigid T).
    """
    if unknown:
        raise KinematicsError(
            f"unknown IK option(s) {', '.join(sorted(unknown))}; valid: config, method, "
            + ", ".join(_VALID_OPTIONS)
        )
    if method not in ("mink", "newton-gauss"):
        raise KinematicsError(f"unknown IK method {method!r}; valid: 'mink', 'newton-gauss'")
    try:
        T_target = as_transform(T, rigid=True, name="IK target")
    except GeometryError as exc:
        raise KinematicsError(str(exc)) from exc
    if not (tol_position > 0 and tol_orientation > 0):
        raise KinematicsError(
            f"tolerances must be > 0, got tol_position={tol_position}, tol_orientation={tol_orientation}"
        )
    iters = DEFAULT_MAX_ITERATIONS[method] if max_iterations is None else int(max_iterations)
    nrest = DEFAULT_RESTARTS[method] if restarts is None else int(restarts)
    if iters < 1 or nrest < 0:
        raise KinematicsError(
            f"max_iterations must be >= 1 and restarts >= 0, got {max_iterations}, {restarts}"
        )
    cfg = _check_config(robot, config)
    rng = np.random.default_rng(seed)
    q_start = _start(robot, q0)
    if method == "mink":
        return _solve_mink(
            robot, T_target, q_start, cfg, tol_position, tol_orientation, iters, nrest, rng
        )
    return _solve_newton_gauss(
        robot,
        T_target,
        None if q0 is None else q_start,
        cfg,
        tol_position,
        tol_orientation,
        iters,
        nrest,
        rng,
    )
