"""Configurations in the vendors' terms: which joint solution a Cartesian target means.

Our letters (:mod:`workcell.robots.ik_closed`): shoulder ``r``/``l`` (the wrist point
ahead of or behind axis 1), elbow ``u``/``d`` (above or below the shoulder-wrist line),
wrist ``n``/``f``. The vendors' published definitions, and how they map:

- **KUKA Status S** (bits): bit 0 = 1 when the wrist root point has a negative x in the
  A1 coordinate system ("overhead area": our ``l``); bit 1 = 1 when A3 >= phi, the
  stretched-arm angle (KUKA's home A2 = -90, A3 = 90 reads bit 1 = 1): the elbow on the
  upper side of the arm itself, which is our ``u`` while the wrist is ahead of the
  shoulder and our ``d`` behind it (our letters say up and down in the base's z); bit 2 = 1 when A5 <= 0
  (-180 < A5 <= 0 or A5 >= 180), 0 when sin(A5) > 0. **Turn T**: bit i = 1 when axis
  i+1 is negative.
- **ABB confdata** [cf1, cf4, cf6, cfx]: cfN the quadrant of axis N, floor(angle / 90
  deg) (0 for 0..90, -1 for -90..0, ...); cfx 0..7 = 4 x (wrist centre behind axis 1:
  ``l``) + 2 x (wrist centre behind the lower arm: the elbow on the arm's lower side, as
  KUKA's bit 1 = 0) + (axis 5 negative).
- **FANUC CONFIG** 'F|N U|D T|B, t4, t5, t6': flip (``f``) or no flip (``n``; the LR Mate
  200iD at J5 = -90, tool down, is N), elbow up or down (on the arm's upper side, as
  KUKA's bit 1), front (T, ``r``) or back (B), and
  the turn numbers of J4, J5, J6 ($SCR_GRP.$TURN_AXIS's default): floor((J + 180) / 360)
  with J in degrees (0 for -180 <= J < 180, 1 for 180 <= J < 540, ...).
- **Universal Robots**: none in the pose; ``get_inverse_kin(p, qnear=q)`` picks the
  solution nearest ``q`` (we write the solution itself as qnear).

:func:`solutions` lists every joint solution of a pose within the limits (the closed
form's, and each one's other whole-turn representatives); :func:`select` picks the one
whose vendor configuration is the given one (nearest the current joints when the format
leaves joints unnamed, e.g. FANUC J1-J3 turns). FANUC joint values: the controller's J3
is measured from the horizontal, J3_fanuc = J3 - J2 on the LR Mate 200iD (the
ROS-Industrial driver's J23_factor = 1: J3_ros = J3_fanuc + J2_fanuc).

A joint within 1e-9 rad of a boundary counts as on it (0 is positive, a quadrant or turn
starts at its lower edge), so rounding in the last digits never changes a bit.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.errors import KinematicsError, ProgramError
from workcell.robots.ik_closed import config_of, family_model
from workcell.robots.opw_solve import arm_plane
from workcell.robots.robot import Robot

__all__ = [
    "abb_confdata",
    "fanuc_config",
    "fanuc_from_joints",
    "fanuc_j23",
    "fanuc_to_joints",
    "kuka_status_turn",
    "letters",
    "select",
    "solutions",
]

Array = NDArray[np.float64]
_TWO_PI = 2.0 * math.pi
EPS = 1e-9  # rad: a joint this close to a boundary (0, a quadrant, +-180) counts as on it


def letters(robot: Robot, q: ArrayLike) -> str | None:
    """Our configuration letters of q, or None for a robot without a closed form."""
    if robot.ik_family is None:
        return None
    try:
        return config_of(robot, q)
    except KinematicsError:
        return None


def _arm_up(robot: Robot, q: Array, c: str) -> bool:
    """The elbow on the arm's own upper side (KUKA's A3 >= phi): for an OPW arm the side
    it has with the elbow up and the wrist ahead of the shoulder (our ``u`` there, ``d``
    when the wrist is behind the shoulder); for other arms our ``u``."""
    if robot.ik_family == "opw":
        m = family_model(robot)
        return arm_plane(m, m.theta(q[None, :])[0])[1] >= 0.0
    return c[1] == "u"


def kuka_status_turn(robot: Robot, q: ArrayLike) -> tuple[int, int]:
    """KUKA's Status and Turn of joint values q (rad), module doc."""
    v = np.asarray(q, dtype=np.float64)
    c = letters(robot, v) or "ru"
    s = (c[0] == "l") | _arm_up(robot, v, c) << 1 | (math.sin(float(v[4])) < EPS) << 2
    t = sum(1 << i for i in range(min(6, len(v))) if v[i] < -EPS)
    return int(s), int(t)


