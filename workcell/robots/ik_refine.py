"""Refinement of joint vectors onto a pose, on the robot's own chain, many at once.

A robot file rounds its numbers (the ROS Puma 560 writes pi/2 as 1.570796325), so the
closed-form family found in it (:mod:`workcell.robots.axes`) is the nearest exact
geometry, a few nanometres and nanoradians from the real chain. Its solutions are then
polished here, in three stages, each for what the one before could not refine:

1. Newton steps ``J dq = e`` on the robot's chain, all vectors at once (``e`` the
   position error (m) and the rotation vector of ``R_target R^T`` (rad), ``J`` the
   geometric Jacobian, solved in the least-squares sense), at most
   ``REFINE_ITERATIONS``, each vector moving at most ``REFINE_MAX_MOTION``: one or two
   steps refine a solution away from singularities;
2. near a singular arm (folded or stretched elbow, wrist point near axis 1) the rounding
   moves a solution farther and plain Newton overshoots: Levenberg-Marquardt steps
   (adaptive damping, a step kept only when it lowers ``|e|``), at most
   ``LM_ITERATIONS``, moving at most ``LM_MAX_MOTION``;
3. at a singular wrist the exact geometry's solutions form a family (any q4 with the
   matching q6) while the rounded chain's are isolated points of it: a vector marked
   ``free`` is searched for along that family (the direction the Jacobian cannot see,
   a full turn), then refined by stage 2 from the best points found.

A vector that none refines to within ``REFINE_TOL`` m and rad (the nearest exact
geometry differs too much there) is reported as failed: callers drop it, never return
it. Errors are measured as :mod:`workcell.robots.ik_closed` measures them: the distance
of the tool points (m) and ``2 asin(|R - R_target|_F / sqrt(8))`` (rad).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from workcell.robots.robot import Robot

__all__ = [
    "LM_MAX_MOTION",
    "REFINE_ITERATIONS",
    "REFINE_MAX_MOTION",
    "REFINE_TOL",
    "pose_jacobians",
    "refine",
]

Array = NDArray[np.float64]
REFINE_TOL = 1e-10
"""m and rad: a refined solution is this close to its target pose."""
REFINE_ITERATIONS = 6
"""Newton steps at most (from the nanometres of a rounded file, 1 or 2 are needed)."""
REFINE_MAX_MOTION = 1e-3
"""rad (m for prismatic joints), per joint, for the Newton stage."""
LM_ITERATIONS = 60
"""Levenberg-Marquardt steps at most (stages 2 and 3)."""
LM_MAX_MOTION = 2e-2
"""rad (m), per joint: a solution that must move farther than this is not the rounded
file's solution but another geometry's; it fails."""
FAMILY_SAMPLES = 72  # points on a singular solution's family (5 deg apart)
FAMILY_TRIES = 4  # refined from the best of them
FAMILY_STEP = 0.2  # rad: how far a family point may move (> 2.5 deg)


def pose_jacobians(robot: Robot, Q: Array) -> tuple[Array, Array]:
    """Tool poses (m, 4, 4) and geometric Jacobians (m, 6, n) at joint vectors Q (m, n).

    The batched form of :meth:`Robot.pose_jacobian <workcell.robots.robot.Robot.pose_jacobian>`
    (rows: linear velocity (m/s) then angular velocity (rad/s) per unit joint speed, base
    frame).
    """
    m, n = Q.shape
    A = robot._joint_matrices(Q)  # (m, n, 4, 4)
    F = np.empty((m, n + 1, 4, 4))
    F[:, 0] = robot.base
    for i in range(n):
        F[:, i + 1] = F[:, i] @ A[:, i]
    T = F[:, -1] @ robot.tool
    R = F[:, 1:, :3, :3]
    z = np.einsum("mnij,nj->mni", R, robot._axes)  # axis directions (m, n, 3)
    p = np.einsum("mnij,nj->mni", R, robot._points) + F[:, 1:, :3, 3]
    r = T[:, None, :3, 3] - p  # joint axis points to the tool point
    J = np.empty((m, 6, n))
    J[:, 0] = z[..., 1] * r[..., 2] - z[..., 2] * r[..., 1]  # z x r, written out (faster
    J[:, 1] = z[..., 2] * r[..., 0] - z[..., 0] * r[..., 2]  # than np.cross on small arrays)
    J[:, 2] = z[..., 0] * r[..., 1] - z[..., 1] * r[..., 0]
    J[:, 3:] = z.transpose(0, 2, 1)
    if robot._any_prismatic:
        pr = robot._prismatic
        J[:, :3, pr] = z[:, pr].transpose(0, 2, 1)
        J[:, 3:, pr] = 0.0
    return T, J


def _errors(T: Array, G: Array) -> tuple[Array, Array, Array]:
    """Position errors (m,), orientation errors (m,) and the Newton right-hand sides (m, 6)."""
    dp = G[:, :3, 3] - T[:, :3, 3]
    D = G[:, :3, :3] - T[:, :3, :3]
    f = np.sqrt(np.einsum("mij,mij->m", D, D) / 8.0)
    eo = 2.0 * np.arcsin(np.minimum(f, 1.0))
    E = G[:, :3, :3] @ T[:, :3, :3].transpose(0, 2, 1)  # R_target R^T
    w = 0.5 * np.stack(
        [E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], -1
    )
    s = np.linalg.norm(w, axis=1)  # sin of the rotation angle; the angle is small here
    scale = np.where(s > 1e-12, np.arcsin(np.minimum(s, 1.0)) / np.maximum(s, 1e-300), 1.0)
    e = np.concatenate([dp, w * scale[:, None]], axis=1)
    return np.linalg.norm(dp, axis=1), eo, e


def _newton(robot: Robot, Q: Array, G: Array) -> tuple[Array, Array, Array, NDArray[np.bool_]]:
    """Stage 1 on every row of Q (m, n) towards G (m, 4, 4); see the module doc."""
    Q = np.array(Q, dtype=np.float64, copy=True)
    m = len(Q)
    start = Q.copy()
    done = np.zeros(m, dtype=bool)
    ep = np.full(m, np.inf)
    eo = np.full(m, np.inf)
    active = np.arange(m)
    for it in range(REFINE_ITERATIONS + 1):
        T, J = pose_jacobians(robot, Q[active])
        p, o, e = _errors(T, G[active])
        ep[active], eo[active] = p, o
        hit = (p <= REFINE_TOL) & (o <= REFINE_TOL)
        done[active[hit]] = True
        keep = ~hit
        if it == REFINE_ITERATIONS or not keep.any():
            break
        active, J, e = active[keep], J[keep], e[keep]
        dq = np.einsum("mij,mj->mi", np.linalg.pinv(J, rcond=1e-12), e)
        Q[active] += dq
        far = np.abs(Q[active] - start[active]).max(axis=1) > REFINE_MAX_MOTION
        active = active[~far]
        if not len(active):
            break
    return Q, ep, eo, done


def _lm(robot: Robot, q: Array, G: Array, cap: float) -> tuple[Array, float, float, bool]:
    """Stage 2 for one vector q (n,) towards G (4, 4): (q, ep m, eo rad, converged)."""
    q0 = q = np.array(q, dtype=np.float64, copy=True)
    T, J = robot.pose_jacobian(q)
    p, o, e = _errors(T[None], G[None])
    ep, eo, e = float(p[0]), float(o[0]), e[0]
    lam = 1e-12
    eye = np.eye(robot.dof)
    for _ in range(LM_ITERATIONS):
        if ep <= REFINE_TOL and eo <= REFINE_TOL:
            return q, ep, eo, True
        H, g = J.T @ J, J.T @ e
        scale = max(float(np.trace(H)) / robot.dof, 1e-300)
        q_new = q + np.linalg.solve(H + lam * scale * eye, g)
        if np.abs(q_new - q0).max() > cap:
            lam *= 10.0
            if lam > 1e6:
                break
            continue
        T_n, J_n = robot.pose_jacobian(q_new)
        p, o, e_n = _errors(T_n[None], G[None])
        if float(e_n[0] @ e_n[0]) < float(e @ e):
            q, J, e, ep, eo = q_new, J_n, e_n[0], float(p[0]), float(o[0])
            lam = max(lam / 10.0, 1e-15)
        else:
            lam *= 10.0
            if lam > 1e6:
                break
    return q, ep, eo, ep <= REFINE_TOL and eo <= REFINE_TOL


def _along_family(robot: Robot, q: Array, G: Array) -> tuple[Array, float, float, bool]:
    """Stage 3 for one singular solution q (n,) towards G (4, 4): (q, ep, eo, converged).

    The family's direction is the Jacobian's weakest right singular vector at q (scaled
    so its largest joint moves 1 rad per unit). ``FAMILY_SAMPLES`` points of it, half a
    turn either way, are scored by the part of their pose error that the other five
    directions cannot correct (its component along the weakest left singular vector: the
    solution is where it vanishes); stage 2 (cap ``FAMILY_STEP``) runs from the best
    ``FAMILY_TRIES`` of them in order; the first that converges is it.
    """
    _, J = pose_jacobians(robot, q[None])
    d = np.linalg.svd(J[0])[2][-1]
    d /= np.abs(d).max()
    t = np.linspace(-np.pi, np.pi, FAMILY_SAMPLES, endpoint=False)
    Qs = q + t[:, None] * d
    T, Js = pose_jacobians(robot, Qs)
    _, _, e = _errors(T, np.broadcast_to(G, T.shape))
    weak = np.linalg.svd(Js)[0][:, :, -1]  # (samples, 6)
    found = (q, np.inf, np.inf, False)
    for k in np.argsort(np.abs(np.einsum("ki,ki->k", weak, e)))[:FAMILY_TRIES]:
        found = _lm(robot, Qs[k], G, FAMILY_STEP)
        if found[3]:
            break
    return found


def refine(
    robot: Robot, Q: Array, targets: Array, free: NDArray[np.bool_] | None = None
) -> tuple[Array, Array, Array, NDArray[np.bool_]]:
    """Refine joint vectors Q (m, n) onto poses ``targets`` ((4, 4) or (m, 4, 4), the
    frame of ``robot.fk``) on the robot's own chain (module doc); ``free`` (m,) marks the
    singular ones, which may move along their family when the other stages fail.

    Returns (refined Q (m, n), position errors (m,) m, orientation errors (m,) rad,
    converged (m,)): converged rows are within ``REFINE_TOL`` of their pose; the others
    must not be used.
    """
    m = len(Q)
    G = np.broadcast_to(targets, (m, 4, 4))
    Qr, ep, eo, done = _newton(robot, Q, G)
    free = np.zeros(m, dtype=bool) if free is None else np.asarray(free, dtype=bool)
    for i in np.flatnonzero(~done):
        q = np.asarray(Q[i], dtype=np.float64)
        Qr[i], ep[i], eo[i], done[i] = _lm(robot, q, G[i], LM_MAX_MOTION)
        if not done[i] and free[i]:
            Qr[i], ep[i], eo[i], done[i] = _along_family(robot, q, G[i])
    return Qr, ep, eo, done
