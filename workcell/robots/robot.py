"""Serial robots identified by Denavit-Hartenberg parameters (thesis §4.2).

A :class:`Robot` is an ordered list of :class:`Joint` rows plus a base and a tool
transform. Standard DH (the default) places frame i from frame i-1 by
``Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``; modified DH (Craig) by
``Rx(alpha_i) Tx(a_i) Rz(theta_i) Tz(d_i)``, with a row's ``a``, ``alpha`` being the
a_{i-1}, alpha_{i-1} of the textbook. A revolute joint varies theta = q + offset, a
prismatic joint varies d = q + offset. Units: metres, radians, seconds.

Forward kinematics ``fk(q) = base @ A_1(q_1) ... A_n(q_n) @ tool``: the tool pose in the
robot's base frame (``base`` is the identity unless set).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.errors import JointLimitError, KinematicsError, UnreachableError
from workcell.spatial import as_transform

if TYPE_CHECKING:
    from workcell.modeller.model import Model
    from workcell.robots.gripper import Gripper

__all__ = ["IKSolution", "Joint", "LinkGeometry", "Robot"]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class Joint:
    """One DH row and its joint: ``kind`` revolute (q in rad) or prismatic (q in m).

    ``limits`` (lo, hi) and ``max_speed`` (rad/s or m/s) bound the joint variable q;
    ``offset`` is added to q (theta = q + offset, or d = q + offset for prismatic joints).
    """

    name: str
    a: float = 0.0
    alpha: float = 0.0
    d: float = 0.0
    theta: float = 0.0
    offset: float = 0.0
    kind: Literal["revolute", "prismatic"] = "revolute"
    limits: tuple[float, float] = (-np.pi, np.pi)
    max_speed: float = float("inf")

    def __post_init__(self) -> None:
        if self.kind not in ("revolute", "prismatic"):
            raise KinematicsError(
                f"joint '{self.name}': kind must be revolute or prismatic, got {self.kind!r}"
            )
        lo, hi = self.limits
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise KinematicsError(
                f"joint '{self.name}': limits must be finite with lo < hi, got {self.limits}"
            )
        if not self.max_speed > 0:
            raise KinematicsError(
                f"joint '{self.name}': max_speed must be > 0, got {self.max_speed}"
            )


@dataclass(frozen=True)
class LinkGeometry:
    """A modeller block drawn on link ``link`` (0 = base, i = after joint i), placed by ``transform``."""

    link: int
    block: str
    transform: Array
    colour: tuple[float, ...] | None = None


@dataclass(frozen=True)
class IKSolution:
    """One inverse-kinematics answer.

    ``q`` (n,) joint values; ``success`` when the pose is reached within tolerance and the
    limits; ``config`` the Puma configuration letters (arm l|r, elbow u|d, wrist n|f) when
    known; ``within_limits``; ``singular`` at a wrist singularity (q5 ~ 0); errors in m and
    rad; ``iterations`` used; ``reason`` says why it failed (empty on success).
    """

    q: Array
    success: bool
    config: str | None = None
    within_limits: bool = True
    singular: bool = False
    position_error: float = 0.0
    orientation_error: float = 0.0
    iterations: int = 0
    reason: str = ""
    method: str = ""


@dataclass(eq=False)
class Robot:
    """A serial manipulator: DH joints, base and tool transforms, named poses, link geometry.

    ``nominal_speed`` (rad/s) is the thesis's robot speed: the speed of the joint that
    moves most in a joint-space motion. ``family`` names a closed-form IK solver
    (``"puma"``) when the geometry admits one. ``model`` holds the link solids named by
    ``geometry``; ``source`` cites where the parameters come from.
    """

    name: str
    joints: tuple[Joint, ...]
    base: Array = field(default_factory=lambda: np.eye(4))
    tool: Array = field(default_factory=lambda: np.eye(4))
    convention: Literal["standard", "modified"] = "standard"
    poses: Mapping[str, Array] = field(default_factory=dict)
    nominal_speed: float = 0.3
    family: str | None = None
    model: Model | None = None
    geometry: tuple[LinkGeometry, ...] = ()
    source: str = ""
    gripper: Gripper | None = None

    def __post_init__(self) -> None:
        self.joints = tuple(self.joints)
        if not self.joints:
            raise KinematicsError(f"robot '{self.name}' has no joints")
        if self.convention not in ("standard", "modified"):
            raise KinematicsError(f"robot '{self.name}': convention must be standard or modified")
        names = [j.name for j in self.joints]
        if len(set(names)) != len(names):
            raise KinematicsError(f"robot '{self.name}': joint names repeat: {names}")
        self.base = as_transform(self.base, rigid=True, name=f"{self.name} base")
        self.tool = as_transform(self.tool, rigid=True, name=f"{self.name} tool")
        self.poses = {k: self._vector(v, f"pose '{k}'") for k, v in dict(self.poses).items()}
        if not self.nominal_speed > 0:
            raise KinematicsError(f"robot '{self.name}': nominal_speed must be > 0 rad/s")
        p = np.array(
            [[j.a, j.alpha, j.d, j.theta, j.offset] for j in self.joints], dtype=np.float64
        )
        self._a, self._alpha, self._d, self._theta, self._offset = p.T
        self._prismatic = np.array([j.kind == "prismatic" for j in self.joints])
        self._lo = np.array([j.limits[0] for j in self.joints])
        self._hi = np.array([j.limits[1] for j in self.joints])
        self._ca, self._sa = np.cos(self._alpha), np.sin(self._alpha)

    # ---------------------------------------------------------------- basics
    @property
    def dof(self) -> int:
        """Number of joints."""
        return len(self.joints)

    @property
    def lower(self) -> Array:
        """Lower joint limits (rad or m)."""
        return self._lo.copy()

    @property
    def upper(self) -> Array:
        """Upper joint limits (rad or m)."""
        return self._hi.copy()

    @property
    def max_speeds(self) -> Array:
        """Per-joint speed limits (rad/s or m/s; inf where none is published)."""
        return np.array([j.max_speed for j in self.joints])

    @property
    def revolute(self) -> NDArray[np.bool_]:
        """Mask of the revolute joints."""
        return ~self._prismatic

    def _vector(self, q: ArrayLike, what: str = "q") -> Array:
        v = np.asarray(q, dtype=np.float64)
        if v.shape != (self.dof,) or not np.all(np.isfinite(v)):
            raise KinematicsError(
                f"robot '{self.name}': {what} must be {self.dof} finite numbers, got {q!r}"
            )
        return v

    def pose(self, name: str) -> Array:
        """A named joint pose (rad/m)."""
        if name not in self.poses:
            raise KinematicsError(
                f"robot '{self.name}' has no pose '{name}'; known: {', '.join(self.poses) or 'none'}"
            )
        return self.poses[name].copy()

    def with_(self, **changes: object) -> Robot:
        """A copy with some fields replaced (e.g. ``robot.with_(base=T, name="puma_1")``)."""
        return replace(self, **changes)

    # ---------------------------------------------------------------- limits
    def within_limits(self, q: ArrayLike, tol: float = 1e-9) -> bool:
        """True when every joint value lies within its limits (+- tol)."""
        v = self._vector(q)
        return bool(np.all(v >= self._lo - tol) and np.all(v <= self._hi + tol))

    def check_limits(self, q: ArrayLike, tol: float = 1e-9) -> Array:
        """Return q, or raise JointLimitError naming the first joint outside its limits."""
        v = self._vector(q)
        bad = np.flatnonzero((v < self._lo - tol) | (v > self._hi + tol))
        if len(bad):
            i = int(bad[0])
            unit, k = ("deg", np.degrees) if not self._prismatic[i] else ("m", lambda x: x)
            raise JointLimitError(
                f"robot '{self.name}' joint {i + 1} ('{self.joints[i].name}') = {k(v[i]):.4g} {unit} "
                f"is outside its limits [{k(self._lo[i]):.4g}, {k(self._hi[i]):.4g}] {unit}"
            )
        return v

    def wrap_to_limits(self, q: ArrayLike, near: ArrayLike | None = None) -> Array | None:
        """The 2*pi-equivalent of q inside the limits (revolute joints), nearest to ``near``.

        Returns None when some joint has no equivalent inside its limits. Prismatic joints
        are not wrapped.
        """
        v = self._vector(q).copy()
        ref = v if near is None else self._vector(near, "near")
        for i in np.flatnonzero(~self._prismatic):
            k_lo = np.ceil((self._lo[i] - v[i]) / TWO_PI - 1e-12)
            k_hi = np.floor((self._hi[i] - v[i]) / TWO_PI + 1e-12)
            if k_lo > k_hi:
                return None
            ks = np.arange(k_lo, k_hi + 1)
            cand = v[i] + TWO_PI * ks
            v[i] = cand[np.argmin(np.abs(cand - ref[i]))]
        v = np.clip(v, self._lo, self._hi)  # remove the 1e-12 slack
        return v if np.all(v >= self._lo) and np.all(v <= self._hi) else None

    # ---------------------------------------------------------------- forward kinematics
    def _link_transforms(self, Q: Array) -> Array:
        """(N, n, 4, 4) joint transforms A_i for joint vectors Q (N, n)."""
        N, n = Q.shape
        theta = np.where(self._prismatic, self._theta, Q + self._offset)
        d = np.where(self._prismatic, Q + self._offset, self._d)
        ct, st = np.cos(theta), np.sin(theta)
        ca, sa = np.broadcast_to(self._ca, (N, n)), np.broadcast_to(self._sa, (N, n))
        a = np.broadcast_to(self._a, (N, n))
        A = np.zeros((N, n, 4, 4))
        if self.convention == "standard":
            A[..., 0, 0], A[..., 0, 1], A[..., 0, 2], A[..., 0, 3] = ct, -st * ca, st * sa, a * ct
            A[..., 1, 0], A[..., 1, 1], A[..., 1, 2], A[..., 1, 3] = st, ct * ca, -ct * sa, a * st
            A[..., 2, 1], A[..., 2, 2], A[..., 2, 3] = sa, ca, d
        else:
            A[..., 0, 0], A[..., 0, 1], A[..., 0, 3] = ct, -st, a
            A[..., 1, 0], A[..., 1, 1], A[..., 1, 2], A[..., 1, 3] = st * ca, ct * ca, -sa, -d * sa
            A[..., 2, 0], A[..., 2, 1], A[..., 2, 2], A[..., 2, 3] = st * sa, ct * sa, ca, d * ca
        A[..., 3, 3] = 1.0
        return A

    def _as_batch(self, Q: ArrayLike) -> Array:
        M = np.asarray(Q, dtype=np.float64)
        if M.ndim != 2 or M.shape[1] != self.dof or not np.all(np.isfinite(M)):
            raise KinematicsError(
                f"robot '{self.name}': Q must be (N, {self.dof}) finite, got shape {M.shape}"
            )
        return M

    def fk_batch(self, Q: ArrayLike) -> Array:
        """Tool poses (N, 4, 4) in the base frame for joint vectors Q (N, n) (m, rad)."""
        A = self._link_transforms(self._as_batch(Q))
        T = np.matmul(self.base, A[:, 0])
        for i in range(1, self.dof):
            T = np.matmul(T, A[:, i])
        return np.matmul(T, self.tool)

    def fk(self, q: ArrayLike) -> Array:
        """Tool pose (4, 4) in the base frame for joint vector q (m, rad)."""
        return self.fk_batch(self._vector(q)[None])[0]

    def link_frames(self, q: ArrayLike) -> Array:
        """Frames 0..n (n+1, 4, 4): frame 0 is ``base``, frame i follows joint i (no tool)."""
        A = self._link_transforms(self._vector(q)[None])[0]
        F = np.empty((self.dof + 1, 4, 4))
        F[0] = self.base
        for i in range(self.dof):
            F[i + 1] = F[i] @ A[i]
        return F

    def jacobian(self, q: ArrayLike) -> Array:
        """Geometric Jacobian (6, n) of the tool point in the base frame: rows v (m/s), w (rad/s).

        Joint i moves about (or along) the z axis of frame i-1 (standard DH) or of frame i
        (modified DH).
        """
        F = self.link_frames(q)
        p_tool = (F[-1] @ self.tool)[:3, 3]
        axes = F[:-1] if self.convention == "standard" else F[1:]
        z, o = axes[:, :3, 2], axes[:, :3, 3]
        J = np.zeros((6, self.dof))
        rev = ~self._prismatic
        J[:3, rev] = np.cross(z[rev], p_tool - o[rev]).T
        J[3:, rev] = z[rev].T
        J[:3, self._prismatic] = z[self._prismatic].T
        return J

    # ---------------------------------------------------------------- inverse kinematics
    def ik_closed_form(self, T: ArrayLike, q_current: ArrayLike | None = None) -> list[IKSolution]:
        """Every distinct closed-form solution of pose T (Puma family), up to 8, nearest first."""
        if self.family != "puma":
            raise KinematicsError(
                f"robot '{self.name}' has no closed-form IK (family {self.family!r}); use Robot.ik"
            )
        from workcell.robots.ik_closed import puma_ik

        return puma_ik(self, T, q_current)

    def ik(
        self,
        T: ArrayLike,
        q0: ArrayLike | None = None,
        *,
        config: str | None = None,
        method: Literal["mink", "newton-gauss"] = "mink",
        **options: object,
    ) -> IKSolution:
        """Numerical IK for pose T (4x4, base frame) from q0; never a silent wrong q.

        ``method="mink"`` (differential IK with restarts; Puma robots are also seeded from
        the closed form) or ``"newton-gauss"`` (the thesis's solver). ``config`` restricts
        a Puma solution to a configuration such as ``"lun"``.
        """
        from workcell.robots.ik_numeric import solve

        return solve(self, T, q0, config=config, method=method, **options)

    def ik_or_raise(self, T: ArrayLike, q0: ArrayLike | None = None, **kwargs: object) -> Array:
        """Like :meth:`ik` but returns q, raising UnreachableError with the reason on failure."""
        sol = self.ik(T, q0, **kwargs)
        if not sol.success:
            raise UnreachableError(f"robot '{self.name}' cannot reach the pose: {sol.reason}")
        return sol.q

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, {self.dof} joints, {self.convention} DH)"


def joints_from_table(
    table: Sequence[Sequence[float]],
    limits_deg: Sequence[tuple[float, float]],
    *,
    max_speed_deg: Sequence[float] | None = None,
    names: Sequence[str] | None = None,
) -> tuple[Joint, ...]:
    """Revolute joints from rows (a m, d m, alpha deg, offset deg) and limits in degrees."""
    out = []
    for i, (a, d, alpha, off) in enumerate(table):
        out.append(
            Joint(
                name=names[i] if names else f"j{i + 1}",
                a=float(a),
                d=float(d),
                alpha=float(np.radians(alpha)),
                offset=float(np.radians(off)),
                limits=(float(np.radians(limits_deg[i][0])), float(np.radians(limits_deg[i][1]))),
                max_speed=float(np.radians(max_speed_deg[i])) if max_speed_deg else float("inf"),
            )
        )
    return tuple(out)
