"""Serial robots: a chain of joints, base and tool transforms, link geometry (thesis §4.2).

A :class:`Robot` is an ordered chain of :class:`~workcell.robots.chain.Joint` (a fixed
origin transform, an axis and a kind each; standard and modified DH rows are two ways to
build one, see :mod:`workcell.robots.chain`) plus a base and a tool transform. Units:
metres, radians, seconds.

Forward kinematics ``fk(q) = base @ A_1(q_1) ... A_n(q_n) @ tool`` with
``A_i = origin_i @ M_i(q_i)``: the tool pose in the robot's base frame (``base`` is the
identity unless set). Link frame i (:meth:`Robot.link_frames`) is ``base @ A_1 ... A_i``;
for a robot built from DH rows it is DH frame i.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import partial
from typing import TYPE_CHECKING, Literal, NamedTuple

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from workcell.errors import JointLimitError, KinematicsError, UnreachableError
from workcell.robots.chain import Joint, linear_terms
from workcell.spatial import as_transform

if TYPE_CHECKING:
    from workcell.modeller.model import Model
    from workcell.robots.gripper import Gripper

__all__ = ["IKSolution", "Joint", "LinkGeometry", "Robot"]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi
_FK_CHUNK = 2048  # poses per batched FK step (measured: 1.5M poses/s here against 0.8M unchunked)


@dataclass(frozen=True)
class LinkGeometry:
    """One solid on link ``link`` (0 = base, i = after joint i), placed by ``transform``
    (4x4) in that link's frame: a modeller ``block`` of ``Robot.model``, or a ``mesh``
    (a closed ``trimesh.Trimesh``, m, e.g. read from a robot description's file) with
    its convex ``collision`` pieces (in the mesh's frame; empty: its convex hull).
    Exactly one of ``block`` and ``mesh`` is given. RGBA ``colour``; ``source`` says
    where a mesh came from (a file path), for messages and saving.
    """

    link: int
    block: str | None
    transform: Array
    colour: tuple[float, ...] | None = None
    mesh: trimesh.Trimesh | None = None
    collision: tuple[trimesh.Trimesh, ...] = ()
    source: str = ""

    def __post_init__(self) -> None:
        if (self.block is None) == (self.mesh is None):
            raise KinematicsError(
                f"link {self.link} geometry: give exactly one of a modeller block and a mesh"
            )


class IKSolution(NamedTuple):
    """One inverse-kinematics answer (an immutable record; a named tuple, cheap to build).

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


@dataclass(frozen=True, eq=False)
class Robot:
    """A serial manipulator: a chain of joints, base and tool transforms, named poses, link geometry.

    ``tool`` (4x4) places the tool frame in the last link frame (the flange for robots
    whose tool is not set); ``nominal_speed`` (rad/s) is the thesis's robot speed: the
    speed of the joint that moves most in a joint-space motion. ``model`` holds the link
    solids named by ``geometry``; ``source`` cites where the parameters come from. The
    closed-form IK family (:attr:`ik_family`) is detected from the geometry.
    """

    name: str
    joints: tuple[Joint, ...]
    base: Array = field(default_factory=lambda: np.eye(4))
    tool: Array = field(default_factory=lambda: np.eye(4))
    poses: Mapping[str, Array] = field(default_factory=dict)
    nominal_speed: float = 0.3
    model: Model | None = None
    geometry: tuple[LinkGeometry, ...] = ()
    source: str = ""
    gripper: Gripper | None = None

    def __post_init__(self) -> None:
        put = partial(object.__setattr__, self)  # frozen: derived fields are set once here
        put("joints", tuple(self.joints))
        if not self.joints:
            raise KinematicsError(f"robot '{self.name}' has no joints")
        if not all(isinstance(j, Joint) for j in self.joints):
            raise KinematicsError(f"robot '{self.name}': joints must be Joint objects")
        names = [j.name for j in self.joints]
        if len(set(names)) != len(names):
            raise KinematicsError(f"robot '{self.name}': joint names repeat: {names}")
        put("base", as_transform(self.base, rigid=True, name=f"{self.name} base"))
        put("tool", as_transform(self.tool, rigid=True, name=f"{self.name} tool"))
        put("poses", {k: self._vector(v, f"pose '{k}'") for k, v in dict(self.poses).items()})
        if not self.nominal_speed > 0:
            raise KinematicsError(f"robot '{self.name}': nominal_speed must be > 0 rad/s")
        put("_axes", np.array([j.axis for j in self.joints]))  # (n, 3) in link frames
        put("_points", np.array([j.axis_point for j in self.joints]))  # (n, 3) m
        put("_prismatic", np.array([j.kind == "prismatic" for j in self.joints]))
        put("_any_prismatic", bool(self._prismatic.any()))
        put("_lo", np.array([j.limits[0] for j in self.joints]))
        put("_hi", np.array([j.limits[1] for j in self.joints]))
        put("_lo_turns", self._lo / TWO_PI - 1e-12)  # limits in turns, with the wrap slack
        put("_hi_turns", self._hi / TWO_PI + 1e-12)
        # every joint matrix is linear in (u, v): A = C0 + u C1 + v C2, with (u, v) =
        # (cos q, sin q) for a revolute joint and (q, 0) for a prismatic one
        C0, C12 = linear_terms(self.joints)
        put("_C", (C0, np.ascontiguousarray(C12[:, 0]), np.ascontiguousarray(C12[:, 1])))
        # the same with the base folded into joint 1 and the tool into joint n (for FK)
        C0, C12 = C0.reshape(-1, 4, 4).copy(), C12.reshape(-1, 2, 4, 4).copy()
        C0[0], C12[0] = self.base @ C0[0], self.base @ C12[0]
        C0[-1], C12[-1] = C0[-1] @ self.tool, C12[-1] @ self.tool
        put("_Cf", (C0.reshape(-1, 16), C12[:, 0].reshape(-1, 16), C12[:, 1].reshape(-1, 16)))

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
    def max_accelerations(self) -> Array:
        """Per-joint acceleration limits (rad/s^2 or m/s^2; inf where none is known)."""
        return np.array([j.max_acceleration for j in self.joints])

    @property
    def max_jerks(self) -> Array:
        """Per-joint jerk limits (rad/s^3 or m/s^3; inf where none is known)."""
        return np.array([j.max_jerk for j in self.joints])

    @property
    def revolute(self) -> NDArray[np.bool_]:
        """Mask of the revolute joints."""
        return ~self._prismatic

    def _vector(self, q: ArrayLike, what: str = "q") -> Array:
        v = np.asarray(q, dtype=np.float64)
        if v.shape != (self.dof,) or not np.all(np.isfinite(v)):
            got = f"{v.size} value(s)" if v.ndim == 1 else f"an array of shape {v.shape}"
            if v.shape == (self.dof,):
                got = "a value that is not finite"
            raise KinematicsError(
                f"robot '{self.name}': {what} must be {self.dof} finite numbers (one per "
                f"joint), got {got}"
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

    def wrap_batch(
        self, Q: ArrayLike, near: ArrayLike | None = None
    ) -> tuple[Array, NDArray[np.bool_]]:
        """2*pi-equivalents of joint vectors Q (..., n) inside the limits, vectorised.

        Each revolute joint takes the equivalent nearest to ``near`` (..., n) (default: its
        own value); prismatic joints are not wrapped. Returns (wrapped, ok) where ``ok``
        (..., n) marks the joints that have an in-limit value; a joint without one keeps
        its given value.
        """
        Q = np.asarray(Q, dtype=np.float64)
        turns = Q * (1.0 / TWO_PI)
        k_lo = np.ceil(self._lo_turns - turns)
        k_hi = np.floor(self._hi_turns - turns)
        k = (
            0.0
            if near is None
            else np.rint(np.asarray(near, dtype=np.float64) * (1.0 / TWO_PI) - turns)
        )
        k = np.minimum(np.maximum(k, k_lo), k_hi)
        ok = k_lo <= k_hi
        if self._any_prismatic:  # prismatic joints are not wrapped: in limits or not
            k = np.where(self._prismatic, 0.0, k)
            inside = (self._lo - 1e-12 <= Q) & (self._hi + 1e-12 >= Q)
            ok = np.where(self._prismatic, inside, ok)
        W = np.where(ok, np.minimum(np.maximum(Q + TWO_PI * k, self._lo), self._hi), Q)
        return W, ok

    def wrap_to_limits(self, q: ArrayLike, near: ArrayLike | None = None) -> Array | None:
        """The 2*pi-equivalent of q inside the limits (revolute joints), nearest to ``near``.

        Returns None when some joint has no equivalent inside its limits (see :meth:`wrap_batch`).
        """
        v = self._vector(q)
        W, ok = self.wrap_batch(v, None if near is None else self._vector(near, "near"))
        return W if ok.all() else None

    # ---------------------------------------------------------------- forward kinematics
    def _joint_matrices(self, Q: Array, *, folded: bool = False) -> Array:
        """Joint transforms A_i (..., n, 4, 4) for joint vectors Q (..., n), unvalidated.

        ``folded``: base included in A_1 and tool in A_n, so their product is the tool pose.
        """
        c, s = np.cos(Q), np.sin(Q)
        if self._any_prismatic:
            c[..., self._prismatic] = Q[..., self._prismatic]
            s[..., self._prismatic] = 0.0
        C0, C1, C2 = self._Cf if folded else self._C
        A = c[..., None] * C1
        A += s[..., None] * C2
        A += C0
        return A.reshape(*Q.shape, 4, 4)

    def _as_batch(self, Q: ArrayLike) -> Array:
        M = np.asarray(Q, dtype=np.float64)
        if M.ndim != 2 or M.shape[1] != self.dof or not np.all(np.isfinite(M)):
            raise KinematicsError(
                f"robot '{self.name}': Q must be (N, {self.dof}) finite, got shape {M.shape}"
            )
        return M

    def fk_batch(self, Q: ArrayLike) -> Array:
        """Tool poses (N, 4, 4) in the base frame for joint vectors Q (N, n) (m, rad)."""
        Q = self._as_batch(Q)
        if len(Q) <= _FK_CHUNK:
            return self._fk_unchecked(Q)
        out = np.empty((len(Q), 4, 4))
        for i in range(0, len(Q), _FK_CHUNK):  # chunks keep the temporaries in cache: ~2x faster
            out[i : i + _FK_CHUNK] = self._fk_unchecked(Q[i : i + _FK_CHUNK])
        return out

    def _fk_unchecked(self, Q: Array) -> Array:
        """:meth:`fk_batch` for a finite (N, n) float array (solvers that made Q themselves)."""
        A = self._joint_matrices(Q, folded=True)
        tails = []  # multiply neighbours pairwise (fewer, larger products); odd ones wait
        while A.shape[1] > 1:
            if A.shape[1] % 2:
                tails.append(A[:, -1])
                A = A[:, :-1]
            A = np.matmul(A[:, 0::2], A[:, 1::2])
        T = A[:, 0]
        for t in reversed(tails):
            T = np.matmul(T, t)
        return T

    def fk(self, q: ArrayLike) -> Array:
        """Tool pose (4, 4) in the base frame for joint vector q (m, rad)."""
        return self.fk_batch(self._vector(q)[None])[0]

    def _frames(self, q: Array) -> Array:
        A = self._joint_matrices(q)
        F = np.empty((self.dof + 1, 4, 4))
        F[0] = self.base
        for i in range(self.dof):
            F[i + 1] = F[i] @ A[i]
        return F

    def link_frames(self, q: ArrayLike) -> Array:
        """Frames 0..n (n+1, 4, 4): frame 0 is ``base``, frame i follows joint i (no tool)."""
        return self._frames(self._vector(q))

    def pose_jacobian(self, q: ArrayLike) -> tuple[Array, Array]:
        """Tool pose (4, 4) and geometric Jacobian (6, n) of the tool point, base frame.

        Jacobian rows: linear velocity (m/s) then angular velocity (rad/s) per unit joint
        speed. Joint i turns about (or slides along) its axis line, fixed in link frame i.
        """
        q = np.asarray(q, dtype=np.float64)
        if q.shape != (self.dof,):
            q = self._vector(q)  # raises with a clear message
        F = self._frames(q)
        T = F[-1] @ self.tool
        R = F[1:, :3, :3]
        z = np.einsum("nij,nj->ni", R, self._axes)  # axis directions in the base frame
        p = np.einsum("nij,nj->ni", R, self._points) + F[1:, :3, 3]
        r = T[:3, 3] - p
        J = np.empty((6, self.dof))
        J[0] = z[:, 1] * r[:, 2] - z[:, 2] * r[:, 1]
        J[1] = z[:, 2] * r[:, 0] - z[:, 0] * r[:, 2]
        J[2] = z[:, 0] * r[:, 1] - z[:, 1] * r[:, 0]
        J[3:] = z.T
        if self._any_prismatic:
            J[:3, self._prismatic] = z[self._prismatic].T
            J[3:, self._prismatic] = 0.0
        return T, J

    def jacobian(self, q: ArrayLike) -> Array:
        """Geometric Jacobian (6, n) of the tool point in the base frame (see :meth:`pose_jacobian`)."""
        return self.pose_jacobian(self._vector(q))[1]

    # ---------------------------------------------------------------- inverse kinematics
    @property
    def ik_family(self) -> str | None:
        """The closed-form IK family, ``"opw"``, ``"ur"`` or None, detected from the joint
        axes and verified by FK (:mod:`workcell.robots.ik_closed`; cached per robot)."""
        from workcell.robots.ik_closed import family_of

        return family_of(self)

    def ik_closed_form(self, T: ArrayLike, q_current: ArrayLike | None = None) -> list[IKSolution]:
        """Every distinct closed-form solution of pose T (OPW and UR families), up to 8.

        In-limit solutions first, then nearest to ``q_current`` (see
        :func:`workcell.robots.ik_closed.ik_report` for the fields and the order).
        KinematicsError for a robot without a closed-form family.
        """
        from workcell.robots.ik_closed import ik_all

        return ik_all(self, T, q_current)

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

        ``method="mink"`` (differential IK with restarts; OPW and UR robots are also seeded
        from the closed form) or ``"newton-gauss"`` (the thesis's solver). ``config``
        restricts the solution of an OPW or UR robot to a configuration such as ``"lun"``.
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
        return f"Robot({self.name!r}, {self.dof} joints)"
