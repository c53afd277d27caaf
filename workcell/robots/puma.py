"""The built-in Puma 560 and Puma 260 (thesis §4.2; parameters as tabled in DESIGN.md).

Sources:
- Puma 560: standard DH of P. Corke's Robotics Toolbox (``models/DH/Puma560.py``, after
  Armstrong, Khatib and Burdick 1986), d1 = 0.67183 m the base height; joint limits from
  the same file (after Wang and Chen); named poses qz, qr, qs, qn from the same file
  (qn's q3 = pi is stored as its in-limit equivalent -pi).
- Puma 260: RPI General Robotics Toolbox ``puma260b_robot()``, which cites page 2-2 of the
  Puma 260 manual (a2 = sqrt(7.8^2 + 0.75^2) in, elbow drop absorbed by the
  +-atan2(0.75, 7.8) = +-5.4923 deg offsets; exact values, as DESIGN.md tables them);
  flange at Tz(0.05588) from frame 6; joint speed limits of a 260-class arm from the
  same source. Thesis home pose (0, 0, -90, 0, 90, 0) deg.
- Speeds of the Puma 560: none in the sources used (Corke's model has none); it is given
  the 260-class speeds above (an assumption, documented as such). Accelerations and jerks
  of both are derived from the speeds (:func:`workcell.robots.library.derived_limits`).
  The thesis examples keep their own constant nominal speed (``nominal_speed``, 0.3 rad/s).
"""

from __future__ import annotations

import numpy as np

from workcell import spatial
from workcell.robots.chain import joints_from_table
from workcell.robots.robot import Robot

__all__ = ["PUMA260_A2", "PUMA260_DELTA", "PUMA260_FLANGE", "puma260", "puma560"]

PUMA260_FLANGE = 0.05588  # m, flange from frame 6 along z
_DEG = np.pi / 180

# rows: a (m), d (m), alpha (deg), offset (deg)
_PUMA560 = [
    (0.0, 0.67183, 90.0, 0.0),
    (0.4318, 0.0, 0.0, 0.0),
    (0.0203, 0.15005, -90.0, 0.0),
    (0.0, 0.4318, 90.0, 0.0),
    (0.0, 0.0, -90.0, 0.0),
    (0.0, 0.0, 0.0, 0.0),
]
_PUMA560_LIMITS = [(-160, 160), (-45, 225), (-225, 45), (-110, 170), (-100, 100), (-266, 266)]

# DESIGN.md: the upper arm is 7.8 in long with a 0.75 in elbow drop, absorbed by offsets
PUMA260_A2 = 0.0254 * float(np.hypot(7.8, 0.75))  # m (0.1990337...)
PUMA260_DELTA = float(np.degrees(np.arctan2(0.75, 7.8)))  # deg (5.4923...)
_PUMA260 = [
    (0.0, 0.3302, 90.0, 0.0),
    (PUMA260_A2, 0.0, 0.0, -PUMA260_DELTA),
    (0.0, 0.12446, -90.0, PUMA260_DELTA),
    (0.0, 0.2032, 90.0, 0.0),
    (0.0, 0.0, -90.0, 0.0),
    (0.0, 0.0, 0.0, 0.0),
]
_PUMA260_LIMITS = [(-160, 160), (-76, 256), (-214, 34), (-194, 384), (-122, 122), (-267, 267)]
_PUMA260_SPEEDS = [119, 119, 164, 577, 431, 397]  # deg/s


def _limits(speeds_deg: list[int]) -> dict[str, list[float]]:
    """Speeds (deg/s) and the accelerations and jerks derived from them (deg/s^2, deg/s^3)."""
    from workcell.robots.library import derived_limits

    acc, jerk = derived_limits(speeds_deg)  # linear in the speeds: degrees in, degrees out
    return {"max_speed_deg": speeds_deg, "max_acceleration_deg": acc, "max_jerk_deg": jerk}


def _geometry(robot: Robot, *, scale: float) -> Robot:
    from workcell.robots.geometry import puma_geometry

    return puma_geometry(robot, scale=scale)


def puma560(*, geometry: bool = True) -> Robot:
    """The Puma 560 (standard DH, Corke's table); link solids when ``geometry``."""
    r = Robot(
        name="puma560",
        joints=joints_from_table(_PUMA560, _PUMA560_LIMITS, **_limits(_PUMA260_SPEEDS)),
        poses={
            "qz": np.zeros(6),
            "qr": np.array([0, np.pi / 2, -np.pi / 2, 0, 0, 0]),
            "qs": np.array([0, 0, -np.pi / 2, 0, 0, 0]),
            "qn": np.array([0, np.pi / 4, -np.pi, 0, np.pi / 4, 0]),
            "home": np.array([0, 0, -90, 0, 90, 0]) * _DEG,
        },
        source="P. Corke, Robotics Toolbox for Python, models/DH/Puma560.py (standard DH); "
        "speeds assumed as the Puma 260's (none published in the sources)",
    )
    return _geometry(r, scale=1.0) if geometry else r


def puma260(*, geometry: bool = True) -> Robot:
    """The Puma 260 (standard DH, Puma 560 convention); tool at the flange Tz(0.05588)."""
    r = Robot(
        name="puma260",
        joints=joints_from_table(_PUMA260, _PUMA260_LIMITS, **_limits(_PUMA260_SPEEDS)),
        tool=spatial.translation(0, 0, PUMA260_FLANGE),
        poses={
            "home": np.array([0, 0, -90, 0, 90, 0]) * _DEG,
            "zero": np.zeros(6),
        },
        source="RPI General Robotics Toolbox puma260b_robot(), after the Puma 260 manual p. 2-2 "
        "(geometry and joint speeds)",
    )
    return _geometry(r, scale=0.46) if geometry else r