def abb_confdata(robot: Robot, q: ArrayLike) -> tuple[int, int, int, int]:
    """ABB's confdata (cf1, cf4, cf6, cfx) of joint values q (rad), module doc."""
    v = np.asarray(q, dtype=np.float64)
    c = letters(robot, v) or "ru"

    def quadrant(a: float) -> int:
        return math.floor((a + EPS) / (0.5 * math.pi))

    cfx = 4 * (c[0] == "l") + 2 * (not _arm_up(robot, v, c)) + (float(v[4]) < -EPS)
    return quadrant(float(v[0])), quadrant(float(v[3])), quadrant(float(v[5])), int(cfx)


def fanuc_j23(robot: Robot) -> int:
    """The J2/J3 coupling factor of the robot's FANUC controller: 1 for the LR Mate 200iD
    (ROS-Industrial ``J23_factor``), 0 for every other arm."""
    return 1 if robot.name.startswith("fanuc_lrmate200id") else 0


def fanuc_from_joints(robot: Robot, q: ArrayLike) -> Array:
    """FANUC controller joint values (rad) of our joint values q: J3 - factor x J2."""
    v = np.array(q, dtype=np.float64)
    v[2] -= fanuc_j23(robot) * v[1]
    return v


def fanuc_to_joints(robot: Robot, j: ArrayLike) -> Array:
    """Our joint values (rad) of FANUC controller joint values j: J3 + factor x J2."""
    v = np.array(j, dtype=np.float64)
    v[2] += fanuc_j23(robot) * v[1]
    return v


def _turn(a: float) -> int:
    return math.floor((a + math.pi + EPS) / _TWO_PI)


def fanuc_config(robot: Robot, q: ArrayLike) -> tuple[str, int, int, int]:
    """FANUC's configuration ('N U T', t4, t5, t6) of our joint values q (rad)."""
    v = np.asarray(q, dtype=np.float64)
    c = letters(robot, v) or "run"
    flags = ("F" if c[2] == "f" else "N") + " " + ("U" if _arm_up(robot, v, c) else "D")
    flags += " " + ("T" if c[0] == "r" else "B")
    return flags, _turn(float(v[3])), _turn(float(v[4])), _turn(float(v[5]))


def solutions(robot: Robot, Tb: ArrayLike, q_near: ArrayLike | None = None) -> list[Array]:
    """Every joint solution (rad) of tool pose Tb (4x4, base frame) within the limits: the
    closed form's, each with every whole-turn representative of its revolute joints.
    A robot without a closed form: the one :meth:`Robot.ik` finds from ``q_near``."""
    if robot.ik_family is None:
        sol = robot.ik(Tb, q_near)
        return [np.asarray(sol.q, dtype=np.float64)] if sol.success else []
    out: list[Array] = []
    lo, hi = robot.lower - 1e-9, robot.upper + 1e-9
    for s in robot.ik_closed_form(Tb, q_near):
        base = np.asarray(s.q, dtype=np.float64)
        options = []
        for j, a in enumerate(base):
            if not robot.revolute[j]:
                options.append([a])
                continue
            k0 = math.ceil((lo[j] - a) / _TWO_PI)
            k1 = math.floor((hi[j] - a) / _TWO_PI)
            options.append([a + k * _TWO_PI for k in range(k0, k1 + 1)])
        out.extend(np.array(c) for c in itertools.product(*options))
    return out


def select(
    robot: Robot,
    Tb: ArrayLike,
    key: Callable[[Array], object],
    wanted: object,
    q_current: ArrayLike,
    what: str,
) -> Array:
    """The joint solution of pose Tb (base frame) whose ``key(q)`` is ``wanted``, nearest
    ``q_current`` (in the largest joint change) when several are. ProgramError naming
    ``what`` (the target) and the configurations there are, when none is."""
    cur = np.asarray(q_current, dtype=np.float64)
    sols = solutions(robot, Tb, cur)
    if robot.ik_family is None:  # no configurations to choose from: the numerical IK's
        if not sols:
            raise ProgramError(f"{what}: the pose is out of reach")
        return sols[0]
    match = [q for q in sols if key(q) == wanted]
    if not match:
        have = sorted({str(key(q)) for q in sols})
        raise ProgramError(
            f"{what}: no joint solution within the limits has configuration {wanted}; "
            f"the pose's solutions have: {', '.join(have) or 'none (out of reach)'}"
        )
    return min(match, key=lambda q: float(np.abs(q - cur).max()))
