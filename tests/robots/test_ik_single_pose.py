"""The single-pose closed-form path (``ik_report``, Python floats) against the batched path
(``ik_batch``, numpy) on every library OPW robot, at random poses and at the poses where
the two are most likely to part: aligned and nearly aligned wrists, a stretched or folded
elbow, the wrist centre on the l/r boundary, joints exactly at their limits.

What must agree exactly, away from singular poses: which configurations exist, which are
within the limits, the order. The joint values agree to 1e-12 rad plus what the pose's
conditioning makes of rounding: the two paths compute the angles apart (libm's trigonometry here, numpy's
vectorised one there, ~1 ulp apart), and q4, q6 move by ~1e-16 / |sin theta5| near an
aligned wrist; at a singular pose (flagged) q itself is ill-conditioned, so there both
answers are held to the target by the robot's own FK instead. The reported errors are
the robot's own FK errors of the returned q (``Robot.fk``, an independent numpy chain).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workcell.robots import get, ik_closed, library
from workcell.robots.ik_closed import CONFIGS, ik_batch, ik_report

OPW = [n for n in library() if get(n, geometry=False).ik_family == "opw"]
TWO_PI = 2 * np.pi


def wrapped(a):
    """Angle differences wrapped to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % TWO_PI - np.pi


def fk_errors(robot, q, T):
    """Position (m) and orientation (rad, 2 asin(|dR|_F / sqrt(8))) errors of Robot.fk(q)."""
    D = robot.fk(q) - T
    return np.linalg.norm(D[:3, 3]), 2 * math.asin(min(1.0, np.linalg.norm(D[:3, :3]) / 8**0.5))


@st.composite
def hard_targets(draw, robot):
    """A reachable tool pose of ``robot``, often at a singularity or a joint limit."""
    S = ik_closed._solver(robot)
    signs, offs, (_, gamma) = np.array(S.signs), np.array(S.offs), S.model.forearm
    lo, hi = robot.lower, robot.upper
    q = np.array(
        [draw(st.sampled_from([lo[j], hi[j]]) | st.floats(lo[j], hi[j])) for j in range(6)]
    )
    theta = signs * q - offs  # the OPW angles of q (module doc of opw)
    kind = draw(st.sampled_from(["random", "wrist", "elbow", "shoulder"]))
    if kind == "wrist":  # theta5 = 0 or pi: axes 4 and 6 aligned, or nearly
        theta[4] = draw(st.sampled_from([0.0, np.pi])) + draw(
            st.sampled_from([0.0, 1e-13, -1e-13, 1e-9, -1e-7, 3e-6])
        )
    elif kind == "elbow":  # stretched (theta3 = -gamma) or folded
        theta[2] = draw(st.sampled_from([-gamma, np.pi - gamma])) + draw(
            st.sampled_from([0.0, 1e-10, -1e-8])
        )
    q = signs * (theta + offs)
    T = robot.fk(q)
    if kind == "shoulder":  # the wrist centre onto the l/r boundary (|C_xy| = |b|)
        M = S.pre @ T if S.pre is not None else T.copy()
        M = M @ S.post if S.post is not None else M
        r = math.hypot(M[0, 3], M[1, 3])
        b = abs(S.model.b)
        M[:2, 3] *= b / r if r > 0 else 0.0
        T = np.linalg.inv(S.pre) @ M if S.pre is not None else M
        T = T @ np.linalg.inv(S.post) if S.post is not None else T
        T[3] = (0.0, 0.0, 0.0, 1.0)
    near = draw(st.sampled_from(["none", "limits", "turns"]))
    q_current = None
    if near == "limits":
        q_current = np.array([draw(st.floats(lo[j], hi[j])) for j in range(6)])
    elif near == "turns":  # far outside the limits: every joint needs its own turn count
        turns = draw(st.lists(st.integers(-3, 3), min_size=6, max_size=6))
        q_current = q + TWO_PI * np.array(turns) + 0.3
    return T, q_current


@pytest.mark.parametrize("name", OPW)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_single_pose_path_matches_the_batch_path_at_hard_poses(name, data):
    robot = get(name, geometry=False)
    S = ik_closed._solver(robot)
    T, q_current = data.draw(hard_targets(robot))
    sols, reason = ik_report(robot, T, q_current)
    Q, valid = ik_batch(robot, T, q_current)
    present = {c for c, row in zip(CONFIGS, Q[0], strict=True) if not np.isnan(row).any()}
    singular = any(s.singular for s in sols)
    if singular:
        # the solution sets may differ here, where the two paths' rounding falls on either
        # side of a threshold: an aligned wrist (|sin theta5| < 1e-12: one solution, or the
        # twins) or a stretched elbow (acos turns 1e-16 of rounding into ~1e-7 rad: the u
        # and d branches merged, or kept 1e-7 apart); every answer must reach the target
        for c in present:
            assert max(fk_errors(robot, Q[0, CONFIGS.index(c)], T)) < 1e-9
    else:
        assert sorted(s.config for s in sols) == sorted(present)
    for s in sols:
        dp, dr = fk_errors(robot, s.q, T)
        assert abs(s.position_error - dp) < 1e-12
        assert abs(s.orientation_error - dr) < 1e-12
        if singular:  # q is ill-conditioned here: the answers reach the target (above)
            assert s.success == s.within_limits
            continue
        k = CONFIGS.index(s.config)
        sin5 = abs(math.sin(S.signs[4] * s.q[4] - S.offs[4]))  # |sin theta5|
        tol = np.full(6, 1e-12)
        tol[[3, 5]] += 1e-14 / sin5
        assert (np.abs(wrapped(s.q - Q[0, k])) <= tol).all()
        # a value on a limit: the two paths' values, tol apart, may fall on either side
        on_limit = np.zeros(6, dtype=bool)
        for v in (s.q, Q[0, k]):
            for edge in (robot.lower, robot.upper):
                on_limit |= np.abs(wrapped(v - edge)) <= tol + 1e-12
        if not on_limit.any():
            assert s.within_limits == valid[0, k]
        # within the limits both pick the same representative (ties at +-pi, or half a
        # turn from q_current, may round either way; so may a value on a limit)
        toward = Q[0, k] if q_current is None else wrapped(Q[0, k] - q_current)
        tie = (np.abs(np.abs(toward) - np.pi) < 1e-9) | on_limit
        if s.within_limits and valid[0, k]:
            assert (np.abs(s.q - Q[0, k])[~tie] <= tol[~tie]).all()
    if q_current is None:
        keys = [(not s.within_limits, CONFIGS.index(s.config)) for s in sols]
    else:
        keys = [(not s.within_limits, np.abs(s.q - q_current).max()) for s in sols]
    assert keys == sorted(keys)
    assert (reason == "") == any(s.within_limits for s in sols)
