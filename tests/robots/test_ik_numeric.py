"""Tests of the numerical IK (workcell.robots.ik_numeric): mink and the thesis's Newton-Gauss.

Expected numbers come from outside the solver: targets are ``robot.fk`` of seeded random
joint vectors, errors are re-measured with ``spatial.pose_error`` (scipy rotations),
closest distances of unreachable targets come from the published DH lengths, the
configuration letters and the in-limit solution sets from the closed-form solver
(``ik_closed``), Jacobians from central finite differences of ``robot.fk``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from workcell import spatial
from workcell.errors import KinematicsError, UnreachableError
from workcell.robots import (
    Joint,
    Robot,
    ik_closed,
    ik_common,
    ik_mink,
    ik_newton,
    ik_numeric,
    puma260,
    puma560,
)
from workcell.robots.chain import joints_from_table

TOL_P, TOL_O = 1e-6, 1e-6


# ----------------------------------------------------------------------------- robots
def ur5_modified() -> Robot:
    """A UR5 (non-spherical wrist) in modified DH, a generic 6R robot with no closed form.

    Rows (alpha_{i-1} deg, a_{i-1} m, d_i m) converted from the UR5's published standard
    DH (d1 0.089159, a2 -0.425, a3 -0.39225, d4 0.10915, d5 0.09465, d6 0.0823,
    alpha 90, 0, 0, 90, -90, 0); joint limits +-360 deg as on the real arm.
    """
    rows = [
        (0, 0, 0.089159),
        (90, 0, 0),
        (0, -0.425, 0),
        (0, -0.39225, 0.10915),
        (90, 0, 0.09465),
        (-90, 0, 0.0823),
    ]
    joints = tuple(
        Joint.from_dh(
            f"j{i + 1}",
            a=a,
            alpha=math.radians(al),
            d=d,
            convention="modified",
            limits=(-2 * math.pi, 2 * math.pi),
        )
        for i, (al, a, d) in enumerate(rows)
    )
    return Robot("ur5_modified", joints)


def ur5_standard() -> Robot:
    rows = [  # d, a, alpha
        (0.089159, 0, 90),
        (0, -0.425, 0),
        (0, -0.39225, 0),
        (0.10915, 0, 90),
        (0.09465, 0, -90),
        (0.0823, 0, 0),
    ]
    joints = tuple(
        Joint.from_dh(
            f"j{i + 1}", a=a, alpha=math.radians(al), d=d, limits=(-2 * math.pi, 2 * math.pi)
        )
        for i, (d, a, al) in enumerate(rows)
    )
    return Robot("ur5_standard", joints)


def puma_placed() -> Robot:
    """A Puma 560 hung upside down at an offset, with a tilted 12 cm tool."""
    return puma560(geometry=False).with_(
        name="puma_placed",
        base=spatial.translation(0.5, -0.2, 1.8) @ spatial.rot_x(math.pi),
        tool=spatial.translation(0, 0.02, 0.12) @ spatial.rot_y(0.3),
    )


ROBOTS = {
    "puma560": lambda: puma560(geometry=False),
    "puma260": lambda: puma260(geometry=False),
    "ur5_modified": ur5_modified,
    "puma_placed": puma_placed,
}
_MADE: dict[str, Robot] = {}


def robot_named(name: str) -> Robot:
    if name not in _MADE:  # one object per name, so the solver caches are shared
        _MADE[name] = ROBOTS[name]()
    return _MADE[name]


def random_targets(robot: Robot, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    Q = np.random.default_rng(seed).uniform(robot.lower, robot.upper, size=(n, robot.dof))
    return Q, robot.fk_batch(Q)


def assert_solution(robot: Robot, sol, T) -> None:
    assert sol.success, sol.reason
    assert sol.reason == ""
    assert np.all(np.isfinite(sol.q))
    assert np.all(sol.q >= robot.lower)
    assert np.all(sol.q <= robot.upper)
    dp, do = spatial.pose_error(robot.fk(sol.q), T)
    assert dp <= TOL_P
    assert do <= TOL_O
    assert sol.position_error == pytest.approx(dp, abs=1e-12)
    assert sol.orientation_error == pytest.approx(do, abs=1e-9)


# --------------------------------------------------------------------- building blocks
def test_ur5_modified_matches_published_standard_dh():
    a, b = ur5_modified(), ur5_standard()
    for q in np.random.default_rng(3).uniform(-6, 6, (50, 6)):
        np.testing.assert_allclose(a.fk(q), b.fk(q), atol=1e-14)


@given(
    axis=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 1e-3),
    angle=st.one_of(st.floats(0, math.pi), st.floats(0, 1e-7)),
)
@settings(max_examples=60, deadline=None)
def test_orientation_error_is_the_rotation_angle(axis, angle):
    k = np.array(axis) / np.linalg.norm(axis)
    R0 = Rotation.from_rotvec([0.3, -1.1, 2.0]).as_matrix()
    R1 = R0 @ Rotation.from_rotvec(angle * k).as_matrix()
    assert spatial.angle_between(R0, R1) == pytest.approx(angle, rel=1e-9, abs=3e-16)


def test_max_reach_bounds_every_tool_point():
    for name in ROBOTS:
        r = robot_named(name)
        _, T = random_targets(r, 500, 4)
        origin = r.base[:3, 3]
        assert np.linalg.norm(T[:, :3, 3] - origin, axis=1).max() <= ik_common.max_reach(r)


def test_newton_gauss_equations_and_jacobian():
    """vect(E) = sin(t) k and (trace E - 3)/2 = cos(t) - 1 for a known error; the analytic
    7xn Jacobian agrees with central finite differences of the equations built from fk."""
    for name in ("puma260", "ur5_modified", "puma_placed"):
        r = robot_named(name)
        rng = np.random.default_rng(5)
        q = rng.uniform(r.lower, r.upper)
        k = np.array([2.0, -1.0, 0.5]) / np.linalg.norm([2.0, -1.0, 0.5])
        t = 0.7
        T = r.fk(q)
        T_target = T.copy()
        T_target[:3, :3] = Rotation.from_rotvec(t * k).as_matrix() @ T[:3, :3]
        T_target[:3, 3] += [0.1, -0.2, 0.05]
        f, Jf, Tq = ik_newton.ng_residual_jacobian(r, q, T_target, length=0.5)
        np.testing.assert_allclose(Tq, T, atol=1e-14)
        np.testing.assert_allclose(f[:3], -np.array([0.1, -0.2, 0.05]) / 0.5, atol=1e-14)
        np.testing.assert_allclose(f[3:6], math.sin(t) * k, atol=1e-14)
        assert f[6] == pytest.approx(math.cos(t) - 1.0, abs=1e-14)

        def eqs(qq, r=r, T_target=T_target):
            Tf = r.fk(qq)
            E = T_target[:3, :3] @ Tf[:3, :3].T
            v = 0.5 * np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])
            p = (Tf[:3, 3] - T_target[:3, 3]) / 0.5
            return np.concatenate([p, v, [(np.trace(E) - 3) / 2]])

        h = 1e-6
        fd = np.column_stack([(eqs(q + h * e) - eqs(q - h * e)) / (2 * h) for e in np.eye(r.dof)])
        np.testing.assert_allclose(Jf, fd, atol=1e-8)


def test_position_gradient_and_hessian_match_finite_differences():
    """The closest-position objective's analytic gradient and exact Hessian (revolute and
    prismatic joints, both conventions) against central differences of robot.fk."""
    rows = (
        dict(name="a", a=0.1, alpha=0.3, d=0.2),
        dict(name="b", kind="prismatic", a=0.2, alpha=-1.0, theta=0.3, limits=(0.0, 1.0)),
        dict(name="c", a=0.3, alpha=1.2, d=0.1),
        dict(name="d", kind="prismatic", a=0.1, alpha=0.5, limits=(0.0, 1.0)),
        dict(name="e", a=0.2, alpha=0.7, d=0.1),
    )
    robots = [
        robot_named("puma260"),
        robot_named("puma_placed"),
        Robot("mixed_std", [Joint.from_dh(**r) for r in rows]),
        Robot("mixed_mod", [Joint.from_dh(**r, convention="modified") for r in rows]),
    ]
    P = np.array([1.0, -0.5, 0.3])

    def g(r, q):
        e = r.fk(q)[:3, 3] - P
        return 0.5 * e @ e

    h = 1e-5
    for r in robots:
        for q in np.random.default_rng(7).uniform(r.lower, r.upper, (5, r.dof)):
            f, grad, H = ik_common.position_gradient_hessian(r, q, P)
            assert f == pytest.approx(g(r, q), rel=1e-14)
            E = np.eye(r.dof) * h
            fd_grad = np.array([(g(r, q + e) - g(r, q - e)) / (2 * h) for e in E])
            np.testing.assert_allclose(grad, fd_grad, atol=1e-9)
            fd_hess = np.array(
                [
                    [
                        (g(r, q + a + b) - g(r, q + a - b) - g(r, q - a + b) + g(r, q - a - b))
                        / (4 * h * h)
                        for b in E
                    ]
                    for a in E
                ]
            )
            np.testing.assert_allclose(H, fd_hess, atol=2e-5)


# ------------------------------------------------------------------------------ mink
@pytest.mark.parametrize("name", list(ROBOTS))
def test_mink_reaches_random_full_range_targets(name):
    r = robot_named(name)
    _, Ts = random_targets(r, 30, 11)
    for T in Ts:
        sol = ik_numeric.solve(r, T)
        assert_solution(r, sol, T)
        assert sol.method == "mink"
        if r.ik_family is not None:
            assert sol.config == ik_closed.config_of(r, sol.q)


@given(q=st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
@settings(max_examples=25, deadline=None)
def test_mink_from_nearby_q0_returns_the_nearby_solution(q):
    """Started 0.02 rad from a well-conditioned solution, the solver converges to it."""
    r = robot_named("puma260")
    centre = np.radians([0, 30, -130, 20, 60, 10])
    q_true = np.clip(centre + np.array(q), r.lower + 0.05, r.upper - 0.05)
    assume(np.linalg.cond(r.jacobian(q_true)) < 100)
    T = r.fk(q_true)
    sol = r.ik(T, q_true + 0.02)
    assert_solution(r, sol, T)
    np.testing.assert_allclose(sol.q, q_true, atol=1e-4)


def test_mink_wrist_singular_target():
    r = robot_named("puma560")
    q_true = np.radians([20, 40, -150, 30, 0, 10])  # q5 = 0: wrist axes 4 and 6 aligned
    T = r.fk(q_true)
    sol = r.ik(T)
    assert_solution(r, sol, T)
    assert sol.singular


@pytest.mark.parametrize("name", ["puma560", "puma260", "puma_placed"])
def test_config_selects_that_closed_form_solution(name):
    r = robot_named(name)
    _, Ts = random_targets(r, 8, 12)
    for T in Ts:
        by_config = {s.config: s for s in ik_closed.ik_all(r, T) if s.within_limits}
        for config in ik_closed.CONFIGS:
            sol = r.ik(T, config=config)
            if config in by_config:
                assert_solution(r, sol, T)
                assert sol.config == config
                diff = (sol.q - by_config[config].q + math.pi) % (2 * math.pi) - math.pi
                assert np.abs(diff).max() < 1e-5  # the same solution, modulo 2 pi
            else:
                assert not sol.success
                assert f"configuration '{config}'" in sol.reason


def test_config_without_closed_form_seeds(monkeypatch):
    """Without the closed form (mink alone, seeded in the configuration) a configuration is
    found exactly when the closed form has an in-limit solution in it, and it is that one."""
    r = robot_named("puma560")
    _, Ts = random_targets(r, 10, 13)
    monkeypatch.setattr(ik_mink, "_closed_form_seeds", lambda *a: None)
    for T in Ts:
        valid = {s.config: s for s in ik_closed.ik_all(r, T) if s.within_limits}
        for config in ("run", "ldf"):
            sol = r.ik(T, config=config)
            assert sol.success == (config in valid), sol.reason
            if sol.success:
                assert_solution(r, sol, T)
                diff = (sol.q - valid[config].q + math.pi) % (2 * math.pi) - math.pi
                assert np.abs(diff).max() < 1e-5
            else:
                assert sol.reason


def test_config_is_refused_without_a_family_and_bad_letters():
    # a Puma 560 whose wrist axes 4 and 5 miss each other by 5 cm: neither OPW nor UR
    rows = [(0, 0.67183, 90, 0), (0.4318, 0, 0, 0), (0.0203, 0.15005, -90, 0)]
    rows += [(0.05, 0.4318, 90, 0), (0, 0, -90, 0), (0, 0, 0, 0)]
    bent = Robot("bent", joints_from_table(rows, [(-170, 170)] * 6))
    assert bent.ik_family is None
    with pytest.raises(KinematicsError, match="closed-form family"):
        bent.ik(np.eye(4), config="lun")
    with pytest.raises(KinematicsError, match="three letters"):
        robot_named("puma560").ik(np.eye(4), config="lux")


def test_target_reachable_only_outside_the_limits_fails():
    """A pose whose every closed-form solution violates a limit: never a silent wrong q."""
    r = robot_named("puma560")
    rng = np.random.default_rng(14)
    cases = []
    for _ in range(500):  # 8 draws give 3 cases with this seed
        T = r.fk(rng.uniform(-math.pi, math.pi, 6))
        sols = ik_closed.ik_all(r, T)
        if sols and not any(s.within_limits for s in sols):
            cases.append(T)
        if len(cases) == 3:
            break
    assert len(cases) == 3
    for T in cases:
        for method in ("mink", "newton-gauss"):
            sol = r.ik(T, method=method)
            assert not sol.success
            assert sol.reason
            assert np.all(sol.q >= r.lower)
            assert np.all(sol.q <= r.upper)
            dp, do = spatial.pose_error(r.fk(sol.q), T)
            assert sol.position_error == pytest.approx(dp, abs=1e-12)
            assert dp > TOL_P or do > TOL_O


# ------------------------------------------------------------------------ unreachable
# Published DH lengths (m): (d1, a2, a3, d3, d4, tool offset along z6)
_PUMA_DH = {
    "puma560": (0.67183, 0.4318, 0.0203, 0.15005, 0.4318, 0.0),
    "puma260": (0.3302, 0.0254 * math.hypot(7.8, 0.75), 0.0, 0.12446, 0.2032, 0.05588),
}


@pytest.mark.parametrize("method", ["mink", "newton-gauss"])
@pytest.mark.parametrize("name", ["puma560", "puma260"])
def test_unreachable_target_two_metres_out(name, method):
    """2 m beyond the reach: success False with a reason, a finite in-limit q, and a position
    error equal to the true closest distance. The tool point of a Puma lies within
    R = sqrt(d3^2 + (a2 + sqrt(a3^2 + d4^2))^2) + tool of the shoulder (0, 0, d1), and a
    target straight out from the shoulder along a reachable horizontal direction is
    therefore exactly |target - shoulder| - R away."""
    r = robot_named(name)
    d1, a2, a3, d3, d4, tool = _PUMA_DH[name]
    shoulder = np.array([0.0, 0.0, d1])
    reach = math.hypot(d3, a2 + math.hypot(a3, d4)) + tool
    for direction in ([1.0, 0.0, 0.0], [0.0, -1.0, 0.0]):
        T = spatial.translation(*(shoulder + (reach + 2.0) * np.array(direction)))
        sol = r.ik(T, method=method)
        assert not sol.success
        assert sol.method == method
        assert sol.reason.startswith("unreachable")
        assert np.all(np.isfinite(sol.q))
        assert np.all(sol.q >= r.lower)
        assert np.all(sol.q <= r.upper)
        assert sol.position_error >= 2.0 - 1e-9  # no pose is closer
        assert sol.position_error == pytest.approx(2.0, abs=1e-4)
        # bounded work: a few attempts, not the full restart budget
        assert sol.iterations <= 4 * ik_common.DEFAULT_MAX_ITERATIONS[method] * 3
        with pytest.raises(UnreachableError, match="unreachable"):
            r.ik_or_raise(T, method=method)


def test_unreachable_generic_robot_reports_the_gap():
    r = robot_named("ur5_modified")
    T = spatial.translation(3.0, 0.0, 0.0)
    sol = r.ik(T)
    assert not sol.success
    assert "beyond the robot's reach" in sol.reason
    assert sol.position_error >= 3.0 - ik_common.max_reach(r)
    assert np.all(sol.q >= r.lower)
    assert np.all(sol.q <= r.upper)


# ----------------------------------------------------------------------- newton-gauss
@pytest.mark.parametrize("name", ["puma560", "puma260", "ur5_modified", "puma_placed"])
def test_newton_gauss_success_rate(name):
    """Measured on these 50 full-range targets: 50/50 for each robot (>= 95 % required)."""
    r = robot_named(name)
    _, Ts = random_targets(r, 50, 21)
    ok = 0
    for T in Ts:
        sol = r.ik(T, method="newton-gauss")
        assert sol.method == "newton-gauss"
        assert np.all(sol.q >= r.lower)
        assert np.all(sol.q <= r.upper)
        if sol.success:
            ok += 1
            assert_solution(r, sol, T)
        else:
            assert sol.reason
    assert ok >= 48


def test_newton_gauss_config():
    r = robot_named("puma260")
    _, Ts = random_targets(r, 5, 22)
    for T in Ts:
        valid = {s.config for s in ik_closed.ik_all(r, T) if s.within_limits}
        for config in sorted(valid)[:2]:
            sol = r.ik(T, method="newton-gauss", config=config)
            if sol.success:
                assert_solution(r, sol, T)
                assert sol.config == config


def test_newton_gauss_starts_at_small_condition_numbers():
    """Every start's condition number is at most that of the robot's named poses whose
    configuration it shares ... and below the median of random configurations."""
    r = robot_named("puma560")
    ctx = ik_newton.newton_gauss_context(r)
    conds = [c for _, c, _ in ctx.starts]
    assert conds == sorted(conds)
    assert len({cfg for _, _, cfg in ctx.starts}) == 8  # a start on every branch
    rng = np.random.default_rng(0)

    def cond(q):
        J = r.jacobian(q)
        J[:3] /= ctx.length
        s = np.linalg.svd(J, compute_uv=False)
        return s[0] / s[-1]

    for q, c, _ in ctx.starts:
        assert c == pytest.approx(cond(q), rel=1e-9)
    random_median = np.median([cond(q) for q in rng.uniform(r.lower, r.upper, (200, 6))])
    assert conds[0] < random_median


# ------------------------------------------------------------------ caching and input
def test_mink_context_is_built_once_per_robot(monkeypatch):
    r = puma560(geometry=False)
    T = r.fk(r.pose("qn"))
    r.ik(T)
    ctx = ik_mink.mink_context(r)
    parts = (ctx.model, ctx.configuration, ctx.task, ctx.limits, ctx.limits[0])
    calls = []
    monkeypatch.setattr(ik_mink, "kinematic_model", lambda robot: calls.append(robot))
    r.ik(T)
    r.ik(T, method="newton-gauss")
    again = ik_mink.mink_context(r)
    assert again is ctx
    assert all(
        a is b
        for a, b in zip(
            parts,
            (again.model, again.configuration, again.task, again.limits, again.limits[0]),
            strict=True,
        )
    )
    assert calls == []
    assert ik_newton.newton_gauss_context(r) is ik_newton.newton_gauss_context(r)
    other = r.with_(name="other", base=spatial.translation(1, 0, 0))
    monkeypatch.undo()
    assert ik_mink.mink_context(other) is not ctx


def test_bad_input_is_refused():
    r = robot_named("puma560")
    with pytest.raises(KinematicsError, match="unknown IK method"):
        r.ik(np.eye(4), method="ccd")
    with pytest.raises(KinematicsError, match="unknown IK option"):
        r.ik(np.eye(4), tolerance=1e-3)
    with pytest.raises(KinematicsError, match="not rigid"):
        r.ik(np.diag([2.0, 1, 1, 1]))
    with pytest.raises(KinematicsError, match="q0"):
        r.ik(np.eye(4), [0.0, 1.0])
    with pytest.raises(KinematicsError, match="tolerances"):
        r.ik(np.eye(4), tol_position=0)


def test_q0_outside_limits_is_brought_inside():
    r = robot_named("puma560")
    T = r.fk(r.pose("qn"))
    q0 = r.pose("qn") + np.array([0, 0, 0, 0, 0, 4 * math.pi])  # q6 beyond +-266 deg
    sol = r.ik(T, q0)
    assert_solution(r, sol, T)
